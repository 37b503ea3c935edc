"""The CSV export of the history: one row per run per characteristic (RFC 4180).

Columns: ``part, feature, characteristic, run, time, serial, subgroup, nominal, lsl, usl,
measured, u, status``.  Rows go part by part, characteristic by characteristic (the order
of the series given), run by run (oldest first); a run in which a characteristic has no
value is a NOT EVALUATED row (:mod:`probegen.qdas.runs`).  Numbers are plain decimals
(a point, no exponent, at most nine decimal places, trailing zeros dropped); an absent
value (no limit, no measurement, no uncertainty, no serial) is an empty field.  Fields
that need it are quoted; lines end in CRLF as RFC 4180 says.
"""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Sequence

from probegen.errors import ProbegenError
from probegen.qdas.runs import aligned, by_part, part_runs
from probegen.spc.series import Series

COLUMNS = ("part", "feature", "characteristic", "run", "time", "serial", "subgroup",
           "nominal", "lsl", "usl", "measured", "u", "status")


def to_csv(series: Sequence[Series]) -> str:
    """The CSV text (RFC 4180, CRLF, a header row) of ``series``; see the module docstring.

    Raises:
        ProbegenError: a characteristic twice, a time that is not ISO 8601, or a number
            that is not finite.
    """
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\r\n")
    w.writerow(COLUMNS)
    for group in by_part(series):
        runs = part_runs(group)
        for s in group:
            for v in aligned(s, runs):
                w.writerow([s.part, s.feature, s.characteristic, v.run, v.time,
                            v.serial or "", v.subgroup or "", plain(s.nominal),
                            plain(s.lsl), plain(s.usl), plain(v.measured), plain(v.u),
                            v.status])
    return buf.getvalue()


def plain(x: float | None) -> str:
    """``x`` as a plain decimal (at most 9 places, trailing zeros dropped, never ``-0``);
    ``""`` for None."""
    if x is None:
        return ""
    if not math.isfinite(x):
        raise ProbegenError(f"CSV export: expected a finite number, found {x}")
    text = f"{x:.9f}".rstrip("0").rstrip(".")
    return "0" if text in ("-0", "") else text
