"""Program identity and the planned probing moves a DPRNT log is checked against.

A program prints its identity on its first log line (``docs/results.md``, "Log identity"):

    PGSTART O1001 V1 H3F09A2C1

``H`` and 8 upper-case hex digits are the first 32 bits of the SHA-256 of a canonical
text made of

* the spec's content: the spec file parsed as TOML and written back as JSON with sorted
  keys (comments, blank lines, key order and line endings do not count; every value does,
  tolerances included, since the in-process decisions the program prints depend on
  them); a spec built in code without a readable file counts by the ``repr`` of its
  program number, name and features;
* the planned touches: for each probing move of the program in order, its kind (``PT`` or
  ``LOC``), feature id, index, the nominal ball centre where the search starts and where
  it ends (work coordinates, mm, 4 decimals as a program prints them).

Why this and not the emitted program text: the touches are exactly what ``ingest``
matches a log against, and the same spec gives the same touches for every dialect that
prints a DPRNT log (Fanuc, Haas, LinuxCNC), so a log is accepted whichever of them ran it,
and a new probegen release that only words a comment differently does not orphan old
logs; a changed spec value, model, profile (feeds aside) or plan changes the identity.
The text is rounded as programs are, so it is repeatable across machines like the
golden programs are.

:func:`planned_touches` evaluates the program nominally (run-time variables at their
nominal values, as :mod:`probegen.planning.collision` does) to give each touch's search
segment and how far the run-time location may move it (:attr:`PlannedTouch.uncertainty`).
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from probegen import ir
from probegen.planning.collision import _Walker
from probegen.results.dprnt_records import IDENTITY_DIGITS

if TYPE_CHECKING:
    from probegen.spec import Spec

Vec3 = tuple[float, float, float]

IDENTITY_PREFIX = "H"
"""The letter before the hex digits of the identity token (``H3F09A2C1``)."""


@dataclass(frozen=True, slots=True)
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

    def distance(self, xyz: Vec3) -> float:
        """Distance (mm) of ball centre ``xyz`` from the planned search segment."""
        a, b, p = np.array(self.start), np.array(self.end), np.array(xyz)
        ab = b - a
        t = float(np.clip((p - a) @ ab / max(float(ab @ ab), 1e-300), 0.0, 1.0))
        return float(np.linalg.norm(p - (a + t * ab)))


def planned_touches(program: ir.Program, plans: Sequence[Any] = ()) -> tuple[PlannedTouch, ...]:
    """Every probing move of ``program`` in order, evaluated at nominal.

    ``plans`` are the located features (see :func:`probegen.planning.collision.located`):
    their uncertainty goes to every touch placed from a run-time value or a local frame.
    """
    r = program.setup.ball_diameter / 2.0
    w = _Walker(plans, r)
    out: list[PlannedTouch] = []
    for node in ir.walk(program.body):
        if isinstance(node, ir.Assign):
            a = w.value(node.a)
            w.values[node.name] = (a + w.value(node.b)) / 2.0 if node.b is not None else (
                a + node.offset)
        elif isinstance(node, ir.LocalFrame):
            w.frames.append((node.name, w.centres[node.feature]))
        elif isinstance(node, ir.RestoreFrame):
            w.frames.pop()
        elif isinstance(node, ir.Touch):
            n = np.array(node.normal)
            contact = w.point(node.contact)
            start = contact + (r + node.approach) * n
            end = contact + (r - node.overtravel) * n
            moved = bool(w.frames) or any(isinstance(c, ir.Var) for c in node.contact)
            kind: Literal["PT", "LOC"] = "LOC" if node.role is ir.TouchRole.LOCATE else "PT"
            out.append(PlannedTouch(kind, node.feature, node.index, _vec(start), _vec(end),
                                    w.uncertainty if moved else 0.0))
            for axis, name in enumerate(node.store):
                if name is not None:
                    w.values[name] = float((contact + r * n - w.origin())[axis])
    return tuple(out)


def _vec(a: np.ndarray) -> Vec3:
    x, y, z = (float(v) for v in a)
    return x, y, z


def _mm(v: float) -> str:
    """A length as programs print it (4 decimals, never ``-0.0000``)."""
    return f"{round(v, 4) + 0.0:.4f}"


def spec_content(spec: Spec) -> str:
    """The spec's canonical content (see the module docstring)."""
    import tomllib

    try:
        data = Path(spec.source).read_bytes()
        doc = tomllib.loads(data.decode("utf-8"))
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError):
        return repr((spec.program_number, spec.program_name, spec.features))
    return json.dumps(doc, sort_keys=True, default=str, ensure_ascii=True)


def identity_of(content: str, touches: Sequence[PlannedTouch]) -> str:
    """The identity token (``H`` + 8 upper-case hex digits) of ``content`` and ``touches``."""
    lines = [content] + [
        f"{t.kind} {t.feature} {t.index} " + " ".join(_mm(v) for v in (*t.start, *t.end))
        for t in touches]
    digest = hashlib.sha256("\n".join(lines).encode("utf-8")).hexdigest()
    return IDENTITY_PREFIX + digest[:IDENTITY_DIGITS].upper()


def program_identity(spec: Spec, program: ir.Program) -> str:
    """The identity of the program planned from ``spec``."""
    return identity_of(spec_content(spec), planned_touches(program))
