"""Trend charts of characteristics over many runs, and the report's history section.

One SVG per :class:`~probegen.spc.series.Series`: the values in run order (x: the run's
position in the series, oldest first; its run key, serial and time in the tooltip), the
tolerance limits, the nominal, the control chart's centre line and control limits
(:mod:`probegen.spc.control`: individuals, or subgroup means over faint single values for
an X̄-R chart), points beyond the control limits filled red, points in a run or trend
ringed orange (classes ``ooc``, ``run``, ``trend`` on the point), NOT EVALUATED runs as
grey marks on the x axis.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from probegen.report import palette
from probegen.report.svg import Frame, axes, esc, line, nice_ticks, px, svg_open, text
from probegen.spc import ControlChart, Series, capability
from probegen.spc.control import Point
from probegen.spc.table import COLUMNS, FIRST, spc_rows

WIDTH = 720.0
HEIGHT = 300.0
MARGIN = (64.0, 52.0, 28.0, 42.0)
"""Left, right (room for the limit labels), top, bottom, px."""

DECIMALS = 6
"""Decimals of values in the tooltips (as the SPC table prints them)."""


def trend_svg(series: Series) -> str:
    """The trend chart of ``series`` as inline SVG, or a ``<p class="empty">`` saying why
    there is none (no evaluated value, values beyond what a chart can scale)."""
    cap = capability(series)
    chart = cap.chart
    values = [v.measured for v in series.values if v.measured is not None]
    limits = [y for y in (series.lsl, series.usl) if y is not None]
    if chart is not None:
        limits += [chart.centre, chart.lcl, chart.ucl]
    frame_ticks = _frame(len(series.values), [*values, *limits]) if values else None
    if frame_ticks is None:
        why = "no evaluated value" if not values else "values beyond a chart's scale"
        return f'<p class="empty">{esc(_title(series))}: {why}, no trend chart.</p>'
    frame, xt, yt = frame_ticks
    title = _title(series)
    out = [svg_open(WIDTH, HEIGHT, f"trend chart of {title}")]
    out += axes(frame, xt, yt, title=title, x_label="run (oldest first)",
                y_label=f"{series.characteristic} ({series.unit})")
    out += _limit_lines(frame, series, chart)
    out += _not_evaluated(frame, series)
    out += _values(frame, series, chart)
    out.append("</svg>")
    return "\n".join(out)


def trend_section(series: Sequence[Series]) -> str:
    """The report's ``<section id="history">``: the SPC table and a trend chart per series."""
    rows = spc_rows(series)
    head = "".join(f"<th>{esc(c)}</th>" for c in ("part", *FIRST, "chart", "signals"))
    body = []
    for r in rows:
        f = r.fields()
        cells = "".join(f"<td>{esc(f[c]) or '&ndash;'}</td>"
                        for c in ("n", "mean", "sigma", "cp", "cpk", "chart", "signals"))
        body.append(f'<tr><td>{esc(f["part"])}</td><td>{esc(f["feature"])}</td>'
                    f'<th scope="row">{esc(f["characteristic"])}</th>{cells}</tr>')
    out = ['<section id="history">', "<h2>History</h2>"]
    if rows:
        out += ['<table class="chars" id="spc">', f"<thead><tr>{head}</tr></thead>", "<tbody>",
                *body, "</tbody>", "</table>"]
    else:
        out.append('<p class="empty">No history given.</p>')
    for r in rows:
        s = r.series
        out.append(f"<h3>{esc(_title(s))}</h3>")
        out.append(f'<div class="plots">\n{trend_svg(s)}\n</div>')
        notes = r.fields()["notes"]
        if notes:
            out.append(f'<p class="unit">{esc(notes)}</p>')
    out.append(f'<p class="unit">{esc(LEGEND)}</p>')
    out.append("</section>")
    return "\n".join(out) + "\n"


LEGEND = (
    "Values in the series' unit, runs oldest first. sigma: within standard deviation "
    "(moving range / 1.128, or mean subgroup range / d2); Cp = (USL - LSL) / 6 sigma, "
    "Cpk = min(USL - mean, mean - LSL) / 3 sigma (ISO 22514-2, normal distribution; no index "
    "from fewer than 10 values). Charts: red lines the tolerance limits, green the centre "
    "line, dashed orange the control limits (individuals: mean +/- 2.66 MR; X-bar-R: "
    "grand mean +/- A2 R). Red points lie beyond the control limits, orange rings mark 8 in a "
    "row on one side of the centre line or 6 in a row rising or falling; grey marks on the "
    "axis are NOT EVALUATED runs. Columns of " + ",".join(COLUMNS[:7]) + " as in "
    "probegen spc --format csv.")
"""The caption under the history section (what the colours and columns are)."""


def _title(series: Series) -> str:
    return f"{series.part} {series.feature} {series.characteristic}"


def _frame(count: int, ys: Sequence[float],
           ) -> tuple[Frame, tuple[list[float], int], tuple[list[float], int]] | None:
    """The plot frame for ``count`` runs and the data ``ys``, None when it cannot scale."""
    if not ys or not all(math.isfinite(y) for y in ys):
        return None
    lo, hi = min(ys), max(ys)
    span = hi - lo
    if not span > 1e-12 * max(abs(lo), abs(hi)):  # constant (to float precision)
        pad = abs(lo) * 0.1 or 1e-3
    else:
        pad = 0.05 * span
    lo, hi = lo - pad, hi + pad
    if not (math.isfinite(lo) and math.isfinite(hi) and math.isfinite(hi - lo) and hi > lo):
        return None
    yt = nice_ticks(lo, hi)
    if len(yt[0]) > 50 or not all(math.isfinite(t) for t in yt[0]):
        return None
    every = max(1, math.ceil(count / 12))
    xt = ([float(k) for k in range(1, count + 1, every)], 0)
    frame = Frame(WIDTH, HEIGHT, (0.5, count + 0.5), (yt[0][0], yt[0][-1]), margin=MARGIN)
    return frame, xt, yt


def _hline(frame: Frame, y: float, colour: str, *, dashed: bool = False) -> str:
    """A horizontal line across the plot at data ``y``."""
    left, right = frame.margin[0], frame.width - frame.margin[1]
    dash = ' stroke-dasharray="6 4"' if dashed else ""
    return line(left, frame.y(y), right, frame.y(y), colour, width=1.5,
                extra=f' class="limit"{dash}')


LABEL_GAP = 11.0
"""Least vertical distance between two limit labels in the right margin, px."""


def _limit_lines(frame: Frame, series: Series, chart: ControlChart | None) -> list[str]:
    """The nominal, tolerance, centre and control lines, labelled in the right margin
    (labels of lines closer than :data:`LABEL_GAP` are pushed apart, in line order)."""
    lines: list[tuple[float, str, str, bool]] = []
    if frame.y_lim[0] <= series.nominal <= frame.y_lim[1]:
        lines.append((series.nominal, palette.MUTED, "nom", True))
    for value, label in ((series.lsl, "LSL"), (series.usl, "USL")):
        if value is not None:
            lines.append((value, palette.TOLERANCE, label, False))
    if chart is not None:
        lines += [(chart.centre, palette.CENTRE, "CL", False),
                  (chart.lcl, palette.CONTROL, "LCL", True),
                  (chart.ucl, palette.CONTROL, "UCL", True)]
    out = [_hline(frame, y, colour, dashed=dashed) for y, colour, _, dashed in lines]
    placed: list[float] = []
    for y, colour, label, _ in sorted(lines, key=lambda item: -item[0]):
        at = frame.y(y)
        if placed and at < placed[-1] + LABEL_GAP:
            at = placed[-1] + LABEL_GAP
        placed.append(at)
        out.append(text(frame.width - frame.margin[1] + 4, at + 4, label, anchor="start",
                        size=10, extra=f' fill="{colour}"'))
    return out


def _not_evaluated(frame: Frame, series: Series) -> list[str]:
    bottom = frame.height - frame.margin[3]
    return [f'<path class="not-evaluated" d="M{px(frame.x(k + 1))},{px(bottom - 7)} '
            f'l-4,7 h8 z" fill="{palette.MUTED}"><title>{esc(_tip(series, k))}</title></path>'
            for k, v in enumerate(series.values) if v.measured is None]


def _values(frame: Frame, series: Series, chart: ControlChart | None) -> list[str]:
    """The plotted points: the values (I-MR) or the subgroup means over faint values."""
    points = chart.points if chart is not None else tuple(
        Point(k + 1.0, v.measured, (v.run,), (k,))
        for k, v in enumerate(series.values) if v.measured is not None)
    out = []
    if chart is not None and chart.kind != "I-MR":
        out += [f'<circle class="single" cx="{px(frame.x(k + 1))}" '
                f'cy="{px(frame.y(v.measured))}" r="2" fill="{palette.MUTED}">'
                f'<title>{esc(_tip(series, k))}</title></circle>'
                for k, v in enumerate(series.values) if v.measured is not None]
    pts = " ".join(f"{px(frame.x(p.x))},{px(frame.y(p.value))}" for p in points)
    out.append(f'<polyline points="{pts}" fill="none" stroke="{palette.LINE}" '
               'stroke-width="1.2"/>')
    beyond = chart.flagged(("beyond",)) if chart is not None else set()
    pattern = chart.flagged(("run", "trend")) if chart is not None else set()
    for k, p in enumerate(points):
        cls, fill, edge = "point", palette.LINE, palette.LINE
        if k in beyond:
            cls, fill, edge = "point ooc", palette.OUT_OF_CONTROL, palette.OUT_OF_CONTROL
        rules = [] if chart is None else sorted({s.rule for s in chart.signals if k in s.points})
        if k in pattern:
            cls = " ".join([cls, *(r for r in rules if r in ("run", "trend"))])
            edge = palette.CONTROL
        tip = _tip(series, p.indices[0]) if len(p.indices) == 1 else (
            f"subgroup mean {p.value:.{DECIMALS}f} {series.unit} of runs {', '.join(p.runs)}")
        if rules:
            tip += f" [{', '.join(rules)}]"
        ring = ' stroke-width="2.5"' if k in pattern else ""
        out.append(f'<circle class="{cls}" data-run="{esc(p.runs[0])}" cx="{px(frame.x(p.x))}" '
                   f'cy="{px(frame.y(p.value))}" r="{"4.5" if k in pattern else "3.5"}" '
                   f'fill="{fill}" stroke="{edge}"{ring}><title>{esc(tip)}</title></circle>')
    return out


def _tip(series: Series, k: int) -> str:
    """The tooltip of value ``k``: run, serial, time, value."""
    v = series.values[k]
    value = ("NOT EVALUATED" if v.measured is None
             else f"{v.measured:.{DECIMALS}f} {series.unit}")
    return f"run {k + 1} ({v.run}), serial {v.serial or '-'}, {v.time}: {value}"
