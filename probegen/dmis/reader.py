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

from probegen.dmis.lines import Spliced, splice
from probegen.dmis.lines import logical_statements as logical_statements
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
    if statement.major == "" and statement.label is not None:
        return f"({statement.label.name})"  # a program line label
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


@dataclass(frozen=True, slots=True)
class _Comment:
    """A ``$$`` comment before positions are mapped: ``start`` is its logical offset."""

    start: int
    text: str


@v_args(inline=True)
class _Builder(Transformer[Token, Any]):
    """Build typed values while the LALR parser reduces; stateless, so one is shared.

    Positions are offsets into the logical (spliced) text; :class:`_Splice` maps them back.
    """

    def start(self, *lines: list[Any]) -> list[Any]:
        return [item for line in lines for item in line]

    def line(self, *children: Any) -> list[Any]:
        end = children[-1].start_pos
        out: list[Any] = []
        for child in children[:-1]:
            if isinstance(child, Token):
                end = child.start_pos
                out.append(_Comment(child.start_pos or 0, child.value[2:].strip()))
        if isinstance(children[0], _Raw):
            out.insert(0, replace(children[0], end=end))
        return out

    def statement(self, target: Any, major: Token, _slash: Any, params: Any) -> _Raw:
        label, first = target if target else (None, major)
        return _Raw(0, first.start_pos or 0, label, major.upper(), params or ())

    def variable_statement(self, target: tuple[Param, Token], major: Token, _slash: Any,
                           params: tuple[Param, ...]) -> _Raw:
        """``X=MAJOR/p1,...`` (a variable target) is read as ``MAJOR/X=p1,...``."""
        var, first = target
        return _Raw(0, first.start_pos or 0, None, major.upper(),
                    (Expr("=", (var, params[0])), *params[1:]))

    def variable(self, name: Token) -> tuple[Param, Token]:
        return name.upper(), name

    def variable_index(self, name: Token, indices: tuple[Param, ...]) -> tuple[Param, Token]:
        return Expr("[]", (name.upper(), *indices)), name

    def jump_label(self, name: Token) -> _Raw:
        """``(name)``: a program line label (the target of ``JUMPTO``), major word ``""``."""
        return _Raw(0, name.start_pos or 0, Label("", name.upper()), "", ())

    def target(self, kind: Token, name: Param) -> tuple[Label, Token]:
        """Return the label and the token where the statement starts."""
        text = name if isinstance(name, str) else format_param(name)
        return Label(kind.upper(), text), kind

    def label_target(self, token: Token) -> tuple[Label, Token]:
        kind, name = _split_label(token)
        return Label(kind, name), token

    def label(self, token: Token) -> Label | Call:
        kind, name = _split_label(token)
        if _FLOAT.fullmatch(name):  # F(1.5): a call with a number, as before labels had dots
            return Call(kind, (float(name),))
        return Label(kind, name)

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


_FLOAT = re.compile(r"\d*\.\d*(?:E[+-]?\d+)?|\d+E[+-]?\d+")
_INTEGER = re.compile(r"\d+")


def _split_label(token: Token) -> tuple[str, str]:
    """Return (kind, name) of a ``LABELREF`` token, upper-cased, blanks removed."""
    kind, _, rest = token.value.partition("(")
    name = re.sub(r"[ \t]", "", rest[:-1]).upper()
    return kind.strip().upper(), str(int(name)) if _INTEGER.fullmatch(name) else name


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
        text: the whole file; CRLF, LF or CR line ends; a leading BOM is ignored;
            continued lines are joined first (:func:`splice`).
        source: the file name used in error messages.

    Returns:
        The statements in order and the comments, with physical line numbers.

    Raises:
        ProgramParseError: on a syntax error; the message names ``source:line:column``
            (physical), what was expected and what was found, and shows the line with a caret.
    """
    joined = splice(text)
    return _build(joined, _parse_range(joined, 0, len(joined.logical), source), source)


def read_dmis(path: str | Path) -> DmisFile:
    """Read and parse a DMIS file (UTF-8 with or without BOM, or Latin-1 when not UTF-8).

    Raises:
        ProgramParseError: the file cannot be read, is binary (holds NUL bytes) or
            does not parse.
    """
    return parse_dmis(read_dmis_text(path), source=str(path))


def read_dmis_all(path: str | Path) -> DmisFile:
    """Read and parse a DMIS file like :func:`read_dmis`, but report every statement that
    does not parse, not only the first (:func:`parse_dmis_all`).

    Raises:
        ProgramParseError: as :func:`read_dmis`; its diagnostics list every bad statement.
    """
    return parse_dmis_all(read_dmis_text(path), source=str(path))


def parse_dmis_all(text: str, *, source: str = "<string>") -> DmisFile:
    """Parse DMIS text like :func:`parse_dmis`, but read on after a bad statement and
    report every one (line, column, what was expected and found, the line).

    Raises:
        ProgramParseError: one diagnostic per bad statement; the message lists them all.
    """
    parsed, diagnostics = parse_dmis_recovering(text, source=source)
    if diagnostics:
        lines = [str(d) for d in diagnostics]
        if len(lines) > 1:
            lines.insert(0, f"{source}: {len(lines)} statements do not parse:")
        raise ProgramParseError("\n".join(lines), diagnostics)
    return parsed


def read_dmis_text(path: str | Path) -> str:
    """Return the text of a DMIS file as every command reads it: UTF-8 (a BOM dropped),
    or Latin-1 when the bytes are not UTF-8.

    Raises:
        ProgramParseError: the file cannot be read or holds NUL bytes (binary, UTF-16).
    """
    source = str(path)
    try:
        data = Path(path).read_bytes()
    except OSError as exc:
        raise ProgramParseError(f"{source}: cannot read: {exc.strerror}") from None
    return decode_dmis(data, source)


def parse_dmis_recovering(
    text: str, *, source: str = "<string>"
) -> tuple[DmisFile, tuple[Diagnostic, ...]]:
    """Parse DMIS text, keeping every statement that parses and reporting the others.

    A file that parses whole is returned as :func:`parse_dmis` returns it.  Otherwise
    each logical line (physical lines joined by continuations, :func:`splice`) is parsed
    alone: a bad statement costs only itself.

    Args:
        text: the whole file; CRLF, LF or CR line ends; a leading BOM is ignored.
        source: the file name used in diagnostics.

    Returns:
        The good statements and comments with physical line numbers, and one
        diagnostic (line, column, expected, found, caret) per bad statement.
    """
    joined = splice(text)
    try:
        return _build(joined, _parse_range(joined, 0, len(joined.logical), source), source), ()
    except ProgramParseError:
        pass
    items: list[Any] = []
    diagnostics: list[Diagnostic] = []
    start = 0
    logical = joined.logical
    while start < len(logical):
        stop = logical.find("\n", start)
        stop = len(logical) if stop < 0 else stop + 1
        try:
            items.extend(_parse_range(joined, start, stop, source))
        except ProgramParseError as exc:
            diagnostics.extend(exc.diagnostics)
        start = stop
    return _build(joined, items, source), tuple(diagnostics)


# ------------------------------------------------------------------------------ parsing


def _parse_range(joined: Spliced, start: int, stop: int, source: str) -> list[Any]:
    """Parse ``joined.logical[start:stop]``; return raw statements and comments with
    logical offsets, or raise a ProgramParseError at the physical position."""
    chunk = joined.logical[start:stop]
    try:
        items = cast(list[Any], _parser().parse(chunk))
    except UnexpectedInput as exc:
        raise _syntax_error(exc, joined, start, source) from None
    items = [replace(item, start=chunk.rfind("(", 0, item.start))
             if isinstance(item, _Raw) and item.major == "" else item for item in items]
    if start:
        items = [replace(item, start=item.start + start, end=item.end + start)
                 if isinstance(item, _Raw) else replace(item, start=item.start + start)
                 for item in items]
    for raw in items:
        if isinstance(raw, _Raw) and _too_deep(raw.params):
            line, column = joined.position(raw.start)
            message = f"expected parameters nested at most {MAX_DEPTH} deep, found deeper nesting"
            raise _error(source, line, column, message, joined.physical)
    return items


def _build(joined: Spliced, items: list[Any], source: str) -> DmisFile:
    """Return the DmisFile of parsed items, positions mapped back to physical lines."""
    statements = tuple(
        Statement(joined.position(item.start)[0], item.label, item.major, item.params,
                  joined.logical[item.start : item.end].rstrip())
        for item in items if isinstance(item, _Raw)
    )
    comments = tuple((joined.position(item.start)[0], item.text)
                     for item in items if isinstance(item, _Comment))
    return DmisFile(source=source, statements=statements, comments=comments)


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


def _error(source: str, line: int, column: int, message: str,
           lines: tuple[str, ...] | list[str]) -> ProgramParseError:
    """Return the error for ``message`` at a 1-based position, showing physical line ``line``."""
    physical = lines[line - 1].rstrip("\r") if 0 < line <= len(lines) else ""
    diag = Diagnostic(source, line, column, message, physical)
    return ProgramParseError(str(diag), (diag,))


def decode_dmis(data: bytes, source: str) -> str:
    """Decode file bytes, refusing binary data with a located error."""
    nul = data.find(b"\x00")
    if nul >= 0:
        line = data.count(b"\n", 0, nul) + 1
        column = nul - (data.rfind(b"\n", 0, nul) + 1) + 1
        message = "not a DMIS text file: found a NUL byte (binary or UTF-16 data?)"
        raise _error(source, line, column, message, ())
    try:
        return data.decode("utf-8").removeprefix("\ufeff")
    except UnicodeDecodeError:
        return data.decode("latin-1")


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


def _syntax_error(exc: UnexpectedInput, joined: Spliced, start: int,
                  source: str) -> ProgramParseError:
    """Translate a lark error on ``joined.logical[start:]`` into a ProgramParseError at the
    physical line and column."""
    text = joined.logical
    if isinstance(exc, UnexpectedToken):
        expected, found = set(exc.accepts or exc.expected), _describe(exc.token)
        at_end = exc.token.type == "$END"
        offset = start + (exc.token.start_pos or 0)
    elif isinstance(exc, UnexpectedCharacters):
        offset = start + (exc.pos_in_stream or 0)
        expected, found = _allowed(exc), _describe_char(text[offset])
        at_end = False
    else:  # UnexpectedEOF: not raised by the LALR parser, kept for safety
        expected, found = set(getattr(exc, "expected", ())), "end of file"
        at_end, offset = True, 0
    line, column = _end_position(joined.physical) if at_end else joined.position(offset)
    message = f"expected {_expected_list(expected)}, found {found}"
    return _error(source, line, column, message, joined.physical)


def _allowed(exc: UnexpectedCharacters) -> set[str]:
    """Return the terminals the parser accepts where the lexer failed (exact, not the state's)."""
    parser = getattr(exc, "interactive_parser", None)
    return set(parser.accepts()) if parser is not None else set(exc.allowed or ())


def _expected_list(terminals: set[str]) -> str:
    """Return ``"a, b or c"`` for the expected terminals; operators become one entry."""
    terminals = terminals - {"LABELREF", "LOGICAL"}  # accepted where a word is: "a word" says it
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


def _end_position(lines: tuple[str, ...]) -> tuple[int, int]:
    """Return the 1-based (line, column) just after the last character of the text."""
    count = len(lines)
    while count > 1 and not lines[count - 1]:
        count -= 1
    return count, len(lines[count - 1]) + 1 if lines else 1
