"""Modal state, offsets and motion of the virtual LinuxCNC control.

A :class:`NgcMotion` is the Macro B control's :class:`~probegen.sim.macrob.motion.Motion`
(coordinates, units, tool length, work offsets, the machine calls, the virtual clock)
with LinuxCNC's G codes and numbered parameters.  Coordinates as there::

    machine = (R(program) + G54..G59.3 offset + G92/G52 offset + (0, 0, tool length)) * unit

with ``R`` the rotation ``R`` of the selected coordinate system (``G10 L2 Pn R``, about
its origin), ``unit`` 25.4 under G20; every number is as written (no least input
increments: ``X10`` is 10 mm).

G codes (LinuxCNC 2.9 G-code list): motion ``G0 G1 G38.2 G38.3`` (modal, group 1) and
``G80``; ``G17-G19``, ``G20 G21``, ``G40``, ``G43 [H]`` (no H: the tool in the spindle)
and ``G49``, ``G54-G59 G59.1-G59.3``, ``G61 G61.1 G64``, ``G90 G91 G90.1 G91.1``,
``G94``, ``G97``, ``G98 G99``; non-modal ``G4 P`` (seconds), ``G10 L2``/``L20`` (work
offsets; ``P0`` the current one), ``G28 G30`` (through the named axes to the position
held in ``#5161-#5163`` / ``#5181-#5183``, machine coordinates) and ``G28.1 G30.1``,
``G53`` (with G0 or G1), ``G92 G92.1 G92.2 G92.3 G52`` (one offset added to every
coordinate system; ``#5210`` says whether it is applied).  Other LinuxCNC codes (arcs,
cutter compensation, canned cycles, ``G38.4``/``G38.5``, inverse time ...) raise alarm
9010 (not supported by the virtual machine); a code LinuxCNC does not have is the
interpreter's error ``Unknown g code used``.

Rotary axes B and C (a five-axis B/C machine) turn as on the Macro B control
(``Motion.turn``: ``G0``/``G1``/``G53`` with the linear axes still, C the shorter way);
LinuxCNC's ``#5224``-style offsets of the coordinate system apply.

Probing (``G38.2``, ``G38.3``): a straight move at the feed toward the point that stops
where the probe trips.  ``#5061-#5063`` hold the trip point in the coordinate system of
the move, ``#5070`` 1; without contact the end point and 0, and ``G38.2`` stops the
program (``G38.2 probe move finished without contact``).  A probe move shorter than
0.254 mm (0.01 inch) is the interpreter's error ``Start point too close to probe point``.
"""

from __future__ import annotations

import math

from probegen.sim.alarms import SimAlarm
from probegen.sim.macrob.base import UNSUPPORTED, Machine, Settings, alarm
from probegen.sim.macrob.motion import ROTARY_SLOTS, Motion
from probegen.sim.macrob.variables import EXTERNAL, Store
from probegen.sim.ngc.expr import error

PROBE_ALARM = 9302
"""Alarm number of a G38.2 that ends without contact."""
SYSTEMS = {54.0: 1, 55.0: 2, 56.0: 3, 57.0: 4, 58.0: 5, 59.0: 6, 59.1: 7, 59.2: 8, 59.3: 9}
"""Coordinate system code → its number (``#5220``) and its set in the offset store."""
SLOTS = (0, 1, 2, 5, ROTARY_SLOTS["B"], ROTARY_SLOTS["C"], 6, 7, 8, 9)
"""LinuxCNC's axis order in a parameter set (X Y Z A B C U V W R) → slot in the store."""
ROTATION_SLOT = 9
GROUPS = {0: 1, 10: 1, 382: 1, 383: 1, 800: 1, 170: 2, 180: 2, 190: 2, 900: 3, 910: 3,
          901: 4, 911: 4, 940: 5, 200: 6, 210: 6, 400: 7, 430: 8, 490: 8, 980: 10, 990: 10,
          970: 13, 610: 15, 611: 15, 640: 15, **{round(k * 10): 14 for k in SYSTEMS}}
"""Supported modal G codes (tenths) → their key in ``Motion.modal``."""
DWELL, DATA, HOME, HOME_SET, SECOND, SECOND_SET, MACHINE = 40, 100, 280, 281, 300, 301, 530
OFFSET_CODES = (920, 921, 922, 923, 520)
ONE_SHOT = frozenset({DWELL, DATA, HOME, HOME_SET, SECOND, SECOND_SET, MACHINE, *OFFSET_CODES})
NOT_MODELLED = frozenset(
    [20, 30, 50, 51, 52, 53, 70, 80, 171, 181, 191, 330, 331, 384, 385, 410, 411, 420, 421,
     431, 432, 730, 740, 760, 930, 950, 960, 762] + list(range(810, 900, 10)))
"""LinuxCNC G codes the virtual machine does not model (alarm 9010)."""
PROBES = (382, 383)
MIN_PROBE = 0.254
"""Shortest probe move, mm (rs274ngc ``convert_probe``: 0.254 mm or 0.01 inch)."""


class NgcMotion(Motion):
    """LinuxCNC's G codes and system parameters on the Macro B control's motion."""

    def __init__(self, machine: Machine, store: Store, settings: Settings) -> None:
        self.g92_saved = [0.0] * 10
        self.g92_on = False
        self.homes: dict[int, float] = {}
        self.tripped = False
        super().__init__(machine, store, settings)
        self.modal.update({1: 80.0, 15: 64.0, 5: 94.0})

    # -- offsets ----------------------------------------------------------------------
    @property
    def system(self) -> int:
        """The coordinate system in force, 1 (G54) to 9 (G59.3)."""
        return SYSTEMS[self.modal[14]]

    def refresh(self) -> None:
        """Offsets changed: the rotation of the coordinate system too."""
        degrees = self.store.work_offset(self.wcs)[ROTATION_SLOT]
        self.rotation = (0.0, 0.0, degrees) if degrees else None
        super().refresh()

    def apply_offsets(self) -> None:
        """Select the coordinate system and tool length of the modal state."""
        self.wcs = self.system
        self.tlo = self.store.tool_length(self.h) if self.modal[8] == 43.0 else 0.0
        self.refresh()

    def select(self, number: int) -> None:
        """Select coordinate system ``number`` (1-9), as ``#5220`` written."""
        codes = {v: k for k, v in SYSTEMS.items()}
        if number not in codes:
            raise error(f"Coordinate system index parameter 5220 out of range ({number})")
        self.modal[14] = codes[number]
        self.apply_offsets()

    def set_g92(self, values: list[float], on: bool) -> None:
        """Apply (``on``) or remove the G92/G52 offset; ``values`` are kept in #5211-."""
        self.g92_saved, self.g92_on = list(values), on
        for i, slot in enumerate(SLOTS[:9]):
            self.store.set_work_offset(EXTERNAL, slot, values[i] if on else 0.0)
        self.sync()

    # -- one line ---------------------------------------------------------------------
    def modal_codes(self, values: list[float]) -> int | None:
        """Apply a line's G codes; return its non-modal code (tenths) or None."""
        one_shot, groups = None, set()
        before = (self.modal[6], self.modal[14], self.modal[8])
        self.codes = []
        for value in values:
            code = round(value * 10)
            if abs(value * 10 - code) > 1e-3:
                raise error(f"Unknown g code used (G{value:g})")
            group = GROUPS.get(code)
            key = 0 if code in ONE_SHOT else group
            if key in groups:
                raise error("Two G-codes used from same modal group")
            groups.add(key)
            self.codes.append(code)
            if group is not None:
                self.modal[group] = code / 10
            elif code in ONE_SHOT:
                one_shot = code
            elif code in NOT_MODELLED:
                raise alarm(UNSUPPORTED, f"G{value:g}")
            else:
                raise error(f"Unknown g code used (G{value:g})")
        self.changed = before != (self.modal[6], self.modal[14], self.modal[8])
        return one_shot

    def block(self, gs: list[float], addr: dict[str, float]) -> None:  # type: ignore[override]
        """Execute a line's G codes and axis words (F S T already taken, M codes apart)."""
        self.sync()
        one_shot = self.modal_codes(gs)
        if 430 in self.codes:
            self.take_length(round(addr["H"]) if "H" in addr else self.tool)
        if self.changed:
            self.apply_offsets()
        words = {k: (v, False) for k, v in addr.items()}
        axes = self.axes(words, one_shot)
        turns = self.rotary_words(words, one_shot)
        if one_shot == MACHINE and turns:
            self.turn(turns, axes, one_shot)
            return
        if one_shot is not None:
            self.non_modal(one_shot, words, axes)
            return
        if not axes and not turns:
            return
        mode = round(self.modal[1] * 10)
        if mode == 800:
            raise error("Cannot use axis values without a g code that uses them")
        if turns:
            self.turn(turns, axes, one_shot)
        elif mode in PROBES:
            self.probe(axes, mode)
        else:
            if mode == 10 and self.feed <= 0.0:
                raise error("Cannot do g1 with zero feed rate")
            self.move(axes, skip=False)

    def non_modal(self, code: int, words: dict[str, tuple[float, bool]],
                  axes: dict[int, float]) -> None:
        """G4, G10, G28/G30 (.1), G53, G92 (.1 .2 .3), G52."""
        if code == DWELL:
            self.clock_ms += words.get("P", (0.0, False))[0] * 1000.0
        elif code == DATA:
            self.g10(words)
        elif code in (HOME, SECOND):
            self.go_home(axes, 5161 if code == HOME else 5181)
        elif code in (HOME_SET, SECOND_SET):
            base = 5161 if code == HOME_SET else 5181
            for i in range(3):
                self.homes[base + i] = self.position[i] / self.unit
        elif code == MACHINE:
            if round(self.modal[1]) not in (0, 1):
                raise error("Must use G0 or G1 with G53")
            self.machine_move(axes)
        else:
            self.g92(code, axes)

    def go_home(self, axes: dict[int, float], base: int) -> None:
        """G28/G30: rapid through the named axes' point to the stored position."""
        if axes:
            self.rapid(self.position, self.to_machine(self.target(axes), set(axes)))
        named = set(axes) or {0, 1, 2}
        unit = self.unit
        x, y, z = (self.homes.get(base + i, 0.0) * unit if i in named else self.position[i]
                   for i in range(3))
        self.rapid(self.position, (x, y, z))
        self.work = self.to_work(self.position)

    def g92(self, code: int, axes: dict[int, float]) -> None:
        if code in (920, 520):
            if not axes:
                raise error(f"All axes missing with G{code / 10:g}")
            if self.rotation is not None:
                raise alarm(UNSUPPORTED, f"G{code / 10:g} IN A ROTATED COORDINATE SYSTEM")
            values = list(self.g92_saved if self.g92_on else [0.0] * 10)
            for i, value in axes.items():
                values[i] = value if code == 520 else values[i] + self.work[i] - value
            self.set_g92(values, True)
        elif code == 921:
            self.set_g92([0.0] * 10, False)
        elif code == 922:
            self.set_g92(self.g92_saved, False)
        else:
            self.set_g92(self.g92_saved, True)

    def g10(self, words: dict[str, tuple[float, bool]]) -> None:
        """G10 L2 / L20 Pn (0: the current system; 1-9 G54-G59.3)."""
        line = round(words.get("L", (0.0, False))[0])
        number = round(words.get("P", (-1.0, False))[0])
        if line not in (2, 20):
            raise alarm(UNSUPPORTED, f"G10 L{line}")
        if not 0 <= number <= 9:
            raise error(f"P-value not an integer from 0 to 9 with G10 L{line} ({number})")
        key = number or self.system
        if line == 20 and self.rotation is not None:
            raise alarm(UNSUPPORTED, "G10 L20 IN A ROTATED COORDINATE SYSTEM")
        external = self.store.work_offset(EXTERNAL)
        machine = [p / self.unit for p in self.position]
        for i, letter in enumerate("XYZ"):
            if letter in words:
                value = words[letter][0]
                if line == 20:
                    value = machine[i] - external[i] - (self.tlo if i == 2 else 0.0) - value
                self.store.set_work_offset(key, i, value)
        if "R" in words:
            self.store.set_work_offset(key, ROTATION_SLOT, words["R"][0])
        self.sync()

    # -- probing ----------------------------------------------------------------------
    def probe(self, axes: dict[int, float], mode: int) -> None:
        """G38.2 / G38.3 toward the named point; the trip point into #5061-#5063."""
        end = self.target(axes)
        start, stop = self.position, self.to_machine(end, set(axes))
        feed = self.feed * self.unit
        if feed <= 0.0:
            raise error("Cannot probe with zero feed rate")
        if math.dist(start, stop) < MIN_PROBE:
            raise error("Start point too close to probe point")
        if not self.override_locked:
            feed *= self.settings.feed_override / 100.0
        self.advance(start, stop, feed)
        self.skip_feeds.append(feed)
        self.tripped = self.skip(start, stop, feed, end)
        if mode == 382 and not self.tripped:
            raise SimAlarm(PROBE_ALARM, "G38.2 probe move finished without contact")

    # -- parameters ---------------------------------------------------------------------
    def read_param(self, number: int) -> float | None:
        """The system parameters (``#5021``-``#5428``); None for a plain parameter."""
        self.sync()
        if 5061 <= number <= 5069:
            return self.skip_point[number - 5061] if number < 5064 else 0.0
        if number == 5070:
            return float(self.tripped)
        if 5021 <= number <= 5029:
            return self.position[number - 5021] / self.unit if number < 5024 else 0.0
        if 5081 <= number <= 5089:
            return self.tlo if number == 5083 else 0.0
        if number == 5210:
            return float(self.g92_on)
        if 5211 <= number <= 5219:
            return self.g92_saved[number - 5211]
        if number == 5220:
            return float(self.system)
        if 5221 <= number <= 5390:
            group, axis = divmod(number - 5221, 20)
            return self.store.work_offset(group + 1)[SLOTS[axis]] if axis < 10 else None
        if number in (5161, 5162, 5163, 5181, 5182, 5183):
            return self.homes.get(number, 0.0)
        if number == 5400:
            return float(self.tool)
        if 5401 <= number <= 5413:
            return self.store.tool_length(self.tool) if number == 5403 else 0.0
        if 5420 <= number <= 5428:
            return self.work[number - 5420] if number < 5423 else 0.0
        return None

    def write_param(self, number: int, value: float) -> bool:
        """Write a system parameter; False for a plain one.  Read-only ones are errors."""
        if (5061 <= number <= 5070 or 5021 <= number <= 5029 or 5081 <= number <= 5089
                or 5400 <= number <= 5428):
            raise error(f"Cannot assign to read-only parameter #{number}")
        if number == 5210:
            self.set_g92(self.g92_saved, value != 0.0)
        elif 5211 <= number <= 5219:
            values = list(self.g92_saved)
            values[number - 5211] = value
            self.set_g92(values, self.g92_on)
        elif number == 5220:
            self.select(round(value))
        elif 5221 <= number <= 5390 and (number - 5221) % 20 < 10:
            group, axis = divmod(number - 5221, 20)
            self.store.set_work_offset(group + 1, SLOTS[axis], value)
        elif number in (5161, 5162, 5163, 5181, 5182, 5183):
            self.homes[number] = value
        else:
            return False
        return True

    def predefined(self) -> dict[str, float]:
        """The modal predefined named parameters (``#<_metric>``, ``#<_coord_system>`` ...)."""
        self.sync()
        m = self.modal
        return {
            "_motion_mode": round(m[1] * 10), "_plane": round(m[2] * 10),
            "_ccomp": 400.0, "_metric": float(m[6] == 21.0), "_imperial": float(m[6] == 20.0),
            "_absolute": float(m[3] == 90.0), "_incremental": float(m[3] == 91.0),
            "_inverse_time": 0.0, "_units_per_minute": 1.0, "_units_per_rev": 0.0,
            "_coord_system": round(m[14] * 10), "_tool_offset": float(m[8] == 43.0),
            "_retract_r_plane": float(m[10] == 98.0), "_retract_old_z": float(m[10] == 99.0),
            "_feed": self.feed, "_rpm": self.spindle, "_current_tool": float(self.tool),
            "_selected_tool": float(self.next_tool),
            "_x": self.work[0], "_y": self.work[1], "_z": self.work[2],
            "_abs_x": self.position[0] / self.unit, "_abs_y": self.position[1] / self.unit,
            "_abs_z": self.position[2] / self.unit,
        }
