"""Evaluate DMIS expressions against the variables of a run (:mod:`probegen.dmis.execute`).

Scopes: ``DECL/COMMON`` and ``DECL/GLOBAL`` variables live in one table for the whole
run; ``DECL/LOCAL`` ones in the frame of the main program or of the macro call that
declared them (a macro's parameters are locals of its call).  A name is looked up in
the current frame, then in the global table, then among the macro's textual arguments
(labels and words passed to ``CALL/M(x)``).

A value that comes from a measurement (``OBTAIN`` of an actual ``FA(x)``) is marked with
the line of that ``OBTAIN``, and so is every value computed from it: the post-processor
refuses to branch on it or to move with it (:attr:`Evaluator.measured`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

from probegen.dmis.reader import Call, Expr, Group, Label, Param, Text
from probegen.dmis.values import (
    EvalError,
    Function,
    Functions,
    Value,
    Variable,
    Vector,
    arithmetic,
    relation,
    show,
    truth,
)


class UnknownName(EvalError):
    """A word that is no variable, or a call that is no function: not an expression of
    the executable half (a keyword, a label-like call); left as written."""


@dataclass(slots=True)
class Frame:
    """The main program's or one macro call's locals.

    Attributes:
        scope: LOCAL variables (and the macro's parameters).
        words: textual arguments of the call: labels and keywords, by parameter name.
        macro: the macro's name (None: the main program).
        back: the statement index to return to after ENDMAC.
        loops: the open DO loops, innermost last: (DO index, ENDDO index, variable,
            stop, step).
    """

    scope: dict[str, Variable] = field(default_factory=dict)
    words: dict[str, Param] = field(default_factory=dict)
    macro: str | None = None
    back: int = -1
    loops: list[tuple[int, int, str, float, float]] = field(default_factory=list)


@dataclass(slots=True)
class Evaluator:
    """Expressions of one run: the variables, the functions and the measured-value marks.

    ``measured`` is the line of the ``OBTAIN`` of an actual behind the last value
    evaluated (None when every value it used was known before the run).
    """

    globals: dict[str, Variable] = field(default_factory=dict)
    frames: list[Frame] = field(default_factory=lambda: [Frame()])
    angle: float = Functions().angle
    measured: int | None = None
    _table: dict[str, tuple[int, int, Function]] = field(
        default_factory=lambda: Functions().table())

    @property
    def frame(self) -> Frame:
        return self.frames[-1]

    def set_angle(self, radians_per_unit: float) -> None:
        """Use ``radians_per_unit`` for the trigonometric functions (UNITS)."""
        if radians_per_unit != self.angle:
            self.angle = radians_per_unit
            self._table = Functions(radians_per_unit).table()

    def variable(self, name: str) -> Variable | None:
        """Return the variable ``name`` visible here, or None."""
        return self.frame.scope.get(name) or self.globals.get(name)

    def evaluate(self, param: Param) -> Value:
        """Evaluate ``param``; :attr:`measured` says whether a measured value went in.

        Raises:
            UnknownName: a word that is no variable, a call that is no function.
            EvalError: anything else that cannot be evaluated (the message says what).
        """
        self.measured = None
        return self.value(param)

    def value(self, param: Param) -> Value:
        """Evaluate ``param`` without resetting :attr:`measured`."""
        if isinstance(param, bool):
            return param
        if isinstance(param, int | float):
            return param
        if isinstance(param, Text):
            return param.value
        if isinstance(param, Label):
            return self.label(param)
        if isinstance(param, str):
            return self.word(param)
        if isinstance(param, Group):
            if len(param.items) != 1:
                raise EvalError(f"expected one value in parentheses, found {param}")
            return self.value(param.items[0])
        if isinstance(param, Call):
            return self.call(param)
        return self.expr(param)

    def word(self, name: str) -> Value:
        if name in (".TRUE.", ".FALSE."):
            return name == ".TRUE."
        var = self.variable(name)
        if var is None:
            word = self.frame.words.get(name)
            if isinstance(word, Label):
                return word
            raise UnknownName(f"{name} is not a declared variable")
        if var.dims:
            raise EvalError(f"{name} is an array: give its index, {name}[i]")
        self._mark(var, 0)
        return var.values[0]

    def label(self, label: Label) -> Value:
        """A label as a value (a macro argument), its name resolved (``F(P[I])``)."""
        return Label(label.kind, self.label_name(label.name))

    def label_name(self, name: str) -> str:
        """Resolve a label name: a macro parameter holding a label or string, and
        variables inside ``[...]`` (``P[I]`` with I = 3 -> ``P[3]``)."""
        word = self.frame.words.get(name)
        if isinstance(word, Label):
            return word.name
        if isinstance(word, Text | str) and not isinstance(word, Label):
            return (word.value if isinstance(word, Text) else word).upper()
        var = self.variable(name)
        if var is not None and var.type == "CHAR" and not var.dims:
            self._mark(var, 0)
            return str(var.values[0]).upper()
        base, bracket, rest = name.partition("[")
        if not bracket or not rest.endswith("]"):
            return name
        parts = []
        for piece in rest[:-1].split(","):
            piece = piece.strip()
            if piece.isdigit() or not piece:
                parts.append(piece)
                continue
            value = self.word(piece)
            if isinstance(value, bool) or not isinstance(value, int | float) or \
                    value != int(value):
                raise EvalError(f"label index {piece} is {show(value)}, not an integer")
            parts.append(str(int(value)))
        return f"{base}[{','.join(parts)}]"

    def call(self, call: Call) -> Value:
        entry = self._table.get(call.name)
        if entry is None:
            raise UnknownName(f"{call.name} is not a function")
        fewest, most, function = entry
        if not fewest <= len(call.args) <= most:
            wanted = f"{fewest}" if fewest == most else f"{fewest} to {most}"
            raise EvalError(f"{call.name} takes {wanted} arguments, found {len(call.args)}")
        return function(*(self.value(arg) for arg in call.args))

    def expr(self, expr: Expr) -> Value:
        op, operands = expr.op, expr.operands
        if op == "[]":
            var, slot = self.element(expr)
            self._mark(var, slot)
            return var.values[slot]
        if op in ("=", ":"):
            raise EvalError(f"'{op}' inside an expression")
        if op == ".NOT.":
            return not truth(self.value(operands[0]), ".NOT.")
        if op in (".AND.", ".OR."):
            a = truth(self.value(operands[0]), op)
            b = truth(self.value(operands[1]), op)
            return (a and b) if op == ".AND." else (a or b)
        if len(operands) == 1:
            value = self.value(operands[0])
            return arithmetic("*", -1 if op == "-" else 1, value) if isinstance(
                value, Vector) else arithmetic(op, 0, value)
        left, right = self.value(operands[0]), self.value(operands[1])
        if op.startswith("."):
            return relation(op, left, right)
        return arithmetic(op, left, right)

    def element(self, expr: Expr) -> tuple[Variable, int]:
        """Return the array variable and flat slot of ``A[i, ...]``."""
        base = expr.operands[0]
        if not isinstance(base, str):
            raise EvalError(f"{expr}: only a variable can be indexed")
        var = self.variable(base)
        if var is None:
            raise UnknownName(f"{base} is not a declared variable")
        indices = tuple(self.value(index) for index in expr.operands[1:])
        return var, var.slot(indices, base)

    def target(self, param: Param) -> tuple[str, Variable, int]:
        """Return (name, variable, slot) that ``param`` (``X`` or ``A[i]``) assigns to."""
        if isinstance(param, str):
            var = self.variable(param)
            if var is None:
                raise EvalError(f"{param} is not declared (DECL/LOCAL,REAL,{param} ...)")
            if var.dims:
                raise EvalError(f"{param} is an array: give its index, {param}[i]")
            return param, var, 0
        if isinstance(param, Expr) and param.op == "[]":
            mark = self.measured
            var, slot = self.element(param)
            self.measured = mark if mark is not None else self.measured
            return str(param.operands[0]), var, slot
        raise EvalError(f"cannot assign to {param}")

    def assign(self, param: Param, value: Value, measured: int | None) -> None:
        """Store ``value`` (marked ``measured``) in the target ``param``."""
        name, var, slot = self.target(param)
        var.values[slot] = var.convert(value, name)
        var.measured[slot] = measured

    def _mark(self, var: Variable, slot: int) -> None:
        if var.measured[slot] is not None and self.measured is None:
            self.measured = var.measured[slot]
