"""The report's 2-D plots as inline SVG text (deterministic, no JavaScript).

* :func:`bar_chart`: one bar per point (residuals, effective radii);
* :func:`scatter_plot`: residual against polar angle;
* :func:`polar_map`: a value per direction on the hemisphere (effective radius);
* :func:`line_plot`: a sampled function (calibration results).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from probegen.report import palette
from probegen.report.numbers import fixed, signed
from probegen.report.svg import FONT, GRID, INK, Frame, axes, esc, framed, line, px, svg_open, text

WIDTH = 560.0
HEIGHT = 280.0


def bar_chart(values: Sequence[float], *, title: str, y_label: str,
              x_label: str = "point", decimals: int = 2) -> str:
    """Bars from 0 to each value, light when positive, dark when negative.

    Args:
        values: one value per point (point ``i`` is bar ``i + 1``).
        title: plot title.
        y_label: y axis label, with its unit.
        x_label: x axis label.
        decimals: decimals of the values in the tooltips.
    """
    n = len(values)
    every = max(1, math.ceil(n / 25))
    x_ticks = ([float(k) for k in range(1, n + 1, every)], 0)
    frame, _, yt = framed(WIDTH, HEIGHT, [], values, x_ticks=x_ticks, zero=True)
    frame = Frame(WIDTH, HEIGHT, (0.5, n + 0.5), frame.y_lim)
    out = [svg_open(WIDTH, HEIGHT, title)]
    out += axes(frame, x_ticks, yt, title=title, x_label=x_label, y_label=y_label)
    half = 0.35 * (frame.x(1.0) - frame.x(0.0))
    for i, v in enumerate(values, start=1):
        fill, edge = palette.by_sign(v)
        y0, y1 = sorted((frame.y(0.0), frame.y(v)))
        out.append(f'<rect x="{px(frame.x(i) - half)}" y="{px(y0)}" width="{px(2 * half)}" '
                   f'height="{px(y1 - y0)}" fill="{fill}" stroke="{edge}">'
                   f'<title>{i}: {esc(signed(v, decimals))}</title></rect>')
    out.append(line(frame.margin[0], frame.y(0.0), frame.width - frame.margin[1],
                    frame.y(0.0), INK))
    out.append("</svg>")
    return "\n".join(out)


def scatter_plot(xs: Sequence[float], ys: Sequence[float], *, title: str, x_label: str,
                 y_label: str, x_ticks: tuple[list[float], int] | None = None,
                 labels: Sequence[str] = ()) -> str:
    """Points coloured by the sign of y, with a zero line.

    Args:
        xs: x values.
        ys: y values.
        title: plot title.
        x_label: x axis label.
        y_label: y axis label.
        x_ticks: fixed x ticks (and their decimals); default nice ticks around ``xs``.
        labels: a tooltip per point.
    """
    frame, xt, yt = framed(WIDTH, HEIGHT, xs, ys, x_ticks=x_ticks, zero=True)
    lo, hi = frame.x_lim
    pad = 0.03 * (hi - lo)
    frame = Frame(WIDTH, HEIGHT, (lo - pad, hi + pad), frame.y_lim)
    out = [svg_open(WIDTH, HEIGHT, title)]
    out += axes(frame, xt, yt, title=title, x_label=x_label, y_label=y_label)
    out.append(line(frame.margin[0], frame.y(0.0), frame.width - frame.margin[1],
                    frame.y(0.0), INK, extra=' stroke-dasharray="4 3"'))
    for k, (x, y) in enumerate(zip(xs, ys, strict=True)):
        fill, edge = palette.by_sign(y)
        tip = f"<title>{esc(labels[k])}</title>" if k < len(labels) else ""
        out.append(f'<circle cx="{px(frame.x(x))}" cy="{px(frame.y(y))}" r="4.5" '
                   f'fill="{fill}" stroke="{edge}">{tip}</circle>')
    out.append("</svg>")
    return "\n".join(out)


def line_plot(xs: Sequence[float], ys: Sequence[float], *, title: str, x_label: str,
              y_label: str, band: Sequence[float] | None = None) -> str:
    """A polyline with a marker at each sample, over a shaded confidence band.

    Args:
        xs: positions, increasing.
        ys: values.
        title: plot title.
        x_label: x axis label.
        y_label: y axis label.
        band: half width of a band ``ys ± band`` drawn shaded under the line, or None.
    """
    lo = [y - b for y, b in zip(ys, band, strict=True)] if band is not None else []
    hi = [y + b for y, b in zip(ys, band, strict=True)] if band is not None else []
    frame, xt, yt = framed(WIDTH, HEIGHT, xs, [*ys, *lo, *hi])
    out = [svg_open(WIDTH, HEIGHT, title)]
    out += axes(frame, xt, yt, title=title, x_label=x_label, y_label=y_label)
    if band is not None:
        ring = [*zip(xs, hi, strict=True), *reversed(list(zip(xs, lo, strict=True)))]
        pts = " ".join(f"{px(frame.x(x))},{px(frame.y(y))}" for x, y in ring)
        out.append(f'<polygon class="band" points="{pts}" fill="{palette.LINE}" '
                   'fill-opacity="0.18" stroke="none"/>')
    pts = " ".join(f"{px(frame.x(x))},{px(frame.y(y))}" for x, y in zip(xs, ys, strict=True))
    out.append(f'<polyline points="{pts}" fill="none" stroke="{palette.LINE}" '
               'stroke-width="1.5"/>')
    out += [f'<circle cx="{px(frame.x(x))}" cy="{px(frame.y(y))}" r="2.5" '
            f'fill="{palette.LINE}"/>' for x, y in zip(xs, ys, strict=True)]
    out.append("</svg>")
    return "\n".join(out)


def polar_map(directions: Sequence[tuple[float, float, float]], values: Sequence[float],
              *, title: str, decimals: int = 1) -> str:
    """Values per direction on a polar disc: radius = polar angle from +Z, angle = azimuth.

    A dot at each direction, its area growing with ``|value|``, light when positive and
    dark when negative, the value printed under it.

    Args:
        directions: (n) unit vectors.
        values: (n) signed values (e.g. effective radius − nominal, µm).
        title: plot title.
        decimals: decimals of the labels.
    """
    size, radius = 420.0, 140.0
    cx, cy = size / 2, size / 2 + 4
    limit = 180.0 if any(_polar(d) > 90.0 + 1e-9 for d in directions) else 90.0
    out = [svg_open(size, size + 40, title),
           text(cx, 17, title, size=13, extra=' font-weight="bold"')]
    out += _polar_grid(cx, cy, radius, limit)
    biggest = max((abs(v) for v in values), default=0.0) or 1.0
    for d, v in zip(directions, values, strict=True):
        r, phi = _polar(d) / limit * radius, math.atan2(d[1], d[0])
        x, y = cx + r * math.cos(phi), cy - r * math.sin(phi)
        fill, edge = palette.by_sign(v)
        dot = 2.0 + 8.0 * math.sqrt(abs(v) / biggest)
        out.append(f'<circle cx="{px(x)}" cy="{px(y)}" r="{px(dot)}" fill="{fill}" '
                   f'stroke="{edge}"><title>{esc(signed(v, decimals))}</title></circle>')
        out.append(text(x, y + dot + 9, signed(v, decimals), size=9, extra=HALO))
    out.append(text(cx, size + 32, "radius: polar angle \u03b8 from +Z; "
                    "angle: azimuth \u03c6 from +X", size=FONT - 1))
    out.append("</svg>")
    return "\n".join(out)


HALO = ' paint-order="stroke" stroke="#ffffff" stroke-width="3"'
"""Attributes giving a label a white outline, legible over grid lines and dots."""


def _polar(d: tuple[float, float, float]) -> float:
    """Polar angle of a unit vector from +Z, degrees."""
    return math.degrees(math.acos(max(-1.0, min(1.0, d[2]))))


def _polar_grid(cx: float, cy: float, radius: float, limit: float) -> list[str]:
    """Rings every 30° of polar angle and spokes every 45° of azimuth, labelled; the
    rings' scale is a ruler under the disc, clear of the dots."""
    out = []
    rings = range(30, int(limit) + 1, 30)
    for ring in rings:
        out.append(f'<circle cx="{px(cx)}" cy="{px(cy)}" r="{px(ring / limit * radius)}" '
                   f'fill="none" stroke="{GRID if ring < limit else INK}"/>')
    for k in range(8):
        phi = math.radians(45.0 * k)
        x, y = cx + radius * math.cos(phi), cy - radius * math.sin(phi)
        out.append(line(cx, cy, x, y, GRID))
        lx, ly = cx + (radius + 32) * math.cos(phi), cy - (radius + 32) * math.sin(phi)
        out.append(text(lx, ly + 4, f"{45 * k}\u00b0", size=FONT - 1))
    ruler = cy + radius + 50
    out.append(line(cx, ruler, cx + radius, ruler, INK))
    out.append(text(cx - 6, ruler + 4, "\u03b8", anchor="end", size=FONT - 1))
    for ring in (0, *rings):
        x = cx + ring / limit * radius
        out.append(line(x, ruler - 3, x, ruler + 3, INK))
        out.append(text(x, ruler + 14, f"{ring}\u00b0", size=9))
    return out


def polar_angles(directions: Sequence[tuple[float, float, float]]) -> list[float]:
    """Polar angle of each direction from +Z, degrees."""
    return [_polar(d) for d in directions]


def azimuths(directions: Sequence[tuple[float, float, float]]) -> list[float]:
    """Azimuth of each direction from +X towards +Y, degrees in [0, 360)."""
    out = []
    for d in directions:
        a = math.degrees(math.atan2(d[1], d[0]))
        out.append(a + 360.0 if a < -1e-9 else max(a, 0.0))
    return out


def angle_ticks(angles: Sequence[float]) -> tuple[list[float], int]:
    """Ticks for a polar-angle axis: 0-90° by 15°, or 0-180° by 30°."""
    if any(a > 90.0 + 1e-9 for a in angles):
        return [float(a) for a in range(0, 181, 30)], 0
    return [float(a) for a in range(0, 91, 15)], 0


def fmt_angle(value: float) -> str:
    """An angle in degrees for labels."""
    return fixed(value, 1) + "\u00b0"
