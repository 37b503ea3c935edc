"""The Macro B interpreter: runs the parsed blocks of a program text block by block.

Each distinct statement is compiled once into a closure (:mod:`probegen.sim.macrob.expr`
for the expressions); the run loop then only calls closures.  Control flow:

* ``GOTO n`` jumps to the block ``Nn`` of the current program (the first one after
  the current block, else the first one from the top); no such block: alarm 78.
* ``WHILE [..] DOm`` / ``ENDm`` pair up by nesting when the program is loaded; a DO
  whose END is missing raises alarm 124 when the loop must be left, an END without a
  DO when it is reached.  A bare ``DOm`` loops until a GOTO leaves it.
* ``M98 Pn Ll`` calls program n (l times) with the caller's locals; ``G65 Pn Ll``
  with a new local level holding the arguments; ``M99`` returns (``M99 Pn`` to the
  caller's block Nn); the end of a subprogram returns as M99 does.  Programs are
  looked up in the same text first, then as files ``O<n>``, ``O<nnnn>`` (with no
  extension, ``.NC`` or ``.nc``) in the program directory.
* ``M30`` / ``M02`` end the run, as does ``M99`` in the main program (a control would
  start the main program again) and the end of the main program (``stopped="end"``).
* ``M00`` / ``M01`` are recorded and the run goes on (as after cycle start) unless
  ``Settings.stop_at_m00``.  ``#3006 = n (TEXT)`` ends the run with ``stopped =
  "message"`` and the comment as message; ``#3000 = n (TEXT)`` raises alarm 3000 + n.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

from probegen.sim.alarms import SimAlarm
from probegen.sim.macrob import ast
from probegen.sim.macrob.base import (
    ARGUMENT_RANGE,
    BLOCK_LIMIT,
    ILLEGAL_ARGUMENT,
    ILLEGAL_SEQUENCE,
    MACRO_ALARM,
    MISSING_END,
    NESTING,
    NOT_OPEN,
    PROGRAM_NOT_FOUND,
    SEQUENCE_NOT_FOUND,
    WRITE_PROTECTED,
    Machine,
    Settings,
    alarm,
)
from probegen.sim.macrob.dprnt import format_value
from probegen.sim.macrob.expr import (
    Getter,
    Value,
    checked,
    compile_cond,
    compile_expr,
    variable_number,
)
from probegen.sim.macrob.motion import Motion, Word
from probegen.sim.macrob.parse import read_program
from probegen.sim.macrob.variables import Store

if TYPE_CHECKING:
    from collections.abc import Callable

ARGUMENTS = {"A": 1, "B": 2, "C": 3, "D": 7, "E": 8, "F": 9, "H": 11, "M": 13, "Q": 17,
             "R": 18, "S": 19, "T": 20, "U": 21, "V": 22, "W": 23, "X": 24, "Y": 25, "Z": 26}
"""G65 argument specification I: address → local variable (I J K are handled apart)."""
IJK = {"I": 0, "J": 1, "K": 2}
STORED = frozenset({3003, 3004, 3901, 3902})
"""System variables that only hold a value here (single block, feed hold, part counts)."""
OVERRIDE_CONTROL, OVERRIDE_LOCKED = 3004, 2
"""``#3004`` and its bit 1: feed override held at 100 % (bit 0 feed hold, bit 2 exact
stop check are only stored)."""
EXTENSIONS = ("", ".NC", ".nc")
MAX_MACRO_ALARM = 4095
"""Largest n of ``#3000 = n`` (30i; the 0i takes up to 200)."""


@dataclass
class Loaded:
    """A program ready to run: its blocks, their compiled operations, jump tables."""

    number: int | None
    source: str
    blocks: tuple[ast.Block, ...]
    ops: list[Callable[[], None] | None]
    labels: dict[int, list[int]] = field(default_factory=dict)
    loop_end: dict[int, int] = field(default_factory=dict)
    loop_start: dict[int, int] = field(default_factory=dict)


@dataclass
class Frame:
    """A call in progress: where to return and how often to repeat."""

    program: Loaded
    return_pc: int
    macro: bool
    repeats: int
    args: dict[int, float]


class Interpreter:
    """Runs one program text against a machine."""

    def __init__(self, file: ast.ProgramFile, machine: Machine, *, settings: Settings,
                 program_dir: Path | None, block_delete: bool, max_blocks: int) -> None:
        self.file = file
        self.settings = settings
        self.program_dir = program_dir
        self.block_delete = block_delete
        self.max_blocks = max_blocks
        self.store = Store(self)
        self.motion = Motion(machine, self.store, settings)
        self.compiled: dict[int, Callable[[], None] | None] = {}
        self.loaded: dict[int, Loaded] = {}
        self.frames: list[Frame] = []
        self.output: list[str] = []
        self.opened = False
        self.stopped = ""
        self.message = ""
        self.m_codes: list[int] = []
        self.last_seq = 0
        self.timers = [0.0, 0.0]
        self.stored: dict[int, Value] = {}
        self.blocks_executed = 0
        first = file.programs[0] if file.programs else ast.Program(None, ())
        self.prog = self.load(first, file.source)
        self.pc = 0
        self.current = 0

    # -- the run loop -------------------------------------------------------------------
    def run(self) -> SimAlarm | None:
        """Run until the program ends or an alarm; return the alarm (line filled in)."""
        try:
            self.loop()
        except SimAlarm as exc:
            self.stopped = "alarm"
            return exc.at_line(self.line)
        return None

    @property
    def line(self) -> int:
        """The source line of the block being executed."""
        blocks = self.prog.blocks
        return blocks[self.current].line if self.current < len(blocks) else 0

    def loop(self) -> None:
        count, limit, skip_deleted = 0, self.max_blocks, self.block_delete
        try:
            while not self.stopped:
                prog, pc = self.prog, self.pc
                if pc >= len(prog.ops):  # an implicit M99 counts as a block
                    if self.frames and count == limit:
                        raise alarm(BLOCK_LIMIT, f"max_blocks={limit}")
                    count += bool(self.frames)
                    self.end_of_program()
                    continue
                self.pc, self.current = pc + 1, pc
                block = prog.blocks[pc]
                if block.delete and skip_deleted:
                    continue
                if count == limit:
                    raise alarm(BLOCK_LIMIT, f"max_blocks={limit}")
                count += 1
                if block.seq is not None:
                    self.last_seq = block.seq
                op = prog.ops[pc]
                if op is not None:
                    op()
        finally:
            self.blocks_executed = count

    def stop(self, reason: str) -> None:
        self.stopped = reason

    def comment(self) -> str:
        """The comment of the block being executed."""
        blocks = self.prog.blocks
        return blocks[self.current].comment if self.current < len(blocks) else ""

    # -- loading and compiling ----------------------------------------------------------
    def load(self, program: ast.Program, source: str) -> Loaded:
        """Compile a program's blocks and build its label and loop tables."""
        ops = [self.compile(block.statement) for block in program.blocks]
        loaded = Loaded(program.number, source, program.blocks, ops)
        pending: dict[int, list[int]] = {}
        for i, block in enumerate(program.blocks):
            if block.seq is not None:
                loaded.labels.setdefault(block.seq, []).append(i)
            statement = block.statement
            if isinstance(statement, ast.While):
                pending.setdefault(statement.loop, []).append(i)
            elif isinstance(statement, ast.End) and pending.get(statement.loop):
                start = pending[statement.loop].pop()
                loaded.loop_end[start], loaded.loop_start[i] = i, start
        return loaded

    def compile(self, statement: ast.Statement | None) -> Callable[[], None] | None:
        """Compile a statement once (the parser shares equal statements)."""
        if statement is None:
            return None
        key = id(statement)
        if key not in self.compiled:
            self.compiled[key] = self.compile_new(statement)
        return self.compiled[key]

    def compile_new(self, statement: ast.Statement) -> Callable[[], None] | None:
        if isinstance(statement, ast.Words):
            return self.compile_words(statement)
        if isinstance(statement, ast.Assign):
            return self.compile_assign(statement)
        if isinstance(statement, ast.IfGoto):
            return self.compile_if_goto(statement)
        if isinstance(statement, ast.IfThen):
            test, then = compile_cond(statement.cond, self.store), self.compile_assign(
                statement.then)
            return lambda: then() if test() else None
        if isinstance(statement, ast.While):
            return self.compile_while(statement)
        if isinstance(statement, ast.End):
            return self.loop_back
        if isinstance(statement, ast.Goto):
            target = compile_expr(statement.target, self.store)
            return lambda: self.goto(target())
        if isinstance(statement, ast.Dprnt):
            return self.compile_dprnt(statement)
        if isinstance(statement, ast.Popen):
            return lambda: self.open_device(True)
        if isinstance(statement, ast.Pclos):
            return lambda: self.open_device(False)
        return None

    def compile_words(self, statement: ast.Words) -> Callable[[], None]:
        words = [(w.letter, compile_expr(w.value, self.store),
                  isinstance(w.value, ast.Num) and not w.value.point) for w in statement.words]

        def op() -> None:
            values: list[Word] = []
            for letter, get, integer in words:
                value = get()
                if value is not None:  # a vacant variable drops its word
                    values.append((letter, checked(value) or 0.0, integer))
            self.execute(values)

        return op

    def compile_assign(self, statement: ast.Assign) -> Callable[[], None]:
        get = compile_expr(statement.value, self.store)
        target = statement.target
        if isinstance(target, ast.Var):
            write = self.store.writer(target.number)
            return lambda: write(checked(get()))
        index, store = compile_expr(target.index, self.store), self.store
        return lambda: store.write(variable_number(index()), checked(get()))

    def compile_if_goto(self, statement: ast.IfGoto) -> Callable[[], None]:
        test, target = compile_cond(statement.cond, self.store), statement.target
        if isinstance(target, ast.Num):
            number = target.value
            return lambda: self.goto(number) if test() else None
        get = compile_expr(target, self.store)
        return lambda: self.goto(get()) if test() else None

    def compile_while(self, statement: ast.While) -> Callable[[], None]:
        if statement.cond is None:
            return lambda: None
        test = compile_cond(statement.cond, self.store)
        return lambda: None if test() else self.leave_loop()

    def compile_dprnt(self, statement: ast.Dprnt) -> Callable[[], None]:
        parts: list[str | tuple[Getter, int, int]] = [
            item.replace("*", " ") if isinstance(item, str)
            else (self.store.reader(item.number), item.digits, item.decimals)
            for item in statement.items
        ]
        blanks = self.settings.dprnt_blanks

        def op() -> None:
            text = "".join(
                p if isinstance(p, str) else format_value(p[0](), p[1], p[2], blanks=blanks)
                for p in parts)
            self.print_line(text)

        return op

    # -- control flow -------------------------------------------------------------------
    def goto(self, value: Value) -> None:
        """Jump to block N<value> of the current program."""
        number = round(checked(value) or 0.0)
        if not 1 <= number <= 99_999_999:
            raise alarm(ILLEGAL_SEQUENCE, f"GOTO {number}")
        found = self.prog.labels.get(number)
        if not found:
            raise alarm(SEQUENCE_NOT_FOUND, f"N{number}")
        self.pc = next((i for i in found if i >= self.pc), found[0])

    def leave_loop(self) -> None:
        """WHILE condition false: continue after the matching END."""
        end = self.prog.loop_end.get(self.current)
        if end is None:
            statement = self.prog.blocks[self.current].statement
            loop = statement.loop if isinstance(statement, ast.While) else 0
            raise alarm(MISSING_END, f"DO{loop} WITHOUT END{loop}")
        self.pc = end + 1

    def loop_back(self) -> None:
        """ENDm: back to the matching WHILE, which tests its condition again."""
        start = self.prog.loop_start.get(self.current)
        if start is None:
            statement = self.prog.blocks[self.current].statement
            loop = statement.loop if isinstance(statement, ast.End) else 0
            raise alarm(MISSING_END, f"END{loop} WITHOUT DO{loop}")
        self.pc = start

    def end_of_program(self) -> None:
        """Running past the last block: a subprogram returns, the main program ends."""
        if self.frames:
            self.return_from(None)
        else:
            self.stop("end")

    # -- NC blocks ----------------------------------------------------------------------
    def execute(self, words: list[Word]) -> None:
        """Execute an NC block: G65 call, or motion then M codes."""
        if any(letter == "G" and round(v * 10) == 650 for letter, v, _ in words):
            self.macro_call(words)
            return
        self.motion.block(words)
        for letter, value, _ in words:
            if letter == "M":
                self.m_code(round(value), words)

    def m_code(self, code: int, words: list[Word]) -> None:
        self.m_codes.append(code)
        if code in (2, 30):
            self.stop(f"M{code:02d}")
        elif code == 0 and self.settings.stop_at_m00:
            self.stop("M00")
        elif code == 6:
            self.motion.change_tool()
        elif code == 98:
            self.call(_address(words, "P"), _address(words, "L", 1), None)
        elif code == 99:
            seq = _address(words, "P", -1)
            self.return_from(seq if seq >= 0 else None)

    def macro_call(self, words: list[Word]) -> None:
        """G65 P L with arguments (specification I; repeated I J K: specification II)."""
        args: dict[int, float] = {}
        last, group = -1, 0
        for letter, value, integer in words:
            if letter in "GPL":
                if letter == "G" and round(value * 10) != 650:
                    raise alarm(ILLEGAL_ARGUMENT, f"G{value:g} IN G65")
                continue
            if letter in IJK:
                group += IJK[letter] <= last
                last = IJK[letter]
                number = 4 + 3 * group + IJK[letter]
            else:
                number = ARGUMENTS[letter]
            if number > 33:
                raise alarm(ILLEGAL_ARGUMENT, f"{letter} (SET {group + 1})")
            args[number] = self.motion.length(value, integer) if letter in "XYZ" else value
        self.call(_address(words, "P"), _address(words, "L", 1), args)

    def call(self, number: int, repeats: int, args: dict[int, float] | None) -> None:
        """Call program ``number`` (``args`` not None: a G65 macro with a new local level)."""
        if number < 0:
            raise alarm(PROGRAM_NOT_FOUND, "NO P")
        if repeats <= 0:
            return
        program = self.find(number)
        macros = sum(f.macro for f in self.frames) + (args is not None)
        if len(self.frames) >= self.settings.max_nesting or \
                macros > self.settings.max_macro_nesting:
            raise alarm(NESTING, f"O{number}")
        self.frames.append(Frame(self.prog, self.pc, args is not None, repeats - 1, args or {}))
        if args is not None:
            self.store.push_locals(args)
        self.prog, self.pc = program, 0

    def return_from(self, seq: int | None) -> None:
        """M99: repeat the call, or return to the caller (at block N<seq> if given)."""
        if not self.frames:
            self.stop("M99")
            return
        frame = self.frames[-1]
        if frame.repeats > 0:
            frame.repeats -= 1
            if frame.macro:
                self.store.pop_locals()
                self.store.push_locals(frame.args)
            self.pc = 0
            return
        self.frames.pop()
        if frame.macro:
            self.store.pop_locals()
        self.prog, self.pc = frame.program, frame.return_pc
        if seq is not None:
            self.goto(seq)

    def find(self, number: int) -> Loaded:
        """Return program O<number>: in the text, else a file in the program directory."""
        if number in self.loaded:
            return self.loaded[number]
        program = self.file.find(number)
        source = self.file.source
        if program is None:
            program, source = self.from_directory(number)
        self.loaded[number] = loaded = self.load(program, source)
        return loaded

    def from_directory(self, number: int) -> tuple[ast.Program, str]:
        names = dict.fromkeys((f"O{number:04d}", f"O{number}"))
        for name in names:
            for extension in EXTENSIONS:
                path = self.program_dir / (name + extension) if self.program_dir else None
                if path is not None and path.is_file():
                    parsed = read_program(path)
                    found = parsed.find(number) or (parsed.programs or (None,))[0]
                    return found or ast.Program(number, ()), str(path)
        raise alarm(PROGRAM_NOT_FOUND, f"O{number}")

    # -- output -------------------------------------------------------------------------
    def open_device(self, opening: bool) -> None:
        """POPEN / PCLOS: each sends a '%' line."""
        self.opened = opening
        self.output.append("%" + self.settings.dprnt_eol)

    def print_line(self, text: str) -> None:
        if not self.opened:
            raise alarm(NOT_OPEN)
        self.output.append(text + self.settings.dprnt_eol)

    # -- system variables (probegen.sim.macrob.variables.SystemVariables) ----------------------
    def read_system(self, number: int) -> Value:
        """Read #3000-#3999 and #4000-#5999 (timers, modal information, positions)."""
        if number == 3001:
            return self.motion.clock_ms - self.timers[0]
        if number == 3002:
            return (self.motion.clock_ms - self.timers[1]) / 3_600_000.0
        if number in STORED:
            return self.stored.get(number, 0.0)
        if number in (3000, 3006):
            return 0.0
        if number == 4113:
            return float(self.m_codes[-1]) if self.m_codes else 0.0
        if number == 4114:
            return float(self.last_seq)
        if number == 4115:
            return float(self.prog.number or 0)
        return self.motion.read(number)

    def write_system(self, number: int, value: Value) -> None:
        """Write #3000 (alarm), #3006 (stop with message), timers and stored values."""
        if number == 3000:
            code = round(value or 0.0)
            if not 0 <= code <= MAX_MACRO_ALARM:
                raise alarm(ARGUMENT_RANGE, f"#3000={code}")
            raise SimAlarm(MACRO_ALARM + code, self.comment() or "MACRO ALARM")
        if number == 3006:
            self.message = self.comment()
            self.stop("message")
        elif number == 3001:
            self.timers[0] = self.motion.clock_ms - (value or 0.0)
        elif number == 3002:
            self.timers[1] = self.motion.clock_ms - (value or 0.0) * 3_600_000.0
        elif number in STORED:
            self.stored[number] = value
            if number == OVERRIDE_CONTROL:
                self.motion.override_locked = bool(round(value or 0.0) & OVERRIDE_LOCKED)
        else:
            self.read_system(number)  # alarm 115 when the variable does not exist
            raise alarm(WRITE_PROTECTED, f"#{number}")


def _address(words: list[Word], letter: str, default: int = -1) -> int:
    """The rounded value of the last ``letter`` word of a block, or ``default``."""
    found = [value for name, value, _ in words if name == letter]
    return round(found[-1]) if found else default

