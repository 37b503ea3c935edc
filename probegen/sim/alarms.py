"""Alarms of the virtual machine: what a real controller would stop with.

A ``SimAlarm`` is not a ``ProbegenError``: the program was read correctly and the
machine stopped while running it (unexpected contact, no contact where one was
expected), exactly as a real controller raises an alarm.  Interpreters report it in
their run result; the alarm number and message are those shown on the controller.
"""

from __future__ import annotations


class SimAlarm(Exception):
    """The virtual machine stopped with an alarm.

    Attributes:
        number: the alarm number shown by the controller.
        message: the alarm text.
        line: 1-based line of the program statement that raised it, or None when the
            raiser does not know it (the interpreter fills it in).
    """

    def __init__(self, number: int, message: str, line: int | None = None) -> None:
        where = f"line {line}: " if line is not None else ""
        super().__init__(f"{where}alarm {number}: {message}")
        self.number = number
        self.message = message
        self.line = line

    def at_line(self, line: int) -> SimAlarm:
        """Return this alarm with ``line`` filled in (itself if it already has one)."""
        return self if self.line is not None else SimAlarm(self.number, self.message, line)
