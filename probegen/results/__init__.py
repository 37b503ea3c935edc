"""Returned data → typed records: DPRNT logs from Fanuc controls, DMIS output files, and
serial capture.

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
from probegen.results.dmis_output import (
    DmisOutput,
    FeatureActual,
    MeasuredPoint,
    ToleranceActual,
    parse_dmis_output,
    read_dmis_output,
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
    touches_array,
)

__all__ = [
    "DEFAULT_BAUDRATE",
    "FORMAT_VERSION",
    "CaptureReason",
    "CaptureResult",
    "Centre",
    "DmisOutput",
    "DprntLog",
    "FeatureActual",
    "MeasuredPoint",
    "ProgramError",
    "Progress",
    "ToleranceActual",
    "Touch",
    "capture",
    "capture_from",
    "decode_dprnt",
    "parse_dmis_output",
    "parse_dprnt",
    "read_dmis_output",
    "read_dprnt",
    "touches_array",
]
