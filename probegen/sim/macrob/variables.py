"""The variables of the virtual control: locals, commons, offsets and the rest.

Numbers (Fanuc 0i/30i, tool compensation memory C):

| variables | meaning |
|---|---|
| ``#0`` | always vacant, read only |
| ``#1``-``#33`` | locals; a new level per G65 call (M98 subprograms share the caller's) |
| ``#100``-``#199``, ``#500``-``#999`` | common variables |
| ``#2001``-``#2200`` / ``#2201``-``#2400`` | H wear / H geometry of offsets 1-200 |
| ``#10001``-``#10999`` / ``#11001``-``#11999`` | H wear / H geometry of offsets 1-999 |
| ``#12001``-``#12999`` / ``#13001``-``#13999`` | D wear / D geometry of offsets 1-999 |
| ``#5201``-``#5203`` | external work offset X Y Z (G10 L2 P0) |
| ``#5221``-``#5223`` ... ``#5321``-``#5323`` | G54 ... G59 X Y Z (20 numbers per set) |
| ``#7001``-``#7960`` | G54.1 P1-P48 (20 per set); ``#14001``-``#19980`` the same for P1-P300 |

Offsets are plain numbers in the program's input unit, as on a control that does not
convert offsets when G20/G21 changes.  A G43 offset is H geometry + H wear.  Any other
variable the control has (timers, modal information, positions) is read and written
through the :class:`SystemVariables` of the interpreter.  Variables given to
:func:`~probegen.sim.macrob.machine.run_program` that the control does not know (say a
builder's ``#3700``) are kept as extra variables, readable and writable.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Protocol

from probegen.sim.alarms import SimAlarm
from probegen.sim.macrob.base import VARIABLE_RANGE, WRITE_PROTECTED, alarm
from probegen.sim.macrob.expr import Getter, Value, checked

Setter = Callable[[Value], None]
"""Writes one variable."""

H_WEAR, H_GEOMETRY, D_WEAR, D_GEOMETRY = 0, 1, 2, 3
"""Kinds of tool offsets (the thousands digit of ``#10001``-``#13999``)."""
EXTERNAL, G54 = 0, 1
"""Work offset set numbers: external (G10 L2 P0) and G54 (P1 ... G59 = 6)."""
EXTENDED = 100
"""Set number of G54.1 P1 (P n is EXTENDED + n - 1)."""
AXES = 20
"""Numbers per work offset set."""


def work_offset_slot(number: int) -> tuple[int, int] | None:
    """Return (set, axis index) of a work offset variable, or None."""
    if 5201 <= number <= 5340:
        return divmod(number - 5201, AXES)
    if 7001 <= number <= 7960:
        group, axis = divmod(number - 7001, AXES)
        return EXTENDED + group, axis
    if 14001 <= number <= 19980:
        group, axis = divmod(number - 14001, AXES)
        return EXTENDED + group, axis
    return None


def tool_offset_slot(number: int) -> tuple[int, int] | None:
    """Return (kind, offset number) of a tool offset variable, or None."""
    if 10001 <= number <= 13999:
        kind, offset = divmod(number - 10000, 1000)
        return (kind, offset) if offset else None
    if 2001 <= number <= 2400:
        kind, offset = divmod(number - 2001, 200)
        return kind, offset + 1
    return None


class SystemVariables(Protocol):
    """The interpreter's side of the variables (#3000, timers, modal data, positions)."""

    def read_system(self, number: int) -> Value:
        """Read system variable ``number``; alarm 115 if there is none."""
        ...

    def write_system(self, number: int, value: Value) -> None:
        """Write system variable ``number``; alarm 115 or 116 if it cannot be written."""
        ...


class Store:
    """All variables of one run."""

    def __init__(self, system: SystemVariables) -> None:
        self.system = system
        self.locals: list[Value] = [None] * 34
        self.levels: list[list[Value]] = []
        self.common: list[Value] = [None] * 1000
        self.work: dict[int, list[float]] = {k: [0.0] * AXES for k in range(7)}
        self.tools: dict[tuple[int, int], float] = {}
        self.extra: dict[int, Value] = {}
        self.version = 0
        """Counts work offset changes (positions in work coordinates depend on them)."""

    # -- local levels ---------------------------------------------------------------
    def push_locals(self, values: dict[int, float]) -> None:
        """Open a new local level (G65) holding ``values``; the rest are vacant."""
        self.levels.append(self.locals)
        self.locals = [None] * 34
        for number, value in values.items():
            self.locals[number] = value

    def pop_locals(self) -> None:
        """Return to the caller's local level (M99 of a G65 macro)."""
        self.locals = self.levels.pop()

    # -- reading and writing --------------------------------------------------------
    def reader(self, number: int) -> Getter:
        """Return a function reading ``number`` (fast paths for locals and commons)."""
        if 1 <= number <= 33:
            return lambda: self.locals[number]
        if 100 <= number <= 199 or 500 <= number <= 999:
            common = self.common
            return lambda: common[number]
        if number == 0:
            return lambda: None
        return lambda: self.read(number)

    def writer(self, number: int) -> Setter:
        """Return a function writing ``number``."""
        if 1 <= number <= 33:
            def write_local(value: Value) -> None:
                self.locals[number] = value
            return write_local
        if 100 <= number <= 199 or 500 <= number <= 999:
            common = self.common

            def write_common(value: Value) -> None:
                common[number] = value
            return write_common
        return lambda value: self.write(number, value)

    def read(self, number: int) -> Value:
        """Read variable ``number``."""
        if 1 <= number <= 33:
            return self.locals[number]
        if 100 <= number <= 199 or 500 <= number <= 999:
            return self.common[number]
        if number == 0:
            return None
        slot = work_offset_slot(number)
        if slot is not None:
            return self.work_offset(slot[0])[slot[1]]
        tool = tool_offset_slot(number)
        if tool is not None:
            return self.tools.get(tool, 0.0)
        if number in self.extra:
            return self.extra[number]
        return self.system.read_system(number)

    def write(self, number: int, value: Value) -> None:
        """Write variable ``number`` (offsets hold 0 for a vacant value)."""
        if 1 <= number <= 33:
            self.locals[number] = value
        elif 100 <= number <= 199 or 500 <= number <= 999:
            self.common[number] = value
        elif number == 0:
            raise alarm(WRITE_PROTECTED, "#0")
        elif (slot := work_offset_slot(number)) is not None:
            self.work_offset(slot[0])[slot[1]] = value or 0.0
            self.version += 1
        elif (tool := tool_offset_slot(number)) is not None:
            self.tools[tool] = value or 0.0
        elif number in self.extra:
            self.extra[number] = value
        else:
            self.system.write_system(number, value)

    def seed(self, number: int, value: float) -> None:
        """Set a variable before the run; unknown numbers become extra variables.

        Raises:
            ValueError: ``number`` is a variable the program cannot write (#0, #5001...).
        """
        try:
            self.write(number, checked(value))
        except SimAlarm as exc:
            if exc.number != VARIABLE_RANGE or number < 0:
                raise ValueError(f"cannot preset variable #{number}: {exc.message}") from None
            self.extra[number] = value

    # -- offsets ----------------------------------------------------------------------
    def work_offset(self, key: int) -> list[float]:
        """Return the work offset set ``key`` (created on first use for G54.1 Pn)."""
        found = self.work.get(key)
        if found is None:
            found = self.work[key] = [0.0] * AXES
        return found

    def set_work_offset(self, key: int, axis: int, value: float) -> None:
        """Write one axis of a work offset set."""
        self.work_offset(key)[axis] = value
        self.version += 1

    def tool_length(self, number: int) -> float:
        """Return the tool length offset H ``number``: geometry + wear (H0 is 0)."""
        if number == 0:
            return 0.0
        return self.tools.get((H_GEOMETRY, number), 0.0) + self.tools.get((H_WEAR, number), 0.0)

    # -- the result ---------------------------------------------------------------------
    def snapshot(self) -> dict[int, float]:
        """Return every variable holding a value: level-0 locals, commons, extras and the
        offsets that are not zero (G54.1 sets under their #14001- numbers)."""
        out: dict[int, float] = {}
        base = self.levels[0] if self.levels else self.locals
        for number in range(1, 1000):
            value = base[number] if number <= 33 else self.common[number] if number >= 100 else None
            if value is not None:
                out[number] = value
        for key, values in sorted(self.work.items()):
            start = 5201 + AXES * key if key < EXTENDED else 14001 + AXES * (key - EXTENDED)
            out.update({start + axis: v for axis, v in enumerate(values) if v})
        for (kind, offset), value in sorted(self.tools.items()):
            if value:
                out[10000 + 1000 * kind + offset] = value
        out.update({k: v for k, v in self.extra.items() if v is not None})
        return out


def unknown(number: int) -> SimAlarm:
    """The alarm for a variable number the control does not have."""
    return alarm(VARIABLE_RANGE, f"#{number}")
