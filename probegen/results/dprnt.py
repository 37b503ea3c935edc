"""Read the DPRNT measuring log a Fanuc Macro B program prints over RS-232.

The format is described in ``docs/dprnt-format.md``.  The log is read one line at a
time with ``grammars/dprnt.lark``; a line that does not parse becomes a
:class:`~probegen.errors.Diagnostic` (line, column, what was expected, what was found)
and every good line is still returned, so one bit of serial noise never costs the
other points.  ``strict=True`` turns any diagnostic into a
:class:`~probegen.errors.ResultsParseError`.

Well-formed ``PT``/``LOC``/``CTR`` lines, the bulk of a log, are read by a compiled
regular expression that accepts only lines the grammar reads to the same record; every
other line goes to lark, so the log and its diagnostics are those of the grammar alone
(``parse_dprnt(text, fast=False)``), about 30 times faster (``docs/benchmarks.md``).
:func:`touches_array` gives the skip positions as one numpy array.

Example:
    >>> log = parse_dprnt("PGSTART O1001 V1\\nPT SPH1 1 X1. Y2. Z-3.5\\nPGEND O1001\\n")
    >>> log.touches[0].xyz, log.complete
    ((1.0, 2.0, -3.5), True)
"""

from __future__ import annotations

import dataclasses
import functools
import itertools
import math
import os
import re
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Literal

from lark import Lark, Token, Transformer
from lark.exceptions import UnexpectedEOF, UnexpectedInput, UnexpectedToken, VisitError

from probegen.errors import Diagnostic, ProbegenError, strict_error
from probegen.gcpause import collector_paused
from probegen.resources import grammar_text

if TYPE_CHECKING:
    import numpy as np
    from numpy.typing import NDArray

__all__ = [
    "FORMAT_VERSION",
    "Centre",
    "DprntLog",
    "ProgramError",
    "Result",
    "Touch",
    "decode_dprnt",
    "parse_dprnt",
    "read_dprnt",
    "touches_array",
]

FORMAT_VERSION = 1
"""The log format version this reader understands (the ``V1`` of ``PGSTART``)."""

MAX_FEATURE_ID = 16
"""Longest feature id the Fanuc dialect prints."""

MAX_INDEX_DIGITS = 6
"""Touch and point indices run from 1 to 999999."""

MAX_PROGRAM_DIGITS = 8
"""Program numbers run from O1 to O99999999 (8 digits on recent controls)."""

_LINE_BREAK = re.compile(r"\r*\n\r*|\r+")
"""A LF with any CRs beside it (LF, CRLF, LFCR, LF CR CR) or a run of lone CRs."""

_NOISE = re.compile("[\x00\x11-\x14]")
"""NUL (tape feed), DC1/DC3 (XON/XOFF) and DC2/DC4 (POPEN/PCLOS device codes)."""

_UPPER = {c: c - 32 for c in range(ord("a"), ord("z") + 1)}
"""ASCII-only upper-casing: ``str.upper`` would turn 'ſ' into 'S'."""

_PICTURES = {c: 0x2400 + c for c in range(32) if c != 9} | {127: 0x2421}
"""Control characters shown as their Unicode control pictures, one column each."""

_SURROGATE = re.compile("[\ud800-\udfff]")

_RECORD_KEYWORDS = frozenset({"PGSTART", "LOC", "CTR", "PT", "RES", "ERR", "PGEND"})
"""The keywords that start a record."""

_NAMES = {
    "FEATURE": "a feature id",
    "INDEX": "an index",
    "UNUMBER": "a number",
    "SIGN": "a sign",
    "AX": "'X'",
    "AY": "'Y'",
    "AZ": "'Z'",
    "PROGNUM": "a program number (O and digits)",
    "VERSION": "a format version (V and digits)",
    "ERRCODE": "an error code (NOTOUCH, COLLISION, OUTTOL, BIGCORR or BADFIT)",
    "KEY": "a result name (letters)",
    "_PCT": "'%'",
    "$END": "end of line",
}
"""Readable names for the grammar's terminals, used in diagnostics."""


@dataclass(frozen=True, slots=True)
class Touch:
    """One skip position printed by the program.

    Attributes:
        kind: ``"PT"`` for a measuring touch, ``"LOC"`` for a locating touch.
        feature: feature id, upper case.
        index: 1-based point (or touch) index within the feature.
        xyz: the skip position ``#5061``-``#5063`` (the stylus ball centre), mm.
        line: 1-based line number in the log.
        run: 0 for the first run of the program, 1 after the first restart, ...
    """

    kind: Literal["PT", "LOC"]
    feature: str
    index: int
    xyz: tuple[float, float, float]
    line: int
    run: int = 0


@dataclass(frozen=True, slots=True)
class Centre:
    """A feature centre the program computed at run time (``CTR`` record).

    Attributes:
        feature: feature id, upper case.
        xyz: the computed centre, mm.
        line: 1-based line number in the log.
        run: the program run it belongs to (see :attr:`Touch.run`).
    """

    feature: str
    xyz: tuple[float, float, float]
    line: int
    run: int = 0


@dataclass(frozen=True, slots=True)
class Result:
    """A ``RES`` record: values the program computed for a feature (``docs/actions.md``).

    Attributes:
        feature: feature id, upper case.
        values: (name, value) pairs in the order printed (``X``, ``D``, ``NG`` ...).
        line: 1-based line number in the log.
        run: the program run it belongs to (see :attr:`Touch.run`).
    """

    feature: str
    values: tuple[tuple[str, float], ...]
    line: int
    run: int = 0


ErrorCode = Literal["NOTOUCH", "COLLISION", "OUTTOL", "BIGCORR", "BADFIT"]
"""``ERR`` codes: no skip signal, signal on a guarded move, a feature out of tolerance,
a tool correction beyond its maximum, touches that fit no circle."""


@dataclass(frozen=True, slots=True)
class ProgramError:
    """An ``ERR`` record: the program printed it just before raising an alarm.

    Attributes:
        code: see :data:`ErrorCode`.
        feature: feature id, upper case.
        index: the point index being measured.
        line: 1-based line number in the log.
        run: the program run it belongs to (see :attr:`Touch.run`).
    """

    code: ErrorCode
    feature: str
    index: int
    line: int
    run: int = 0


@dataclass(frozen=True, slots=True)
class DprntLog:
    """Everything read from one DPRNT log, good records and diagnostics side by side.

    Attributes:
        source: file name, ``<string>`` or ``<serial>``.
        program: program number of the first ``PGSTART`` (else of the first ``PGEND``).
        touches: ``PT`` and ``LOC`` records in log order, all runs.
        centres: ``CTR`` records in log order.
        errors: ``ERR`` records in log order.
        complete: True when the last run ended with ``PGEND``.
        restarts: how many times the program started again: a ``PGSTART`` after an
            earlier ``PGSTART`` or after records (a resumed or re-run program).
        diagnostics: one per malformed or out-of-place line, in line order.
        results: ``RES`` records in log order.
    """

    source: str
    program: int | None
    touches: tuple[Touch, ...]
    centres: tuple[Centre, ...]
    errors: tuple[ProgramError, ...]
    complete: bool
    restarts: int
    diagnostics: tuple[Diagnostic, ...]
    results: tuple[Result, ...] = ()

    def latest_touches(self) -> tuple[Touch, ...]:
        """Return one touch per (kind, feature, index), the last one read, in line order.

        After a restart the resumed run re-measures some points; its touches replace
        those of the interrupted run.
        """
        latest = {(t.kind, t.feature, t.index): t for t in self.touches}
        return tuple(sorted(latest.values(), key=lambda t: t.line))


@dataclass(frozen=True, slots=True)
class _Header:
    program: int
    version: int
    version_column: int


@dataclass(frozen=True, slots=True)
class _End:
    program: int


_Record = Touch | Centre | ProgramError | Result | _Header | _End


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
        return _Header(_program(c[1]), version, c[2].column or 0)

    def end(self, c: list[Token]) -> _End:
        return _End(_program(c[1]))

    def loc(self, c: list[Any]) -> Touch:
        return Touch("LOC", _feature(c[1]), _index(c[2]), c[3], 0)

    def pt(self, c: list[Any]) -> Touch:
        return Touch("PT", _feature(c[1]), _index(c[2]), c[3], 0)

    def ctr(self, c: list[Any]) -> Centre:
        return Centre(_feature(c[1]), c[2], 0)

    def err(self, c: list[Token]) -> ProgramError:
        code: ErrorCode = str(c[1])  # type: ignore[assignment]
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
        return "a record (PGSTART, LOC, CTR, PT, RES, ERR or PGEND)"
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


def _display(clean: str) -> str:
    """Return the line as shown under a diagnostic: printable, one column per character."""
    return _SURROGATE.sub("\ufffd", clean.translate(_PICTURES))


def _split_lines(text: str) -> list[str]:
    """Split on LF, CR, CRLF and LFCR alike and remove NUL and DC1-DC4.

    The noise characters are never line breaks, so removing them from the whole text
    first gives the same lines; a text without CR splits on LF alone.
    """
    if _NOISE.search(text):
        text = _NOISE.sub("", text)
    return text.split("\n") if "\r" not in text else _LINE_BREAK.split(text)


def decode_dprnt(data: bytes) -> str:
    """Decode raw log bytes as ASCII, keeping each undecodable byte as a lone surrogate.

    :func:`parse_dprnt` reports those bytes by value (``undecodable byte 0xC1``); they
    never reach a record, a diagnostic's text or its message.
    """
    return data.decode("ascii", errors="surrogateescape")


class _Builder:
    """Collect records line by line, tracking runs (PGSTART ... PGEND)."""

    def __init__(self, source: str) -> None:
        self.source = source
        self.lineno, self.clean = 0, ""
        self.program: int | None = None
        self.run_program: int | None = None
        self.started = False
        self.end_line = 0
        self.run = 0
        self.headless_reported = False
        self.touches: list[Touch] = []
        self.centres: list[Centre] = []
        self.errors: list[ProgramError] = []
        self.results: list[Result] = []
        self.diagnostics: list[Diagnostic] = []

    def at(self, lineno: int, clean: str) -> None:
        """Move to line ``lineno`` (its text after cleaning)."""
        self.lineno, self.clean = lineno, clean

    def diagnose(self, message: str, column: int = 0) -> None:
        """Record a problem on the current line (column 0: the record's first word)."""
        column = column or _first_column(self.clean)
        text = _display(self.clean)
        self.diagnostics.append(Diagnostic(self.source, self.lineno, column, message, text))

    def add(self, rec: _Record) -> None:
        """Add one record parsed from the current line."""
        if isinstance(rec, _Header):
            self._start(rec)
            return
        self._check_place()
        if isinstance(rec, _End):
            self._end(rec)
            return
        rec = dataclasses.replace(rec, line=self.lineno, run=self.run)
        if isinstance(rec, Touch):
            self.touches.append(rec)
        elif isinstance(rec, Centre):
            self.centres.append(rec)
        elif isinstance(rec, Result):
            self.results.append(rec)
        else:
            self.errors.append(rec)

    def place(self, lineno: int, clean: str) -> None:
        """Check the place of a record read without :meth:`add` (see ``_read_lines``)."""
        if self.end_line or not self.started:
            self.at(lineno, clean)
            self._check_place()

    def _start(self, rec: _Header) -> None:
        if self.program is None:
            self.program = rec.program
        elif rec.program != self.program:
            self.diagnose(
                f"expected program O{self.program} (as in the first header), "
                f"found O{rec.program}: one log per program"
            )
        if rec.version != FORMAT_VERSION:
            message = f"expected format version V{FORMAT_VERSION}, found V{rec.version}"
            self.diagnose(message, rec.version_column)
        if self.started or self.headless_reported:
            self.run += 1
        self.started, self.end_line, self.run_program = True, 0, rec.program

    def _end(self, rec: _End) -> None:
        if self.run_program is not None and rec.program != self.run_program:
            self.diagnose(
                f"expected PGEND O{self.run_program} (the program started), "
                f"found PGEND O{rec.program}"
            )
        if self.program is None:
            self.program = rec.program
        self.end_line = self.lineno

    def _check_place(self) -> None:
        """Diagnose a record outside PGSTART ... PGEND (the record is still kept)."""
        if self.end_line:
            self.diagnose(
                "expected PGSTART to begin a new run, "
                f"found a record after PGEND (line {self.end_line})"
            )
        elif not self.started and not self.headless_reported:
            self.headless_reported = True
            self.diagnose(
                "expected the PGSTART header before the first record "
                "(was the capture started late?)"
            )

    def result(self) -> DprntLog:
        """Return the finished log."""
        return DprntLog(
            source=self.source,
            program=self.program,
            touches=tuple(self.touches),
            centres=tuple(self.centres),
            errors=tuple(self.errors),
            complete=bool(self.end_line),
            restarts=self.run,
            diagnostics=tuple(self.diagnostics),
            results=tuple(self.results),
        )


def _first_column(clean: str) -> int:
    """Return the 1-based column of the first character that is not a blank or '%'."""
    return len(clean) - len(clean.lstrip(" \t%")) + 1


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


_NUMBER = r"([+-]?[0-9.]+)[ \t]*"
_XYZ = rf"X[ \t]*{_NUMBER}Y[ \t]*{_NUMBER}Z[ \t]*{_NUMBER}"
_FEATURE = rf"([A-Z][A-Z0-9]{{0,{MAX_FEATURE_ID - 1}}})[ \t]+"
_FAST_TOUCH = re.compile(
    rf"[ \t]*(PT|LOC)[ \t]+{_FEATURE}0*([1-9][0-9]{{0,{MAX_INDEX_DIGITS - 1}}})\.?[ \t]+{_XYZ}"
)
"""A well-formed upper-case ``PT``/``LOC`` line, the bulk of every log.

A line it matches in full whose three numbers ``float()`` reads as finite, the grammar
reads to the same record: a number or an index is matched whole (a shorter match would
leave a digit or a point where a letter or a blank must follow), so a run of digits and
points that ``float()`` accepts is one UNUMBER; ids have at most MAX_FEATURE_ID
characters, indices run from 1 to 999999.  A sign must touch its digits here (the
grammar allows a blank between them: such lines go to lark, as do ``1.2.3``, ``.`` and
numbers out of range).
"""
_FAST_CENTRE = re.compile(rf"[ \t]*CTR[ \t]+{_FEATURE}{_XYZ}")
"""A well-formed upper-case ``CTR`` line (same rules)."""

_KINDS: dict[str, Literal["PT", "LOC"]] = {"PT": "PT", "LOC": "LOC"}
_UNREAD = (math.nan, math.nan, math.nan)


def _touch_maker() -> Callable[[str, str, int, tuple[float, float, float], int, int], Touch]:
    """Return ``make(kind, feature, index, xyz, line, run) -> Touch`` that fills the slots
    directly: the frozen dataclass ``__init__`` costs twice as much, which counts at a
    million touches.  The unpacking below fails at import if Touch gains a field."""
    kind, feature, index, xyz, line, run = (
        getattr(Touch, field.name).__set__ for field in dataclasses.fields(Touch)
    )
    new = object.__new__

    def make(k: str, f: str, i: int, p: tuple[float, float, float], n: int, r: int) -> Touch:
        touch: Touch = new(Touch)
        kind(touch, k), feature(touch, f), index(touch, i)
        xyz(touch, p), line(touch, n), run(touch, r)
        return touch

    return make


_make_touch = _touch_maker()


def _fast_centre(builder: _Builder, lineno: int, clean: str) -> bool:
    """Read a well-formed CTR line without lark; False: leave the line to lark."""
    match = _FAST_CENTRE.fullmatch(clean)
    if match is None:
        return False
    feature, x, y, z = match.groups()
    xyz = _fast_xyz(x, y, z)
    if not math.isfinite(xyz[0] + xyz[1] + xyz[2]):
        return False
    builder.place(lineno, clean)
    builder.centres.append(Centre(feature, xyz, lineno, builder.run))
    return True


def _fast_xyz(x: str, y: str, z: str) -> tuple[float, float, float]:
    """Return the three numbers, or NaNs if one is not a number (``1.2.3``, ``.``)."""
    try:
        return float(x) + 0.0, float(y) + 0.0, float(z) + 0.0
    except ValueError:
        return _UNREAD


def _no_match(clean: str) -> None:
    """Stand-in for the fast pattern when every line goes to lark."""


def _read_lines(builder: _Builder, lines: list[str], *, fast: bool) -> None:
    """Read every line into ``builder``: well-formed PT/LOC/CTR lines with the patterns
    above (when ``fast``), the others with lark.

    Only lines the grammar reads to exactly the same record take the fast way, so the
    log is the one lark alone gives (``+ 0.0`` turns ``-0.0`` into ``0.0`` as there).
    """
    touch_line = _FAST_TOUCH.fullmatch if fast else _no_match
    touches, isfinite = builder.touches, math.isfinite
    for lineno, clean in enumerate(lines, start=1):
        match = touch_line(clean)
        if match is not None:
            kind, feature, index, x, y, z = match.groups()
            try:  # inline: this loop runs once per line of the log
                xyz = (float(x) + 0.0, float(y) + 0.0, float(z) + 0.0)
            except ValueError:
                xyz = _UNREAD
            if isfinite(xyz[0] + xyz[1] + xyz[2]):  # else lark reports (or reads) it
                if builder.end_line or not builder.started:
                    builder.place(lineno, clean)
                touch = _make_touch(_KINDS[kind], feature, int(index), xyz, lineno, builder.run)
                touches.append(touch)
                continue
        if not (fast and _fast_centre(builder, lineno, clean)) and clean.strip(" \t"):
            _read_line(builder, lineno, clean)


def parse_dprnt(
    text: str | bytes, *, source: str = "<string>", strict: bool = False, fast: bool = True
) -> DprntLog:
    """Parse a DPRNT log.

    Args:
        text: the log; bytes are decoded with :func:`decode_dprnt`.
        source: name used in diagnostics.
        strict: raise instead of returning a log that has diagnostics.
        fast: read well-formed ``PT``/``LOC``/``CTR`` lines with a compiled regular
            expression and only the others with the lark parser (about 30 times
            faster); ``False`` sends every line through lark.  Both give the same log.

    Returns:
        The records of every line that parsed, and one diagnostic per line that did not.

    Raises:
        ResultsParseError: ``strict`` is set and there is at least one diagnostic; it
            carries all of them.
    """
    if isinstance(text, bytes):
        text = decode_dprnt(text)
    builder = _Builder(source)
    with collector_paused():
        _read_lines(builder, _split_lines(text), fast=fast)
        log = builder.result()
    if strict and log.diagnostics:
        raise strict_error(log.source, "DPRNT log", log.diagnostics)
    return log


def read_dprnt(path: str | os.PathLike[str], *, strict: bool = False) -> DprntLog:
    """Read and parse a raw DPRNT log file (as written by :func:`~probegen.results.capture`).

    Args:
        path: the log file.
        strict: raise instead of returning a log that has diagnostics.

    Raises:
        ProbegenError: the file cannot be read.
        ResultsParseError: ``strict`` is set and the log has diagnostics.
    """
    try:
        with open(path, "rb") as f:
            data = f.read()
    except OSError as exc:
        raise ProbegenError(f"cannot read DPRNT log '{os.fspath(path)}': {exc.strerror}") from exc
    return parse_dprnt(data, source=os.fspath(path), strict=strict)


def touches_array(touches: DprntLog | tuple[Touch, ...]) -> NDArray[np.float64]:
    """Return the skip positions of ``touches`` (or of a log's touches) as one array.

    For vectorised work on large logs (compensation, fits): ``(n, 3)`` float64, one row
    per touch in order, mm.  numpy is imported here, not with the module, so reading a
    log on a shop-floor PC stays light.
    """
    import numpy as np

    records = touches.touches if isinstance(touches, DprntLog) else touches
    flat = itertools.chain.from_iterable(touch.xyz for touch in records)
    return np.fromiter(flat, dtype=np.float64, count=3 * len(records)).reshape(-1, 3)
