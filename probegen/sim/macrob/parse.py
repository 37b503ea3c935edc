"""Parse Fanuc Macro B program text (custom macro B, 0i/30i) into blocks.

The text is read as a control reads a tape:

* Lines end with LF, CR LF or CR; a leading ``%`` opens the tape and the next ``%``
  line ends it (nothing after it is read).  ``Onnnn`` (or ``:nnnn``) starts a program;
  lines before the first one form an unnumbered program when they hold any block.
* ``(...)`` is a comment anywhere on a line (it ends at the first ``)``: comments do
  not nest on Fanuc; an unclosed ``(`` is an error).  Blanks are ignored everywhere
  outside comments, so ``G 0 1`` is ``G01``; letters may be lower case.
* ``/`` at the start of a block marks it for block delete.

Each block is parsed with the LALR grammar ``grammars/macrob.lark``.  Programs repeat
the same block shapes thousands of times with different numbers, so a block is parsed
once per *shape*: every number is replaced by a marker holding its position (``#190=
#104+8.75`` becomes ``#0=#1+2.``), the shape is parsed once (cached), and the parse
result is a builder that makes the block's nodes from the block's own numbers.  The
markers keep what the grammar cares about (a number, with or without a point), so a
shape parses exactly when the block does; errors are reported from the block itself.

Errors are collected for every line and raised together as one
:class:`~probegen.errors.ProgramParseError` with ``source:line:column``, what was
expected, what was found and the line with a caret under the fault.
"""

from __future__ import annotations

import functools
import re
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any, TypeAlias, cast

from lark import Lark, Token, Transformer, v_args
from lark.exceptions import UnexpectedInput

from probegen.errors import Diagnostic, ProgramParseError
from probegen.resources import grammar_text
from probegen.sim.macrob import ast
from probegen.sim.macrob.syntax import syntax_error

MAX_BLOCK = 256
"""Longest block accepted, in characters after comments and blanks are removed."""
MAX_SHOWN = 10
"""Diagnostics shown in the error message (all are kept in ``error.diagnostics``)."""
MAX_LOOP = 3
"""Loop identifiers of ``DOm`` / ``ENDm`` run from 1 to this."""
MAX_DPRNT_DIGITS = 8
"""Most digits (integer plus fraction) a DPRNT format ``[ab]`` may ask for."""

_NUMBER = re.compile(r"[0-9]+(?:\.[0-9]*)?|\.[0-9]+")
_MARK = re.compile(r"[0-9]+\.?")
_UPPER = str.maketrans("abcdefghijklmnopqrstuvwxyz", "ABCDEFGHIJKLMNOPQRSTUVWXYZ")

Builder = Callable[[Sequence[str]], Any]
"""Makes nodes from a block's number literals (as written, in order)."""


class _LiteralError(Exception):
    """A number that parses but is not allowed where it stands (``DO4``, ``#1[93]``)."""

    def __init__(self, index: int, message: str) -> None:
        super().__init__(message)
        self.index = index
        self.message = message


class _LineError(Exception):
    """A line that cannot be split into comments and code (an unclosed comment)."""

    def __init__(self, column: int, message: str) -> None:
        super().__init__(message)
        self.column = column
        self.message = message


def _slot(token: Token) -> int:
    return int(token.rstrip("."))


def _integer(lits: Sequence[str], k: int, what: str, low: int, high: int) -> int:
    value = int(lits[k])
    if not low <= value <= high:
        raise _LiteralError(k, f"expected {what} from {low} to {high}, found {lits[k]}")
    return value


@v_args(inline=True)
class _Templates(Transformer[Token, Builder]):
    """Turn a shape's parse into a builder; stateless, so one instance is shared."""

    def start(self, seq: Builder | None, statement: Builder | None) -> Builder:
        return lambda lits: (seq(lits) if seq else None, statement(lits) if statement else None)

    def seq(self, token: Token) -> Builder:
        k = _slot(token)
        return lambda lits: _integer(lits, k, "a sequence number", 0, 99_999_999)

    def header(self, token: Token) -> Builder:
        k = _slot(token)
        return lambda lits: ast.Header(_integer(lits, k, "a program number", 1, 99_999_999))

    def words(self, *words: Builder) -> Builder:
        return lambda lits: ast.Words(tuple(w(lits) for w in words))

    def word(self, letter: Token, value: Builder) -> Builder:
        name = str(letter)
        return lambda lits: ast.Word(name, value(lits))

    def literal(self, token: Token) -> Builder:
        k = _slot(token)
        return lambda lits: ast.Num(float(lits[k]), "." in lits[k])

    def signed_literal(self, sign: Token, token: Token) -> Builder:
        k, factor = _slot(token), -1.0 if sign == "-" else 1.0
        return lambda lits: ast.Num(factor * float(lits[k]), "." in lits[k])

    def signed(self, sign: Token, operand: Builder) -> Builder:
        op = str(sign)
        return lambda lits: ast.Unary(op, operand(lits))

    unary = signed

    def var(self, token: Token) -> Builder:
        k = _slot(token)
        return lambda lits: ast.Var(int(lits[k]))

    def indirect(self, index: Builder) -> Builder:
        return lambda lits: ast.Indirect(index(lits))

    def binary(self, left: Builder, op: Token, right: Builder) -> Builder:
        name = str(op)
        return lambda lits: ast.Binary(name, left(lits), right(lits))

    def call(self, name: Token, *args: Builder) -> Builder:
        fname = str(name)
        return lambda lits: ast.Call(fname, tuple(a(lits) for a in args))

    def compare(self, left: Builder, op: Token, right: Builder) -> Builder:
        name = str(op)
        return lambda lits: ast.Compare(name, left(lits), right(lits))

    def logic(self, first: Builder, *rest: Any) -> Builder:
        pairs = [(str(rest[i]), rest[i + 1]) for i in range(0, len(rest), 2)]

        def build(lits: Sequence[str]) -> ast.Cond:
            cond = first(lits)
            for op, right in pairs:
                cond = ast.Logic(op, cond, right(lits))
            return cond

        return build

    def assign(self, target: Builder, value: Builder) -> Builder:
        return lambda lits: ast.Assign(target(lits), value(lits))

    def if_goto(self, cond: Builder, target: Builder) -> Builder:
        return lambda lits: ast.IfGoto(cond(lits), target(lits))

    def if_then(self, cond: Builder, then: Builder) -> Builder:
        return lambda lits: ast.IfThen(cond(lits), then(lits))

    def while_do(self, cond: Builder, loop: Token) -> Builder:
        k = _slot(loop)
        return lambda lits: ast.While(cond(lits), _integer(lits, k, "a loop number", 1, MAX_LOOP))

    def do_loop(self, loop: Token) -> Builder:
        k = _slot(loop)
        return lambda lits: ast.While(None, _integer(lits, k, "a loop number", 1, MAX_LOOP))

    def end_loop(self, loop: Token) -> Builder:
        k = _slot(loop)
        return lambda lits: ast.End(_integer(lits, k, "a loop number", 1, MAX_LOOP))

    def goto(self, target: Builder) -> Builder:
        return lambda lits: ast.Goto(target(lits))

    def popen(self) -> Builder:
        return lambda lits: ast.Popen()

    def pclos(self) -> Builder:
        return lambda lits: ast.Pclos()

    def dprnt(self, *items: Token | Builder) -> Builder:
        parts = [_text_builder(i) if isinstance(i, Token) else i for i in items]
        return lambda lits: ast.Dprnt(tuple(p(lits) for p in parts))

    def dvar(self, number: Token, fmt: Token) -> Builder:
        kn, kf = _slot(number), _slot(fmt)
        return lambda lits: _dprnt_var(lits, kn, kf)


def _text_builder(token: Token) -> Builder:
    """Return a builder restoring the DPRNT text of ``token`` (numbers put back)."""
    text = str(token)
    if not _MARK.search(text):
        return lambda lits: text
    return lambda lits: _MARK.sub(lambda m: lits[int(m.group().rstrip("."))], text)


def _dprnt_var(lits: Sequence[str], kn: int, kf: int) -> ast.DprntVar:
    fmt = lits[kf]
    if len(fmt) != 2 or not 1 <= int(fmt[0]) + int(fmt[1]) <= MAX_DPRNT_DIGITS:
        raise _LiteralError(
            kf,
            f"expected a DPRNT format [ab] of two digits (a integer and b fraction digits, "
            f"1 to {MAX_DPRNT_DIGITS} in all), found [{fmt}]",
        )
    return ast.DprntVar(int(lits[kn]), int(fmt[0]), int(fmt[1]))


@functools.cache
def _parser() -> Lark:
    """Build the LALR parser once; it returns a builder instead of a tree."""
    return Lark(
        grammar_text("macrob"), parser="lalr", transformer=_Templates(), maybe_placeholders=True
    )


@functools.lru_cache(maxsize=4096)
def _template(shape: str) -> Builder | None:
    """Return the builder for a block shape, or None when the shape does not parse."""
    try:
        return cast(Builder, _parser().parse(shape))
    except UnexpectedInput:
        return None


Parsed: TypeAlias = "tuple[int | None, ast.Statement | None]"


def _build(compact: str) -> Parsed:
    """Parse one block (comments and blanks removed, upper case) into (seq, statement)."""
    lits: list[str] = []

    def mark(match: re.Match[str]) -> str:
        lits.append(match.group())
        return f"{len(lits) - 1}." if "." in match.group() else str(len(lits) - 1)

    builder = _template(_NUMBER.sub(mark, compact))
    if builder is None:
        position, message = syntax_error(compact)
        raise _BlockError(position, message)
    try:
        return cast(Parsed, builder(lits))
    except _LiteralError as exc:
        match = list(_NUMBER.finditer(compact))[exc.index]
        raise _BlockError(match.start(), exc.message) from None


class _BlockError(Exception):
    """A block that does not parse; ``position`` indexes the compact block text."""

    def __init__(self, position: int, message: str) -> None:
        super().__init__(message)
        self.position = position
        self.message = message


def _split(raw: str) -> tuple[str, list[str]]:
    """Return the code of a line (comments cut out) and its comments."""
    if "(" not in raw:
        return raw, []
    parts: list[str] = []
    comments: list[str] = []
    start = 0
    while (opening := raw.find("(", start)) >= 0:
        parts.append(raw[start:opening])
        closing = raw.find(")", opening + 1)
        if closing < 0:
            raise _LineError(
                len(raw.rstrip()) + 1,
                f"expected ')' closing the comment opened at column {opening + 1}, "
                "found end of line",
            )
        comments.append(raw[opening + 1 : closing])
        start = closing + 1
    parts.append(raw[start:])
    return "".join(parts), comments


def _compact(code: str) -> str:
    """Remove blanks and upper-case ASCII letters (column positions stay one-to-one)."""
    text = "".join(code.split())
    return text.upper() if text.isascii() else text.translate(_UPPER)


def _columns(raw: str) -> list[int]:
    """Return the 1-based column in ``raw`` of each character of the compact code."""
    columns: list[int] = []
    in_comment = False
    for column, char in enumerate(raw, 1):
        if in_comment:
            in_comment = char != ")"
        elif char == "(":
            in_comment = True
        elif not char.isspace():
            columns.append(column)
    return columns


def _lines(text: str) -> list[str]:
    """Split ``text`` into physical lines (LF, CR LF or CR)."""
    return text.removeprefix("\ufeff").replace("\r\n", "\n").replace("\r", "\n").split("\n")


class _Reader:
    """Collects the blocks and diagnostics of one text."""

    def __init__(self, source: str) -> None:
        self.source = source
        self.cache: dict[str, Parsed] = {}
        self.diagnostics: list[Diagnostic] = []
        self.programs: list[tuple[int | None, list[ast.Block]]] = [(None, [])]

    def error(self, line: int, column: int, message: str, raw: str) -> None:
        self.diagnostics.append(Diagnostic(self.source, line, column, message, raw))

    def read(self, text: str) -> ast.ProgramFile:
        started = False
        for number, raw in enumerate(_lines(text), 1):
            if raw.lstrip().startswith("%"):
                if started:
                    break
                continue
            started = self.line(number, raw) or started
        if self.diagnostics:
            raise _parse_error(self.diagnostics)
        programs = tuple(
            ast.Program(num, tuple(blocks))
            for num, blocks in self.programs
            if num is not None or blocks
        )
        return ast.ProgramFile(self.source, programs)

    def line(self, number: int, raw: str) -> bool:
        """Read one line; return True when it held a block."""
        try:
            code, comments = _split(raw)
        except _LineError as exc:
            self.error(number, exc.column, exc.message, raw)
            return True
        compact = _compact(code)
        delete = compact.startswith("/")
        if delete:
            compact = compact[1:]
        if not compact:
            return False
        if len(compact) > MAX_BLOCK:
            message = f"expected a block of at most {MAX_BLOCK} characters, found {len(compact)}"
            self.error(number, 1, message, raw)
            return True
        try:
            seq, statement = self.parsed(compact)
        except _BlockError as exc:
            self.error(number, _column(raw, exc.position + delete), exc.message, raw)
            return True
        self.add(number, delete, seq, statement, comments[0].strip() if comments else "")
        return True

    def parsed(self, compact: str) -> Parsed:
        found = self.cache.get(compact)
        if found is None:
            found = self.cache[compact] = _build(compact)
        return found

    def add(self, line: int, delete: bool, seq: int | None,
            statement: ast.Statement | None, comment: str) -> None:
        if isinstance(statement, ast.Header):
            self.programs.append((statement.number, []))
            return
        block = ast.Block(line, delete, seq, statement, comment)
        self.programs[-1][1].append(block)


def _column(raw: str, position: int) -> int:
    """Return the 1-based column in ``raw`` of compact position ``position``."""
    columns = _columns(raw)
    if position < len(columns):
        return columns[position]
    return columns[-1] + 1 if columns else 1


def _parse_error(diagnostics: list[Diagnostic]) -> ProgramParseError:
    shown = "\n".join(str(d) for d in diagnostics[:MAX_SHOWN])
    more = len(diagnostics) - MAX_SHOWN
    if more > 0:
        shown += f"\n... and {more} more error{'s' if more > 1 else ''}"
    return ProgramParseError(shown, tuple(diagnostics))


def parse_program(text: str, *, source: str = "<program>") -> ast.ProgramFile:
    """Parse Macro B program text.

    Args:
        text: the program text (one or more ``O`` programs, optionally between ``%``).
        source: the file name used in error messages.

    Returns:
        The programs of the text in order; the first is the main program.

    Raises:
        ProgramParseError: when any line does not parse; it carries one diagnostic per
            bad line (``source:line:column``, expected, found, the line and a caret).
    """
    return _Reader(source).read(text)


def read_program(path: str | Path) -> ast.ProgramFile:
    """Read and parse a program file (ASCII; bytes outside ASCII are read as Latin-1).

    Raises:
        ProgramParseError: the file cannot be read or does not parse.
    """
    try:
        data = Path(path).read_bytes()
    except OSError as exc:
        raise ProgramParseError(f"{path}: cannot read: {exc.strerror}") from None
    return parse_program(data.decode("latin-1"), source=str(path))
