"""Program identity (the ``H`` token of ``PGSTART``) and the planned touches a log is checked
against: the light half, which reading a log needs (no planning imported).

A program prints its identity on its first log line (``docs/results.md``, "Log identity"):

    PGSTART O1001 V1 H3F09A2C1

``H`` and 8 upper-case hex digits are the first 32 bits of the SHA-256 of the program's
canonical content: the IR program (:mod:`probegen.ir`) as planned for a controller that
computes at run time, every node written out field by field, lengths and other numbers
rounded to 4 decimals as programs print them, comments left out.  So the identity covers
everything the program does and prints: the setup (number, units, stylus, feeds, work
offset), every move and touch of the plan, and the limits of its in-process decisions.

Why the IR and not the emitted text or the spec file: ``ingest`` plans the spec again and
gets the same IR without emitting a program, for every dialect that prints a DPRNT log
(Fanuc, Haas, LinuxCNC: a log is accepted whichever of them ran it); a new release that
only words a comment differently does not orphan old logs; and a spec change the program
does not see (a tolerance evaluated offline, a comment, a moved file) leaves the identity
alone, so a log can be evaluated again against a revised tolerance.  Any change to what
the machine does (a feature, the model, the profile's stylus or feeds, an action's
limits) changes it.  Rounded as programs are, it is repeatable across machines like the
golden programs.

:func:`probegen.planning.identity.planned_touches` evaluates a program nominally (run-time
variables at their nominal values, as :mod:`probegen.planning.collision` does) to give
each touch's search segment and how far the run-time location may move it
(:attr:`PlannedTouch.uncertainty`); this module holds what reading a log needs and
imports no planning.
"""

from __future__ import annotations

import dataclasses
import hashlib
from collections.abc import Sequence
from enum import Enum
from typing import Any, Literal

import numpy as np

from probegen import ir

Vec3 = tuple[float, float, float]

IDENTITY_PREFIX = "H"
"""The letter before the hex digits of the identity token (``H3F09A2C1``)."""

IDENTITY_DIGITS = 8
"""Hex digits of the program identity on ``PGSTART`` (``H`` and 8 digits: the first 32
bits of the SHA-256 of the program's canonical content)."""


@dataclasses.dataclass(frozen=True, slots=True)
class PlannedTouch:
    """One probing move as planned, in the terms a DPRNT record names it.

    Attributes:
        kind: ``"PT"`` (measuring) or ``"LOC"`` (locating), the DPRNT keyword.
        feature: feature id.
        index: the printed index.
        start: nominal ball centre where the search starts (work coordinates, mm).
        end: nominal ball centre where the search ends, ``overtravel`` past the nominal
            contact (mm).
        uncertainty: how far the real search line may lie from the nominal one because
            the program places it from values measured at run time (a located sphere's
            centre), mm; 0 for a move at fixed coordinates.
    """

    kind: Literal["PT", "LOC"]
    feature: str
    index: int
    start: Vec3
    end: Vec3
    uncertainty: float

    def offset(self, xyz: Vec3) -> np.ndarray:
        """Ball centre ``xyz`` less the nearest point of the planned search segment, mm."""
        a, b, p = np.array(self.start), np.array(self.end), np.array(xyz)
        ab = b - a
        t = float(np.clip((p - a) @ ab / max(float(ab @ ab), 1e-300), 0.0, 1.0))
        return p - (a + t * ab)

    def distance(self, xyz: Vec3) -> float:
        """Distance (mm) of ball centre ``xyz`` from the planned search segment."""
        return float(np.linalg.norm(self.offset(xyz)))

    def worst_axis(self, xyz: Vec3) -> int:
        """The axis (0, 1, 2) along which ``xyz`` is farthest from the search segment."""
        return int(np.argmax(np.abs(self.offset(xyz))))


def vec3_of(a: np.ndarray) -> Vec3:
    x, y, z = (float(v) for v in a)
    return x, y, z


def _mm(v: float) -> str:
    """A length as programs print it (4 decimals, never ``-0.0000``)."""
    return f"{round(v, 4) + 0.0:.4f}"


def canonical(value: Any) -> str:
    """A repeatable text of an IR value (see the module docstring): dataclasses field by
    field, floats to 4 decimals, enums by value, ``Comment`` nodes and the fields of
    ``_LEFT_OUT`` left out, and so is every field at its default value (a release that
    adds an optional IR field keeps the identity of every program that does not use it,
    so the logs of those programs still read)."""
    if isinstance(value, ir.Comment):
        return ""
    if isinstance(value, bool | int | str) or value is None:
        return repr(value)
    if isinstance(value, float):
        return _mm(value)
    if isinstance(value, Enum):
        return repr(value.value)
    if isinstance(value, tuple | list):
        return "[" + ",".join(canonical(v) for v in value) + "]"
    if dataclasses.is_dataclass(value):
        fields = [f"{f.name}={canonical(getattr(value, f.name))}"
                  for f in dataclasses.fields(value)
                  if (type(value).__name__, f.name) not in _LEFT_OUT
                  and not _at_default(f, getattr(value, f.name))]
        return f"{type(value).__name__}({','.join(fields)})"
    return repr(value)


_LEFT_OUT = {("Setup", "identity"), ("Setup", "calibration"), ("Setup", "calibration_id"),
             ("Check", "corrections"), ("Check", "ball_radius"), ("Setup", "options"),
             ("Setup", "line_length"), ("Setup", "program_memory"),
             ("Setup", "limits_source"), ("Setup", "program_size"),
             ("Setup", "common_variables"), ("Setup", "alarm_text_length")}
"""Fields the identity leaves out: the identity itself, and the probe calibration a program
was compiled with and the radius it gives the on-control fits (its own ``PGCAL`` line ties
the log to it, and ingest warns when it differs: a recalibrated program measures the same
touches); and the control's options and limits (which reset codes and override locks the
text carries, how long it may be: the same touches either way)."""


def _at_default(field: dataclasses.Field[Any], value: Any) -> bool:
    """Whether ``value`` is the field's declared default."""
    if field.default is not dataclasses.MISSING:
        return bool(value == field.default)
    if field.default_factory is not dataclasses.MISSING:
        return bool(value == field.default_factory())
    return False


def identity_of(content: str) -> str:
    """The identity token (``H`` + 8 upper-case hex digits) of a canonical text."""
    digest = hashlib.sha256(content.encode("utf-8")).hexdigest()
    return IDENTITY_PREFIX + digest[:IDENTITY_DIGITS].upper()


def map_identity(text: str, touches: Sequence[Any]) -> str:
    """The identity of a posted program (``probegen post``): the DMIS program as posted
    and its touches (``post.featuremap.PostTouch``: id, index, start, direction, reach)."""
    lines = [text] + [f"PT {t.id} {t.index} {canonical((t.start, t.direction, t.reach))}"
                      for t in touches]
    return identity_of("\n".join(lines))
