"""Run rs274ngc program text (LinuxCNC 2.9) as the control would, line by line.

The LinuxCNC half of the virtual machine, beside the Macro B control (``sim/macrob``):
it reads the program *text*, keeps the parameters, modal state and coordinates
(:mod:`probegen.sim.ngc.motion`, the Macro B control's motion with LinuxCNC's G codes)
and drives the same :class:`~probegen.sim.macrob.base.Machine`.  ``run_ngc`` returns
what the program's ``(LOG,...)`` comments wrote, how it stopped and its parameters.

A line runs in LinuxCNC's order: its values are read (every expression, with the
parameters as they were before the line), its parameter settings made (the last of a
parameter wins), its comment acted on (``MSG`` ``DEBUG`` ``PRINT`` messages, ``LOGOPEN``
``LOGAPPEND`` ``LOG`` ``LOGCLOSE``, ``ABORT``), F S T, the M codes (M6 tool change, M3-M5,
M7-M9, M19, M48/M49 feed override enabled/held at 100 %, M70-M73 modal state saved and
restored), the G codes and the motion (:mod:`~probegen.sim.ngc.motion`), then the
stops ``M0 M1`` (recorded, the run goes on) and ``M2 M30`` (the end).  Other M codes are
the interpreter's error ``Unknown m code used``, except user M100-M199 and Fanuc-style
``M98``/``M99`` (alarm 9010, not modelled).

O-words (:mod:`~probegen.sim.ngc.flow`): a ``sub`` body is skipped where it stands;
``o<name> call [a] [b]`` finds the body in the file, else in ``<name>.ngc`` (``<n>.ngc``
for ``o<n>``; lower case) in ``program_dir``, with ``a``, ``b`` in ``#1``, ``#2``, the
other locals 0; ``return``/``endsub`` give back the caller's ``#1-#30`` and local names
and set ``#<_value>``, ``#<_value_returned>``; calls nest 10 deep.  ``continue`` in a
``do`` loop goes to its closing ``while`` (the documented meaning; ``rs274`` 2.9.0~pre1
leaves the loop instead).

Logs: ``LOGOPEN`` starts the named file empty, ``LOGAPPEND`` adds to it (a file the
run did not write starts empty: the virtual machine has no earlier runs), ``LOG``
writes its text and a line feed to the open file (nothing when none is open); the run's
``output`` is every file's text, in the order they were first opened.

Errors stop the run as an alarm with the line and the column: the interpreter's own
errors (alarm 9300, LinuxCNC's message), ``(ABORT,text)`` (9301, the text), a ``G38.2``
without contact (9302), the machine's alarms (9100 collision, 9010 not modelled);
``max_lines`` lines run is alarm 9000 (an endless loop).  A file that does not parse,
or whose o-words do not pair up, raises :class:`~probegen.errors.ProgramParseError`
before it runs (a called file when it is called).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from probegen.sim.alarms import SimAlarm
from probegen.sim.macrob.base import BLOCK_LIMIT, UNSUPPORTED, Machine, Settings, alarm
from probegen.sim.macrob.variables import Store
from probegen.sim.ngc import ast
from probegen.sim.ngc.expr import Getter, compile_expr, error, expand, index_of
from probegen.sim.ngc.flow import Flow, build_flow
from probegen.sim.ngc.motion import NgcMotion
from probegen.sim.ngc.params import Parameters
from probegen.sim.ngc.parse import parse_program, read_program

ABORT_ALARM = 9301
MAX_CALLS = 10
VERSION = (2.9, 0.0)
"""``#<_vmajor>``, ``#<_vminor>``: the LinuxCNC this control is."""
STOPS = frozenset({0, 1, 2, 30, 60})
QUIET_M = frozenset({3, 4, 5, 7, 8, 9, 19, 50, 51, 52, 53, 62, 63, 64, 65, 67, 68})
"""M codes that change nothing the virtual machine models (spindle, coolant, outputs)."""


@dataclass
class Loaded:
    """A parsed file and its o-word structure."""

    file: ast.ProgramFile
    flow: Flow


@dataclass
class Frame:
    """A call in progress: where it returns to and the modal state M73 saved."""

    loaded: Loaded
    return_pc: int
    saved: tuple[dict[int, float], float, float, int] | None = None
    counts: dict[int, int] = field(default_factory=dict)


@dataclass(frozen=True)
class NgcAlarm:
    """The alarm a run stopped with (``line``, ``column`` 1-based; 0 if unknown)."""

    number: int
    message: str
    line: int
    column: int
    source: str

    def __str__(self) -> str:
        where = f"line {self.line}" + (f", column {self.column}" if self.column else "")
        return f"{self.number} {self.message} ({where})"


@dataclass(frozen=True)
class NgcResult:
    """What a run did.

    Attributes:
        output: the text of the log files the program wrote, as the files hold it.
        alarm: the alarm it stopped with, or None.
        stopped: ``"M2"``, ``"M30"``, ``"end"`` (past the closing ``%``) or ``"alarm"``.
        variables: the numbered parameters written and the offsets that are not 0.
        messages: ``MSG``, ``DEBUG`` and ``PRINT`` texts, in order.
        logs: each log file's name and text.
        lines: lines run.
        m_codes: the M codes run, in order.
    """

    output: str
    alarm: NgcAlarm | None
    stopped: str
    variables: dict[int, float]
    messages: tuple[str, ...]
    logs: dict[str, str]
    lines: int
    m_codes: tuple[int, ...]


class Interpreter:
    """Runs one rs274ngc program against a machine."""

    def __init__(self, main: ast.ProgramFile, machine: Machine, *, settings: Settings,
                 program_dir: Path | None, block_delete: bool, max_lines: int) -> None:
        self.store = Store(self)  # type: ignore[arg-type]  # offsets only
        self.motion = NgcMotion(machine, self.store, settings)
        self.params = Parameters(self.motion, self.predefined)
        self.modal_names = frozenset(self.motion.predefined())
        self.program_dir = program_dir
        self.block_delete = block_delete
        self.max_lines = max_lines
        self.main = Loaded(main, build_flow(main))
        self.files: dict[str, Loaded] = {}
        self.frames: list[Frame] = []
        self.current = self.main
        self.counts: dict[int, int] = {}
        self.pc = 0
        self.line: ast.Line | None = None
        self.column = 0
        self.stopped = ""
        self.value = (0.0, 0.0)
        self.logs: dict[str, list[str]] = {}
        self.log: str | None = None
        self.messages: list[str] = []
        self.m_codes: list[int] = []
        self.saved: tuple[dict[int, float], float, float, int] | None = None
        self.compiled: dict[int, Callable[[], None]] = {}
        self.executed = 0

    # -- named parameters the interpreter knows ---------------------------------------------
    def predefined(self, name: str) -> float | None:
        own = {"_value": self.value[0], "_value_returned": self.value[1],
               "_call_level": float(len(self.frames)), "_vmajor": VERSION[0],
               "_vminor": VERSION[1], "_task": 1.0,
               "_line": float(self.line.number if self.line else 0)}
        if name in own:
            return own[name]
        return self.motion.predefined().get(name) if name in self.modal_names else None

    # -- the run loop -------------------------------------------------------------------
    def run(self) -> SimAlarm | None:
        try:
            while not self.stopped:
                lines = self.current.file.lines
                if self.pc >= len(lines):
                    self.end_of_file()
                    continue
                if self.executed == self.max_lines:
                    raise alarm(BLOCK_LIMIT, f"max_lines={self.max_lines}")
                self.executed += 1
                k = self.pc
                self.pc = k + 1
                self.line = lines[k]
                self.column = 0
                if self.line.delete and self.block_delete:
                    continue
                if self.line.oword is not None:
                    self.column = self.line.oword.column
                    self.oword(k, self.line.oword)
                else:
                    self.op(self.line)()
        except SimAlarm as exc:
            self.stopped = "alarm"
            return exc
        return None

    def end_of_file(self) -> None:
        if self.current.file.percent or self.frames:
            self.stopped = "end"
            return
        raise error("File ended with no percent sign or program end")

    # -- o-words ------------------------------------------------------------------------
    def cond(self, o: ast.OWord) -> float:
        return self.expr(o.args[0])()

    def expr(self, e: ast.Expr) -> Getter:
        return compile_expr(e, self.params)

    def oword(self, k: int, o: ast.OWord) -> None:
        flow, word = self.current.flow, o.keyword
        if word == "sub":
            self.pc = flow.end[k] + 1
        elif word in ("endsub", "return"):
            value = self.cond(o) if o.args else None
            self.return_from(value)
        elif word == "call":
            self.call(o)
        elif word == "if":
            self.branch(flow.branches[k], o)
        elif word in ("elseif", "else"):
            self.pc = flow.end[k] + 1
        elif word == "while":
            self.loop_test(k, o, flow)
        elif word in ("endwhile",):
            self.pc = flow.start[k]
        elif word == "repeat":
            count = round(self.cond(o))
            if count > 0:
                self.counts[k] = count - 1
            else:
                self.pc = flow.end[k] + 1
        elif word == "endrepeat":
            self.next_repeat(flow.start[k], k)
        elif word == "break":
            start = flow.loop[k]
            self.counts.pop(start, None)
            self.pc = flow.end[start] + 1
        elif word == "continue":
            start = flow.loop[k]
            first = self.current.file.lines[start].oword
            self.pc = start if first is not None and first.keyword == "while" else (
                flow.end[start])
        # do, endif: nothing to do

    def branch(self, branches: list[int], o: ast.OWord) -> None:
        if self.cond(o):
            return
        lines = self.current.file.lines
        for b in branches:
            other = lines[b].oword
            assert other is not None
            if other.keyword != "elseif" or self.cond(other):
                self.pc = b + 1
                return

    def loop_test(self, k: int, o: ast.OWord, flow: Flow) -> None:
        true = bool(self.cond(o))
        if k in flow.closing:
            if true:
                self.pc = flow.start[k] + 1
        elif not true:
            self.pc = flow.end[k] + 1

    def next_repeat(self, start: int, end: int) -> None:
        left = self.counts.get(start, 0)
        if left > 0:
            self.counts[start] = left - 1
            self.pc = start + 1
        else:
            self.counts.pop(start, None)

    def call(self, o: ast.OWord) -> None:
        label = o.label if isinstance(o.label, str) else str(index_of(self.expr(o.label)()))
        args = [self.expr(a)() for a in o.args]
        loaded, start = self.find(label)
        if len(self.frames) >= MAX_CALLS:
            raise error(f"Too many nested subroutine calls (o{label}: more than {MAX_CALLS})")
        self.frames.append(Frame(self.current, self.pc, None, self.counts))
        self.params.push(args)
        self.value = (0.0, 0.0)
        self.current, self.pc, self.counts = loaded, start + 1, {}

    def return_from(self, value: float | None) -> None:
        if not self.frames:
            raise error("Return or endsub outside a subroutine call")
        frame = self.frames.pop()
        self.params.pop()
        if frame.saved is not None:
            self.restore(frame.saved)
        self.current, self.pc, self.counts = frame.loaded, frame.return_pc, frame.counts
        self.value = (value or 0.0, float(value is not None))

    def find(self, label: str) -> tuple[Loaded, int]:
        """The file and line of subroutine ``label``: this file, the main program, a
        file loaded before, else ``<name>.ngc`` in the program directory."""
        for loaded in (self.current, self.main, *self.files.values()):
            if label in loaded.flow.subs:
                return loaded, loaded.flow.subs[label]
        name = label.strip("<>").lower() + ".ngc"
        path = self.program_dir / name if self.program_dir is not None else None
        if path is None or not path.is_file():
            raise error(f"Unable to open file for subroutine o{label} (looked for {name} "
                        f"in {self.program_dir or 'no folder'})")
        parsed = read_program(path)
        loaded = self.files[name] = Loaded(parsed, build_flow(parsed))
        if label not in loaded.flow.subs:
            raise error(f"File {path} does not define subroutine o{label}")
        return loaded, loaded.flow.subs[label]

    # -- a line of words ------------------------------------------------------------------
    def op(self, line: ast.Line) -> Callable[[], None]:
        found = self.compiled.get(id(line))
        if found is None:
            found = self.compiled[id(line)] = self.compile_line(line)
        return found

    def compile_line(self, line: ast.Line) -> Callable[[], None]:
        words = [(w.letter, self.expr(w.value), w.column) for w in line.words]
        assigns = [(a.target, self.target(a.target), self.expr(a.value), a.column)
                   for a in line.assigns]

        def run() -> None:
            values: list[tuple[str, float]] = []
            for letter, get, column in words:
                self.column = column
                values.append((letter, get()))
            settings: list[tuple[ast.Param | ast.Named, float, float, int]] = []
            for target, number, get, column in assigns:
                self.column = column
                settings.append((target, number(), get(), column))
            for target, index, value, column in settings:
                self.column = column
                if isinstance(target, ast.Named):
                    self.params.write_named(target.name, value)
                else:
                    self.params.write(int(index), value)
            if line.comment is not None and line.comment.kind:
                self.column = line.comment.column
                self.comment(line.comment)
            if values:
                self.column = line.words[0].column
                self.execute(values)

        return run

    def target(self, target: ast.Param | ast.Named) -> Callable[[], float]:
        """The parameter number a setting writes (0 for a named parameter)."""
        if isinstance(target, ast.Named):
            return lambda: 0.0
        index = self.expr(target.index)
        return lambda: float(index_of(index()))

    def execute(self, values: list[tuple[str, float]]) -> None:
        gs = [v for letter, v in values if letter == "G"]
        ms = [round(v) for letter, v in values if letter == "M"]
        addr = {letter: v for letter, v in values if letter not in "GM"}
        motion = self.motion
        if "F" in addr:
            motion.feed = addr["F"]
        if "S" in addr:
            motion.spindle = addr["S"]
        if "T" in addr:
            motion.next_tool = round(addr["T"])
        for code in ms:
            if code not in STOPS:
                self.m_code(code, addr)
        motion.block(gs, addr)
        for code in ms:
            if code in STOPS:
                self.m_codes.append(code)
                if code in (2, 30):
                    self.stopped = f"M{code}"

    def m_code(self, code: int, addr: dict[str, float]) -> None:
        self.m_codes.append(code)
        if code == 6:
            self.motion.change_tool()
        elif code == 61:
            self.motion.tool = round(addr.get("Q", 0.0))
        elif code in (48, 49):
            self.motion.override_locked = code == 49
        elif code == 66:
            self.params.write(5399, 0.0)
        elif code in (70, 73):
            state = (dict(self.motion.modal), self.motion.feed, self.motion.spindle,
                     self.motion.h)
            if code == 70:
                self.saved = state
            elif self.frames:
                self.frames[-1].saved = state
        elif code == 71:
            self.saved = None
        elif code == 72:
            if self.saved is None:
                raise error("Cannot restore state: no M70 before M72")
            self.restore(self.saved)
        elif code in (98, 99) or 100 <= code <= 199:
            raise alarm(UNSUPPORTED, f"M{code}")
        elif code not in QUIET_M:
            raise error(f"Unknown m code used (M{code})")

    def restore(self, state: tuple[dict[int, float], float, float, int]) -> None:
        modal, feed, spindle, h = state
        self.motion.modal, self.motion.feed, self.motion.spindle, self.motion.h = (
            dict(modal), feed, spindle, h)
        self.motion.apply_offsets()

    # -- comments -------------------------------------------------------------------------
    def comment(self, c: ast.Comment) -> None:
        kind = c.kind
        if kind == "MSG":
            self.messages.append(c.text)
        elif kind == "PRINT" or (kind == "DEBUG" and self.params.read(5599)):
            self.messages.append(expand(c.text, self.params))
        elif kind in ("LOGOPEN", "LOGAPPEND"):
            self.log = c.text
            if kind == "LOGOPEN" or c.text not in self.logs:
                self.logs[c.text] = []
        elif kind == "LOG":
            if self.log is not None:
                self.logs[self.log].append(expand(c.text, self.params) + "\n")
        elif kind == "LOGCLOSE":
            self.log = None
        elif kind == "ABORT":
            raise SimAlarm(ABORT_ALARM, expand(c.text, self.params))
        # PROBEOPEN / PROBECLOSE: the probe log file is not modelled


def run_ngc(text: str, machine: Machine, *, source: str = "<program>",
            program_dir: Path | None = None, parameters: dict[int, float] | None = None,
            settings: Settings | None = None, block_delete: bool = False,
            max_lines: int = 5_000_000) -> NgcResult:
    """Parse and run rs274ngc program text against ``machine``.

    Args:
        text: the program.
        machine: the machine and part (:class:`~probegen.sim.macrob.base.Machine`).
        source: the file name for messages.
        program_dir: where ``o<name> call`` looks for ``<name>.ngc``.
        parameters: numbered parameters before the run, as a ``.var`` file gives them
            (``#5221``- the G54 offset, ``#5220`` the coordinate system, ``#5210`` ...).
        settings: the machine's start position and feed override (``Settings.home``,
            ``Settings.feed_override``).
        block_delete: skip lines starting with ``/``.
        max_lines: stop with alarm 9000 after this many lines (an endless loop).

    Raises:
        ProgramParseError: the program (or a called file) does not parse.
    """
    interp = Interpreter(parse_program(text, source=source), machine,
                         settings=settings or Settings(), program_dir=program_dir,
                         block_delete=block_delete, max_lines=max_lines)
    for number, value in (parameters or {}).items():
        interp.params.write(number, value)
    interp.motion.refresh()
    raised = interp.run()
    found = None
    if raised is not None:
        line = interp.line.number if interp.line else 0
        found = NgcAlarm(raised.number, raised.message, line, interp.column,
                         interp.current.file.source)
    logs = {name: "".join(lines) for name, lines in interp.logs.items()}
    return NgcResult(
        output="".join(logs.values()), alarm=found, stopped=interp.stopped,
        variables=interp.params.snapshot(), messages=tuple(interp.messages), logs=logs,
        lines=interp.executed, m_codes=tuple(interp.m_codes))
