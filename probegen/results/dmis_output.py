"""Read DMIS output files: feature actuals, tolerance actuals and measured points.

A DMIS measuring program writes its results as DMIS statements (``OUTPUT/FA(C1)``
gives ``FA(C1)=FEAT/CIRCLE,...``).  This reader keeps what a report needs:

* **feature actuals** ``FA(name)=FEAT/<type>,...`` for POINT, PLANE, LINE, CIRCLE,
  SPHERE, CYLNDR, CONE and TORUS, decoded into :class:`FeatureActual` (see ``LAYOUTS``);
* **tolerance actuals** ``TA(name)=TOL/<kind>,...,INTOL|OUTOL`` as
  :class:`ToleranceActual`;
* **measured points** as :class:`MeasuredPoint`: ``PTMEAS/CART|POL,...`` lines echoed
  in the output (named after the enclosing ``MEAS/<type>,F(name),n`` ... ``ENDMES``
  block) and every ``FA(name)=FEAT/POINT`` actual (also listed as a feature).

Lengths are returned in mm whatever ``UNITS/MM|CM|METER|INCH|FEET`` says (the setting
in force at each statement; mm before the first), angles in degrees (``ANGDEC`` or
``ANGRAD``).  ``POL`` positions ``(r, angle, z)`` become Cartesian.  Direction vectors
are returned as unit vectors; a vector of three direction *angles* in degrees, as some
vendors write it (``179.99, 90.01, 90.0``), is recognised and turned into cosines.
Nominals (``F(name)=FEAT/...``), datums, sensors and every other statement are read
past.

Robustness is statement by statement (:func:`probegen.dmis.parse_dmis_recovering`): a
statement that does not parse, or a feature or tolerance whose parameters do not fit
its type, becomes a :class:`~probegen.errors.Diagnostic` (line, column, what was
expected, what was found, caret) and every good statement is still returned.
``strict=True`` turns any diagnostic into a :class:`~probegen.errors.ResultsParseError`.

Example:
    >>> out = parse_dmis_output("FA(C1)=FEAT/CIRCLE,INNER,CART,1,2,3,0,0,1,10\\n")
    >>> out.features[0].position, out.features[0].diameter
    ((1.0, 2.0, 3.0), 10.0)
"""

from __future__ import annotations

import math
import os
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any, Literal

from probegen.dmis import Label, Param, Statement, Text, format_param, parse_dmis_recovering
from probegen.errors import (
    Diagnostic,
    ProbegenError,
    did_you_mean,
    strict_error,
)

Vec3 = tuple[float, float, float]

__all__ = [
    "LAYOUTS",
    "DmisOutput",
    "FeatureActual",
    "MeasuredPoint",
    "ToleranceActual",
    "parse_dmis_output",
    "read_dmis_output",
]


@dataclass(frozen=True, slots=True)
class FeatureActual:
    """A measured feature, ``FA(name)=FEAT/<type>,...``; lengths mm, angles degrees.

    Attributes:
        name: the label name, upper case (``A_CIRCLE`` of ``FA(A_CIRCLE)``).
        type: the DMIS feature type: ``POINT``, ``PLANE``, ``LINE``, ``CIRCLE``,
            ``SPHERE``, ``CYLNDR``, ``CONE`` or ``TORUS``.
        material: ``"INNER"`` (a hole; a torus: air inside the tube), ``"OUTER"`` (a
            boss; a torus: material inside the tube) or None (types without).
        position: the feature's point: centre (circle, sphere, torus), a point on the axis
            (cylinder), the apex (cone), the point (point, plane, line start).
        direction: unit normal (point, plane, circle), axis (cylinder, cone, torus),
            direction (line); None for a point written without one (or as 0, 0, 0)
            and a sphere without an axis.
        diameter: circle, sphere and cylinder diameter; a torus's major diameter
            (twice the radius of the tube's centre circle).
        minor_diameter: a torus's tube (minor) diameter.
        length: cylinder length when written; bounded line length.
        angle: cone included (full apex) angle, degrees.
        end: end point of a bounded line (``LINE,BND``).
        normal: unit normal of the plane a line lies in, when written.
        line: 1-based line number of the statement in the file.
    """

    name: str
    type: str
    material: Literal["INNER", "OUTER"] | None
    position: Vec3
    direction: Vec3 | None
    diameter: float | None = None
    minor_diameter: float | None = None
    length: float | None = None
    angle: float | None = None
    end: Vec3 | None = None
    normal: Vec3 | None = None
    line: int = 0

    @property
    def inner(self) -> bool | None:
        """True for an inner (hole) feature, False for outer, None if not stated."""
        return None if self.material is None else self.material == "INNER"

    @property
    def radius(self) -> float | None:
        """Half the diameter, or None."""
        return None if self.diameter is None else self.diameter / 2.0


@dataclass(frozen=True, slots=True)
class ToleranceActual:
    """An evaluated tolerance, ``TA(name)=TOL/<kind>,...,INTOL|OUTOL``.

    Attributes:
        name: the label name, upper case.
        kind: the tolerance kind (``DIAM``, ``POS``, ``FLAT``, ``CORTOL``, ...).
        values: the numbers as written, in order, converted to mm (or degrees for
            ``ANGL``, ``ANGLB`` and ``ANGLWRT``).
        qualifiers: the words other than INTOL/OUTOL (``2D``, ``XAXIS``, ``RFS``...).
        status: ``"INTOL"`` or ``"OUTOL"``.
        line: 1-based line number of the statement.
    """

    name: str
    kind: str
    values: tuple[float, ...]
    qualifiers: tuple[str, ...]
    status: Literal["INTOL", "OUTOL"]
    line: int = 0

    @property
    def value(self) -> float:
        """The actual (the first number written)."""
        return self.values[0]

    @property
    def intol(self) -> bool:
        """True when the machine judged the feature within tolerance."""
        return self.status == "INTOL"


@dataclass(frozen=True, slots=True)
class MeasuredPoint:
    """A measured point, mm.

    Attributes:
        feature: the feature it belongs to (the ``MEAS`` block's label name, or the
            point feature's own name), None outside any block.
        xyz: the point.
        normal: unit approach/surface normal when written, else None.
        line: 1-based line number of the statement.
        via: ``"PTMEAS"`` (an echoed ``PTMEAS`` line) or ``"FEAT/POINT"`` (a point
            feature actual).
    """

    feature: str | None
    xyz: Vec3
    normal: Vec3 | None
    line: int = 0
    via: Literal["PTMEAS", "FEAT/POINT"] = "PTMEAS"


@dataclass(frozen=True, slots=True)
class DmisOutput:
    """Everything read from one DMIS output file, good records and diagnostics side by side.

    Attributes:
        source: file name or ``<string>``.
        features: feature actuals in file order.
        tolerances: tolerance actuals in file order.
        points: measured points in file order.
        diagnostics: one per statement that could not be read, in line order.
    """

    source: str
    features: tuple[FeatureActual, ...]
    tolerances: tuple[ToleranceActual, ...]
    points: tuple[MeasuredPoint, ...]
    diagnostics: tuple[Diagnostic, ...]

    def feature(self, name: str) -> FeatureActual:
        """Return the last actual of feature ``name`` (any case).

        Raises:
            ProbegenError: no such feature; the message suggests the closest name.
        """
        wanted = name.upper()
        found = [f for f in self.features if f.name == wanted]
        if not found:
            names = {f.name for f in self.features}
            hint = did_you_mean(wanted, names)
            raise ProbegenError(f"{self.source}: no feature actual FA({wanted}){hint}")
        return found[-1]


# ----------------------------------------------------------------------------- decoding

MM_PER_UNIT = {"MM": 1.0, "CM": 10.0, "METER": 1000.0, "INCH": 25.4, "FEET": 304.8}
"""Millimetres per DMIS length unit (the inch is 25.4 mm exactly, by definition)."""

DEGREES_PER_UNIT = {"ANGDEC": 1.0, "ANGRAD": 180.0 / math.pi}
"""Degrees per DMIS angle unit (``ANGDMS`` is not supported)."""

LAYOUTS: dict[str, tuple[tuple[str, ...], ...]] = {
    "POINT": (("position", "direction"), ("position",)),
    "PLANE": (("position", "direction"),),
    "LINE UNBND": (("position", "direction"), ("position", "direction", "normal")),
    "LINE BND": (("position", "end"), ("position", "end", "normal")),
    "CIRCLE": (("position", "direction", "diameter"),),
    "SPHERE": (("position", "diameter"), ("position", "direction", "diameter")),
    "CYLNDR": (
        ("position", "direction", "diameter"),
        ("position", "direction", "diameter", "length"),
    ),
    "CONE": (("position", "direction", "angle"),),
    "TORUS": (("position", "direction", "diameter", "minor_diameter"),),
}
"""The numbers after ``CART``/``POL`` each feature type may have, as field names.

``position``, ``direction``, ``end`` and ``normal`` take three numbers, the sizes one.
A line is ``LINE,UNBND`` (point and direction) or ``LINE,BND`` (start and end points).
"""

FEATURE_TYPES = ("POINT", "PLANE", "LINE", "CIRCLE", "SPHERE", "CYLNDR", "CONE", "TORUS")
"""The feature types read (other types are reported as not supported)."""

_AXIAL = frozenset({"PLANE", "CIRCLE", "CYLNDR", "CONE", "TORUS", "LINE"})
"""Types whose direction may not be 0, 0, 0."""
_WIDTH = {"position": 3, "direction": 3, "end": 3, "normal": 3}
_MATERIAL = ("INNER", "OUTER")
_COORDINATES = ("CART", "POL")
_BOUNDS = ("BND", "UNBND")
_ANGULAR_TOLERANCES = frozenset({"ANGL", "ANGLB", "ANGLWRT"})
_STATUS = ("INTOL", "OUTOL")
_UNIT_TOLERANCE = 1e-6
"""How far from 1 the norm of three direction cosines written as angles may be."""


@dataclass(slots=True)
class _Units:
    """The UNITS in force: mm and degrees per file unit."""

    length: float = 1.0
    angle: float = 1.0


class _DecodeError(Exception):
    """A parameter that does not fit; ``index`` is its position (-1: the statement)."""

    def __init__(self, index: int, message: str) -> None:
        super().__init__(message)
        self.index = index
        self.message = message

    def note(self, text: str) -> _DecodeError:
        """Return the same error with ``(text)`` added to its message."""
        return _DecodeError(self.index, f"{self.message} ({text})")


def _choices(words: tuple[str, ...] | list[str]) -> str:
    return words[0] if len(words) == 1 else ", ".join(words[:-1]) + " or " + words[-1]


def _found(params: tuple[Param, ...], index: int) -> str:
    """Describe parameter ``index`` (or the end of the statement) for a message."""
    if index >= len(params):
        return "end of statement"
    param = params[index]
    if isinstance(param, int | float):
        return f"the number {format_param(param)}"
    if isinstance(param, str):
        return f"the word '{param}'"
    if isinstance(param, Text):
        return "a quoted string"
    text = format_param(param)
    return f"'{text[:24]}...'" if len(text) > 24 else f"'{text}'"


def _fail(params: tuple[Param, ...], index: int, expected: str) -> _DecodeError:
    return _DecodeError(index, f"expected {expected}, found {_found(params, index)}")


def _word(params: tuple[Param, ...], index: int, choices: tuple[str, ...], what: str) -> str:
    """Return parameter ``index`` if it is one of ``choices``."""
    word = params[index] if index < len(params) else None
    if isinstance(word, str) and word in choices:
        return word
    hint = did_you_mean(word, choices) if isinstance(word, str) else ""
    raise _DecodeError(
        index, f"expected {what} ({_choices(choices)}), found {_found(params, index)}{hint}"
    )


def _number(params: tuple[Param, ...], index: int, scale: float, what: str) -> float:
    """Return parameter ``index`` as a finite float times ``scale``."""
    param = params[index] if index < len(params) else None
    if not isinstance(param, int | float):
        raise _fail(params, index, what)
    try:
        value = float(param) * scale
    except OverflowError:
        value = math.inf
    if not math.isfinite(value):
        raise _DecodeError(index, f"expected {what} within range, found {_found(params, index)}")
    return value + 0.0


def _update_units(units: _Units, params: tuple[Param, ...]) -> None:
    """Apply ``UNITS/<length>[,<angle>][,<temperature>]``."""
    units.length = MM_PER_UNIT[_word(params, 0, tuple(MM_PER_UNIT), "a length unit")]
    if len(params) < 2 or params[1] in ("TEMPC", "TEMPF"):
        return
    if params[1] == "ANGDMS":
        raise _fail(params, 1, "an angle unit (ANGDEC or ANGRAD)").note(
            "degrees, minutes and seconds are not supported"
        )
    units.angle = DEGREES_PER_UNIT[_word(params, 1, tuple(DEGREES_PER_UNIT), "an angle unit")]


def _position(params: tuple[Param, ...], at: int, polar: bool, units: _Units) -> Vec3:
    """Read a position: Cartesian ``x, y, z`` or polar ``r, angle, z``."""
    names = ("r", "the polar angle", "z") if polar else ("x", "y", "z")
    scales = (units.length, units.angle if polar else units.length, units.length)
    a, b, c = (_number(params, at + k, scales[k], f"a number ({names[k]})") for k in range(3))
    if not polar:
        return a, b, c
    x, y = a * math.cos(math.radians(b)), a * math.sin(math.radians(b))
    return x + 0.0, y + 0.0, c


def _vector(params: tuple[Param, ...], at: int, units: _Units, what: str) -> Vec3 | None:
    """Read ``i, j, k`` as a unit vector (None for 0, 0, 0); direction angles allowed."""
    v = tuple(_number(params, at + k, 1.0, f"a number ({what} {'ijk'[k]})") for k in range(3))
    norm = math.hypot(*v)
    if norm == 0.0:
        return None
    if not math.isfinite(norm):
        raise _DecodeError(at, f"expected a {what} vector within range, found {v}")
    if norm > 1.5 and all(0.0 <= c * units.angle <= 180.0 for c in v):
        cosines = tuple(math.cos(math.radians(c * units.angle)) for c in v)
        if abs(math.hypot(*cosines) - 1.0) < _UNIT_TOLERANCE:
            v, norm = cosines, math.hypot(*cosines)
    return v[0] / norm + 0.0, v[1] / norm + 0.0, v[2] / norm + 0.0


def _size(params: tuple[Param, ...], at: int, name: str, units: _Units) -> float:
    """Read a diameter, length (mm, above 0) or cone angle (degrees, 0 to 180)."""
    if name == "angle":
        value = _number(params, at, units.angle, "a number (cone angle)")
        if not 0.0 < value < 180.0:
            raise _fail(params, at, "a cone angle between 0 and 180 degrees")
        return value
    what = name.replace("_", " ")
    value = _number(params, at, units.length, f"a number ({what})")
    if not value > 0.0:
        raise _fail(params, at, f"a {what} above 0")
    return value


def _keywords(params: tuple[Param, ...], ftype: str) -> tuple[dict[str, str], int]:
    """Read the words after the feature type: material, BND/UNBND, CART/POL.

    Returns:
        The words found by role and the index of the first number.
    """
    roles = {"coordinates": _COORDINATES}
    if ftype in ("CIRCLE", "SPHERE", "CYLNDR", "CONE", "TORUS"):
        roles["material"] = _MATERIAL
    if ftype == "LINE":
        roles["bounds"] = _BOUNDS
    found: dict[str, str] = {}
    index = 1
    while index < len(params) and isinstance(params[index], str):
        word = params[index]
        role = next((r for r, words in roles.items() if word in words and r not in found), None)
        if role is None:
            expected = [w for r, words in roles.items() if r not in found for w in words]
            raise _fail(params, index, _choices(expected or ["a number"]))
        found[role] = str(word)
        index += 1
    missing = [w for r, words in roles.items() if r not in found for w in words]
    if missing:
        raise _fail(params, index, _choices(missing))
    return found, index


def _decode_feature(units: _Units, params: tuple[Param, ...]) -> dict[str, Any]:
    """Decode ``FEAT/<type>,...`` into FeatureActual fields (without name and line)."""
    ftype = _word(params, 0, FEATURE_TYPES, "a feature type")
    words, first = _keywords(params, ftype)
    key = f"LINE {words['bounds']}" if ftype == "LINE" else ftype
    layout = _layout(params, first, key)
    fields: dict[str, Any] = {"type": ftype, "material": words.get("material"), "direction": None}
    polar, at = words["coordinates"] == "POL", first
    for name in layout:
        if name in ("position", "end"):
            fields[name] = _position(params, at, polar, units)
        elif name in ("direction", "normal"):
            fields[name] = _vector(params, at, units, name)
        else:
            fields[name] = _size(params, at, name, units)
        at += _WIDTH.get(name, 1)
    _finish_feature(fields, params, first)
    return fields


def _layout(params: tuple[Param, ...], first: int, key: str) -> tuple[str, ...]:
    """Pick the layout of ``key`` that has as many numbers as the statement."""
    count = len(params) - first
    for layout in LAYOUTS[key]:
        if sum(_WIDTH.get(name, 1) for name in layout) == count:
            return layout
    options = " or ".join(
        f"{sum(_WIDTH.get(n, 1) for n in layout)} ({', '.join(layout)})" for layout in LAYOUTS[key]
    )
    raise _DecodeError(first, f"expected {options} numbers for {key}, found {count}")


def _finish_feature(fields: dict[str, Any], params: tuple[Param, ...], first: int) -> None:
    """Check the direction a type needs and derive a bounded line's direction and length."""
    if fields["type"] in _AXIAL and "end" not in fields:
        if fields["direction"] is None:
            raise _fail(params, first + 3, "a direction (i, j, k) other than 0, 0, 0")
    if "end" in fields:
        start, end = fields["position"], fields["end"]
        delta = [e - s for s, e in zip(start, end, strict=True)]
        length = math.hypot(*delta)
        if not 0.0 < length < math.inf:
            raise _fail(params, first + 3, "an end point other than the start point")
        fields["length"] = length
        fields["direction"] = tuple(d / length + 0.0 for d in delta)


def _decode_tolerance(
    units: _Units, params: tuple[Param, ...]
) -> tuple[str, tuple[float, ...], tuple[str, ...], Literal["INTOL", "OUTOL"]]:
    """Decode ``TOL/<kind>,...,INTOL|OUTOL``: kind, values, qualifiers, status."""
    kind = params[0] if params else None
    if not isinstance(kind, str):
        raise _fail(params, 0, "a tolerance kind (DIAM, POS, FLAT...)")
    scale = units.angle if kind in _ANGULAR_TOLERANCES else units.length
    values: list[float] = []
    words: list[str] = []
    for index, param in enumerate(params[1:], start=1):
        if isinstance(param, int | float):
            values.append(_number(params, index, scale, "a number"))
        elif isinstance(param, str):
            words.append(param)
        elif not isinstance(param, Label | Text):
            raise _fail(params, index, "a number, a word or a label")
    statuses = [w for w in words if w in _STATUS]
    if len(statuses) != 1:
        raise _fail(params, len(params), "one INTOL or OUTOL")
    if not values:
        raise _fail(params, 1, "the actual value (a number)")
    status: Literal["INTOL", "OUTOL"] = "INTOL" if statuses[0] == "INTOL" else "OUTOL"
    qualifiers = tuple(w for w in words if w not in _STATUS)
    return kind, tuple(values), qualifiers, status


def _decode_point(units: _Units, params: tuple[Param, ...]) -> tuple[Vec3, Vec3 | None]:
    """Decode ``PTMEAS/CART|POL,x,y,z[,i,j,k]``: the point and its normal."""
    polar = _word(params, 0, _COORDINATES, "coordinates") == "POL"
    if len(params) not in (4, 7):
        raise _DecodeError(
            min(len(params), 7),
            f"expected 3 (x, y, z) or 6 (x, y, z, i, j, k) numbers "
            f"after {params[0]}, found {len(params) - 1}",
        )
    xyz = _position(params, 1, polar, units)
    return xyz, _vector(params, 4, units, "normal") if len(params) == 7 else None


# -------------------------------------------------------------------- where a parameter is


def _code_chars(lines: list[str], first: int) -> Iterator[tuple[int, int, str, bool]]:
    """Yield ``(line, column, char, quoted)`` for a statement's text across continuations,
    stopping at a ``$$`` comment or the end of its last line."""
    lineno = first
    while 0 < lineno <= len(lines):
        line, quoted, continues = lines[lineno - 1].rstrip("\r"), False, False
        for column, char in enumerate(line, start=1):
            if char == "'":
                quoted = not quoted
            elif char == "$" and not quoted:
                continues = not line.startswith("$", column)
                break
            yield lineno, column, char, quoted or char == "'"
        if not continues:
            return
        lineno += 1


def _param_position(lines: list[str], first: int, index: int) -> tuple[int, int]:
    """Return the physical ``(line, column)`` where parameter ``index`` of the statement
    starting on line ``first`` begins: -1 means the statement's first character, an
    index past the last parameter the end of the statement."""
    depth, slash, commas, ready = 0, False, 0, False
    where = (first, 1)
    for lineno, column, char, quoted in _code_chars(lines, first):
        if char in " \t\f":
            continue
        if ready or index < 0:
            return lineno, column
        where = (lineno, column + 1)
        if quoted:
            continue
        if char in "([":
            depth += 1
        elif char in ")]":
            depth -= 1
        elif char == "/" and not slash:
            slash, ready = True, index == 0
        elif char == "," and slash and depth == 0:
            commas += 1
            ready = commas == index
    return where


# ------------------------------------------------------------------------------ reading


class _Reader:
    """Walk the statements in order, keeping the units and the current MEAS block."""

    def __init__(self, source: str, lines: list[str]) -> None:
        self.source, self.lines = source, lines
        self.units = _Units()
        self.block: str | None = None
        self.features: list[FeatureActual] = []
        self.tolerances: list[ToleranceActual] = []
        self.points: list[MeasuredPoint] = []
        self.diagnostics: list[Diagnostic] = []

    def read(self, stmt: Statement) -> None:
        """Read one statement; a parameter that does not fit becomes a diagnostic."""
        try:
            self._dispatch(stmt)
        except _DecodeError as exc:
            line, column = _param_position(self.lines, stmt.line, exc.index)
            text = self.lines[line - 1].rstrip("\r") if line <= len(self.lines) else ""
            head = f"{stmt.label}={stmt.major}" if stmt.label else stmt.major
            message = f"{head}: {exc.message}"
            self.diagnostics.append(Diagnostic(self.source, line, column, message, text))

    def _dispatch(self, stmt: Statement) -> None:
        kind = stmt.label.kind if stmt.label else ""
        name = stmt.label.name if stmt.label else ""
        if stmt.major == "UNITS":
            _update_units(self.units, stmt.params)
        elif stmt.major in ("MEAS", "RMEAS"):
            self.block = _block_name(stmt.params)
        elif stmt.major == "ENDMES":
            self.block = None
        elif stmt.major == "PTMEAS":
            xyz, normal = _decode_point(self.units, stmt.params)
            self.points.append(MeasuredPoint(self.block, xyz, normal, stmt.line))
        elif kind == "FA" and stmt.major == "FEAT":
            self._feature(name, stmt)
        elif kind == "TA" and stmt.major == "TOL":
            fields = _decode_tolerance(self.units, stmt.params)
            self.tolerances.append(ToleranceActual(name, *fields, line=stmt.line))

    def _feature(self, name: str, stmt: Statement) -> None:
        fields = _decode_feature(self.units, stmt.params)
        feature = FeatureActual(name, line=stmt.line, **fields)
        self.features.append(feature)
        if feature.type == "POINT":
            xyz, normal = feature.position, feature.direction
            self.points.append(MeasuredPoint(name, xyz, normal, stmt.line, "FEAT/POINT"))

    def result(self, parse_errors: tuple[Diagnostic, ...]) -> DmisOutput:
        """Return the finished output, all diagnostics in line order."""
        diagnostics = sorted((*parse_errors, *self.diagnostics), key=lambda d: (d.line, d.column))
        return DmisOutput(
            self.source,
            tuple(self.features),
            tuple(self.tolerances),
            tuple(self.points),
            tuple(diagnostics),
        )


def _block_name(params: tuple[Param, ...]) -> str | None:
    """Return the feature name of ``MEAS/<type>,F(name),n``, or None."""
    label = params[1] if len(params) > 1 else None
    return label.name if isinstance(label, Label) else None


def parse_dmis_output(text: str, *, source: str = "<string>", strict: bool = False) -> DmisOutput:
    """Parse the text of a DMIS output file.

    Args:
        text: the whole file; CRLF, LF or CR line ends; ``$`` continuations.
        source: the file name used in diagnostics.
        strict: raise instead of returning an output that has diagnostics.

    Returns:
        The feature actuals, tolerance actuals and measured points of every statement
        that could be read, and one diagnostic per statement that could not.

    Raises:
        ResultsParseError: ``strict`` is set and there is at least one diagnostic; it
            carries all of them.
    """
    dmis, parse_errors = parse_dmis_recovering(text, source=source)
    lines = text.removeprefix("\ufeff").replace("\r\n", "\n").replace("\r", "\n").split("\n")
    reader = _Reader(source, lines)
    for stmt in dmis.statements:
        reader.read(stmt)
    output = reader.result(parse_errors)
    if strict and output.diagnostics:
        raise strict_error(output.source, "DMIS output", output.diagnostics)
    return output


def read_dmis_output(path: str | os.PathLike[str], *, strict: bool = False) -> DmisOutput:
    """Read and parse a DMIS output file (UTF-8, or Latin-1 when not valid UTF-8).

    Args:
        path: the file.
        strict: raise instead of returning an output that has diagnostics.

    Raises:
        ProbegenError: the file cannot be read.
        ResultsParseError: ``strict`` is set and the file has diagnostics.
    """
    try:
        with open(path, "rb") as handle:
            data = handle.read()
    except OSError as exc:
        name = os.fspath(path)
        raise ProbegenError(f"cannot read DMIS output '{name}': {exc.strerror}") from exc
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError:
        text = data.decode("latin-1")
    return parse_dmis_output(text, source=os.fspath(path), strict=strict)
