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

The reader is split by responsibility: :mod:`~probegen.results.dprnt_records` (the
records and the assembly of a log), :mod:`~probegen.results.dprnt_grammar` (the lark
path and its diagnostics) and :mod:`~probegen.results.dprnt_fast` (the regular-expression
path); this module holds the public entry points and re-exports the record types.
"""

from __future__ import annotations

import itertools
import os
import re
from typing import TYPE_CHECKING

from probegen.errors import ProbegenError, strict_error
from probegen.results.dprnt_fast import _read_lines
from probegen.results.dprnt_records import (
    FORMAT_VERSION,
    Centre,
    DprntLog,
    ProgramError,
    Result,
    Run,
    Touch,
    _Builder,
)
from probegen.results.gcpause import collector_paused

if TYPE_CHECKING:
    import numpy as np
    from numpy.typing import NDArray

__all__ = [
    "FORMAT_VERSION",
    "Centre",
    "DprntLog",
    "ProgramError",
    "Result",
    "Run",
    "Touch",
    "decode_dprnt",
    "log_lines",
    "parse_dprnt",
    "read_dprnt",
    "touches_array",
]


_LINE_BREAK = re.compile(r"\r*\n\r*|\r+")
"""A LF with any CRs beside it (LF, CRLF, LFCR, LF CR CR) or a run of lone CRs."""

_NOISE = re.compile("[\x00\x11-\x14]")
"""NUL (tape feed), DC1/DC3 (XON/XOFF) and DC2/DC4 (POPEN/PCLOS device codes)."""


def _split_lines(text: str) -> list[str]:
    """Split on LF, CR, CRLF and LFCR alike and remove NUL and DC1-DC4.

    The noise characters are never line breaks, so removing them from the whole text
    first gives the same lines; a text without CR splits on LF alone.
    """
    if _NOISE.search(text):
        text = _NOISE.sub("", text)
    return text.split("\n") if "\r" not in text else _LINE_BREAK.split(text)


def log_lines(data: bytes | str) -> list[str]:
    """The lines of a raw log as the reader numbers them (line ``k`` is ``[k - 1]``), noise
    removed: for quoting a line in a diagnostic made after reading."""
    return _split_lines(decode_dprnt(data) if isinstance(data, bytes) else data)


def decode_dprnt(data: bytes) -> str:
    """Decode raw log bytes as ASCII, keeping each undecodable byte as a lone surrogate.

    :func:`parse_dprnt` reports those bytes by value (``undecodable byte 0xC1``); they
    never reach a record, a diagnostic's text or its message.
    """
    return data.decode("ascii", errors="surrogateescape")


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
    return parse_dprnt(read_raw(path), source=os.fspath(path), strict=strict)


def read_raw(path: str | os.PathLike[str]) -> bytes:
    """The raw bytes of a log file, for :func:`parse_dprnt` and :func:`log_lines`.

    Raises:
        ProbegenError: the file cannot be read.
    """
    try:
        with open(path, "rb") as f:
            return f.read()
    except OSError as exc:
        raise ProbegenError(f"cannot read DPRNT log '{os.fspath(path)}': {exc.strerror}") from exc


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
