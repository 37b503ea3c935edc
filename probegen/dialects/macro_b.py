"""The values of a Fanuc Macro B program: common variables, block labels, feeds.

What the Fanuc dialect (``dialects/fanuc.py``, and Haas through it) and its in-process
decisions (``dialects/fanuc_actions.py``) both use: run-time values live in common
variables from the profile's ``variable_base`` (``#100`` by default), named values from
base+0, scratch at base+90..base+93; forward GOTOs jump to fresh block numbers from
N1001; feeds are printed in program units per minute with a decimal point.
"""

from __future__ import annotations

import re
from typing import ClassVar

from probegen import ir
from probegen.constants import tol
from probegen.dialects.base import Dialect
from probegen.errors import UnsupportedError

SCRATCH = 90
"""Offset of the scratch variables (three targets and one check sum) from the base."""
MESSAGE = re.compile(r"#300[06]=[^(]*\(([^)]*)\)")
"""A macro alarm or stop with its message (the message is group 1)."""


class MacroB(Dialect):
    """A Macro B dialect's values and print formats (not a dialect by itself: no ``NAME``)."""

    RUNTIME_VARIABLES: ClassVar[bool] = True
    DPRNT_FORMAT: ClassVar[dict[str, str]] = {"mm": "44", "inch": "35"}
    """Integer and fraction digits of printed positions (``#5061[44]``)."""
    RADIUS_WEAR_FACTOR: ClassVar[float] = 1.0
    """What a radius correction is multiplied by in ``G10 L13`` (Fanuc memory C: the D
    offset is a radius)."""
    ALARM_TEXT_LENGTH: ClassVar[int] = 26
    """Longest message of ``#3000=n(TEXT)`` and ``#3006=n(TEXT)``, characters: 26 on the
    Fanuc 0i series (a longer one is cut on the alarm screen, and some controls refuse
    the block); ``fanuc_actions.alarm_text`` keeps probegen's texts within it and
    :meth:`check_messages` refuses any longer one."""
    TILT_REFUSAL: ClassVar[str] = ""
    """Why the dialect writes no tilted frame ("": it writes G68.2/G53.1,
    :mod:`probegen.dialects.fanuc_orient`)."""
    CHECK_SUM: ClassVar[float] = 5.0 * tol.skip_check
    """A skip position within this (sum of |dX|+|dY|+|dZ|, mm) of the end point means the
    skip did not fire: the end point itself is rounded to the least input increment."""

    def __init__(self) -> None:
        super().__init__()
        self.vars: dict[str, int] = {}
        self.base = 100
        self.label = 1000
        self.frame: ir.Orient | None = None
        """The tilted frame in force where the program being written stands."""
        self.axes: tuple[str, ...] = ()
        """The rotary axes the orientations name (returned to 0 at the vertical)."""
        self.tool = 0
        """The tool (and length offset) number of the stylus in the spindle."""
        self.ball = 0.0
        """Its ball diameter, mm."""
        self.level = 0.0
        """The clearance level of the vertical probe (work Z, mm)."""
        self.restate: ir.Orient | None = None
        """The frame a split part starts in (``split`` sets it): set again, no move."""

    def var(self, name: str) -> str:
        """The ``#n`` holding run-time value ``name`` (allocated on first use)."""
        if name not in self.vars:
            if len(self.vars) >= SCRATCH:
                raise self.unsupported(ir.Var(name), f"more than {SCRATCH} run-time values")
            self.vars[name] = self.base + len(self.vars)
        return f"#{self.vars[name]}"

    def expr(self, c: ir.Coord) -> str:
        """A coordinate as a Macro B expression (no outer brackets)."""
        e = self.sum_expr(c)
        return self.length(c) if e is None else e  # type: ignore[arg-type]

    def addr(self, c: ir.Coord) -> str:
        """A coordinate as an address value: a number, ``#n`` or ``[expression]``."""
        e = self.expr(c)
        return e if not isinstance(c, ir.Var) or "+" not in e and "-" not in e else f"[{e}]"

    def scratch(self, k: int) -> str:
        """Scratch variable ``k`` (0-2 targets, 3 the check sum)."""
        return f"#{self.base + SCRATCH + k}"

    def next_label(self) -> int:
        """A fresh block number for a forward GOTO."""
        self.label += 1
        return self.label

    def alarm_length(self) -> int:
        """The longest alarm message of the program being written: the profile's
        ``[controller] alarm_text_length`` when it sets one, else ``ALARM_TEXT_LENGTH``."""
        limits = self.limits
        return limits.alarm_text_length if limits and limits.alarm_text_length else \
            self.ALARM_TEXT_LENGTH

    def check_messages(self, text: str) -> None:
        """Refuse a ``#3000``/``#3006`` message longer than :meth:`alarm_length`.

        Raises:
            UnsupportedError: names the line, the message, the limit and what sets it.
        """
        limit = self.alarm_length()
        source = (f" ({self.limits.limits_source}: controller.alarm_text_length)"
                  if self.limits and self.limits.alarm_text_length else "")
        for number, line in enumerate(text.split("\n"), start=1):
            found = MESSAGE.match(line)
            if found and len(found[1]) > limit:
                raise UnsupportedError(
                    f"dialect {self.NAME!r}: line {number}: expected an alarm message of at "
                    f"most {limit} characters{source}, found {len(found[1])}: "
                    f"{found[1]!r}")

    def generate(self, program: ir.Program) -> str:
        """The program text, its common variables checked against the profile's
        (:meth:`check_common_variables`)."""
        text = super().generate(program)
        self.check_common_variables(program)
        return text

    def used_variables(self, program: ir.Program) -> list[tuple[int, str]]:
        """The common variables the program writes, with what each holds: the named
        run-time values from ``#base``, the scratch values (the macro library's commons
        in a compact program) at ``#base+90``..``#base+93``, and the variables in-process
        decisions name (a check's ``flag``, an alignment's ``variable``)."""
        base = program.setup.variable_base
        used = [(number, "a run-time value") for number in sorted(self.vars.values())]
        used += [(base + SCRATCH + k, "a scratch value") for k in range(4)]
        for node in ir.walk(program.body):
            if isinstance(node, ir.Check) and node.flag is not None:
                used.append((node.flag, f"the flag of feature {node.feature}"))
            if isinstance(node, ir.Align) and node.variable is not None:
                used.append((node.variable, f"the angle of feature {node.feature}"))
        return used

    def check_common_variables(self, program: ir.Program) -> None:
        """Refuse a variable outside the control's common variables
        (``ir.Setup.common_variables``, the profile's ``[controller]
        common_variables``; not checked when empty).

        Raises:
            UnsupportedError: names the variable, what it holds, the ranges and the keys.
        """
        s = program.setup
        ranges = s.common_variables
        if not ranges:
            return
        for number, what in self.used_variables(program):
            if not any(first <= number <= last for first, last in ranges):
                have = ", ".join(f"#{a}-#{b}" for a, b in ranges)
                raise UnsupportedError(
                    f"dialect {self.NAME!r}: the program uses #{number} ({what}; "
                    f"#{s.variable_base}-#{s.variable_base + SCRATCH + 3} from "
                    f"{s.limits_source}: controller.variable_base), expected a common "
                    f"variable of the control: {have} ({s.limits_source}: "
                    "controller.common_variables); move variable_base (or the action's "
                    "variable) into a range the control has, or declare the range if it "
                    "has it (the option for #100-#499 on a Fanuc 0i)")

    def feed(self, mm_per_min: float) -> str:
        """A feed in program units per minute, with the decimal point Fanuc wants."""
        return self.num(self.scale(mm_per_min), 0) + "."
