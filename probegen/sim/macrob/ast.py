"""The parsed form of a Fanuc Macro B program: frozen dataclasses, one per construct.

Expressions (:data:`Expr`) and conditions (:data:`Cond`) are trees of these nodes;
a :class:`Block` is one line of the program with its statement.  Numbers are floats as
the control holds them; :class:`Num` remembers whether the literal was written with
a decimal point, because an axis word without one (``X10``) is counted in least input
increments on a control set up that way.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TypeAlias


@dataclass(frozen=True, slots=True)
class Num:
    """A number as written; ``point`` is True when it had a decimal point (``10.``)."""

    value: float
    point: bool = True


@dataclass(frozen=True, slots=True)
class Var:
    """A variable ``#n`` with a literal number."""

    number: int


@dataclass(frozen=True, slots=True)
class Indirect:
    """A variable whose number is computed: ``#[expr]``."""

    index: Expr


@dataclass(frozen=True, slots=True)
class Unary:
    """A sign applied to an operand: ``-#1``, ``+[...]``."""

    op: str
    operand: Expr


@dataclass(frozen=True, slots=True)
class Binary:
    """An operator (``+ - OR XOR * / AND MOD``) applied to two operands."""

    op: str
    left: Expr
    right: Expr


@dataclass(frozen=True, slots=True)
class Call:
    """A function: ``SIN[x]``, ``ATAN[a]/[b]`` and ``ATAN[a,b]`` (two args), ``POW[a,b]``."""

    name: str
    args: tuple[Expr, ...]


Expr: TypeAlias = "Num | Var | Indirect | Unary | Binary | Call"


@dataclass(frozen=True, slots=True)
class Compare:
    """A comparison ``left op right`` with op one of ``EQ NE GT GE LT LE``."""

    op: str
    left: Expr
    right: Expr


@dataclass(frozen=True, slots=True)
class Logic:
    """Bracketed conditions combined with ``AND``, ``OR`` or ``XOR``."""

    op: str
    left: Cond
    right: Cond


Cond: TypeAlias = "Compare | Logic"


@dataclass(frozen=True, slots=True)
class Word:
    """An address and its value: ``G31``, ``X[#101+1.5]``, ``F#9``."""

    letter: str
    value: Expr


@dataclass(frozen=True, slots=True)
class Words:
    """An NC block: the words in the order written."""

    words: tuple[Word, ...]


@dataclass(frozen=True, slots=True)
class Assign:
    """``#n = expr`` or ``#[expr] = expr``."""

    target: Var | Indirect
    value: Expr


@dataclass(frozen=True, slots=True)
class IfGoto:
    """``IF [cond] GOTO n``."""

    cond: Cond
    target: Expr


@dataclass(frozen=True, slots=True)
class IfThen:
    """``IF [cond] THEN #i = expr``."""

    cond: Cond
    then: Assign


@dataclass(frozen=True, slots=True)
class While:
    """``WHILE [cond] DOm``; ``cond`` is None for a bare ``DOm`` (an endless loop)."""

    cond: Cond | None
    loop: int


@dataclass(frozen=True, slots=True)
class End:
    """``ENDm``."""

    loop: int


@dataclass(frozen=True, slots=True)
class Goto:
    """``GOTO n``, ``GOTO #i`` or ``GOTO [expr]``."""

    target: Expr


@dataclass(frozen=True, slots=True)
class DprntVar:
    """``#n[ab]`` in a DPRNT: variable ``number`` with ``digits`` integer and
    ``decimals`` fraction digits."""

    number: int
    digits: int
    decimals: int


@dataclass(frozen=True, slots=True)
class Dprnt:
    """``DPRNT[...]``: text (as written, ``*`` not yet turned into blanks) and variables."""

    items: tuple[str | DprntVar, ...]


@dataclass(frozen=True, slots=True)
class Popen:
    """``POPEN``: open the external output device."""


@dataclass(frozen=True, slots=True)
class Pclos:
    """``PCLOS``: close the external output device."""


@dataclass(frozen=True, slots=True)
class Header:
    """A program number ``Onnnn`` (or ``:nnnn``)."""

    number: int


Statement: TypeAlias = (
    "Words | Assign | IfGoto | IfThen | While | End | Goto | Dprnt | Popen | Pclos | Header"
)


@dataclass(frozen=True, slots=True)
class Block:
    """One program line that does something (blank and comment-only lines are dropped).

    Attributes:
        line: 1-based physical line in the source text.
        delete: the line starts with ``/`` (skipped when block delete is on).
        seq: the sequence number ``Nn``, or None.
        statement: what the block does; None for a block holding only ``Nn``.
        comment: the text of the first comment on the line, without the parentheses
            (the message of ``#3000`` and ``#3006``), or ``""``.
    """

    line: int
    delete: bool
    seq: int | None
    statement: Statement | None
    comment: str = ""


@dataclass(frozen=True, slots=True)
class Program:
    """One program of a text: its number (None before the first ``O`` line) and blocks."""

    number: int | None
    blocks: tuple[Block, ...]


@dataclass(frozen=True, slots=True)
class ProgramFile:
    """A parsed program text: the programs in order (the first one is the main program)."""

    source: str
    programs: tuple[Program, ...]

    def find(self, number: int) -> Program | None:
        """Return the program ``O<number>`` of this text, or None."""
        return next((p for p in self.programs if p.number == number), None)
