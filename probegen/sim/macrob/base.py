"""Settings of the virtual Fanuc control, the alarms its Macro B interpreter raises and
the :class:`Machine` protocol: the kinematics and part the control drives (what
``execute``, ``motion`` and ``machine`` all share).

Alarm numbers follow the Fanuc 0i-F program (PS) alarm list where one fits; alarms
only the virtual machine raises (a limit of the simulation, not of the program) are
numbered from 9000.  Macro alarms raised by the program itself (``#3000 = n``) are
3000 + n, as on the control.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from typing import Any, Protocol

from probegen.sim.alarms import SimAlarm

IMPROPER_G_CODE = 10
FEED_ZERO = 11
ILLEGAL_OFFSET = 30
PROGRAM_NOT_FOUND = 76
NESTING = 77
SEQUENCE_NOT_FOUND = 78
OVERFLOW = 111
ZERO_DIVIDE = 112
VARIABLE_RANGE = 115
WRITE_PROTECTED = 116
ARGUMENT_RANGE = 119
MISSING_END = 124
ILLEGAL_LOOP = 126
ILLEGAL_SEQUENCE = 128
ILLEGAL_ARGUMENT = 129
MACRO_ALARM = 3000
BLOCK_LIMIT = 9000
NOT_OPEN = 9001
UNSUPPORTED = 9010
ILLEGAL_G10 = 9011

MESSAGES = {
    IMPROPER_G_CODE: "IMPROPER G-CODE",
    FEED_ZERO: "FEED ZERO (COMMAND)",
    ILLEGAL_OFFSET: "ILLEGAL OFFSET NUMBER",
    PROGRAM_NOT_FOUND: "PROGRAM NOT FOUND",
    NESTING: "SUB PROGRAM NESTING ERROR",
    SEQUENCE_NOT_FOUND: "SEQUENCE NUMBER NOT FOUND",
    OVERFLOW: "CALCULATED DATA OVERFLOW",
    ZERO_DIVIDE: "ZERO DIVIDE",
    VARIABLE_RANGE: "VARIABLE NO. OUT OF RANGE",
    WRITE_PROTECTED: "WRITE PROTECTED VARIABLE",
    ARGUMENT_RANGE: "ARGUMENT VALUE OUT OF RANGE",
    MISSING_END: "MISSING END STATEMENT",
    ILLEGAL_LOOP: "ILLEGAL LOOP NUMBER",
    ILLEGAL_SEQUENCE: "ILLEGAL MACRO SEQUENCE NUMBER",
    ILLEGAL_ARGUMENT: "ILLEGAL ARGUMENT ADDRESS",
    BLOCK_LIMIT: "BLOCK LIMIT REACHED",
    NOT_OPEN: "DPRNT WITHOUT POPEN",
    UNSUPPORTED: "NOT SUPPORTED BY THE VIRTUAL MACHINE",
    ILLEGAL_G10: "ILLEGAL G10 COMMAND",
}
"""The message of each alarm number (as the control shows it)."""


def alarm(number: int, detail: str = "") -> SimAlarm:
    """Return the alarm ``number`` with its standard message and an optional detail."""
    message = MESSAGES.get(number, "ALARM")
    return SimAlarm(number, f"{message} ({detail})" if detail else message)


@dataclass(frozen=True, slots=True)
class Settings:
    """Parameters of the virtual control (the defaults are a stock 0i-F mill).

    Attributes:
        dprnt_blanks: DPRNT prints leading zeros as blanks, right-aligning numbers in
            their field (parameter PRT = 0); the default suppresses them (PRT = 1), so
            ``#1[53]`` of 12.3456 prints ``12.346`` and of 0.5 prints ``.500``.
        dprnt_eol: what ends a DPRNT line (real controls send LF or CR LF per I/O
            parameter; the default is LF).
        calculator_input: an axis value written without a decimal point is in mm
            (``X10`` = 10 mm, parameter DPI = 1); the default is the Fanuc default
            (DPI = 0): it counts least input increments, ``X10`` = 0.010 mm
            (0.0010 inch under G20).  Applies to literal numbers of X, Y, Z (also in
            G10 and G65) and R in G10; values of variables and expressions are mm.
        stop_at_m00: M00 ends the run (``stopped == "M00"``); by default M00 and M01
            are recorded and the program continues, as after a cycle start.
        rapid_mm_min: rapid traverse rate for the virtual clock (``#3001``).
        home: the machine position when the program starts (machine coordinates, mm);
            a real program starts wherever the last one left the spindle, usually at
            the tool-change position high above the table.
        max_nesting: subprogram and macro calls nested at most this deep (M98 + G65).
        max_macro_nesting: G65 macro calls nested at most this deep (new local levels).
        g_aliases: G codes of a builder's control read as Fanuc codes, e.g.
            ``{100: 0, 131: 31}`` runs Brother programs whose G100 (tool change with
            positioning) and G131 (skip) should move as G0 and G31 here.
        g_missing: Fanuc G codes the builder's control does not have: alarm 10
            (IMPROPER G-CODE) as for any unknown code (checked as written, before
            ``g_aliases``).
        feed_override: the operator's feed override dial, percent: every G1 and G31 feed
            is multiplied by it / 100, except while ``#3004`` bit 1 (value 2) holds
            feed override at 100 % (the feeds run are ``RunResult.skip_feeds``).
        table_pivot: where the trunnion table's tilt and C axes meet, machine
            coordinates, mm (G53.1 turns the table about it; :mod:`probegen.sim.macrob.tilt`).
        tilt_axis: the trunnion's tilt axis, ``"A"`` (about X) or ``"B"`` (about Y).
        tilt_range: its travel, deg, or None (not limited).
    """

    dprnt_blanks: bool = False
    dprnt_eol: str = "\n"
    calculator_input: bool = False
    stop_at_m00: bool = False
    rapid_mm_min: float = 10_000.0
    max_nesting: int = 10
    max_macro_nesting: int = 5
    g_aliases: Mapping[float, float] = field(default_factory=dict)
    g_missing: frozenset[float] = frozenset()
    home: tuple[float, float, float] = (0.0, 0.0, 0.0)
    feed_override: float = 100.0
    table_pivot: tuple[float, float, float] = (0.0, 0.0, 0.0)
    tilt_axis: str = "A"
    tilt_range: tuple[float, float] | None = None


CONTROLS: Mapping[str, Settings] = {
    "fanuc": Settings(),
    "haas": Settings(g_aliases={100.0: 50.1, 101.0: 51.1, 154.0: 54.1, 268.0: 68.2,
                                253.0: 53.1, 269.0: 69.0},
                     g_missing=frozenset({15.0, 16.0, 50.1, 51.1, 68.2, 53.1})),
}
"""The controls the virtual machine can be (``probegen sim --control``).

``haas``: a Haas mill (classic and NGC) runs Fanuc Macro B, but its G-code list cancels
mirror image with G100 (G101 sets it; group 0) where Fanuc writes G50.1 (G51.1), and has
no polar-coordinate mode (G15/G16): G100 and G101 are read as G50.1 and G51.1 (which
the virtual machine does not model: alarm 9010), and G15, G16, G50.1 and G51.1 as written
are alarm 10, as on the machine (``dialects/haas.py`` writes the same words).  G154 Pn
(P1-P99) selects the additional work offsets as Fanuc's G54.1 Pn does, with the same
variables (#7001-, #14001-: 20 per offset).  G268 X Y Z I J K (the feature coordinate
system), G253 (the spindle normal to it) and G269 (cancel) are read as Fanuc's G68.2,
G53.1 and G69 (:mod:`probegen.sim.macrob.tilt`); G68.2 and G53.1 as written are alarm 10,
and a ``Q`` word (another Euler order) on G268 is alarm 9010."""


def control_settings(control: str, **changes: Any) -> Settings:
    """The settings of the virtual ``control`` (a key of :data:`CONTROLS`) with
    ``changes`` (other :class:`Settings` fields, e.g. ``home``) applied.

    Raises:
        KeyError: ``control`` is not a key of :data:`CONTROLS`.
    """
    return replace(CONTROLS[control], **changes)


Point = tuple[float, float, float]
"""A position in machine coordinates, mm."""


class Machine(Protocol):
    """The machine and part the control drives; every position is in machine
    coordinates, mm (the interpreter converts work coordinates, offsets, tool length
    and inch before calling).

    Each method may raise :class:`SimAlarm` (for instance a collision on a rapid or
    feed move); the run then stops with that alarm at the current program line.  A run
    starts at machine zero ``(0, 0, 0)`` (the reference position); moves that go
    nowhere are not passed on, G31 moves always are.
    """

    def rapid(self, start: Point, end: Point) -> None:
        """A G0 (or G28/G53) move from ``start`` to ``end``."""
        ...

    def feed(self, start: Point, end: Point, feed_mm_min: float) -> None:
        """A G1 move at ``feed_mm_min``."""
        ...

    def skip(self, start: Point, end: Point, feed_mm_min: float) -> Point | None:
        """A G31 move: return where the skip signal fired, or None if it never did."""
        ...


class RotaryMachine(Machine, Protocol):
    """A machine with rotary axes: the control also calls :meth:`rotate` (a machine
    without the method makes B and C words raise alarm 9010)."""

    def rotate(self, start: dict[str, float], end: dict[str, float], at: Point) -> None:
        """Turn the rotary axes from ``start`` to ``end`` (machine angles by axis letter,
        deg; linear in angle, C possibly past 360) with the linear axes at ``at``."""
        ...
