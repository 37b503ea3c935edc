"""The ``ProbegenError`` family.

Every bad input (spec, STEP model, returned data, serial noise) ends in one of these,
with a message that says *where* (file, key path or line/column), *what was expected*
and *what was found*.  The CLI prints ``str(error)`` and exits with ``error.exit_code``;
a traceback is only ever shown for a bug, never for a user error.
"""

from __future__ import annotations

import difflib
from collections.abc import Iterable
from dataclasses import dataclass
from enum import IntEnum


@dataclass(frozen=True, slots=True)
class Diagnostic:
    """One problem found in outside data, kept beside the good data that was read.

    Attributes:
        source: file name (or ``<stdin>``, ``<serial>``).
        line: 1-based line number, 0 when unknown.
        column: 1-based column number, 0 when unknown.
        message: what was expected and what was found.
        text: the offending line, for the caret display.
    """

    source: str
    line: int
    column: int
    message: str
    text: str = ""

    def __str__(self) -> str:
        where = self.source
        if self.line:
            where += f":{self.line}"
            if self.column:
                where += f":{self.column}"
        out = f"{where}: {self.message}"
        if self.text:
            out += "\n" + caret(self.text, self.column)
        return out


def caret(text: str, column: int) -> str:
    """Return ``text`` and a caret line under 1-based ``column`` (tabs kept aligned)."""
    line = text.rstrip("\r\n")
    pad = "".join("\t" if ch == "\t" else " " for ch in line[: max(column - 1, 0)])
    return f"    {line}\n    {pad}^"


def readable_list(terminals: Iterable[str], readable: dict[str, str]) -> str:
    """``"a, b or c"`` for a parser's expected terminals: those ``readable`` names in its
    order, then the others by name; ``"nothing more"`` when there are none."""
    terminals = set(terminals)
    order = list(readable)
    known = sorted((t for t in terminals if t in readable), key=order.index)
    names = [readable[t] for t in known] + sorted(t for t in terminals if t not in readable)
    if not names:
        return "nothing more"
    return names[0] if len(names) == 1 else f"{', '.join(names[:-1])} or {names[-1]}"


def did_you_mean(word: str, choices: Iterable[str]) -> str:
    """Return ``" (did you mean 'x'?)"`` for the closest choice, or ``""``."""
    close = difflib.get_close_matches(word, sorted(choices), n=1, cutoff=0.6)
    return f" (did you mean '{close[0]}'?)" if close else ""


class ProbegenError(Exception):
    """Base of every error probegen raises on purpose.

    ``exit_code`` is what the CLI returns for it (see :class:`ExitCode` below).
    """

    exit_code = 1


class SpecError(ProbegenError):
    """The feature spec or machine profile is invalid (file, key path, value)."""

    exit_code = 2


class ModelError(ProbegenError):
    """The part model (STEP) cannot be used: missing, empty, truncated, not STEP."""

    exit_code = 3


class ModelWarning(UserWarning):
    """Something in the part model probegen ignores and the user should know of (a
    colour or style entity that does not parse): the model loads without it.  The
    command line prints it as one line, ``probegen: warning: <message>``."""


class PlanningError(ProbegenError):
    """No safe measuring plan exists for the request."""

    exit_code = 4


class CollisionError(PlanningError):
    """A planned move would bring the stylus into the part."""

    exit_code = 4


class UnsupportedError(ProbegenError):
    """An IR node (or a statement of an input program) a dialect cannot express."""

    exit_code = 5


class ParseError(ProbegenError):
    """Text that does not follow its grammar; carries the diagnostics (line, column, caret)."""

    exit_code = 6

    def __init__(self, message: str, diagnostics: tuple[Diagnostic, ...] = ()) -> None:
        super().__init__(message)
        self.diagnostics = diagnostics


class ProgramParseError(ParseError):
    """A measuring program (DMIS, Macro B) that does not parse."""


class ResultsParseError(ParseError):
    """Returned data (DPRNT log, DMIS output) that does not parse."""


class IncompleteRunError(ResultsParseError):
    """Returned data of a run cut short (no end marker, a no-contact touch) that lacks
    what the evaluation needs: NOT EVALUATED, exit code 11 (``cli_exit.INCOMPLETE``)."""

    exit_code = 11


def strict_error(source: str, what: str, diagnostics: tuple[Diagnostic, ...],
                 shown: int = 10) -> ResultsParseError:
    """The error a reader raises in strict mode: the first ``shown`` diagnostics in full."""
    count = len(diagnostics)
    lines = [f"{source}: {count} problem{'s' if count > 1 else ''} in the {what}"]
    lines += [str(d) for d in diagnostics[:shown]]
    if count > shown:
        lines.append(f"... and {count - shown} more")
    return ResultsParseError("\n".join(lines), diagnostics)


class CalibrationError(ProbegenError):
    """Calibration data that cannot determine what was asked."""

    exit_code = 7


class ExitCode(IntEnum):
    """Process exit codes (the list with their meaning: the README).

    The verdict of ``ingest`` and ``post-ingest``: ``OK`` (0) every toleranced
    characteristic evaluated and conforming (or nothing toleranced); ``NOT_OK`` (8) at least
    one out of tolerance; ``INCOMPLETE`` (11) nothing out of tolerance, but a feature or a
    toleranced characteristic could not be evaluated (missing or no-contact touches, a
    failed fit) or the run did not finish (no ``PGEND``).  When both happen ``NOT_OK`` wins:
    a characteristic out of tolerance, measured completely, is a definite finding that the
    missing measurements cannot reverse (the part is rejected either way); the output still
    lists every NOT EVALUATED feature.  Input errors keep their own codes (1-7, 64).
    """

    OK = 0
    ERROR = 1
    SPEC = 2
    MODEL = 3
    PLANNING = 4
    UNSUPPORTED = 5
    PARSE = 6
    CALIBRATION = 7
    NOT_OK = 8
    CAPTURE_INCOMPLETE = 9
    SIM_ALARM = 10
    INCOMPLETE = 11
    USAGE = 64
    INTERNAL = 70
    OUTPUT = 73
    INTERRUPTED = 130
