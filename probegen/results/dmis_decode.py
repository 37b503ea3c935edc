"""Decode the parameters of DMIS output statements into record fields.

``UNITS``, ``FEAT/<type>``, ``TOL/<kind>`` and ``PTMEAS`` parameters become mm, degrees
and unit vectors (see :mod:`probegen.results.dmis_output`).  A parameter that does not
fit raises :class:`_DecodeError` carrying its index, for the reader to turn into a
diagnostic.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Literal

from probegen.dmis.reader import Label, Param, Text, format_param
from probegen.errors import did_you_mean
from probegen.results.dmis_records import Vec3

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
