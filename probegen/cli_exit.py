"""The command line's process exit codes (see :mod:`probegen.cli`)."""

from __future__ import annotations

from enum import IntEnum


class ExitCode(IntEnum):
    """Process exit codes (the list with their meaning: :mod:`probegen.cli` and the README)."""

    OK = 0
    ERROR = 1
    SPEC = 2
    MODEL = 3
    PLANNING = 4
    UNSUPPORTED = 5
    PARSE = 6
    CALIBRATION = 7
    NOT_OK = 8
    CAPTURE_INCOMPLETE = 9
    SIM_ALARM = 10
    USAGE = 64
    INTERNAL = 70
    OUTPUT = 73
    INTERRUPTED = 130
