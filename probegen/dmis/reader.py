"""Parse DMIS programs and DMIS output files (DMIS 3-5) into a typed statement list.

The grammar (``grammars/dmis.lark``) is deliberately general: every statement has the
shape ``[label "="] MAJOR_WORD ["/" param, param, ...]``, so anything of the standard's
shape parses and meaning is checked by later stages.  Line handling follows the
standard: a statement ends at the end of its line, ``$`` as the last character of a line
continues it on the next, ``$$`` starts a comment to the end of the line; CRLF, LF and
CR line ends are accepted.  Line and column numbers always refer to the physical file.

Parameters (:data:`Param`) are plain values where possible:

* ``int`` / ``float``: numbers; a literal with ``.`` or an exponent is a float
  (``4`` -> 4, ``05.0`` -> 5.0, ``-1.`` -> -1.0, ``1e3`` -> 1000.0); signs are folded in.
* ``str``: a keyword or variable name, upper-cased (``cart`` -> ``"CART"``).
* :class:`Text`: a quoted string, verbatim (``''`` inside stands for one quote).
* :class:`Label`: a label reference such as ``F(C1)``, ``FA(C1)``, ``DAT(A)``, ``S(PRB1)``.
* :class:`Call`: ``NAME(args)`` that is not a label: a function such as ``SQRT(V1)``.
* :class:`Group`: a parenthesised list, e.g. the condition of ``IF/(V1.EQ.2)``.
* :class:`Expr`: an operator applied to operands: ``"+" "-" "*" "/" "**"``,
  ``".EQ." ".NE." ".LT." ".LE." ".GT." ".GE." ".AND." ".OR." ".NOT."``, ``"="``
  (``ASSIGN/V1=2``), ``":"`` (a ``WRITE`` format ``V1:8:3``) and ``"[]"`` (an index
  ``V1[2]``, operands ``(base, *indices)``).  Unary ``-`` and ``.NOT.`` have one operand.

:func:`format_statement` writes a statement back as canonical DMIS text that parses to
the same statement.  :func:`parse_dmis_recovering` parses statement by statement, so a
bad statement becomes a diagnostic and the others are kept (reading DMIS output files).
"""

from __future__ import annotations

import functools
import math
import re
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, TypeAlias, cast

from lark import Lark, Token, Transformer, v_args
from lark.exceptions import UnexpectedCharacters, UnexpectedInput, UnexpectedToken

from probegen.errors import Diagnostic, ProgramParseError, readable_list
from probegen.resources import grammar_text

LABEL_KINDS = frozenset(
    "CR CS CZ D DA DAT DI DID DME DR DS DV F FA FS G GS GSA KC KCA LI M MA MD OP P PC PL "
    "PN PR PS PV Q QIS RT S SA SE SG SGS SS SW SX T TA TH TL U V VA VF VL VW".split()
)
"""Label kinds of DMIS 5 (``F(name)``, ``FA(name)`` ...); other ``NAME(x)`` are calls."""


@dataclass(frozen=True, slots=True)
class Text:
    """A quoted string; ``value`` is the text between the quotes, ``''`` undoubled."""

    value: str

    def __str__(self) -> str:
        return "'" + self.value.replace("'", "''") + "'"


@dataclass(frozen=True, slots=True)
class Label:
    """A label such as ``F(C1)``: ``kind`` ``"F"`` and ``name`` ``"C1"``, both upper-cased."""

    kind: str
    name: str

    def __str__(self) -> str:
        return f"{self.kind}({self.name})"


@dataclass(frozen=True, slots=True)
class Call:
    """``NAME(args)`` that is not a label, e.g. a function ``SQRT(V1)``; ``name`` upper-cased."""

    name: str
    args: tuple[Param, ...]

    def __str__(self) -> str:
        return f"{self.name}({_join(self.args)})"


@dataclass(frozen=True, slots=True)
class Group:
    """A parenthesised list ``(a, b, ...)`` as written, e.g. ``IF/(V1.EQ.2)``."""

    items: tuple[Param, ...]

    def __str__(self) -> str:
        return f"({_join(self.items)})"


@dataclass(frozen=True, slots=True)
class Expr:
    """Operator ``op`` applied to ``operands`` (see the module docstring for the ops)."""

    op: str
    operands: tuple[Param, ...]

    def __str__(self) -> str:
        parts = [format_param(p) for p in self.operands]
        if self.op == "[]":
            return f"{parts[0]}[{','.join(parts[1:])}]"
        if len(parts) == 1:
            return f"{self.op} {parts[0]}" if self.op.startswith(".") else self.op + parts[0]
        sep = self.op if self.op in (":", "=") else f" {self.op} "
        return sep.join(parts)


Param: TypeAlias = "int | float | str | Text | Label | Call | Group | Expr"


@dataclass(frozen=True, slots=True)
class Statement:
    """One logical DMIS statement.

    Attributes:
        line: 1-based physical line where the statement starts.
        label: the label assigned to (``F(C1)`` in ``F(C1)=FEAT/...``), or None.
        major: the major word, upper-cased (``"FEAT"``, ``"PTMEAS"``, ``"ENDMES"``).
        params: the parameters after ``/`` (empty for a bare major word).
        text: the statement as written, continuations joined, without its comment.
    """

    line: int
    label: Label | None
    major: str
    params: tuple[Param, ...]
    text: str


@dataclass(frozen=True, slots=True)
class DmisFile:
    """A parsed DMIS file: statements in order and the ``$$`` comments as (line, text)."""

    source: str
    statements: tuple[Statement, ...]
    comments: tuple[tuple[int, str], ...]


def format_param(param: Param) -> str:
    """Return the DMIS text of one parameter (floats in shortest round-trip form)."""
    if isinstance(param, float):
        if math.isinf(param):
            return "-1E999" if param < 0 else "1E999"
        return repr(param)
    return str(param)


def format_statement(statement: Statement) -> str:
    """Return canonical DMIS text for ``statement``; it parses back to the same statement."""
    head = f"{statement.label}={statement.major}" if statement.label else statement.major
    return f"{head}/{_join(statement.params)}" if statement.params else head


def _join(params: tuple[Param, ...]) -> str:
    return ",".join(format_param(p) for p in params)


@dataclass(frozen=True, slots=True)
class _Raw:
    """A statement before its text is cut from the source (``start``/``end`` are offsets)."""

    line: int
    start: int
    label: Label | None
    major: str
    params: tuple[Param, ...]
    end: int = 0


@v_args(inline=True)
class _Builder(Transformer[Token, Any]):
    """Build typed values while the LALR parser reduces; stateless, so one is shared."""

    def start(self, *lines: list[Any]) -> list[Any]:
        return [item for line in lines for item in line]

    def line(self, *children: Any) -> list[Any]:
        end = children[-1].start_pos
        out: list[Any] = []
        for child in children[:-1]:
            if isinstance(child, Token):
                end = child.start_pos
                out.append((child.line, child.value[2:].strip()))
        if isinstance(children[0], _Raw):
            out.insert(0, replace(children[0], end=end))
        return out

    def statement(self, target: Any, major: Token, _slash: Any, params: Any) -> _Raw:
        label, first = target if target else (None, major)
        return _Raw(first.line or 1, first.start_pos or 0, label, major.upper(), params or ())

    def target(self, kind: Token, name: Param) -> tuple[Label, Token]:
        """Return the label and the token where the statement starts."""
        text = name if isinstance(name, str) else format_param(name)
        return Label(kind.upper(), text), kind

    def indexed_name(self, name: Token, *indices: Param) -> str:
        return f"{name.upper()}[{_join(indices)}]"

    def params(self, *items: Param) -> tuple[Param, ...]:
        return items

    args = params

    def number(self, token: Token) -> int | float:
        if any(c in token for c in ".eE"):
            return float(token)
        try:
            return int(token)
        except ValueError:  # more digits than int() accepts
            return float(token)

    def word(self, token: Token) -> str:
        return token.upper()

    def text(self, token: Token) -> Text:
        return Text(token[1:-1].replace("''", "'"))

    def call(self, name: Token, args: tuple[Param, ...] | None) -> Label | Call:
        kind, items = name.upper(), args or ()
        label_name = _label_name(items) if kind in LABEL_KINDS else None
        return Call(kind, items) if label_name is None else Label(kind, label_name)

    def group(self, items: tuple[Param, ...]) -> Group:
        return Group(items)

    def index(self, base: Param, indices: tuple[Param, ...]) -> Expr:
        return Expr("[]", (base, *indices))

    def unary(self, op: Token, operand: Param) -> Param:
        if op in "+-" and isinstance(operand, int | float):
            return -operand if op == "-" else operand
        return Expr(op.upper(), (operand,))

    def binary(self, left: Param, op: Token, right: Param) -> Expr:
        return Expr(op.upper(), (left, right))

    def assign(self, left: Param, right: Param) -> Expr:
        return Expr("=", (left, right))

    def formatted(self, *parts: Param) -> Expr:
        return Expr(":", parts)


def _label_name(items: tuple[Param, ...]) -> str | None:
    """Return the label name if ``items`` is one name (``C1``, ``12``, ``P[3]``), else None."""
    if len(items) != 1:
        return None
    item = items[0]
    if _simple(item):
        return str(item)
    if isinstance(item, Expr) and item.op == "[]" and all(_simple(i) for i in item.operands):
        return str(item)
    return None


def _simple(param: Param) -> bool:
    """Return True for a word or a plain non-negative integer."""
    return isinstance(param, str) or (type(param) is int and param >= 0)


@functools.cache
def _parser() -> Lark:
    """Build the LALR parser once; values are built during the parse (no tree, no recursion)."""
    return Lark(
        grammar_text("dmis"), parser="lalr", transformer=_Builder(), maybe_placeholders=True
    )


def parse_dmis(text: str, *, source: str = "<string>") -> DmisFile:
    """Parse DMIS program or output text.

    Args:
        text: the whole file; CRLF, LF or CR line ends; a leading BOM is ignored.
        source: the file name used in error messages.

    Returns:
        The statements in order and the comments.

    Raises:
        ProgramParseError: on a syntax error; the message names ``source:line:column``,
            what was expected and what was found, and shows the line with a caret.
    """
    text = _LONE_CR.sub("\n", text.removeprefix("\ufeff"))
    padded = text if text.endswith("\n") else text + "\n"
    try:
        items = cast(list[Any], _parser().parse(padded))
    except UnexpectedInput as exc:
        raise _syntax_error(exc, padded, source) from None
    raws = [item for item in items if isinstance(item, _Raw)]
    for raw in raws:
        if _too_deep(raw.params):
            column = raw.start - padded.rfind("\n", 0, raw.start)
            message = f"expected parameters nested at most {MAX_DEPTH} deep, found deeper nesting"
            raise _error(source, raw.line, column, message, padded)
    comments = tuple(item for item in items if isinstance(item, tuple))
    statements = tuple(_finish(raw, text) for raw in raws)
    return DmisFile(source=source, statements=statements, comments=comments)


def read_dmis(path: str | Path) -> DmisFile:
    """Read and parse a DMIS file (UTF-8, or Latin-1 when it is not valid UTF-8).

    Raises:
        ProgramParseError: the file cannot be read, is binary (holds NUL bytes) or
            does not parse.
    """
    source = str(path)
    try:
        data = Path(path).read_bytes()
    except OSError as exc:
        raise ProgramParseError(f"{source}: cannot read: {exc.strerror}") from None
    return parse_dmis(_decode(data, source), source=source)


def parse_dmis_recovering(
    text: str, *, source: str = "<string>"
) -> tuple[DmisFile, tuple[Diagnostic, ...]]:
    """Parse DMIS text, keeping every statement that parses and reporting the others.

    A file that parses whole is returned as :func:`parse_dmis` returns it.  Otherwise
    the text is cut into logical statements (physical lines joined by a ``$`` at the end
    of a line; a line with a ``$$`` comment never continues, as in the grammar) and
    each is parsed alone: a bad statement costs only itself.

    Args:
        text: the whole file; CRLF, LF or CR line ends; a leading BOM is ignored.
        source: the file name used in diagnostics.

    Returns:
        The good statements and comments with physical line numbers, and one
        diagnostic (line, column, expected, found, caret) per bad statement.
    """
    try:
        return parse_dmis(text, source=source), ()
    except ProgramParseError:
        pass
    statements: list[Statement] = []
    comments: list[tuple[int, str]] = []
    diagnostics: list[Diagnostic] = []
    for first, chunk in logical_statements(text):
        shift = first - 1
        try:
            part = parse_dmis(chunk, source=source)
        except ProgramParseError as exc:
            diagnostics.extend(replace(d, line=d.line + shift) for d in exc.diagnostics)
            continue
        statements.extend(replace(s, line=s.line + shift) for s in part.statements)
        comments.extend((line + shift, comment) for line, comment in part.comments)
    return DmisFile(source, tuple(statements), tuple(comments)), tuple(diagnostics)


def logical_statements(text: str) -> list[tuple[int, str]]:
    """Cut DMIS text into logical statements: ``(first physical line, text)`` pairs.

    Physical lines are joined while a line ends with ``$`` (blanks after it allowed)
    outside quotes and has no ``$$`` comment.  Every physical line belongs to exactly
    one pair, so line numbers stay physical.
    """
    lines = _LONE_CR.sub("\n", text.removeprefix("\ufeff")).split("\n")
    out: list[tuple[int, str]] = []
    start = 0
    for index, line in enumerate(lines):
        if index + 1 < len(lines) and _continues(line):
            continue
        out.append((start + 1, "\n".join(lines[start : index + 1])))
        start = index + 1
    return out


_QUOTED = re.compile(r"'(?:[^'\r\n]|'')*'")


def _continues(line: str) -> bool:
    """Return True if a physical line continues on the next (``$`` last, no comment)."""
    code = _QUOTED.sub("''", line)
    return "$$" not in code and code.rstrip(" \t\r").endswith("$")


MAX_DEPTH = 100
"""Deepest parameter nesting accepted (parentheses, operators); deeper is refused, not recursed."""


def _too_deep(params: tuple[Param, ...]) -> bool:
    """Return True if ``params`` nest deeper than MAX_DEPTH (an iterative walk)."""
    stack = [(param, 1) for param in params]
    while stack:
        param, depth = stack.pop()
        if depth > MAX_DEPTH:
            return True
        if isinstance(param, Call):
            stack.extend((child, depth + 1) for child in param.args)
        elif isinstance(param, Group | Expr):
            children = param.items if isinstance(param, Group) else param.operands
            stack.extend((child, depth + 1) for child in children)
    return False


def _error(source: str, line: int, column: int, message: str, text: str) -> ProgramParseError:
    """Return the error for ``message`` at a 1-based position, showing physical line ``line``."""
    lines = text.split("\n")
    physical = lines[line - 1].rstrip("\r") if 0 < line <= len(lines) else ""
    diag = Diagnostic(source, line, column, message, physical)
    return ProgramParseError(str(diag), (diag,))


_LONE_CR = re.compile(r"\r(?!\n)")
_CONTINUATION = re.compile(r"('(?:[^'\r\n]|'')*')|\$[ \t]*\r?\n[ \t]*")


def _decode(data: bytes, source: str) -> str:
    """Decode file bytes, refusing binary data with a located error."""
    nul = data.find(b"\x00")
    if nul >= 0:
        line = data.count(b"\n", 0, nul) + 1
        column = nul - (data.rfind(b"\n", 0, nul) + 1) + 1
        message = "not a DMIS text file: found a NUL byte (binary or UTF-16 data?)"
        raise _error(source, line, column, message, "")
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError:
        return data.decode("latin-1")


def _finish(raw: _Raw, text: str) -> Statement:
    """Cut the statement text from the source, joining ``$`` continuation lines."""
    written = _CONTINUATION.sub(lambda m: m.group(1) or "", text[raw.start : raw.end])
    return Statement(raw.line, raw.label, raw.major, raw.params, written.rstrip())


_READABLE = {
    "NUMBER": "a number",
    "NAME": "a word",
    "STRING": "a quoted string",
    "_LPAR": "'('",
    "SIGN": "a sign",
    "NOT": "'.NOT.'",
    "SLASH": "'/'",
    "_EQUAL": "'='",
    "_COMMA": "','",
    "_RPAR": "')'",
    "_RSQB": "']'",
    "_LSQB": "'['",
    "OPERATOR": "an operator",
    "COMMENT": "a '$$' comment",
    "NL": "end of line",
    "$END": "end of file",
}
"""Readable names of the grammar's terminals, in the order an error lists them."""

_OPERATORS = frozenset({"SIGN", "STAR", "SLASH", "POW", "RELOP", "AND", "OR", "_COLON"})
_OPERATORS_AFTER_OPERAND = _OPERATORS | {"_EQUAL", "_LSQB"}


def _syntax_error(exc: UnexpectedInput, text: str, source: str) -> ProgramParseError:
    """Translate a lark error into a ProgramParseError at the physical line and column."""
    line, column = exc.line, exc.column
    if isinstance(exc, UnexpectedToken):
        expected, found = set(exc.accepts or exc.expected), _describe(exc.token)
        if exc.token.type == "$END":
            line, column = _end_position(text)
    elif isinstance(exc, UnexpectedCharacters):
        expected, found = _allowed(exc), _describe_char(text[exc.pos_in_stream or 0])
    else:  # UnexpectedEOF: not raised by the LALR parser, kept for safety
        expected, found = set(getattr(exc, "expected", ())), "end of file"
        line, column = _end_position(text)
    return _error(source, line, column, f"expected {_expected_list(expected)}, found {found}", text)


def _allowed(exc: UnexpectedCharacters) -> set[str]:
    """Return the terminals the parser accepts where the lexer failed (exact, not the state's)."""
    parser = getattr(exc, "interactive_parser", None)
    return set(parser.accepts()) if parser is not None else set(exc.allowed or ())


def _expected_list(terminals: set[str]) -> str:
    """Return ``"a, b or c"`` for the expected terminals; operators become one entry."""
    if "STAR" in terminals:  # after an operand: any binary operator may follow
        terminals = (terminals - _OPERATORS_AFTER_OPERAND) | {"OPERATOR"}
    return readable_list(terminals, _READABLE)


_FOUND = {"STRING": "the quoted string {}", "NAME": "the word '{}'", "NUMBER": "the number {}"}


def _describe(token: Token) -> str:
    """Describe a token that came where it should not."""
    if token.type in ("$END", "NL", "COMMENT"):
        return _READABLE[token.type]
    return _FOUND.get(token.type, "'{}'").format(token.value)


_CHAR_HINTS = {
    "$": "'$' (a '$' continues a statement only at the end of a line)",
    "'": "a quote that is not closed on its line",
}


def _describe_char(char: str) -> str:
    """Describe a character no token starts with, with a hint for the usual mistakes."""
    return _CHAR_HINTS.get(char, repr(char))


def _end_position(text: str) -> tuple[int, int]:
    """Return the 1-based (line, column) just after the last character of ``text``."""
    body = text.rstrip("\r\n")
    return body.count("\n") + 1, len(body) - (body.rfind("\n") + 1) + 1
