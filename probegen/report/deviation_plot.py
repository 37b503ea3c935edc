"""A free-form deviation map (method M3) as inline SVG: one dot per measured point.

The points are drawn in the world plane that faces the mean surface normal best (top view
``x``-``y`` for a face probed from above), at equal scale on both axes; each dot's area
grows with ``|e|``, light where material is added (``e > 0``), dark where it is missing,
as the report's other plots do (``palette.by_sign``).  Deterministic text, no JavaScript.

Feed it from a ``probegen.evaluate.compensate_freeform.DeviationMap``:
``deviation_map_svg(dmap.nominal, dmap.deviation * 1000, normals=dmap.normals, ...)``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from probegen.errors import ProbegenError
from probegen.report import palette
from probegen.report.numbers import fixed, signed
from probegen.report.plots import HALO, WIDTH
from probegen.report.svg import FONT, Frame, axes, esc, nice_ticks, px, svg_open, text

MAX_HEIGHT = 560.0
"""Tallest plot, px (a long narrow face is scaled down to fit)."""

MIN_WIDTH = 380.0
"""Narrowest plot, px (room for the title and legend); a tall map gets wider margins."""

AXES = "xyz"


def view_axes(normals: Sequence[Sequence[float]]) -> tuple[int, int]:
    """Indices of the two world axes the map is drawn in: all but the one the mean
    normal is most parallel to (``(0, 1)``, the top view, for normals near ±Z)."""
    mean = [sum(abs(n[k]) for n in normals) for k in range(3)]
    drop = max(range(3), key=lambda k: (mean[k], k == 2))
    first, second = (k for k in range(3) if k != drop)
    return first, second


def deviation_map_svg(points: Sequence[Sequence[float]], deviations_um: Sequence[float], *,
                      title: str, normals: Sequence[Sequence[float]] = ((0.0, 0.0, 1.0),),
                      decimals: int = 1, labels: Sequence[str] = ()) -> str:
    """The deviation map as an ``<svg>`` element.

    Args:
        points: ``(m, 3)`` nominal points, mm (part frame).
        deviations_um: ``(m,)`` deviations along the nominal normal, µm.
        title: plot title.
        normals: nominal normals (their mean picks the view plane; default top view).
        decimals: decimals of the values in the tooltips and the legend.
        labels: optional tooltip prefix per point (e.g. the point's id).
    """
    if len(points) != len(deviations_um) or not points:
        raise ProbegenError(f"deviation map: expected one deviation per point and at least "
                            f"one point, found {len(points)} points and "
                            f"{len(deviations_um)} deviations")
    ia, ib = view_axes(normals)
    xs = [float(p[ia]) for p in points]
    ys = [float(p[ib]) for p in points]
    if not all(math.isfinite(v) for v in (*xs, *ys, *deviations_um)):
        raise ProbegenError("deviation map: expected finite points and deviations, found "
                            "NaN or infinity")
    frame, xt, yt = _equal_frame(xs, ys)
    out = [svg_open(frame.width, frame.height + 22, title)]
    out += axes(frame, xt, yt, title=title, x_label=f"{AXES[ia]} (mm)",
                y_label=f"{AXES[ib]} (mm)")
    biggest = max((abs(v) for v in deviations_um), default=0.0) or 1.0
    for k, (x, y, v) in enumerate(zip(xs, ys, deviations_um, strict=True)):
        fill, edge = palette.by_sign(v)
        dot = 1.5 + 7.0 * math.sqrt(abs(v) / biggest)
        tip = f"{labels[k]}: " if k < len(labels) else ""
        out.append(f'<circle cx="{px(frame.x(x))}" cy="{px(frame.y(y))}" r="{px(dot)}" '
                   f'fill="{fill}" stroke="{edge}"><title>{esc(tip)}'
                   f'{esc(signed(v, decimals))} \u00b5m</title></circle>')
    low, high = min(deviations_um), max(deviations_um)
    legend = (f"dot area \u221d |e|; light: material added, dark: missing; "
              f"e from {signed(low, decimals)} to {signed(high, decimals)} \u00b5m")
    out.append(text(frame.width / 2, frame.height + 14, legend, size=FONT - 1, extra=HALO))
    out.append("</svg>")
    return "\n".join(out)


def _equal_frame(xs: Sequence[float], ys: Sequence[float]
                 ) -> tuple[Frame, tuple[list[float], int], tuple[list[float], int]]:
    """A frame around the data with the same mm-per-pixel on both axes."""
    xt, yt = nice_ticks(min(xs), max(xs)), nice_ticks(min(ys), max(ys))
    margin = Frame(0, 0, (0, 1), (0, 1)).margin
    x_span = xt[0][-1] - xt[0][0]
    y_span = yt[0][-1] - yt[0][0]
    scale = min((WIDTH - margin[0] - margin[1]) / x_span,
                (MAX_HEIGHT - margin[2] - margin[3]) / y_span)
    pad = max(0.0, MIN_WIDTH - margin[0] - margin[1] - scale * x_span) / scale / 2.0
    width = margin[0] + margin[1] + scale * (x_span + 2.0 * pad)
    height = margin[2] + margin[3] + scale * y_span
    frame = Frame(float(fixed(width, 2)), float(fixed(height, 2)),
                  (xt[0][0] - pad, xt[0][-1] + pad), (yt[0][0], yt[0][-1]))
    return frame, xt, yt
