"""The nodes of a parsed rs274ngc program: expressions, items of a line, lines.

Frozen slotted dataclasses, made by :mod:`probegen.sim.ngc.parse` and run by
:mod:`probegen.sim.ngc.interp`.  Every item keeps the 1-based column where it starts
in its source line, for error messages.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True, slots=True)
class Num:
    """A number literal."""

    value: float


@dataclass(frozen=True, slots=True)
class Param:
    """A numbered parameter ``#n``; ``index`` is itself an expression (``##2``, ``#[1+2]``)."""

    index: Expr


@dataclass(frozen=True, slots=True)
class Named:
    """A named parameter ``#<name>`` (name lower case, blanks removed); global when it
    starts with ``_``."""

    name: str


@dataclass(frozen=True, slots=True)
class Neg:
    """Unary minus (``X-#1``, ``[-[1+2]]``)."""

    arg: Expr


@dataclass(frozen=True, slots=True)
class Func:
    """A unary function ``NAME[arg]`` (ABS ACOS ASIN COS EXP FIX FUP LN ROUND SIN SQRT TAN)."""

    name: str
    arg: Expr


@dataclass(frozen=True, slots=True)
class Atan:
    """``ATAN[y]/[x]``: four-quadrant inverse tangent, degrees."""

    y: Expr
    x: Expr


@dataclass(frozen=True, slots=True)
class Exists:
    """``EXISTS[#<name>]``: 1 if the named parameter exists, else 0."""

    name: str


@dataclass(frozen=True, slots=True)
class Binary:
    """A binary operation (``+ - * / MOD ** EQ NE GT GE LT LE AND OR XOR``, lower case)."""

    op: str
    left: Expr
    right: Expr


Expr = Num | Param | Named | Neg | Func | Atan | Exists | Binary


@dataclass(frozen=True, slots=True)
class Word:
    """A word: letter (upper case) and its value."""

    letter: str
    value: Expr
    column: int


@dataclass(frozen=True, slots=True)
class Assign:
    """A parameter setting ``#target = value``."""

    target: Param | Named
    value: Expr
    column: int


@dataclass(frozen=True, slots=True)
class Comment:
    """The last comment of a line; ``kind`` is the active keyword (``MSG``, ``LOG``, ...,
    upper case) or ``""`` for a plain comment; ``text`` what follows the comma."""

    kind: str
    text: str
    column: int


@dataclass(frozen=True, slots=True)
class OWord:
    """An o-word statement: ``o<label> keyword [args]``.

    ``label`` is the number or name as written (``"100"``, ``"<pg_touch>"``) or, for
    ``o[expr] call``, an expression; ``args`` are the bracketed expressions after the
    keyword (the call's arguments, the condition, the repeat count, the return value).
    """

    label: str | Expr
    keyword: str
    args: tuple[Expr, ...]
    column: int


@dataclass(frozen=True, slots=True)
class Line:
    """One line of the program.

    Attributes:
        number: 1-based line number in its file.
        text: the line as written (for error messages).
        delete: starts with ``/`` (block delete).
        oword: the o-word statement, or None.
        words: the words, in order.
        assigns: the parameter settings, in order.
        comment: the last comment, or None.
    """

    number: int
    text: str
    delete: bool = False
    oword: OWord | None = None
    words: tuple[Word, ...] = ()
    assigns: tuple[Assign, ...] = ()
    comment: Comment | None = None


@dataclass(frozen=True, slots=True)
class ProgramFile:
    """A parsed file: its lines up to the end of the program text (the closing ``%``),
    and whether it is demarcated by a ``%`` line at each end."""

    source: str
    lines: tuple[Line, ...]
    percent: bool
