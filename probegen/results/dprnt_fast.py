"""The fast path of the DPRNT reader: well-formed lines read by regular expressions.

Owns the compiled patterns for upper-case ``PT``/``LOC``/``CTR`` lines, the bulk of
every log, and the loop over the lines of a log that sends each line either through
them or, when they do not match exactly, through the grammar
(:func:`probegen.results.dprnt_grammar._read_line`).  Only lines the grammar reads to
exactly the same record take the fast way, so both paths give the same log.
"""

from __future__ import annotations

import dataclasses
import math
import re
from collections.abc import Callable
from typing import Literal

from probegen.results.dprnt_grammar import _read_line
from probegen.results.dprnt_records import MAX_FEATURE_ID, MAX_INDEX_DIGITS, Centre, Touch, _Builder

_NUMBER = r"([+-]?[0-9.]+)[ \t]*"
_XYZ = rf"X[ \t]*{_NUMBER}Y[ \t]*{_NUMBER}Z[ \t]*{_NUMBER}"
_FEATURE = rf"([A-Z][A-Z0-9]{{0,{MAX_FEATURE_ID - 1}}})[ \t]+"
_INDEX = rf"0*([1-9][0-9]{{0,{MAX_INDEX_DIGITS - 1}}})\.?[ \t]+"
_FAST_TOUCH = re.compile(rf"[ \t]*(PT|LOC)[ \t]+(?:{_FEATURE}|{_INDEX}){_INDEX}{_XYZ}")
"""A well-formed upper-case ``PT``/``LOC`` line, the bulk of every log; its feature by
id or (format V2) by a number a ``FEAT`` line bound before (else the line goes to lark,
which reports it).

A line it matches in full whose three numbers ``float()`` reads as finite, the grammar
reads to the same record: a number or an index is matched whole (a shorter match would
leave a digit or a point where a letter or a blank must follow), so a run of digits and
points that ``float()`` accepts is one UNUMBER; ids have at most MAX_FEATURE_ID
characters, indices run from 1 to 999999.  A sign must touch its digits here (the
grammar allows a blank between them: such lines go to lark, as do ``1.2.3``, ``.`` and
numbers out of range).
"""
_FAST_CENTRE = re.compile(rf"[ \t]*CTR[ \t]+{_FEATURE}{_XYZ}")
"""A well-formed upper-case ``CTR`` line (same rules)."""

_KINDS: dict[str, Literal["PT", "LOC"]] = {"PT": "PT", "LOC": "LOC"}
_UNREAD = (math.nan, math.nan, math.nan)


def _touch_maker() -> Callable[[str, str, int, tuple[float, float, float], int, int], Touch]:
    """Return ``make(kind, feature, index, xyz, line, run) -> Touch`` that fills the slots
    directly: the frozen dataclass ``__init__`` costs twice as much, which counts at a
    million touches.  The unpacking below fails at import if Touch gains a field."""
    kind, feature, index, xyz, line, run = (
        getattr(Touch, field.name).__set__ for field in dataclasses.fields(Touch)
    )
    new = object.__new__

    def make(k: str, f: str, i: int, p: tuple[float, float, float], n: int, r: int) -> Touch:
        touch: Touch = new(Touch)
        kind(touch, k), feature(touch, f), index(touch, i)
        xyz(touch, p), line(touch, n), run(touch, r)
        return touch

    return make


_make_touch = _touch_maker()


def _fast_centre(builder: _Builder, lineno: int, clean: str) -> bool:
    """Read a well-formed CTR line without lark; False: leave the line to lark."""
    match = _FAST_CENTRE.fullmatch(clean)
    if match is None:
        return False
    feature, x, y, z = match.groups()
    xyz = _fast_xyz(x, y, z)
    if not math.isfinite(xyz[0] + xyz[1] + xyz[2]):
        return False
    builder.place(lineno, clean)
    builder.centres.append(Centre(feature, xyz, lineno, builder.run))
    return True


def _fast_xyz(x: str, y: str, z: str) -> tuple[float, float, float]:
    """Return the three numbers, or NaNs if one is not a number (``1.2.3``, ``.``)."""
    try:
        return float(x) + 0.0, float(y) + 0.0, float(z) + 0.0
    except ValueError:
        return _UNREAD


def _no_match(clean: str) -> None:
    """Stand-in for the fast pattern when every line goes to lark."""


def _read_lines(builder: _Builder, lines: list[str], *, fast: bool) -> None:
    """Read every line into ``builder``: well-formed PT/LOC/CTR lines with the patterns
    above (when ``fast``), the others with lark.

    Only lines the grammar reads to exactly the same record take the fast way, so the
    log is the one lark alone gives (``+ 0.0`` turns ``-0.0`` into ``0.0`` as there).
    """
    touch_line = _FAST_TOUCH.fullmatch if fast else _no_match
    touches, isfinite = builder.touches, math.isfinite
    for lineno, clean in enumerate(lines, start=1):
        match = touch_line(clean)
        if match is not None:
            kind, feature, number, index, x, y, z = match.groups()
            if feature is None:
                binding = builder.bound.get(int(number))
                feature = "" if binding is None else binding.feature
        if match is not None and feature:
            try:  # inline: this loop runs once per line of the log
                xyz = (float(x) + 0.0, float(y) + 0.0, float(z) + 0.0)
            except ValueError:
                xyz = _UNREAD
            if isfinite(xyz[0] + xyz[1] + xyz[2]):  # else lark reports (or reads) it
                if builder.end_line or not builder.started:
                    builder.place(lineno, clean)
                touch = _make_touch(_KINDS[kind], feature, int(index), xyz, lineno, builder.run)
                touches.append(touch)
                continue
        if not (fast and _fast_centre(builder, lineno, clean)) and clean.strip(" \t"):
            _read_line(builder, lineno, clean)
