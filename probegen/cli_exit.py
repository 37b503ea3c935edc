"""The command line's process exit codes (see :mod:`probegen.cli`).

The verdict of ``ingest`` and ``post-ingest``: ``OK`` (0) every toleranced
characteristic evaluated and conforming (or nothing toleranced); ``NOT_OK`` (8) at least
one out of tolerance; ``INCOMPLETE`` (11) nothing out of tolerance, but a feature or a
toleranced characteristic could not be evaluated (missing or no-contact touches, a
failed fit) or the run did not finish (no ``PGEND``).  When both happen ``NOT_OK`` wins:
a characteristic out of tolerance, measured completely, is a definite finding that the
missing measurements cannot reverse (the part is rejected either way); the output still
lists every NOT EVALUATED feature.  Input errors keep their own codes (1-7, 64).
"""

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
    INCOMPLETE = 11
    USAGE = 64
    INTERNAL = 70
    OUTPUT = 73
    INTERRUPTED = 130
