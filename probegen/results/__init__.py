"""Returned data → typed records: DPRNT logs from Fanuc controls, and serial capture.

Importing this package loads lark and pyserial only (never OCP/build123d or jinja2),
so ingesting results on a shop-floor PC stays fast.
"""

from probegen.results.capture import (
    DEFAULT_BAUDRATE,
    CaptureReason,
    CaptureResult,
    Progress,
    capture,
    capture_from,
)
from probegen.results.dprnt import (
    FORMAT_VERSION,
    Centre,
    DprntLog,
    ProgramError,
    Touch,
    decode_dprnt,
    parse_dprnt,
    read_dprnt,
)

__all__ = [
    "DEFAULT_BAUDRATE",
    "FORMAT_VERSION",
    "CaptureReason",
    "CaptureResult",
    "Centre",
    "DprntLog",
    "ProgramError",
    "Progress",
    "Touch",
    "capture",
    "capture_from",
    "decode_dprnt",
    "parse_dprnt",
    "read_dprnt",
]
