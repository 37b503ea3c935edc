"""Modal state, coordinates and motion of the virtual Fanuc control.

Coordinates: the program works in *work* coordinates of the tool's controlled point
(the probe's ball centre), in the program's unit.  The machine is driven in *machine*
coordinates, mm::

    machine = (work + external offset + G54..G59 / G54.1 offset + (0, 0, tool length)) * unit

with ``unit`` 25.4 under G20 and 1 under G21, and the tool length ``+H`` under G43,
``-H`` under G44 and 0 under G49 (H geometry + H wear, taken when G43/G44/H is given).
The machine position is the truth: changing an offset, the unit or the tool length
does not move the machine, it changes the work coordinates read back (``#5041``).
An axis not named in a move keeps its machine coordinate.

Rotation ``G68 X Y R`` (plane G17): program coordinates ``p`` become work coordinates
``R(p - c) + c`` (``c`` the centre X Y in absolute work coordinates, the current
position for an axis not given; ``R`` degrees, counter-clockwise) until ``G69``.  Under
G68 every position variable (#5001-, #5041-, #5061-) reads program coordinates, and
a move naming only some axes keeps the others' program coordinates.  The block's X Y
set the centre; it does not move.

Tilted working plane ``G68.2``/``G53.1`` (a trunnion table): :mod:`probegen.sim.macrob.tilt`.

Supported: G0 G1 G31 (skip) G4 G10 (L2, L20, L1/L10-L13) G28 G53 G17-G19 G20 G21
G40 G43 G44 G49 G50 G50.1 G54-G59 G54.1 Pn G61-G64 G67 G68 (G17 only) G68.2 G53.1 G69
G80 G90 G91 G94 G96-G99 G15.  Other Fanuc G codes (G2/G3 arcs, cutter compensation G41/G42,
scaling G51, canned cycles, G52, G92, G95 ...) raise alarm 9010 (not supported by
the virtual machine); a G code Fanuc does not have raises alarm 10, and so does one
the builder's control lacks (``Settings.g_missing``; ``base.CONTROLS``).  Axes other than
X, Y, Z, B, C raise alarm 9010: a dropped move would crash a real machine.

Rotary axes (a five-axis B/C machine: B the 4th axis, C the 5th), in degrees:

* ``G0``/``G1``/``G53`` with B and/or C words position the rotary axes while X, Y, Z
  stand still; a block naming linear and rotary axes together, and G31 or G28 with a
  rotary word, raise alarm 9010 (positioning only; probing with the rotary axes
  stationary).  The machine is told through ``Machine.rotate``; a machine without it
  (or without rotary axes) raises alarm 9010 too.
* Work angle = machine angle − (external + selected work offset) of that axis
  (``#5224``/``#5225`` for G54 ...; ``G10 L2 Pn B.. C..`` writes them).
* B is a linear-type rotary axis (no rollover: ``B-90.`` from ``B90.`` turns through
  0).  C rolls over (Fanuc parameter 1008 ROA = 1, RAB = 0; 0i manual B-63534EN 20.2.1,
  whose example is a test): an absolute command turns the shorter way (a half turn: the
  positive way, as the 15i manual says) and the position reads back in [0, 360); an
  incremental command turns by the amount given.
* A value without a decimal point counts least input increments of 0.001 deg
  (``B90`` = 0.09 deg) unless calculator input is on, as for lengths.
* Rotary feed under G94 is deg/min; rapid turns use ``Settings.rapid_mm_min`` as
  deg/min on the virtual clock.
"""

from __future__ import annotations

import math

from probegen.sim.alarms import SimAlarm
from probegen.sim.macrob.base import (
    FEED_ZERO,
    ILLEGAL_G10,
    ILLEGAL_OFFSET,
    IMPROPER_G_CODE,
    UNSUPPORTED,
    Machine,
    Point,
    Settings,
    alarm,
)
from probegen.sim.macrob.expr import Value
from probegen.sim.macrob.tilt import (
    IDENTITY,
    OUT_OF_TRAVEL,
    TILT_CODE,
    TOOL_AXIS_CODE,
    FeatureFrame,
    check_probing,
    frame_of_block,
    on_table,
    table_rotation,
    turn_table,
    turned,
)
from probegen.sim.macrob.variables import (
    D_GEOMETRY,
    D_WEAR,
    EXTENDED,
    EXTERNAL,
    G54,
    H_GEOMETRY,
    H_WEAR,
    Store,
    unknown,
)

Word = tuple[str, float, bool]
"""An evaluated word: letter, value, and whether it was an integer literal (``X10``)."""

AXIS_LETTERS = "XYZ"
ROTARY_SLOTS = {"B": 3, "C": 4}
"""Rotary axis letter → its index in a work-offset set and in #5001-style axis numbers
(the 4th and 5th axes of a five-axis B/C machine)."""
ROLLOVER = frozenset("C")
"""Rotary axes with rollover and shortest-path absolute positioning."""
ANGLE_INCREMENT = 0.001
"""Least input increment of a rotary axis, deg (IS-B)."""
MODAL_GROUPS: dict[int, int] = {
    0: 1, 10: 1, 170: 2, 180: 2, 190: 2, 900: 3, 910: 3, 940: 5, 200: 6, 210: 6, 400: 7,
    430: 8, 440: 8, 490: 8, 800: 9, 980: 10, 990: 10, 500: 11, 670: 12, 960: 13, 970: 13,
    540: 14, 550: 14, 560: 14, 570: 14, 580: 14, 590: 14, 541: 14, 610: 15, 620: 15,
    630: 15, 640: 15, 680: 16, 682: 16, 690: 16, 150: 17, 501: 22,
}
"""Supported modal G codes (in tenths: G54.1 is 541) and their group."""
DEFAULT_MODAL: dict[int, float] = {
    1: 0.0, 2: 17.0, 3: 90.0, 4: 22.0, 5: 94.0, 6: 21.0, 7: 40.0, 8: 49.0, 9: 80.0,
    10: 98.0, 11: 50.0, 12: 67.0, 13: 97.0, 14: 54.0, 15: 64.0, 16: 69.0, 17: 15.0,
    22: 50.1,
}
"""The modal G codes at power-on (read as #4001-#4022)."""
DWELL, DATA, REFERENCE, SKIP, MACHINE = 40, 100, 280, 310, 530
ONE_SHOT = frozenset({DWELL, DATA, REFERENCE, SKIP, MACHINE, TOOL_AXIS_CODE})
FANUC_G = frozenset(
    [int(g * 10) for g in (2, 3, 5, 7.1, 9, 11, 16, 22, 23, 27, 29, 30, 33, 37, 39, 40.1, 41,
                           41.1, 42, 42.1, 45, 46, 47, 48, 51, 51.1, 52, 60, 65, 66, 92,
                           92.1, 95)]
    + list(range(730, 900, 10))
)
"""Fanuc G codes the virtual machine does not model (alarm 9010 instead of 10)."""
MAX_EXTENDED = 300
"""Highest G54.1 P number."""
MAX_OFFSET = 999
"""Highest tool offset number (H, and P of G10 L10-L13)."""
OFFSET_KINDS = {10: H_GEOMETRY, 1: H_GEOMETRY, 11: H_WEAR, 12: D_GEOMETRY, 13: D_WEAR}
"""G10 L number → tool offset kind (memory C; L1 is memory A's single value)."""


def _g(code: int) -> str:
    return f"G{code / 10:g}"


class Motion:
    """The control's modal state and positions; drives the machine."""

    def __init__(self, machine: Machine, store: Store, settings: Settings) -> None:
        self.machine = machine
        self.store = store
        self.settings = settings
        self.modal = dict(DEFAULT_MODAL)
        self.wcs = G54
        self.extended = 1
        self.tlo = 0.0
        self.h = 0
        self.feed = 0.0
        self.override_locked = False
        """Whether ``#3004`` bit 1 holds feed override at 100 %."""
        self.skip_feeds: list[float] = []
        """The feed each G31 ran at (override applied), mm/min."""
        self.spindle = 0.0
        self.next_tool = 0
        self.tool = 0
        self.d = 0
        self.clock_ms = 0.0
        self.codes: list[int] = []
        self.changed = False
        self.position: Point = settings.home
        self.work = [0.0, 0.0, 0.0]
        self.skip_point: Point = (0.0, 0.0, 0.0)
        self.angles: dict[str, float] = dict.fromkeys(ROTARY_SLOTS, 0.0)
        """Machine angles of the rotary axes, deg (C in [0, 360))."""
        self.version = -1
        self.offset: Point = (0.0, 0.0, 0.0)
        self.rotation: tuple[float, float, float] | None = None
        """G68 in force: centre X, Y (work coordinates, program unit) and degrees."""
        self.feature: FeatureFrame | None = None
        """G68.2 in force (:mod:`probegen.sim.macrob.tilt`), or None."""
        self.table: dict[str, float] = dict(getattr(machine, "table", None) or {
            settings.tilt_axis: 0.0, "C": 0.0})
        """Trunnion table angles, deg: where the machine's table stands (a program run after
        one that left it turned starts there), then where G53.1 turned it."""
        self.table_matrix = table_rotation(self.table) if turned(self.table) else IDENTITY
        self.sync()

    # -- coordinates ----------------------------------------------------------------
    @property
    def unit(self) -> float:
        """Millimetres per program unit (25.4 under G20)."""
        return 25.4 if self.modal[6] == 20.0 else 1.0

    def refresh(self) -> None:
        """Recompute the offset and the work position after offsets or units changed."""
        self.version = self.store.version
        ext, wcs = self.store.work_offset(EXTERNAL), self.store.work_offset(self.wcs)
        self.offset = (ext[0] + wcs[0], ext[1] + wcs[1], ext[2] + wcs[2] + self.tlo)
        self.work = self.to_work(self.position)

    def sync(self) -> None:
        """Refresh if a work offset variable was written since the last look."""
        if self.version != self.store.version:
            self.refresh()

    def to_work(self, point: Point) -> list[float]:
        """Machine coordinates (mm) → work (program) coordinates (program unit)."""
        unit, off = self.unit, self.offset
        if self.feature is not None:
            if turned(self.table):
                point = self.table_point(point, -1)
            return self.feature.to_frame([point[i] / unit - off[i] for i in range(3)])
        work = [point[i] / unit - off[i] for i in range(3)]
        return self.rotate(work, -1.0) if self.rotation else work

    def to_machine(self, work: list[float], named: set[int]) -> Point:
        """Work (program) coordinates → machine; axes not in ``named`` keep their
        machine value (under G68 and G68.2: their program value)."""
        unit, off, pos = self.unit, self.offset, self.position
        if self.feature is not None and named:
            w = self.feature.to_work(work)
            q = ((w[0] + off[0]) * unit, (w[1] + off[1]) * unit, (w[2] + off[2]) * unit)
            return self.table_point(q, 1) if turned(self.table) else q
        if self.rotation:
            work = self.rotate(work, 1.0)
            named = named | ({0, 1} if named & {0, 1} else set())
        x, y, z = ((work[i] + off[i]) * unit if i in named else pos[i] for i in range(3))
        return x, y, z

    def table_point(self, point: Point, sense: int) -> Point:
        """A table-frame point where the turned table carries it (1) or back (-1)."""
        return on_table(point, sense, self.tlo * self.unit, self.table_matrix,
                        self.settings.table_pivot)

    def rotate(self, p: list[float], sense: float) -> list[float]:
        """G68: program → work coordinates (``sense`` 1) or back (-1)."""
        assert self.rotation is not None
        cx, cy, degrees = self.rotation
        a = math.radians(degrees) * sense
        u, v = p[0] - cx, p[1] - cy
        return [cx + u * math.cos(a) - v * math.sin(a), cy + u * math.sin(a) + v * math.cos(a),
                p[2]]

    def length(self, value: float, integer: bool) -> float:
        """An axis value as written: an integer literal counts input increments."""
        if not integer or self.settings.calculator_input:
            return value
        return value * (0.0001 if self.modal[6] == 20.0 else 0.001)

    # -- one block --------------------------------------------------------------------
    def block(self, words: list[Word]) -> None:
        """Execute the G, F, S, T, H, D and axis words of one block (M codes excluded)."""
        self.sync()
        one_shot = self.modal_codes([v for letter, v, _ in words if letter == "G"])
        addr = {letter: (v, integer) for letter, v, integer in words if letter not in "GM"}
        self.registers(addr)
        if one_shot == DATA:
            self.g10(addr)
            return
        if TILT_CODE in self.codes or TOOL_AXIS_CODE in self.codes:
            others = [c for c in self.codes if c in ONE_SHOT and c != TOOL_AXIS_CODE]
            if TILT_CODE in self.codes and TOOL_AXIS_CODE in self.codes:
                others.append(TOOL_AXIS_CODE)
            if others:
                raise alarm(UNSUPPORTED, f"G68.2/G53.1 WITH {_g(others[0])} IN ONE BLOCK")
        if TILT_CODE in self.codes:
            self.g68_2(addr)
            return
        if 680 in self.codes:
            self.g68(addr)
            return
        if 690 in self.codes and (self.rotation is not None or self.feature is not None):
            self.rotation = self.feature = None
            self.work = self.to_work(self.position)
        if one_shot == TOOL_AXIS_CODE:
            self.tool_axis()
            return
        if one_shot == MACHINE and self.table_words(addr):
            self.table_move(addr)
            return
        axes = self.axes(addr, one_shot)
        turns = self.rotary_words(addr, one_shot)
        if turns:
            self.turn(turns, axes, one_shot)
        elif one_shot == DWELL:
            self.dwell(addr)
        elif one_shot == REFERENCE:
            self.reference(axes)
        elif one_shot == MACHINE:
            self.machine_move(axes)
        elif axes:
            self.move(axes, skip=one_shot == SKIP)

    def modal_codes(self, values: list[float]) -> int | None:
        """Apply the modal G codes of a block; return its one-shot code (G4/10/28/31/53)."""
        one_shot = None
        before = (self.modal[6], self.modal[14], self.modal[8])
        missing = self.settings.g_missing
        for value in values:
            if missing and round(value, 1) in missing:
                raise alarm(IMPROPER_G_CODE, f"G{value:g}")
        aliases = self.settings.g_aliases
        if aliases:
            values = [aliases.get(value, value) for value in values]
        self.codes = codes = [round(value * 10) for value in values]
        for value, code in zip(values, codes, strict=True):
            group = MODAL_GROUPS.get(code)
            if group is not None:
                self.modal[group] = code / 10
            elif code in ONE_SHOT:
                one_shot = code
            elif code in FANUC_G:
                raise alarm(UNSUPPORTED, _g(code))
            else:
                raise alarm(IMPROPER_G_CODE, f"G{value:g}")
        self.changed = before != (self.modal[6], self.modal[14], self.modal[8])
        return one_shot

    def registers(self, addr: dict[str, tuple[float, bool]]) -> None:
        """Take F S T D H and P (G54.1) and apply unit, work offset and tool length changes."""
        for letter, (value, _) in addr.items():
            if letter == "F":
                self.feed = value
            elif letter == "S":
                self.spindle = value
            elif letter == "T":
                self.next_tool = round(value)
            elif letter == "D":
                self.d = round(value)
        if 541 in self.codes:
            self.extended = round(addr["P"][0]) if "P" in addr else 1
            if not 1 <= self.extended <= MAX_EXTENDED:
                raise alarm(ILLEGAL_OFFSET, f"G54.1 P{self.extended}")
        if "H" in addr and self.modal[8] != 49.0:
            self.take_length(round(addr["H"][0]))
            if not 0 <= self.h <= MAX_OFFSET:
                raise alarm(ILLEGAL_OFFSET, f"H{self.h}")
        if self.changed:
            self.apply_offsets()

    def apply_offsets(self) -> None:
        """Select the work offset and tool length of the modal state; refresh positions."""
        wcs = self.modal[14]
        self.wcs = EXTENDED + self.extended - 1 if wcs == 54.1 else round(wcs) - 54 + G54
        sign = {43.0: 1.0, 44.0: -1.0}.get(self.modal[8], 0.0)
        self.tlo = sign * self.store.tool_length(self.h) if sign else 0.0
        self.refresh()

    def axes(self, addr: dict[str, tuple[float, bool]], one_shot: int | None) -> dict[int, float]:
        """Return the named X Y Z values (lengths); alarm for axes not modelled."""
        for letter in "AUVW":
            if letter in addr:
                raise alarm(UNSUPPORTED, f"AXIS {letter}")
        if one_shot == DWELL:
            return {}
        return {i: self.length(*addr[a]) for i, a in enumerate(AXIS_LETTERS) if a in addr}

    def angle(self, value: float, integer: bool) -> float:
        """A rotary axis value as written, deg (an integer literal counts increments)."""
        return value if not integer or self.settings.calculator_input else (
            value * ANGLE_INCREMENT)

    def rotary_words(self, addr: dict[str, tuple[float, bool]],
                     one_shot: int | None) -> dict[str, float]:
        """The named B and C values, deg (none for G4 and G10, which read them otherwise)."""
        if one_shot in (DWELL, DATA):
            return {}
        return {a: self.angle(*addr[a]) for a in ROTARY_SLOTS if a in addr}

    # -- rotary axes --------------------------------------------------------------------
    def rotary_offset(self, letter: str) -> float:
        """External + selected work offset of rotary axis ``letter``, deg."""
        slot = ROTARY_SLOTS[letter]
        return (self.store.work_offset(EXTERNAL)[slot]
                + self.store.work_offset(self.wcs)[slot])

    def turn(self, turns: dict[str, float], axes: dict[int, float], one_shot: int | None) -> None:
        """Position the rotary axes (G0, G1 or G53) with the linear axes standing still."""
        names = "".join(turns)
        if one_shot in (SKIP, REFERENCE):
            raise alarm(UNSUPPORTED, f"{_g(one_shot)} WITH ROTARY AXIS {names}")
        if axes:
            raise alarm(UNSUPPORTED, f"LINEAR AND ROTARY AXES IN ONE BLOCK ({names})")
        rotate = getattr(self.machine, "rotate", None)
        if rotate is None:
            raise alarm(UNSUPPORTED, f"AXIS {names[0]}")
        start = dict(self.angles)
        end = dict(start)
        incremental = self.modal[3] == 91.0 and one_shot != MACHINE
        for letter, value in turns.items():
            if one_shot == MACHINE:
                target = value
            elif incremental:
                target = start[letter] + value
            else:
                target = value + self.rotary_offset(letter)
            if letter in ROLLOVER and not incremental:
                target -= 360.0 * math.ceil((target - start[letter] - 180.0) / 360.0)
            end[letter] = target
        swept = max(abs(end[a] - start[a]) for a in end)
        linear = self.modal[1] == 1.0 and one_shot != MACHINE
        if linear and self.feed <= 0:
            raise alarm(FEED_ZERO, "G1")
        self.clock_ms += swept / (self.feed if linear else self.settings.rapid_mm_min) * 60_000.0
        rotate(start, end, self.position)
        self.angles = {a: v % 360.0 if a in ROLLOVER else v for a, v in end.items()}

    # -- moves ------------------------------------------------------------------------
    def target(self, axes: dict[int, float]) -> list[float]:
        """The end point in work coordinates (absolute or incremental)."""
        end = list(self.work)
        incremental = self.modal[3] == 91.0
        for i, value in axes.items():
            end[i] = end[i] + value if incremental else value
        return end

    def move(self, axes: dict[int, float], *, skip: bool) -> None:
        """G0, G1 or G31 to the named axes."""
        end = self.target(axes)
        start, stop = self.position, self.to_machine(end, set(axes))
        if skip or self.modal[1] == 1.0:
            feed = self.feed * self.unit
            if feed <= 0:
                raise alarm(FEED_ZERO, "G31" if skip else "G1")
            if not self.override_locked:
                feed *= self.settings.feed_override / 100.0
            self.advance(start, stop, feed)
            if skip:
                self.skip_feeds.append(feed)
                self.skip(start, stop, feed, end)
                return
            if stop != start:
                self.machine.feed(start, stop, feed)
        else:
            self.rapid(start, stop)
        self.position, self.work = stop, end

    def skip(self, start: Point, stop: Point, feed: float, end: list[float]) -> bool:
        """G31: move until the skip signal; record the skip point (#5061-#5063).
        Return whether the signal came (the LinuxCNC control's ``#5070``)."""
        check_probing(self.feature, self.table, self.table_matrix)
        hit = self.machine.skip(start, stop, feed)
        if hit is None:
            self.position, self.work = stop, end
        else:
            self.position = (float(hit[0]), float(hit[1]), float(hit[2]))
            self.work = self.to_work(self.position)
        self.skip_point = (self.work[0], self.work[1], self.work[2])
        return hit is not None

    def rapid(self, start: Point, stop: Point) -> None:
        """A rapid move (skipped when it goes nowhere) on the virtual clock."""
        if stop != start:
            self.advance(start, stop, self.settings.rapid_mm_min)
            self.machine.rapid(start, stop)
        self.position = stop

    def advance(self, start: Point, stop: Point, feed: float) -> None:
        """Run the virtual clock for a move at ``feed`` mm/min."""
        self.clock_ms += math.dist(start, stop) / feed * 60_000.0

    def reference(self, axes: dict[int, float]) -> None:
        """G28: rapid to the intermediate point, then the named axes to machine zero."""
        self.rapid(self.position, self.to_machine(self.target(axes), set(axes)))
        home = tuple(0.0 if i in axes else self.position[i] for i in range(3))
        self.rapid(self.position, (home[0], home[1], home[2]))
        self.work = self.to_work(self.position)

    def machine_move(self, axes: dict[int, float]) -> None:
        """G53: rapid to machine coordinates (program unit) for this block only."""
        unit = self.unit
        x, y, z = (axes[i] * unit if i in axes else self.position[i] for i in range(3))
        self.rapid(self.position, (x, y, z))
        self.work = self.to_work(self.position)

    def dwell(self, addr: dict[str, tuple[float, bool]]) -> None:
        """G4: P in milliseconds or X in seconds, on the virtual clock."""
        if "P" in addr:
            self.clock_ms += addr["P"][0]
        elif "X" in addr:
            value, integer = addr["X"]
            self.clock_ms += (value * 0.001 if integer else value) * 1000.0

    def change_tool(self) -> None:
        """M6: the selected tool goes into the spindle (a machine with a stylus rack,
        ``select_tool``, takes that stylus or raises the alarm naming the tool)."""
        self.tool = self.next_tool
        select = getattr(self.machine, "select_tool", None)
        if select is not None:
            select(self.tool)

    def take_length(self, h: int) -> None:
        """G43/G44 H: the length offset ``h`` from now on (a machine with a stylus rack,
        ``check_length``, refuses an H that is not the tool in the spindle)."""
        self.h = h
        self.changed = True
        check = getattr(self.machine, "check_length", None)
        if check is not None:
            check(h, self.tool)

    # -- G68 ----------------------------------------------------------------------------
    def g68(self, addr: dict[str, tuple[float, bool]]) -> None:
        """G68 X Y R: rotate the program frame (plane G17, absolute centre)."""
        if self.modal[2] != 17.0:
            raise alarm(UNSUPPORTED, "G68 OUTSIDE G17")
        self.feature = None  # G68 and G68.2 share modal group 16
        here = self.to_work(self.position)
        if self.rotation is not None:
            here = self.rotate(here, 1.0)
        cx, cy = (self.length(*addr[a]) if a in addr else here[i]
                  for i, a in enumerate("XY"))
        degrees = addr.get("R", (0.0, False))[0]
        self.rotation = (cx, cy, degrees)
        self.work = self.to_work(self.position)

    # -- G68.2 / G53.1 (probegen.sim.macrob.tilt) ----------------------------------------
    def g68_2(self, addr: dict[str, tuple[float, bool]]) -> None:
        """G68.2 X Y Z I J K: the feature coordinate system (the block does not move)."""
        self.rotation = None
        self.feature = frame_of_block(addr, self.length, self.angle)
        self.work = self.to_work(self.position)

    def tool_axis(self) -> None:
        """G53.1: turn the trunnion table so that the tool axis is the frame's +Z."""
        end = turn_table(self.feature, self.machine, self.table, self.position,
                         self.settings.tilt_range)
        swept = max(abs(end[a] - self.table[a]) for a in end)
        self.clock_ms += swept / self.settings.rapid_mm_min * 60_000.0
        self.table, self.table_matrix = end, table_rotation(end)
        self.work = self.to_work(self.position)

    def table_words(self, addr: dict[str, tuple[float, bool]]) -> bool:
        """Whether a G53 block turns the trunnion table: a machine with ``tilt`` and no
        B/C head, the tilt axis named (with or without C)."""
        if getattr(self.machine, "tilt", None) is None or getattr(self.machine, "rotary",
                                                                    False):
            return False  # no table, or the B/C head machine (its B and C: ``turn``)
        return self.settings.tilt_axis in addr  # C alone: the rotary axes' own G53

    def table_move(self, addr: dict[str, tuple[float, bool]]) -> None:
        """``G53 A.. C..`` (or ``B.. C..``): turn the trunnion table to machine angles,
        the linear axes standing still (a block naming a linear axis too is alarm 9010);
        how a program brings the table back after ``G69``, which leaves it turned."""
        named = [a for a in "XYZUVW" if a in addr]
        if named:
            raise alarm(UNSUPPORTED, f"G53 WITH {named[0]} AND A TABLE AXIS IN ONE BLOCK")
        end = dict(self.table)
        for letter in end:
            if letter in addr:
                end[letter] = self.angle(*addr[letter])
        low, high = self.settings.tilt_range or (-360.0, 360.0)
        tilt_axis = self.settings.tilt_axis
        if not low - 1e-9 <= end[tilt_axis] <= high + 1e-9:
            raise SimAlarm(OUT_OF_TRAVEL, f"G53 {tilt_axis}{end[tilt_axis]:g}: OUTSIDE "
                           f"{low:g}..{high:g} (THE TILT AXIS'S TRAVEL)")
        if end != self.table:
            self.machine.tilt(dict(self.table), end, self.position)  # type: ignore[attr-defined]
            swept = max(abs(end[a] - self.table[a]) for a in end)
            self.clock_ms += swept / self.settings.rapid_mm_min * 60_000.0
        self.table = end
        self.table_matrix = table_rotation(end) if turned(end) else IDENTITY
        self.work = self.to_work(self.position)

    # -- G10 ----------------------------------------------------------------------------
    def g10(self, addr: dict[str, tuple[float, bool]]) -> None:
        """G10 L2/L20 (work offsets) and L1/L10-L13 (tool offsets); G91 adds."""
        line = round(addr.get("L", (0.0, False))[0])
        number = round(addr.get("P", (-1.0, False))[0])
        add = self.modal[3] == 91.0
        if line in (2, 20):
            self.g10_work(line, number, addr, add)
        elif line in OFFSET_KINDS and 1 <= number <= MAX_OFFSET and "R" in addr:
            key = (OFFSET_KINDS[line], number)
            value = self.length(*addr["R"])
            self.store.tools[key] = self.store.tools.get(key, 0.0) * add + value
        else:
            raise alarm(ILLEGAL_G10, f"L{line} P{number}")

    def g10_work(self, line: int, number: int, addr: dict[str, tuple[float, bool]],
                 add: bool) -> None:
        if line == 2 and 0 <= number <= 6:
            key = number
        elif line == 20 and 1 <= number <= MAX_EXTENDED:
            key = EXTENDED + number - 1
        else:
            raise alarm(ILLEGAL_G10, f"L{line} P{number}")
        values = self.store.work_offset(key)
        for i, letter in enumerate(AXIS_LETTERS):
            if letter in addr:
                value = self.length(*addr[letter])
                self.store.set_work_offset(key, i, values[i] * add + value)
        for letter, slot in ROTARY_SLOTS.items():
            if letter in addr:
                value = self.angle(*addr[letter])
                self.store.set_work_offset(key, slot, values[slot] * add + value)
        self.sync()

    # -- system variables ---------------------------------------------------------------
    def read(self, number: int) -> Value:
        """Read the modal (#4001-#4130) and position (#5001-#5108) variables."""
        self.sync()
        if 4001 <= number <= 4030:
            return self.modal.get(number - 4000, 0.0)
        if 4101 <= number <= 4130:
            return self.register(number - 4100)
        if 5001 <= number <= 5108:
            kind, axis = divmod(number - 5001, 20)
            return self.axis_value(kind, axis) if axis < 8 else self._unknown(number)
        raise unknown(number)

    def register(self, letter: int) -> Value:
        """#4100 + n: the modal value of an address (7 D, 9 F, 11 H, 19 S, 20 T, 30 P)."""
        values = {7: self.d, 9: self.feed, 11: self.h, 19: self.spindle,
                  20: self.next_tool, 30: self.extended}
        return float(values.get(letter, 0.0))

    def axis_value(self, kind: int, axis: int) -> float:
        """#5001 + 20 kind + axis: end point, machine, work, skip, tool length, deviation."""
        if axis >= 3:
            return self.rotary_value(kind, axis)
        if kind == 0 or kind == 2:
            return self.work[axis]
        if kind == 1:
            return self.position[axis] / self.unit
        if kind == 3:
            return self.skip_point[axis]
        if kind == 4:
            return self.tlo if axis == 2 else 0.0
        return 0.0

    def rotary_value(self, kind: int, axis: int) -> float:
        """The 4th (B) and 5th (C) axis of :meth:`axis_value`, deg (0 for the others)."""
        letter = next((a for a, slot in ROTARY_SLOTS.items() if slot == axis), None)
        if letter is None or kind not in (0, 1, 2, 3):
            return 0.0
        machine = self.angles[letter]
        return machine if kind == 1 else machine - self.rotary_offset(letter)

    def _unknown(self, number: int) -> Value:
        raise unknown(number)
