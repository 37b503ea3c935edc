"""The lark path of the DPRNT reader: one line through ``grammars/dprnt.lark``.

Owns the LALR parser, the transformer from parse tree to record (with the checks of
field values the grammar cannot express), and the wording of a diagnostic for a line
the grammar rejects (column, what was expected, what was found).  Every line the regular
expressions of :mod:`probegen.results.dprnt_fast` do not take comes here, so the records
and diagnostics of a log are those of the grammar alone.
"""

from __future__ import annotations

import functools
import math
import re
from typing import Any, Literal

from lark import Lark, Token, Transformer
from lark.exceptions import UnexpectedEOF, UnexpectedInput, UnexpectedToken, VisitError

from probegen.resources import grammar_text
from probegen.results.dprnt_records import (
    MAX_FEATURE_ID,
    MAX_INDEX_DIGITS,
    MAX_PROGRAM_DIGITS,
    MAX_SERIAL,
    CalibrationMark,
    Centre,
    ErrorCode,
    ProgramError,
    Result,
    SerialMark,
    Touch,
    _Bind,
    _Builder,
    _End,
    _Header,
    _Numbered,
    _Record,
)

_UPPER = {c: c - 32 for c in range(ord("a"), ord("z") + 1)}
"""ASCII-only upper-casing: ``str.upper`` would turn 'ſ' into 'S'."""

_RECORD_KEYWORDS = frozenset({"PGSTART", "PGCAL", "PGSERIAL", "FEAT", "LOC", "CTR", "PT", "RES",
                              "ERR", "PGEND"})
"""The keywords that start a record."""

_NAMES = {
    "FEATURE": "a feature id",
    "INDEX": "an index",
    "FEATNUM": "a feature number",
    "UNUMBER": "a number",
    "SIGN": "a sign",
    "AX": "'X'",
    "AY": "'Y'",
    "AZ": "'Z'",
    "PROGNUM": "a program number (O and digits)",
    "VERSION": "a format version (V and digits)",
    "IDENTITY": "a program identity (H and 8 hex digits)",
    "ERRCODE": "an error code (NOTOUCH, COLLISION, OUTTOL, BIGCORR or BADFIT)",
    "KEY": "a result name (letters)",
    "SERIAL": "a serial number (letters, digits, . _ / -)",
    "_PCT": "'%'",
    "$END": "end of line",
}
"""Readable names for the grammar's terminals, used in diagnostics."""


class _FieldError(Exception):
    """A line that parses but holds an impossible value (raised inside the transformer)."""

    def __init__(self, column: int, message: str) -> None:
        super().__init__(message)
        self.column = column
        self.message = message


class _ToRecord(Transformer[Token, "_Record | None"]):
    """Turn the parse tree of one line into a record (line and run filled in later)."""

    def start(self, children: list[_Record]) -> _Record | None:
        return children[0] if children else None

    def header(self, c: list[Token]) -> _Header:
        version = _digits(c[2], 1, "a format version")
        identity = str(c[3]) if len(c) > 3 else None
        return _Header(_program(c[1]), version, c[2].column or 0, identity,
                       c[3].column or 0 if len(c) > 3 else 0)

    def cal(self, c: list[Token]) -> CalibrationMark:
        return CalibrationMark(str(c[1]), 0)

    def serial(self, c: list[Token]) -> SerialMark:
        text = str(c[1])
        if len(text) > MAX_SERIAL:
            raise _FieldError(c[1].column or 0, f"expected a serial number of at most "
                              f"{MAX_SERIAL} characters, found '{text[:40]}' "
                              f"({len(text)} characters)")
        if text.endswith(".") and text[:-1].isdigit():
            text = text[:-1]  # DPRNT's "4711." for a variable with no fraction digits
        return SerialMark(text, 0)

    def end(self, c: list[Token]) -> _End:
        return _End(_program(c[1]))

    def feat(self, c: list[Token]) -> _Bind:
        return _Bind(_feature(c[1]), _number(c[2]), c[2].column or 0)

    def loc(self, c: list[Any]) -> Touch | _Numbered:
        return _touch("LOC", c)

    def pt(self, c: list[Any]) -> Touch | _Numbered:
        return _touch("PT", c)

    def ctr(self, c: list[Any]) -> Centre:
        return Centre(_feature(c[1]), c[2], 0)

    def err(self, c: list[Token]) -> ProgramError | _Numbered:
        code: ErrorCode = str(c[1])  # type: ignore[assignment]
        if c[2].type == "FEATNUM":
            return _Numbered(_number(c[2]), c[2].column or 0,
                             ProgramError(code, "", _index(c[3]), 0))
        return ProgramError(code, _feature(c[2]), _index(c[3]), 0)

    def res(self, c: list[Any]) -> Result:
        return Result(_feature(c[1]), tuple(c[2:]), 0)

    def keyed(self, c: list[Token]) -> tuple[str, float]:
        return (str(c[0]), self.number(c[1:]))

    def xyz(self, c: list[Token | float]) -> tuple[float, float, float]:
        return (float(c[1]), float(c[3]), float(c[5]))

    def number(self, c: list[Token]) -> float:
        value = float("".join(c))
        if not math.isfinite(value):
            raise _FieldError(c[0].column or 0, f"number '{''.join(c)}' is out of range")
        return value + 0.0  # -0.0 -> 0.0


def _touch(kind: Literal["PT", "LOC"], c: list[Any]) -> Touch | _Numbered:
    """A touch naming its feature by id, or by number (format V2, resolved by the
    builder)."""
    if c[1].type == "FEATNUM":
        return _Numbered(_number(c[1]), c[1].column or 0, Touch(kind, "", _index(c[2]), c[3], 0))
    return Touch(kind, _feature(c[1]), _index(c[2]), c[3], 0)


def _feature(tok: Token) -> str:
    if len(tok) > MAX_FEATURE_ID:
        raise _FieldError(
            tok.column or 0,
            f"expected a feature id of at most {MAX_FEATURE_ID} characters, "
            f"found '{tok}' ({len(tok)} characters)",
        )
    return str(tok)


def _digits(tok: Token, skip: int, what: str, ndigits: int = MAX_INDEX_DIGITS) -> int:
    """Return the integer after ``skip`` leading letters of ``tok``, at least 1."""
    digits = tok[skip:].rstrip(".")
    significant = digits.lstrip("0")
    if len(significant) > ndigits or not significant:
        top = "9" * ndigits
        raise _FieldError(
            tok.column or 0,
            f"expected {what} from {tok[:skip]}1 to {tok[:skip]}{top}, found '{tok}'",
        )
    return int(significant)


def _index(tok: Token) -> int:
    return _digits(tok, 0, "an index")


def _number(tok: Token) -> int:
    return _digits(tok, 0, "a feature number")


def _program(tok: Token) -> int:
    return _digits(tok, 1, "a program number", MAX_PROGRAM_DIGITS)


@functools.cache
def _parser() -> Lark:
    """Build the LALR line parser once."""
    return Lark(grammar_text("dprnt"), parser="lalr", lexer="contextual")


def _parse_line(clean: str) -> _Record | None:
    """Parse one cleaned line; raise ``UnexpectedInput`` or ``_FieldError``."""
    tree = _parser().parse(clean.translate(_UPPER))
    try:
        return _ToRecord().transform(tree)
    except VisitError as exc:
        if isinstance(exc.orig_exc, _FieldError):
            raise exc.orig_exc from None
        raise


def _describe(exc: UnexpectedInput, clean: str) -> tuple[int, str]:
    """Return the column and the message for a line the grammar rejected."""
    at_end = isinstance(exc, UnexpectedEOF)
    if at_end or (isinstance(exc, UnexpectedToken) and exc.token.type == "$END"):
        column = len(clean.rstrip(" \t")) + 1
    else:
        column = exc.column if exc.column and exc.column > 0 else 1
    expected = _expected_names(_expected_at(clean, column))
    return column, f"expected {expected}, found {_found(clean, column)}"


def _expected_at(clean: str, column: int) -> set[str]:
    """Return the terminals the grammar accepts at ``column``.

    The line up to ``column`` is fed to an interactive parser: its ``accepts()`` is
    exact, where the lexer's set at a bad character is an LALR superset.
    """
    cursor = _parser().parse_interactive(clean[: column - 1].translate(_UPPER))
    try:
        cursor.exhaust_lexer()
    except UnexpectedInput:
        return set()
    return set(cursor.accepts())


def _expected_names(names: set[str]) -> str:
    """Return readable text for a set of terminal names."""
    if _RECORD_KEYWORDS <= names:
        return "a record (PGSTART, PGCAL, PGSERIAL, FEAT, LOC, CTR, PT, RES, ERR or PGEND)"
    if "UNUMBER" in names:
        names = names - {"SIGN"}
    if "$END" in names:
        names = names - {"_PCT"}
    labels = sorted(_NAMES.get(name, name) for name in names)
    if not labels:
        return "a record"
    return labels[0] if len(labels) == 1 else ", ".join(labels[:-1]) + " or " + labels[-1]


def _found(clean: str, column: int) -> str:
    """Describe what stands at 1-based ``column`` of the line."""
    if column > len(clean.rstrip(" \t")):
        return "end of line"
    ch = clean[column - 1]
    code = ord(ch)
    if 0xDC80 <= code <= 0xDCFF:
        return (
            f"undecodable byte 0x{code - 0xDC00:02X} (not 7-bit ASCII: "
            "check the port is set to 7 data bits, even parity)"
        )
    if code < 32 or code == 127:
        return f"control character 0x{code:02X}"
    if code > 127:
        return f"non-ASCII character {ch!r} (U+{code:04X})"
    word = re.match(r"[!-~]+", clean[column - 1 :])
    text = word.group() if word else ch
    return f"'{text[:24]}...'" if len(text) > 24 else f"'{text}'"


def _read_line(builder: _Builder, lineno: int, clean: str) -> None:
    """Parse one line into ``builder``: a record or a diagnostic."""
    builder.at(lineno, clean)
    try:
        rec = _parse_line(clean)
    except UnexpectedInput as exc:
        column, message = _describe(exc, clean)
        builder.diagnose(message, column)
    except _FieldError as exc:
        builder.diagnose(exc.message, exc.column)
    else:
        if rec is not None:
            builder.add(rec)
