"""Expressions and comment text of the rs274ngc control: evaluation and formatting.

Semantics (LinuxCNC 2.9 documentation, "G-code overview", checked with ``rs274``):

* Angles of ``SIN COS TAN`` and of ``ASIN ACOS ATAN[y]/[x]`` are degrees, computed in
  long double as rs274ngc does (``COS[90]`` is -2.5e-20, a hair below 0).
* ``FIX`` rounds down, ``FUP`` up, ``ROUND`` to the nearest integer, halves away from
  zero (``ROUND[-2.5]`` = -3).
* ``a MOD b`` is ``fmod(a, b)``, plus ``|b|`` when negative (``-5 MOD 3`` = 1).
* ``EQ``/``NE`` call values within 1e-4 equal (``TOLERANCE_EQUAL``, as ``rs274`` 2.9
  does; the current documentation says 1e-6); ``GT GE LT LE`` compare exactly;
  ``AND OR XOR`` are logical (non-zero is true); every comparison or logical operation
  gives 1 or 0.
* Errors stop the program with the interpreter's message (``Attempt to divide by
  zero``, ``Negative argument to sqrt``, ``Argument to acos out of range``, ``Zero or
  negative argument to ln``, ``Calculation resulted in 'infinity'`` (``0 ** -1``, an
  overflow), ``Calculation resulted in 'not a number'`` (``1 MOD 0``), ``Named parameter
  #<x> not defined`` ...); checked against ``rs274`` on random expressions
  (tests/test_ngc.py).  ``FIX`` and ``FUP`` keep the sign of a zero, as C's ``floor`` and
  ``ceil`` do.

Comment text (``DEBUG``, ``PRINT``, ``LOG``, ``ABORT``): ``#n`` and ``#<name>`` are
replaced by the parameter's value, ``######`` for a named parameter that does not exist;
a value within ``TOLERANCE_EQUAL`` of 0 prints as 0 (``-0.00004`` as ``0.0000``).
The format is ``%lf`` (6 decimals) until a format sets another for the rest of the
line: ``%d`` (0 decimals), ``%f`` (4), ``%.Nf`` (N = 0-9 decimals); the format need not
stand next to the parameter.  As ``rs274`` 2.9 does: ``%.`` not followed by a digit and
``f`` drops the ``%`` and prints the rest; any other ``%`` (``%lf`` too) prints as written.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any, Protocol

import numpy as np

from probegen.sim.alarms import SimAlarm
from probegen.sim.ngc import ast

Getter = Callable[[], float]

NGC_ERROR = 9300
"""Alarm number of an error of the rs274ngc interpreter (LinuxCNC has no numbers; the
message is the interpreter's)."""
TOLERANCE_EQUAL = 1e-4
"""rs274ngc's ``TOLERANCE_EQUAL`` as LinuxCNC 2.9 (``rs274`` 2.9.0~pre1) has it: ``EQ``
and ``NE`` call values this close equal, and comment text prints a value this close to
0 as 0.  (Later LinuxCNC sources and the current documentation have 1e-6.)"""
DEFAULT_DECIMALS = 6
"""``%lf``: the format of a parameter in comment text when no format precedes it."""
UNDEFINED = "######"


def error(message: str) -> SimAlarm:
    """The alarm for an interpreter error."""
    return SimAlarm(NGC_ERROR, message)


class Scope(Protocol):
    """Where expressions read parameters (``probegen.sim.ngc.params.Parameters``)."""

    def read(self, index: int) -> float:
        """Numbered parameter ``index``; an error when out of range."""
        ...

    def read_named(self, name: str) -> float:
        """Named parameter ``name``; an error when it does not exist."""
        ...

    def lookup_named(self, name: str) -> float | None:
        """Named parameter ``name``, or None when it does not exist."""
        ...


def index_of(value: float) -> int:
    """A parameter number from a value (within 1e-4 of an integer, as rs274ngc asks)."""
    number = round(value)
    if abs(value - number) > 1e-4:
        raise error(f"Parameter number {value:g} is not an integer")
    return number


def _finite(value: float) -> float:
    if math.isnan(value):
        raise error("Calculation resulted in 'not a number'")
    if math.isinf(value):
        raise error("Calculation resulted in 'infinity'")
    return value


PI = np.longdouble("3.141592653589793238462643383279502884")
"""pi in long double: rs274ngc computes its angles in long double (``COS[90]`` is
-2.5e-20 there, not 6.1e-17; ``FIX[COS[90]]`` is -1)."""


def _trig(f: Callable[[Any], Any]) -> Callable[[float], float]:
    """A function of degrees, in long double as rs274ngc computes it."""
    return lambda x: float(f(np.longdouble(x) * PI / 180))


def _arc(f: Callable[[Any], Any]) -> Callable[[float], float]:
    """An inverse function in degrees, in long double."""
    return lambda x: float(f(np.longdouble(x)) * 180 / PI)


def _round(x: float) -> float:
    return math.copysign(math.floor(abs(x) + 0.5), x)


def _domain(name: str, test: Callable[[float], bool], f: Callable[[float], float],
            message: str) -> Callable[[float], float]:
    def checked(x: float) -> float:
        if not test(x):
            raise error(message)
        return f(x)
    checked.__name__ = name
    return checked


FUNCTIONS: dict[str, Callable[[float], float]] = {
    "abs": abs,
    "acos": _domain("acos", lambda x: -1.0 <= x <= 1.0, _arc(np.arccos),
                    "Argument to acos out of range"),
    "asin": _domain("asin", lambda x: -1.0 <= x <= 1.0, _arc(np.arcsin),
                    "Argument to asin out of range"),
    "cos": _trig(np.cos),
    "exp": lambda x: math.exp(x) if x < 709.0 else math.inf,
    "fix": lambda x: math.copysign(math.floor(x), x),  # C floor/ceil keep -0.0, so
    "fup": lambda x: math.copysign(math.ceil(x), x),   # ATAN[FUP[-0.5]]/[-1] is -180
    "ln": _domain("ln", lambda x: x > 0.0, math.log, "Zero or negative argument to ln"),
    "round": _round,
    "sin": _trig(np.sin),
    "sqrt": _domain("sqrt", lambda x: x >= 0.0, math.sqrt, "Negative argument to sqrt"),
    "tan": _trig(np.tan),
}


def _divide(a: float, b: float) -> float:
    if b == 0.0:
        raise error("Attempt to divide by zero")
    return a / b


def _mod(a: float, b: float) -> float:
    if b == 0.0:
        raise error("Calculation resulted in 'not a number'")
    r = math.fmod(a, b)
    return r + abs(b) if r < 0.0 else r


def _power(a: float, b: float) -> float:
    if a < 0.0 and b != math.floor(b):
        raise error("Attempt to raise negative to non integer power")
    if a == 0.0 and b < 0.0:
        raise error("Calculation resulted in 'infinity'")
    try:
        return math.pow(a, b)
    except OverflowError:
        return math.inf


OPERATORS: dict[str, Callable[[float, float], float]] = {
    "+": lambda a, b: a + b,
    "-": lambda a, b: a - b,
    "*": lambda a, b: a * b,
    "/": _divide,
    "mod": _mod,
    "**": _power,
    "eq": lambda a, b: float(abs(a - b) < TOLERANCE_EQUAL),
    "ne": lambda a, b: float(abs(a - b) >= TOLERANCE_EQUAL),
    "gt": lambda a, b: float(a > b),
    "ge": lambda a, b: float(a >= b),
    "lt": lambda a, b: float(a < b),
    "le": lambda a, b: float(a <= b),
    "and": lambda a, b: float(a != 0.0 and b != 0.0),
    "or": lambda a, b: float(a != 0.0 or b != 0.0),
    "xor": lambda a, b: float((a != 0.0) != (b != 0.0)),
}


def compile_expr(e: ast.Expr, scope: Scope) -> Getter:
    """A function evaluating ``e`` against ``scope`` (parameters read when called)."""
    if isinstance(e, ast.Num):
        value = e.value
        return lambda: value
    if isinstance(e, ast.Named):
        name = e.name
        return lambda: scope.read_named(name)
    if isinstance(e, ast.Param):
        if isinstance(e.index, ast.Num):
            number = index_of(e.index.value)
            return lambda: scope.read(number)
        index = compile_expr(e.index, scope)
        return lambda: scope.read(index_of(index()))
    if isinstance(e, ast.Neg):
        arg = compile_expr(e.arg, scope)
        return lambda: -arg()
    if isinstance(e, ast.Func):
        f, arg = FUNCTIONS[e.name], compile_expr(e.arg, scope)
        return lambda: _finite(f(arg()))
    if isinstance(e, ast.Atan):
        y, x = compile_expr(e.y, scope), compile_expr(e.x, scope)
        return lambda: float(np.arctan2(np.longdouble(y()), np.longdouble(x())) * 180 / PI)
    if isinstance(e, ast.Exists):
        name = e.name
        return lambda: float(scope.lookup_named(name) is not None)
    op = OPERATORS[e.op]
    left, right = compile_expr(e.left, scope), compile_expr(e.right, scope)
    return lambda: _finite(op(left(), right()))


def _format(text: str, i: int) -> tuple[int | None, int, str]:
    """A ``%`` at ``text[i]``: (decimals or None, characters consumed, text printed)."""
    nxt = text[i + 1:i + 2]
    if nxt == "d":
        return 0, 2, ""
    if nxt == "f":
        return 4, 2, ""
    if nxt == ".":
        if text[i + 2:i + 3].isdigit() and text[i + 3:i + 4] == "f":
            return int(text[i + 2]), 4, ""
        return None, 1, ""
    return None, 1, "%"


def _text(value: float | None, decimals: int) -> str:
    if value is None:
        return UNDEFINED
    return f"{0.0 if abs(value) < TOLERANCE_EQUAL else value:.{decimals}f}"


def expand(text: str, scope: Scope) -> str:
    """Comment text with its parameters replaced by their values (module docstring)."""
    out: list[str] = []
    decimals = DEFAULT_DECIMALS
    i, n = 0, len(text)
    while i < n:
        ch = text[i]
        if ch == "%":
            found, used, printed = _format(text, i)
            decimals = decimals if found is None else found
            out.append(printed)
            i += used
            continue
        if ch == "#" and text[i + 1:i + 2] == "<":
            end = text.find(">", i + 2)
            if end > 0:
                name = "".join(text[i + 2:end].split()).lower()
                value = scope.lookup_named(name)
                out.append(_text(value, decimals))
                i = end + 1
                continue
        if ch == "#" and text[i + 1:i + 2].isdigit():
            j = i + 1
            while j < n and text[j].isdigit():
                j += 1
            out.append(_text(scope.read(int(text[i + 1:j])), decimals))
            i = j
            continue
        out.append(ch)
        i += 1
    return "".join(out)
