"""Physical lines of DMIS text joined into logical ones, as CMM software writes them.

:func:`splice` joins continued lines (a ``$`` at the end of a line, anywhere: in a word,
a number, a string, a label or a ``$$`` comment) and keeps the way back to physical
line and column; :func:`logical_statements` cuts the text into statements with their
first physical line.  Used by :mod:`probegen.dmis.reader` before parsing.
"""

from __future__ import annotations

import bisect
import re
from dataclasses import dataclass


def logical_statements(text: str) -> list[tuple[int, str]]:
    """Cut DMIS text into logical statements: ``(first physical line, text)`` pairs.

    Physical lines are joined as :func:`splice` joins them (a continuation ``$`` at the
    end of a line, in a statement, a string or a comment).  Every physical line belongs to
    exactly one pair, so line numbers stay physical.
    """
    joined = splice(text)
    parts = _LINE_END.split(text.removeprefix("\ufeff"))
    out: list[tuple[int, str]] = []
    start = 0
    count = (len(parts) + 1) // 2
    for index in range(count):
        if index + 1 < count and index < len(joined.continues) and joined.continues[index]:
            continue
        out.append((start + 1, "".join(parts[2 * start : 2 * index + 1])))
        start = index + 1
    return out


_LINE_END = re.compile(r"(\r\n|\r|\n)")


# ------------------------------------------------------------------------ continuations

_CODE, _STRING, _COMMENT = 0, 1, 2
"""What a continued line continues: a statement, a quoted string or a ``$$`` comment."""

_STATEMENT_START = re.compile(
    r"[ \t]*(?:\w+[ \t]*\([^()\n]*\)[ \t]*=|[A-Za-z]\w*[ \t]*/"
    r"|\w+[ \t]*(?:\[[^\]\n]*\])?[ \t]*=[ \t]*[A-Za-z]\w*[ \t]*/"
    r"|\([ \t]*\w+[ \t]*\)[ \t]*(?:\$\$|$)"
    r"|(?:ENDMES|ENDFIL|ENDGO|ENDMAC|ENDDO|ENDIF|ELSE|ENDSEL|ENDCAS|DFTCAS|ENDAT|ENDXTN"
    r"|ENDSIMREQT|PAUSE|RMEAS)[ \t]*(?:\$\$|$))",
    re.IGNORECASE,
)
"""A physical line that starts a statement (``X=ASSIGN/...`` and a ``(label)`` line
included): a wrapped comment never goes on onto it."""


_CHFILE_BEGIN = re.compile(r"[ \t]*BEGIN[ \t]*/[ \t]*CHFILE[ \t]*(?:\$\$.*)?$", re.IGNORECASE)
_CHFILE_END = re.compile(r"[ \t]*END[ \t]*/[ \t]*CHFILE[ \t]*(?:\$\$.*)?$", re.IGNORECASE)
"""WinWerth's characterisation block: ``BEGIN/CHFILE``, lines of ``KEY = value`` data (not
DMIS), ``END/CHFILE``; the data lines are read as comments."""


@dataclass(frozen=True, slots=True)
class Spliced:
    """DMIS text with its continued lines joined, and the way back to physical positions.

    Attributes:
        physical: the physical lines (BOM dropped, line ends removed).
        logical: the joined text; each logical line ends with ``\\n`` (the last one not
            when the file ends in a continuation).
        starts: the logical offset where each physical line's kept text begins.
        dropped: per physical line, the leading blanks dropped (a continuation line).
        continues: per physical line, whether it continues on the next.
    """

    physical: tuple[str, ...]
    logical: str
    starts: tuple[int, ...]
    dropped: tuple[int, ...]
    continues: tuple[bool, ...]

    def position(self, offset: int) -> tuple[int, int]:
        """Return the 1-based physical (line, column) of a logical offset."""
        index = max(bisect.bisect_right(self.starts, offset) - 1, 0)
        return index + 1, offset - self.starts[index] + self.dropped[index] + 1

    @property
    def text(self) -> str:
        """The physical text, lines joined with ``\\n``."""
        return "\n".join(self.physical)


def splice(text: str) -> Spliced:
    """Join continued lines the way CMM software writes them.

    A ``$`` that is the last character of a line (blanks after it allowed) continues the
    line on the next one, wherever it stands: between words, inside a word, a number, a
    quoted string or a label (LK CAMIO wraps every line at column 80).  The ``$`` and the
    line end are removed and the next line follows directly; its leading blanks are
    dropped unless it goes on inside a quoted string (indented continuation lines).
    In a ``$$`` comment a last ``$`` after other text continues the comment: the next
    line is comment text, unless it starts a statement (``WORD/...``, ``X(name)=...``
    or a bare ``ENDMES``-like word); a banner of ``$`` alone never continues.  The lines
    between ``BEGIN/CHFILE`` and ``END/CHFILE`` (WinWerth's characterisation data, not
    DMIS) are comment text.
    """
    text = text.removeprefix("\ufeff").replace("\r\n", "\n").replace("\r", "\n")
    lines = text.split("\n")
    if len(lines) > 1 and lines[-1] == "":
        lines.pop()
    pieces: list[str] = []
    starts: list[int] = []
    dropped: list[int] = []
    continues: list[bool] = []
    offset, mode, block = 0, _CODE, False
    for index, line in enumerate(lines):
        blanks = len(line) - len(line.lstrip(" \t")) if index and continues[-1] else 0
        if mode == _STRING:
            blanks = 0
        starts.append(offset)
        dropped.append(blanks)
        fresh = not (index and continues[-1])
        block = block and not (fresh and _CHFILE_END.match(line))
        if block:  # a vendor's characterisation data (KEY = value): comment text
            continues.append(False)
            pieces.append(f"$$ {line}\n")
            offset += len(pieces[-1])
            continue
        block = fresh and bool(_CHFILE_BEGIN.match(line))
        found = _continuation(line, mode)
        if found is not None and found[0] == _COMMENT and (
            index + 1 == len(lines) or _STATEMENT_START.match(lines[index + 1])
        ):
            found = None
        piece = line[blanks : max(found[1], blanks)] if found else line[blanks:] + "\n"
        mode = found[0] if found else _CODE
        continues.append(found is not None)
        pieces.append(piece)
        offset += len(piece)
    return Spliced(tuple(lines), "".join(pieces), tuple(starts), tuple(dropped),
                   tuple(continues))


def _continuation(line: str, mode: int) -> tuple[int, int] | None:
    """Return (what goes on, where the ``$`` is) if ``line``, entered in ``mode``, continues."""
    body = line.rstrip(" \t\f")
    if not body.endswith("$"):
        return None
    cut = len(body) - 1
    if mode == _COMMENT:  # a line of comment text: a "$" alone on it continues too
        return (_COMMENT, cut) if body == "$" or _comment_continues(body) else None
    in_string = mode == _STRING
    for index, char in enumerate(body):
        if char == "'":
            in_string = not in_string  # '' inside a string toggles twice: still inside
        elif char == "$" and not in_string and index < cut:
            if body[index + 1] == "$":
                return (_COMMENT, cut) if _comment_continues(body[index + 2 :]) else None
    return (_STRING if in_string else _CODE, cut)


def _comment_continues(comment: str) -> bool:
    """Return True if comment text ending in ``$`` continues (``$`` after other text)."""
    return len(comment) >= 2 and comment[-2] != "$"
