"""The SPC table: one row per characteristic, as CSV or as text for the terminal.

``spc_csv`` starts with the columns ``feature,characteristic,n,mean,sigma,cp,cpk`` (in
that order, the ones the issue names), then :data:`EXTRA`.  Numbers have fixed decimals
(:data:`DECIMALS` for values in the series' unit, 3 for indices and ratios), a missing
number is an empty field, so the same series give the same bytes.
"""

from __future__ import annotations

import csv
import functools
import io
import math
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass

from probegen.spc.capability import Capability, capability
from probegen.spc.control import RULES
from probegen.spc.series import Series

DECIMALS = 6
"""Decimals of values, means, standard deviations and limits (mm or deg): 0.001 µm."""

INDEX_DECIMALS = 3
"""Decimals of Cp, Cpk, Pp, Ppk and u/σ."""

FIRST = ("feature", "characteristic", "n", "mean", "sigma", "cp", "cpk")
"""The leading columns of the CSV, in this order."""

EXTRA = ("part", "unit", "nominal", "lsl", "usl", "sigma_overall", "pp", "ppk",
         "not_evaluated", "out_of_tolerance", "chart", "centre", "lcl", "ucl", "range_ucl",
         "out_of_control", "signals", "u_mean", "u_ratio", "notes")
"""The columns after :data:`FIRST`."""

COLUMNS = FIRST + EXTRA


@dataclass(frozen=True, slots=True)
class Row:
    """One characteristic's line of the SPC table.

    Attributes:
        series: the series it describes.
        capability: its capability figures and control chart.
    """

    series: Series
    capability: Capability

    def fields(self) -> dict[str, str]:
        """The row as text, one entry per column of :data:`COLUMNS`."""
        s, c = self.series, self.capability
        chart = c.chart
        length = functools.partial(number, decimals=DECIMALS)
        index = functools.partial(number, decimals=INDEX_DECIMALS)
        return {
            "feature": s.feature, "characteristic": s.characteristic, "n": str(c.n),
            "mean": length(c.mean), "sigma": length(c.sigma), "cp": index(c.cp),
            "cpk": index(c.cpk), "part": s.part, "unit": s.unit, "nominal": length(s.nominal),
            "lsl": length(s.lsl), "usl": length(s.usl),
            "sigma_overall": length(c.sigma_overall), "pp": index(c.pp), "ppk": index(c.ppk),
            "not_evaluated": str(c.not_evaluated), "out_of_tolerance": str(c.out_of_tolerance),
            "chart": "" if chart is None else (
                chart.kind if chart.kind == "I-MR" else f"{chart.kind} n={chart.subgroup_size}"),
            **{key: length(None if chart is None else getattr(chart, key))
               for key in ("centre", "lcl", "ucl", "range_ucl")},
            "out_of_control": "" if chart is None else str(len(chart.flagged(("beyond",)))),
            "signals": signals_text(c), "u_mean": length(c.u_mean), "u_ratio": index(c.u_ratio),
            "notes": "; ".join(c.notes + ((chart.note,) if chart and chart.note else ())),
        }


def spc_rows(series: Sequence[Series]) -> list[Row]:
    """One :class:`Row` per series, in the given order."""
    return [Row(s, capability(s)) for s in series]


def spc_csv(series: Sequence[Series]) -> str:
    """The SPC table as CSV (header :data:`COLUMNS`, ``\\n`` line ends)."""
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(COLUMNS)
    for row in spc_rows(series):
        fields = row.fields()
        writer.writerow([fields[c] for c in COLUMNS])
    return out.getvalue()


TABLE_COLUMNS = ("part", "feature", "characteristic", "n", "mean", "sigma", "cp", "cpk",
                 "pp", "ppk", "chart", "signals")
"""The columns :func:`spc_table` prints (the CSV has them all)."""


def spc_table(series: Sequence[Series]) -> str:
    """The SPC table as aligned text for the terminal, the notes under it."""
    rows = spc_rows(series)
    cells = [list(TABLE_COLUMNS)] + [[r.fields()[c] or "-" for c in TABLE_COLUMNS]
                                     for r in rows]
    widths = [max(len(line[k]) for line in cells) for k in range(len(TABLE_COLUMNS))]
    text = ["  ".join(cell.ljust(w) if k < 3 or k >= 10 else cell.rjust(w)
                      for k, (cell, w) in enumerate(zip(line, widths, strict=True))).rstrip()
            for line in cells]
    for r in rows:
        notes = r.fields()["notes"]
        if notes:
            text.append(f"{r.series.feature}.{r.series.characteristic}: {notes}")
    if not rows:
        text.append("(no characteristic)")
    return "\n".join(text) + "\n"


def signals_text(c: Capability) -> str:
    """The run-rule hits as ``rule:count`` words (``beyond:1 trend:2``), or empty."""
    if c.chart is None:
        return ""
    counts = Counter(s.rule for s in c.chart.signals)
    return " ".join(f"{rule}:{counts[rule]}" for rule in RULES if counts[rule])


def number(value: float | None, decimals: int) -> str:
    """``value`` with ``decimals`` fixed decimals, never ``-0``; empty when None."""
    if value is None or not math.isfinite(value):
        return ""
    text = f"{value:.{decimals}f}"
    return text[1:] if text.startswith("-") and text.strip("-0.") == "" else text
