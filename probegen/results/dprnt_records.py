"""The records of a DPRNT log and the assembly of a log from them.

Owns the public record types (:class:`Touch`, :class:`Centre`, :class:`Result`,
:class:`ProgramError`, :class:`DprntLog`), the field limits both readers share, the
internal header/end records, and ``_Builder``, which collects the records of one log
line by line, numbers the runs (``PGSTART`` ... ``PGEND``) and reports records out of
place.  Which line holds which record is decided by :mod:`probegen.results.dprnt_grammar`
(lark) and :mod:`probegen.results.dprnt_fast` (regular expressions); the public entry
points are in :mod:`probegen.results.dprnt`.
"""

from __future__ import annotations

import dataclasses
import re
from dataclasses import dataclass
from typing import Literal

from probegen.errors import Diagnostic
from probegen.ir.identity import IDENTITY_DIGITS

FORMAT_VERSION = 2
"""The newest log format version this reader understands (the ``V2`` of ``PGSTART``);
it reads every version in ``FORMAT_VERSIONS``."""
FORMAT_VERSIONS = (1, 2)
"""V1: touches name their feature by id; V2 adds ``FEAT <id> <n>``, after which a touch
may name its feature by the number ``n`` (``docs/dprnt-format.md``)."""
FEATURE_VERSION = 2
"""The first version with ``FEAT`` records."""

MAX_FEATURE_ID = 16
"""Longest feature id the Fanuc dialect prints."""

MAX_INDEX_DIGITS = 6
"""Touch and point indices run from 1 to 999999."""

MAX_PROGRAM_DIGITS = 8
"""Program numbers run from O1 to O99999999 (8 digits on recent controls)."""

_PICTURES = {c: 0x2400 + c for c in range(32) if c != 9} | {127: 0x2421}
"""Control characters shown as their Unicode control pictures, one column each."""

_SURROGATE = re.compile("[\ud800-\udfff]")


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


@dataclass(frozen=True, slots=True)
class CalibrationMark:
    """A ``PGCAL`` record: the fingerprint of the probe calibration the program was
    compiled with (``compensate.ProbeCalibration.fingerprint``).

    Attributes:
        fingerprint: e.g. ``C1A2B3C4D``.
        line: 1-based line number in the log.
        run: the program run it belongs to (see :attr:`Touch.run`).
    """

    fingerprint: str
    line: int
    run: int = 0


MAX_SERIAL = 32
"""Longest serial number a ``PGSERIAL`` line may print."""


@dataclass(frozen=True, slots=True)
class SerialMark:
    """A ``PGSERIAL`` record: the part's serial number, printed by a line the shop adds
    to the program (``docs/dprnt-format.md``).

    Attributes:
        serial: as printed, upper case; a number's trailing point dropped (``4711.`` is
            ``4711``, as DPRNT prints a variable with no fraction digits on some controls).
        line: 1-based line number in the log.
        run: the program run it belongs to (see :attr:`Touch.run`).
    """

    serial: str
    line: int
    run: int = 0


@dataclass(frozen=True, slots=True)
class FeatureBinding:
    """A ``FEAT`` record (format V2): feature number ``number`` stands for feature
    ``feature`` in the ``PT``/``LOC`` records that follow (in this run and the later ones).

    Attributes:
        feature: feature id, upper case.
        number: 1 to 999999.
        line: 1-based line number in the log.
        run: the program run it belongs to (see :attr:`Touch.run`).
    """

    feature: str
    number: int
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
class Run:
    """One run of the program in the log: a ``PGSTART`` and what follows it.

    Attributes:
        number: 0, 1, ... in log order (the ``run`` of its records).
        start: line of its ``PGSTART``; 0 for records before any ``PGSTART``.
        end: line of its ``PGEND``; 0 when the run was cut short.
        program: the program number its ``PGSTART`` printed (None without one).
        identity: the identity its ``PGSTART`` printed (``H`` and 8 hex digits), None
            when it printed none (a program from before identities, or no ``PGSTART``).
    """

    number: int
    start: int
    end: int
    program: int | None
    identity: str | None

    @property
    def complete(self) -> bool:
        """Whether the run ended with ``PGEND``."""
        return self.end > 0


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
        runs: one per run, in log order (see :class:`Run`).
        calibrations: ``PGCAL`` records in log order.
        serials: ``PGSERIAL`` records in log order.
        features: ``FEAT`` records in log order (format V2); the touches that named a
            feature by number already carry its id.
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
    runs: tuple[Run, ...] = ()
    calibrations: tuple[CalibrationMark, ...] = ()
    serials: tuple[SerialMark, ...] = ()
    features: tuple[FeatureBinding, ...] = ()

    @property
    def serial(self) -> str | None:
        """The serial number the log printed (``PGSERIAL``): the last one read in its
        runs (after :func:`~probegen.results.logcheck.select_runs`, the runs read: a
        resumed run whose serial was printed before the cut counts), or None."""
        numbers = {r.number for r in self.runs}
        marks = [s.serial for s in self.serials if s.run in numbers or not numbers]
        return marks[-1] if marks else None

    def latest_touches(self) -> tuple[Touch, ...]:
        """Return one touch per (kind, feature, index), the last one read, in line order.

        After a restart the resumed run re-measures some points; its touches replace
        those of the interrupted run.
        """
        latest = {(t.kind, t.feature, t.index): t for t in self.touches}
        return tuple(sorted(latest.values(), key=lambda t: t.line))

    def no_contact(self) -> dict[tuple[str, int], int]:
        """The points whose touch reported no contact, by (feature, index), with the line
        of their ``ERR NOTOUCH``: those not measured again (``PT``) after it."""
        lines = {(t.feature, t.index): t.line for t in self.latest_touches() if t.kind == "PT"}
        return {(e.feature, e.index): e.line for e in self.errors
                if e.code == "NOTOUCH" and e.line > lines.get((e.feature, e.index), 0)}


@dataclass(frozen=True, slots=True)
class _Header:
    program: int
    version: int
    version_column: int
    identity: str | None = None
    identity_column: int = 0


@dataclass(frozen=True, slots=True)
class _End:
    program: int


@dataclass(frozen=True, slots=True)
class _Bind:
    """A ``FEAT`` line as parsed; the builder checks it and keeps a FeatureBinding."""

    feature: str
    number: int
    column: int


@dataclass(frozen=True, slots=True)
class _Numbered:
    """A ``PT``/``LOC``/``ERR`` line naming its feature by number (``record`` has no
    feature yet); the builder resolves it."""

    number: int
    column: int
    record: Touch | ProgramError


_Record = (Touch | Centre | ProgramError | Result | CalibrationMark | SerialMark | _Header
           | _End | _Bind | _Numbered)


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
        self.calibrations: list[CalibrationMark] = []
        self.serials: list[SerialMark] = []
        self.features: list[FeatureBinding] = []
        self.bound: dict[int, FeatureBinding] = {}
        """Feature number -> its binding: the id a numbered touch stands for."""
        self.diagnostics: list[Diagnostic] = []
        self.starts: dict[int, _Header] = {}
        self.start_lines: dict[int, int] = {}
        self.ends: dict[int, int] = {}

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
        if isinstance(rec, _Bind):
            self._bind(rec)
            return
        if isinstance(rec, _Numbered):
            binding = self.bound.get(rec.number)
            if binding is None:
                self.diagnose(f"expected a feature number bound by an earlier FEAT record, "
                              f"found {rec.number} (no FEAT <id> {rec.number} before)",
                              rec.column)
                return
            rec = dataclasses.replace(rec.record, feature=binding.feature)
        rec = dataclasses.replace(rec, line=self.lineno, run=self.run)
        if isinstance(rec, Touch):
            self.touches.append(rec)
        elif isinstance(rec, Centre):
            self.centres.append(rec)
        elif isinstance(rec, Result):
            self.results.append(rec)
        elif isinstance(rec, CalibrationMark):
            self.calibrations.append(rec)
        elif isinstance(rec, SerialMark):
            self.serials.append(rec)
        else:
            self.errors.append(rec)

    def _bind(self, rec: _Bind) -> None:
        """Bind a feature number to its id (again after a restart: the first binding
        stays); a number bound to another id is reported and rebound (the later records
        mean the later binding)."""
        head = self.starts.get(self.run)
        if head is not None and head.version < FEATURE_VERSION:
            self.diagnose(f"expected format version V{FEATURE_VERSION} or later for a FEAT "
                          f"record, found V{head.version} (line {self.start_lines[self.run]})")
        earlier = self.bound.get(rec.number)
        if earlier is not None and earlier.feature != rec.feature:
            self.diagnose(f"expected feature number {rec.number} to stand for "
                          f"{earlier.feature} (FEAT on line {earlier.line}), found "
                          f"{rec.feature}", rec.column)
        binding = FeatureBinding(rec.feature, rec.number, self.lineno, self.run)
        if earlier is None or earlier.feature != rec.feature:
            self.bound[rec.number] = binding
        self.features.append(binding)

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
        if rec.identity is not None and len(rec.identity) != 1 + IDENTITY_DIGITS:
            # the run still starts: the wrong identity is kept and refused by ingest
            self.diagnose(f"expected a program identity of H and {IDENTITY_DIGITS} hex "
                          f"digits, found '{rec.identity}'", rec.identity_column)
        if rec.version not in FORMAT_VERSIONS:
            message = (f"expected format version V{FORMAT_VERSIONS[0]} to "
                       f"V{FORMAT_VERSIONS[-1]}, found V{rec.version}")
            self.diagnose(message, rec.version_column)
        if self.started or self.headless_reported:
            self.run += 1
        self.started, self.end_line, self.run_program = True, 0, rec.program
        self.starts[self.run], self.start_lines[self.run] = rec, self.lineno

    def _end(self, rec: _End) -> None:
        if self.run_program is not None and rec.program != self.run_program:
            self.diagnose(
                f"expected PGEND O{self.run_program} (the program started), "
                f"found PGEND O{rec.program}"
            )
        if self.program is None:
            self.program = rec.program
        self.end_line = self.lineno
        self.ends.setdefault(self.run, self.lineno)

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
            runs=tuple(self._run(k) for k in range(self.run + 1)),
            calibrations=tuple(self.calibrations),
            serials=tuple(self.serials),
            features=tuple(self.features),
        )

    def _run(self, k: int) -> Run:
        head = self.starts.get(k)
        return Run(k, self.start_lines.get(k, 0), self.ends.get(k, 0),
                   None if head is None else head.program,
                   None if head is None else head.identity)


def _first_column(clean: str) -> int:
    """Return the 1-based column of the first character that is not a blank or '%'."""
    return len(clean) - len(clean.lstrip(" \t%")) + 1


def _display(clean: str) -> str:
    """Return the line as shown under a diagnostic: printable, one column per character."""
    return _SURROGATE.sub("\ufffd", clean.translate(_PICTURES))
