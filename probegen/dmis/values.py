"""Values of executable DMIS: typed variables, expressions and the intrinsic functions.

Types (``DECL``): ``INTGR`` and ``LONG`` hold Python ``int``; ``REAL`` and ``DOUBLE``
``float``; ``CHAR,n`` ``str`` (at most ``n`` characters); ``BOOL`` ``bool``; ``VECTOR`` a
:class:`Vector`.  A variable declared ``NAME[n]`` or ``NAME[n,m]`` is an array, indexed
from 1.  A value assigned is converted to the variable's type: a real into an ``INTGR``
is truncated toward zero (``INT``), a number into a ``CHAR`` is refused (``STR`` converts).

Expressions (:func:`probegen.dmis.reader` ``Expr``, ``Call``, ``Group``): ``+ - * / **``
(an ``INTGR`` divided by an ``INTGR`` stays an ``INTGR`` when it divides exactly, else it is
a ``REAL``), ``.EQ. .NE. .LT. .LE. .GT. .GE.`` (numbers or strings), ``.AND. .OR.
.NOT.``, ``.TRUE.``, ``.FALSE.``, indexing ``A[i]``, vectors added, subtracted, scaled.
Functions (:data:`FUNCTIONS`): ``ABS SQRT EXP LN LOG SIN COS TAN ASIN ACOS ATAN ATAN2
INT NINT MOD SIGN DTOR RTOD PI STR VAL LEN INDX SUBSTR CONCAT UPC LWC TRIM CHR ORD VCART
VPOL VMAG VUNIT VDOT VCROSS``; the trigonometric functions take and give angles in the
program's angle unit (degrees unless ``UNITS/...,ANGRAD``).  Strings: ``SUBSTR(s, i, j)``
is characters ``i`` to ``j`` (1-based, inclusive), ``INDX(s, t)`` the 1-based position of
``t`` in ``s`` (0 when absent).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TypeAlias

from probegen.dmis.reader import Call, Expr, Group, Label, Param, Text, format_param
from probegen.errors import ProbegenError


class DmisProgramError(ProbegenError):
    """A DMIS program that parses but is wrong: an undefined label or variable, a word where
    a number must be, a MEAS block with too few points, an endless loop.  The message names
    source and line."""

    exit_code = 6


class EvalError(Exception):
    """An expression that cannot be evaluated (the executor adds file, line, statement)."""


@dataclass(frozen=True, slots=True)
class Vector:
    """A DMIS ``VECTOR`` value (three components, program units)."""

    x: float
    y: float
    z: float

    def __str__(self) -> str:
        return f"VCART({format_param(self.x)},{format_param(self.y)},{format_param(self.z)})"


Value: TypeAlias = "bool | int | float | str | Vector | Label"

TYPES = ("INTGR", "LONG", "REAL", "DOUBLE", "CHAR", "BOOL", "VECTOR")
"""The variable types of ``DECL``."""

_DEFAULTS: dict[str, Value] = {"INTGR": 0, "LONG": 0, "REAL": 0.0, "DOUBLE": 0.0, "CHAR": "",
                               "BOOL": False, "VECTOR": Vector(0.0, 0.0, 0.0)}

MAX_ARRAY = 100_000
"""Most elements of one array."""


@dataclass(slots=True)
class Variable:
    """A declared variable: its type, CHAR length, array dimensions (empty for a scalar)
    and value(s) (row-major for an array); ``measured`` is the line of the ``OBTAIN``
    of an actual its value came from (None: known before the run)."""

    type: str
    length: int | None
    dims: tuple[int, ...]
    values: list[Value]
    measured: list[int | None] = field(default_factory=list)

    @classmethod
    def declared(cls, type_: str, length: int | None, dims: tuple[int, ...]) -> Variable:
        count = math.prod(dims) if dims else 1
        if count > MAX_ARRAY:
            raise EvalError(f"an array of {count} elements (at most {MAX_ARRAY})")
        return cls(type_, length, dims, [_DEFAULTS[type_]] * count, [None] * count)

    def slot(self, indices: tuple[Value, ...], name: str) -> int:
        """Return the flat position of ``name[indices]`` (1-based indices)."""
        if len(indices) != len(self.dims):
            raise EvalError(f"{name} has {len(self.dims)} indices, found {len(indices)}"
                            if self.dims else f"{name} is not an array")
        flat = 0
        for index, size in zip(indices, self.dims, strict=True):
            if isinstance(index, bool) or not isinstance(index, int | float) or \
                    index != int(index):
                raise EvalError(f"{name}: an index must be an integer, found {show(index)}")
            if not 1 <= index <= size:
                raise EvalError(f"{name}: index {int(index)} outside 1..{size}")
            flat = flat * size + int(index) - 1
        return flat

    def convert(self, value: Value, name: str) -> Value:
        """Return ``value`` as this variable's type, or raise EvalError."""
        kind = self.type
        if isinstance(value, Label):
            raise EvalError(f"{name} is {kind}: cannot hold the label {value}")
        if kind in ("INTGR", "LONG", "REAL", "DOUBLE"):
            number = _number(value, name)
            return int(number) if kind in ("INTGR", "LONG") else float(number)
        if kind == "BOOL":
            return truth(value, name)
        if kind == "VECTOR":
            if not isinstance(value, Vector):
                raise EvalError(f"{name} is a VECTOR, found {show(value)}")
            return value
        if not isinstance(value, str):
            raise EvalError(f"{name} is CHAR, found the number {show(value)} (STR converts)")
        if self.length is not None and len(value) > self.length:
            raise EvalError(f"{name} is CHAR,{self.length}: '{value}' is {len(value)} long")
        return value


def show(value: Value) -> str:
    """Return a value as DMIS text (a string quoted)."""
    if isinstance(value, bool):
        return ".TRUE." if value else ".FALSE."
    if isinstance(value, str):
        return str(Text(value))
    return format_param(value) if isinstance(value, int | float) else str(value)


def _number(value: Value, what: str) -> int | float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise EvalError(f"{what}: expected a number, found {show(value)}")
    return value


def truth(value: Value, what: str = "a condition") -> bool:
    """Return a BOOL value (a number is true when it is not 0)."""
    if isinstance(value, bool):
        return value
    if isinstance(value, int | float):
        return value != 0
    raise EvalError(f"{what}: expected .TRUE. or .FALSE., found {show(value)}")


def _checked(value: float, what: str) -> float:
    if not math.isfinite(value):
        raise EvalError(f"{what} is not a finite number")
    return value


# ---------------------------------------------------------------------------- functions


def _vec(value: Value, what: str) -> Vector:
    if not isinstance(value, Vector):
        raise EvalError(f"{what}: expected a VECTOR, found {show(value)}")
    return value


def _text(value: Value, what: str) -> str:
    if not isinstance(value, str):
        raise EvalError(f"{what}: expected a string, found {show(value)}")
    return value


def _whole(value: Value, what: str) -> int:
    number = _number(value, what)
    if number != int(number):
        raise EvalError(f"{what}: expected an integer, found {show(value)}")
    return int(number)


def _substr(s: Value, i: Value, j: Value | None = None) -> Value:
    text = _text(s, "SUBSTR")
    first = _whole(i, "SUBSTR start")
    last = len(text) if j is None else _whole(j, "SUBSTR end")
    return text[max(first, 1) - 1 : max(last, 0)]


def _str(value: Value, *_: Value) -> Value:
    if isinstance(value, str):
        return value
    return show(value)


def _val(value: Value) -> Value:
    text = _text(value, "VAL").strip()
    try:
        return int(text) if text.lstrip("+-").isdigit() else float(text)
    except ValueError:
        raise EvalError(f"VAL: '{text}' is not a number") from None


def _unit(v: Value) -> Value:
    vec = _vec(v, "VUNIT")
    norm = math.sqrt(vec.x ** 2 + vec.y ** 2 + vec.z ** 2)
    if norm == 0.0:
        raise EvalError("VUNIT of a zero vector")
    return Vector(vec.x / norm, vec.y / norm, vec.z / norm)


def _cross(a: Value, b: Value) -> Value:
    u, v = _vec(a, "VCROSS"), _vec(b, "VCROSS")
    return Vector(u.y * v.z - u.z * v.y, u.z * v.x - u.x * v.z, u.x * v.y - u.y * v.x)


Function: TypeAlias = Callable[..., Value]


def _numeric(op: Callable[[float], float], name: str) -> Function:
    def call(x: Value) -> Value:
        return _checked(op(float(_number(x, name))), name)
    return call


@dataclass(frozen=True, slots=True)
class Functions:
    """The intrinsic functions for one angle unit (radians per program angle unit)."""

    angle: float = math.pi / 180.0

    def table(self) -> dict[str, tuple[int, int, Function]]:
        """Name -> (fewest arguments, most arguments, function)."""
        a = self.angle

        def trig(op: Callable[[float], float], name: str) -> Function:
            return _numeric(lambda x: op(x * a), name)

        def inverse(op: Callable[[float], float], name: str) -> Function:
            def call(x: Value) -> Value:
                value = float(_number(x, name))
                if op is not math.atan and not -1.0 <= value <= 1.0:
                    raise EvalError(f"{name}({show(x)}): outside -1..1")
                return op(value) / a
            return call

        def atan2(y: Value, x: Value) -> Value:
            return math.atan2(float(_number(y, "ATAN2")), float(_number(x, "ATAN2"))) / a

        def vpol(r: Value, theta: Value, z: Value) -> Value:
            rr, t = float(_number(r, "VPOL")), float(_number(theta, "VPOL")) * a
            return Vector(rr * math.cos(t), rr * math.sin(t), float(_number(z, "VPOL")))

        return {
            "ABS": (1, 1, lambda x: abs(_number(x, "ABS"))),
            "SQRT": (1, 1, _numeric(_sqrt, "SQRT")),
            "EXP": (1, 1, _numeric(_exp, "EXP")),
            "LN": (1, 1, _numeric(lambda x: _log(x, math.log), "LN")),
            "LOG": (1, 1, _numeric(lambda x: _log(x, math.log10), "LOG")),
            "SIN": (1, 1, trig(math.sin, "SIN")), "COS": (1, 1, trig(math.cos, "COS")),
            "TAN": (1, 1, trig(math.tan, "TAN")),
            "ASIN": (1, 1, inverse(math.asin, "ASIN")), "ACOS": (1, 1, inverse(math.acos, "ACOS")),
            "ATAN": (1, 1, inverse(math.atan, "ATAN")), "ATAN2": (2, 2, atan2),
            "INT": (1, 1, lambda x: int(_checked(float(_number(x, "INT")), "INT"))),
            "NINT": (1, 1, lambda x: _nint(_number(x, "NINT"))),
            "MOD": (2, 2, _mod), "SIGN": (2, 2, _sign),
            "DTOR": (1, 1, lambda x: float(_number(x, "DTOR")) * math.pi / 180.0),
            "RTOD": (1, 1, lambda x: float(_number(x, "RTOD")) * 180.0 / math.pi),
            "PI": (0, 0, lambda: math.pi),
            "STR": (1, 3, _str), "VAL": (1, 1, _val),
            "LEN": (1, 1, lambda s: len(_text(s, "LEN"))),
            "INDX": (2, 2, lambda s, t: _text(s, "INDX").find(_text(t, "INDX")) + 1),
            "SUBSTR": (2, 3, _substr),
            "CONCAT": (1, 64, lambda *s: "".join(_text(x, "CONCAT") for x in s)),
            "UPC": (1, 1, lambda s: _text(s, "UPC").upper()),
            "LWC": (1, 1, lambda s: _text(s, "LWC").lower()),
            "TRIM": (1, 1, lambda s: _text(s, "TRIM").strip()),
            "CHR": (1, 1, _chr), "ORD": (1, 1, lambda s: _ord(_text(s, "ORD"))),
            "VCART": (3, 3, lambda x, y, z: Vector(*(float(_number(v, "VCART"))
                                                     for v in (x, y, z)))),
            "VPOL": (3, 3, vpol),
            "VMAG": (1, 1, lambda v: math.sqrt(sum(c * c for c in _parts(_vec(v, "VMAG"))))),
            "VUNIT": (1, 1, _unit),
            "VDOT": (2, 2, lambda u, v: sum(p * q for p, q in zip(
                _parts(_vec(u, "VDOT")), _parts(_vec(v, "VDOT")), strict=True))),
            "VCROSS": (2, 2, _cross),
        }


def _parts(v: Vector) -> tuple[float, float, float]:
    return v.x, v.y, v.z


def _sqrt(x: float) -> float:
    if x < 0.0:
        raise EvalError(f"SQRT of a negative number ({format_param(x)})")
    return math.sqrt(x)


def _exp(x: float) -> float:
    if x > 700.0:
        raise EvalError(f"EXP({format_param(x)}) overflows")
    return math.exp(x)


def _log(x: float, op: Callable[[float], float]) -> float:
    if x <= 0.0:
        raise EvalError(f"the logarithm of {format_param(x)} (must be > 0)")
    return op(x)


def _nint(x: float) -> int:
    value = _checked(float(x), "NINT")
    return int(math.floor(abs(value) + 0.5)) * (1 if value >= 0 else -1)


def _mod(a: Value, b: Value) -> Value:
    x, y = _number(a, "MOD"), _number(b, "MOD")
    if y == 0:
        raise EvalError("MOD by zero")
    return math.fmod(x, y) if isinstance(x, float) or isinstance(y, float) else \
        int(math.fmod(x, y))


def _sign(a: Value, b: Value) -> Value:
    x, y = _number(a, "SIGN"), _number(b, "SIGN")
    return abs(x) if y >= 0 else -abs(x)


def _chr(x: Value) -> Value:
    code = _whole(x, "CHR")
    if not 0 < code < 256:
        raise EvalError(f"CHR({code}): outside 1..255")
    return chr(code)


def _ord(s: str) -> Value:
    if len(s) != 1:
        raise EvalError(f"ORD expects one character, found '{s}'")
    return ord(s)


# --------------------------------------------------------------------------- operators


def arithmetic(op: str, left: Value, right: Value) -> Value:
    """``left op right`` for ``+ - * / **`` (numbers; vectors for ``+ -`` and scaling)."""
    if isinstance(left, Vector) or isinstance(right, Vector):
        return _vector_op(op, left, right)
    if op == "+" and isinstance(left, str) and isinstance(right, str):
        return left + right
    x, y = _number(left, f"'{op}'"), _number(right, f"'{op}'")
    if op == "+":
        return x + y
    if op == "-":
        return x - y
    if op == "*":
        return _checked(x * y, "a product") if isinstance(x * y, float) else x * y
    if op == "/":
        if y == 0:
            raise EvalError("division by zero")
        if isinstance(x, int) and isinstance(y, int) and x % y == 0:
            return x // y
        return _checked(x / y, "a quotient")
    try:
        result = x ** y
    except (OverflowError, ZeroDivisionError):
        raise EvalError(f"{show(x)}**{show(y)} cannot be computed") from None
    if isinstance(result, complex) or (isinstance(result, int) and abs(result) > 10 ** 18):
        raise EvalError(f"{show(x)}**{show(y)} cannot be computed")
    return _checked(result, "a power") if isinstance(result, float) else result


def _vector_op(op: str, left: Value, right: Value) -> Value:
    if isinstance(left, Vector) and isinstance(right, Vector) and op in "+-":
        sign = 1.0 if op == "+" else -1.0
        return Vector(left.x + sign * right.x, left.y + sign * right.y, left.z + sign * right.z)
    if op in ("*", "/"):
        vec, scale = (left, right) if isinstance(left, Vector) else (right, left)
        if isinstance(vec, Vector) and not isinstance(scale, Vector):
            k = float(_number(scale, f"'{op}'"))
            if op == "/":
                if k == 0.0 or not isinstance(left, Vector):
                    raise EvalError("division of a vector by zero, or by a vector")
                k = 1.0 / k
            return Vector(vec.x * k, vec.y * k, vec.z * k)
    raise EvalError(f"'{op}' between {show(left)} and {show(right)}")


_RELATIONS: dict[str, Callable[[object, object], bool]] = {
    ".EQ.": lambda a, b: a == b, ".NE.": lambda a, b: a != b,
    ".LT.": lambda a, b: a < b,  # type: ignore[operator]
    ".LE.": lambda a, b: a <= b,  # type: ignore[operator]
    ".GT.": lambda a, b: a > b,  # type: ignore[operator]
    ".GE.": lambda a, b: a >= b,  # type: ignore[operator]
}


def relation(op: str, left: Value, right: Value) -> bool:
    """``left op right`` for the comparisons (two numbers or two strings; .EQ./.NE. any)."""
    numbers = all(isinstance(v, int | float) and not isinstance(v, bool) for v in (left, right))
    strings = isinstance(left, str) and isinstance(right, str)
    if not (numbers or strings or op in (".EQ.", ".NE.")):
        raise EvalError(f"{op} between {show(left)} and {show(right)}")
    return _RELATIONS[op](left, right)


def to_param(value: Value) -> tuple[Param, ...]:
    """Return a value as statement parameters (a VECTOR as its three components)."""
    if isinstance(value, Vector):
        return value.x, value.y, value.z
    if isinstance(value, bool):
        return (".TRUE." if value else ".FALSE.",)
    if isinstance(value, str):
        return (Text(value),)
    return (value,)


__all__ = [
    "TYPES", "Call", "DmisProgramError", "EvalError", "Expr", "Functions", "Group",
    "Value", "Variable", "Vector", "arithmetic", "relation", "show", "to_param", "truth",
]
