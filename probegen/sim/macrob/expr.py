"""Compile Macro B expressions and conditions into Python closures.

A value is a float or None (*vacant*, ``#0``).  The Fanuc rules for vacant values:

* in arithmetic and functions a vacant value counts as 0 (``#0 + 1`` is 1, ``#0 * 3``
  is 0); a bare variable passes vacancy on (``#2 = #1`` leaves #2 vacant);
* ``EQ`` and ``NE`` tell vacant from 0 (``#1 EQ #0`` holds only when #1 is vacant,
  ``#1 EQ 0`` only when it is 0); ``GT GE LT LE`` treat vacant as 0.

Functions work in degrees and follow parameter NAT = 0 (the default): ``ATAN`` returns
0 to 360 degrees, ``ASIN`` 270 to 90 (a negative angle is returned plus 360), ``ACOS``
0 to 180.  ``ROUND`` rounds half away from zero, ``FIX`` cuts toward zero, ``FUP``
raises away from zero (``FIX[-1.2]`` = -1, ``FUP[-1.2]`` = -2).  ``AND OR XOR`` are
bitwise on the operands rounded to integers; ``a MOD b`` rounds both operands and
keeps the sign of ``a``.  Sines and cosines of multiples of 30 and 45 degrees are
exact (``COS[90]`` is 0, not 6e-17), so comparisons with EQ behave as on the control.

Errors are alarms: division by zero (112), out-of-range arguments such as ``SQRT`` of
a negative number (119), results beyond the control's range of 1e47 (111).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Protocol

from probegen.sim.macrob import ast
from probegen.sim.macrob.base import ARGUMENT_RANGE, OVERFLOW, VARIABLE_RANGE, ZERO_DIVIDE, alarm

Value = float | None
"""A variable's value; None is vacant."""
Getter = Callable[[], Value]
"""A compiled expression: call it to evaluate."""
Test = Callable[[], bool]
"""A compiled condition."""

LIMIT = 1e47
"""Largest magnitude a Macro B value may hold (beyond it: alarm 111)."""


class Variables(Protocol):
    """What compiled expressions need from the variable store."""

    def reader(self, number: int) -> Getter:
        """Return a function reading variable ``number`` (alarm 115 when it has none)."""
        ...

    def read(self, number: int) -> Value:
        """Read variable ``number``."""
        ...


def checked(value: Value) -> Value:
    """Return ``value`` if the control can hold it, else raise alarm 111."""
    if value is None or -LIMIT < value < LIMIT:
        return value
    raise alarm(OVERFLOW, f"{value:g}")


def variable_number(value: Value) -> int:
    """Return the variable number an index expression names (``#[#110+1]``)."""
    index = _round(value or 0.0)
    if index < 0:
        raise alarm(VARIABLE_RANGE, f"#{index}")
    return index


def compile_expr(node: ast.Expr, store: Variables) -> Getter:
    """Compile an expression node into a function of no arguments returning its value."""
    if isinstance(node, ast.Num):
        value = node.value
        if not -LIMIT < value < LIMIT:  # an alarm when (if ever) the block runs
            return lambda: _limit(value)
        return lambda: value
    if isinstance(node, ast.Var):
        return store.reader(node.number)
    if isinstance(node, ast.Indirect):
        index, read = compile_expr(node.index, store), store.read
        return lambda: read(variable_number(index()))
    if isinstance(node, ast.Unary):
        return _unary(node, store)
    if isinstance(node, ast.Binary):
        return _binary(node, store)
    return _call(node, store)


def compile_number(node: ast.Expr, store: Variables) -> Callable[[], float]:
    """Compile an expression whose vacancy does not matter (vacant reads as 0)."""
    get = compile_expr(node, store)
    if isinstance(node, ast.Var | ast.Indirect):
        return lambda: get() or 0.0
    return get  # type: ignore[return-value]


def _unary(node: ast.Unary, store: Variables) -> Getter:
    if isinstance(node.operand, ast.Num):
        value = -node.operand.value if node.op == "-" else node.operand.value
        return lambda: value
    operand = compile_number(node.operand, store)
    if node.op == "+":
        return operand
    return lambda: -operand()


def _binary(node: ast.Binary, store: Variables) -> Getter:
    left, right = compile_number(node.left, store), compile_number(node.right, store)
    op = node.op
    if op == "+":
        return lambda: _limit(left() + right())
    if op == "-":
        return lambda: _limit(left() - right())
    if op == "*":
        return lambda: _limit(left() * right())
    function = _OPERATORS[op]
    return lambda: function(left(), right())


def _limit(value: float) -> float:
    """Return an arithmetic result, or raise alarm 111 beyond the control's range."""
    if -LIMIT < value < LIMIT:
        return value
    raise alarm(OVERFLOW, f"{value:g}")


def _divide(a: float, b: float) -> float:
    if b == 0:
        raise alarm(ZERO_DIVIDE)
    return _limit(a / b)


def _mod(a: float, b: float) -> float:
    divisor = _round(b)
    if divisor == 0:
        raise alarm(ZERO_DIVIDE, "MOD 0")
    return math.fmod(_round(a), divisor)


_OPERATORS: dict[str, Callable[[float, float], float]] = {
    "/": _divide,
    "MOD": _mod,
    "AND": lambda a, b: float(_round(a) & _round(b)),
    "OR": lambda a, b: float(_round(a) | _round(b)),
    "XOR": lambda a, b: float(_round(a) ^ _round(b)),
}


def _round(value: float) -> int:
    """Round half away from zero (alarm 111 for values beyond the control's range)."""
    if not -LIMIT < value < LIMIT:
        raise alarm(OVERFLOW, f"{value}")
    return int(math.floor(abs(value) + 0.5)) * (1 if value >= 0 else -1)


def _call(node: ast.Call, store: Variables) -> Getter:
    args = [compile_number(a, store) for a in node.args]
    if node.name in ("ATAN", "POW") and len(args) == 2:
        first, second = args
        two = _atan2 if node.name == "ATAN" else _power
        return lambda: two(first(), second())
    function, (arg,) = _FUNCTIONS[node.name], args
    if node.name == "TAN":
        return lambda: _limit(function(arg()))
    return lambda: function(arg())


def _exact_sine(degrees: float) -> float | None:
    """Return sin(degrees) for multiples of 30 and 45 degrees (correctly rounded), else None."""
    angle = math.fmod(degrees, 360.0)
    angle = angle + 360.0 if angle < 0 else angle
    return _EXACT_SINES.get(angle)


_HALF_ROOT = math.sqrt(0.5)
_EXACT_SINES = {0.0: 0.0, 30.0: 0.5, 45.0: _HALF_ROOT, 90.0: 1.0, 135.0: _HALF_ROOT,
                150.0: 0.5, 180.0: 0.0, 210.0: -0.5, 225.0: -_HALF_ROOT, 270.0: -1.0,
                315.0: -_HALF_ROOT, 330.0: -0.5}


def _sin(degrees: float) -> float:
    exact = _exact_sine(degrees)
    return exact if exact is not None else math.sin(math.radians(degrees))


def _cos(degrees: float) -> float:
    return _sin(degrees + 90.0)


def _tan(degrees: float) -> float:
    cosine = _cos(degrees)
    if cosine == 0:
        raise alarm(OVERFLOW, f"TAN[{degrees:g}]")
    return _sin(degrees) / cosine


def _full_turn(degrees: float) -> float:
    """Map an angle in (-360, 360) to [0, 360)."""
    return degrees + 360.0 if degrees < 0 else degrees


def _asin(value: float) -> float:
    if not -1.0 <= value <= 1.0:
        raise alarm(ARGUMENT_RANGE, f"ASIN[{value:g}]")
    return _full_turn(math.degrees(math.asin(value)))


def _acos(value: float) -> float:
    if not -1.0 <= value <= 1.0:
        raise alarm(ARGUMENT_RANGE, f"ACOS[{value:g}]")
    return math.degrees(math.acos(value))


def _atan2(y: float, x: float) -> float:
    return _full_turn(math.degrees(math.atan2(y, x)))


def _sqrt(value: float) -> float:
    if value < 0:
        raise alarm(ARGUMENT_RANGE, f"SQRT[{value:g}]")
    return math.sqrt(value)


def _ln(value: float) -> float:
    if value <= 0:
        raise alarm(ARGUMENT_RANGE, f"LN[{value:g}]")
    return math.log(value)


def _exp(value: float) -> float:
    if value > math.log(LIMIT):
        raise alarm(OVERFLOW, f"EXP[{value:g}]")
    return math.exp(value)


def _power(base: float, exponent: float) -> float:
    if base == 0 and exponent < 0:
        raise alarm(ZERO_DIVIDE, "POW")
    if base < 0 and exponent != int(exponent):
        raise alarm(ARGUMENT_RANGE, f"POW[{base:g},{exponent:g}]")
    try:
        return checked(math.pow(base, exponent)) or 0.0
    except OverflowError:
        raise alarm(OVERFLOW, "POW") from None


def _fix(value: float) -> float:
    return float(math.trunc(value))


def _fup(value: float) -> float:
    return float(math.ceil(value) if value >= 0 else math.floor(value))


def _bin(value: float) -> float:
    """BCD to binary: each group of four bits is one decimal digit."""
    code, result, scale = _round(value), 0, 1
    if code < 0:
        raise alarm(ARGUMENT_RANGE, f"BIN[{value:g}]")
    while code:
        code, digit = divmod(code, 16)
        if digit > 9:
            raise alarm(ARGUMENT_RANGE, f"BIN[{value:g}]")
        result, scale = result + digit * scale, scale * 10
    return float(result)


def _bcd(value: float) -> float:
    """Binary to BCD: each decimal digit becomes a group of four bits."""
    number = _round(value)
    if number < 0:
        raise alarm(ARGUMENT_RANGE, f"BCD[{value:g}]")
    return float(int(str(number), 16))


_FUNCTIONS: dict[str, Callable[[float], float]] = {
    "SIN": _sin,
    "COS": _cos,
    "TAN": _tan,
    "ASIN": _asin,
    "ACOS": _acos,
    "ATAN": lambda v: _full_turn(math.degrees(math.atan(v))),
    "SQRT": _sqrt,
    "ABS": abs,
    "ROUND": lambda v: float(_round(v)),
    "FIX": _fix,
    "FUP": _fup,
    "LN": _ln,
    "EXP": _exp,
    "BIN": _bin,
    "BCD": _bcd,
}


def compile_cond(node: ast.Cond, store: Variables) -> Test:
    """Compile a condition (comparison or bracketed conditions joined by AND/OR/XOR)."""
    if isinstance(node, ast.Logic):
        left, right = compile_cond(node.left, store), compile_cond(node.right, store)
        if node.op == "AND":
            return lambda: left() and right()
        if node.op == "OR":
            return lambda: left() or right()
        return lambda: left() != right()
    if node.op in ("EQ", "NE"):
        return _equality(node, store)
    first, second = compile_number(node.left, store), compile_number(node.right, store)
    compare = _ORDER[node.op]
    return lambda: compare(first(), second())


_ORDER: dict[str, Callable[[float, float], bool]] = {
    "GT": lambda a, b: a > b,
    "GE": lambda a, b: a >= b,
    "LT": lambda a, b: a < b,
    "LE": lambda a, b: a <= b,
}


def _equality(node: ast.Compare, store: Variables) -> Test:
    """EQ / NE: vacant equals only vacant."""
    left, right = compile_expr(node.left, store), compile_expr(node.right, store)
    want = node.op == "EQ"

    def test() -> bool:
        a, b = left(), right()
        same = a is None and b is None if a is None or b is None else a == b
        return same == want

    return test
