"""Run Fanuc Macro B program text (custom macro B, 0i/30i) as a controller would.

This is the control half of the virtual machine: it reads the program *text* (never
the IR), keeps Macro B variables, modal state and coordinates, and drives a
:class:`Machine` (the kinematics and the part, modelled elsewhere) through three calls
in machine coordinates.  ``run_program`` returns what the control printed (DPRNT),
how it stopped and its variables::

    result = run_program(text, FreeMachine())
    result.stopped      # "M30", "M02", "M99", "end", "message", "M00" or "alarm"
    result.alarm        # Alarm(number, message, line, source) or None
    result.output       # POPEN "%" line, DPRNT lines, PCLOS "%" line

Conventions (details in the module docstrings of ``probegen.sim.macrob.*``):

* Output: POPEN and PCLOS each send a line ``%``; every DPRNT line ends with LF
  (``Settings.dprnt_eol``; real controls send LF or CR LF per I/O parameter).  DPRNT
  before POPEN raises alarm 9001.  Number format: :mod:`probegen.sim.macrob.dprnt`.
* Variables: :mod:`probegen.sim.macrob.variables` (tool offsets memory C: H geometry
  ``#11001``-, H wear ``#10001``-, also ``#2201``-/``#2001``- for 1-200; work offsets
  ``#5201``- external, ``#5221``- G54 ... 20 per set; G54.1 ``#7001``-/``#14001``-).
* Coordinates and G codes: :mod:`probegen.sim.macrob.motion`.  ``#5061``-``#5063``
  hold the skip position in work coordinates, or the G31 end point when the skip did
  not fire; ``#5021``- machine, ``#5041``- work, ``#5001``- end point, ``#5081``- tool
  length.
* Control flow, calls, M codes, #3000/#3006: :mod:`probegen.sim.macrob.execute`.
* Alarms: :mod:`probegen.sim.macrob.base`.  A program that does not parse raises
  :class:`~probegen.errors.ProgramParseError` before anything runs (a subprogram file
  when it is first called).  ``max_blocks`` stops an endless loop with alarm 9000.
"""

from __future__ import annotations

import gc
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

from probegen.results.gcpause import collector_paused
from probegen.sim.alarms import SimAlarm
from probegen.sim.macrob.base import Machine, Point, RotaryMachine, Settings
from probegen.sim.macrob.execute import Interpreter
from probegen.sim.macrob.parse import parse_program

__all__ = [
    "Alarm",
    "FreeMachine",
    "Machine",
    "Point",
    "RotaryMachine",
    "RunResult",
    "Settings",
    "SimAlarm",
    "run_program",
]


class FreeMachine:
    """A machine with no part: nothing is ever touched, every move succeeds.

    ``moves`` records ``(kind, start, end)`` of each call (kind ``"rapid"``, ``"feed"``
    or ``"skip"``) when ``record`` is True; ``turns`` records ``(start, end)`` angles of
    each rotary move and each G53.1 table turn.
    """

    def __init__(self, *, record: bool = False) -> None:
        self.record = record
        self.moves: list[tuple[str, Point, Point]] = []
        self.turns: list[tuple[dict[str, float], dict[str, float]]] = []

    def rapid(self, start: Point, end: Point) -> None:
        if self.record:
            self.moves.append(("rapid", start, end))

    def feed(self, start: Point, end: Point, feed_mm_min: float) -> None:
        if self.record:
            self.moves.append(("feed", start, end))

    def skip(self, start: Point, end: Point, feed_mm_min: float) -> Point | None:
        if self.record:
            self.moves.append(("skip", start, end))
        return None

    def rotate(self, start: dict[str, float], end: dict[str, float], at: Point) -> None:
        if self.record:
            self.turns.append((dict(start), dict(end)))

    def tilt(self, start: dict[str, float], end: dict[str, float], at: Point) -> None:
        if self.record:
            self.turns.append((dict(start), dict(end)))


@dataclass(frozen=True, slots=True)
class Alarm:
    """The alarm a run stopped with.

    Attributes:
        number: the alarm number (3000 + n for ``#3000 = n``).
        message: the alarm text (the comment of a ``#3000`` block).
        line: 1-based line of the block that raised it (0 if unknown).
        source: the file (or ``source`` name) holding that line.
    """

    number: int
    message: str
    line: int
    source: str = ""

    def __str__(self) -> str:
        return f"{self.source}:{self.line}: alarm {self.number} {self.message}"


@dataclass(frozen=True)
class RunResult:
    """What a run of a program did.

    Attributes:
        output: everything POPEN/DPRNT/PCLOS sent, as the control sends it.
        alarm: the alarm the run stopped with, or None.
        stopped: why the run ended: ``"M30"``, ``"M02"``, ``"M99"`` (end of the main
            program by M99), ``"end"`` (ran past the last block), ``"message"``
            (``#3006``), ``"M00"`` (only with ``Settings.stop_at_m00``) or ``"alarm"``.
        variables: every variable holding a value at the end: level-0 locals,
            commons, extra variables, and the work and tool offsets that are not zero
            (``#5201``-``#5340``; G54.1 Pn as ``#14001``-; tools as ``#10001``-).
        blocks_executed: blocks run (deleted blocks skipped by block delete excluded).
        message: the comment of the ``#3006`` block when ``stopped == "message"``.
        m_codes: the M codes executed, in order.
        tool: the tool in the spindle at the end (the last ``T`` before an M6).
        rotation: the G68 rotation in force at the end (centre X, Y in work
            coordinates, program unit; degrees), or None.
        skip_feeds: the feed every G31 ran at, in order, mm/min (the programmed feed
            times ``Settings.feed_override`` unless ``#3004`` held it).
    """

    output: str
    alarm: Alarm | None
    stopped: str
    variables: dict[int, float]
    blocks_executed: int
    message: str = ""
    m_codes: tuple[int, ...] = field(default=())
    tool: int = 0
    rotation: tuple[float, float, float] | None = None
    skip_feeds: tuple[float, ...] = ()


def run_program(
    text: str,
    machine: Machine,
    *,
    source: str = "<program>",
    program_dir: Path | None = None,
    variables: dict[int, float] | None = None,
    block_delete: bool = False,
    max_blocks: int = 5_000_000,
    settings: Settings | None = None,
) -> RunResult:
    """Parse and run a Macro B program against ``machine``.

    Args:
        text: the program text; its first program is the main program.
        machine: the machine and part (see :class:`Machine`).
        source: the file name used in errors and alarms.
        program_dir: where subprogram files ``O<n>[.NC|.nc]`` are looked for.
        variables: values of variables before the run (commons, offsets, locals of
            the main program, or variables a builder's control has, such as #3700).
        block_delete: skip blocks starting with ``/``.
        max_blocks: stop with alarm 9000 after this many blocks (endless loops).
        settings: control parameters (DPRNT style, decimal point input, ...).

    Returns:
        The run's output, alarm, end reason and variables.

    Raises:
        ProgramParseError: the text (or a subprogram file called) does not parse.
        ValueError: ``variables`` names a variable the program cannot write (#5001).
    """
    with collector_paused():
        parsed = parse_program(text, source=source)
        interpreter = Interpreter(parsed, machine, settings=settings or Settings(),
                                  program_dir=program_dir, block_delete=block_delete,
                                  max_blocks=max_blocks)
    for number, value in (variables or {}).items():
        interpreter.store.seed(number, value)
    interpreter.motion.refresh()
    with _collector_frozen():
        raised = interpreter.run()
    found = None
    if raised is not None:
        found = Alarm(raised.number, raised.message, raised.line or 0, interpreter.prog.source)
    return RunResult(
        output="".join(interpreter.output),
        alarm=found,
        stopped=interpreter.stopped,
        variables=interpreter.store.snapshot(),
        blocks_executed=interpreter.blocks_executed,
        message=interpreter.message,
        m_codes=tuple(interpreter.m_codes),
        tool=interpreter.motion.tool,
        rotation=interpreter.motion.rotation,
        skip_feeds=tuple(interpreter.motion.skip_feeds),
    )


@contextmanager
def _collector_frozen() -> Iterator[None]:
    """Keep the collector off the objects alive when a run starts, for the run.

    A run makes only short-lived objects, but each full collection would traverse
    the whole parsed and compiled program again (over a second for 200,000 lines).
    ``gc.freeze`` sets the objects alive now aside until ``gc.unfreeze`` puts them
    back; nothing is lost, they are only not scanned meanwhile.
    """
    gc.freeze()
    try:
        yield
    finally:
        gc.unfreeze()
