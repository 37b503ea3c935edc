"""Inline SVG building blocks: a plot frame with "nice" ticks, deterministic text.

Coordinates are printed with 2 decimals (px), tick labels with as many decimals as the
tick step needs, so a plot is the same bytes for the same data.  No ``xmlns``: inline
SVG in HTML5 needs none, and the report holds no URL at all.
"""

from __future__ import annotations

import html
import math
from collections.abc import Sequence
from dataclasses import dataclass

from probegen.report.numbers import fixed

FONT = 11
"""Font size of tick labels, px."""

INK = "#333333"
GRID = "#e3e3e3"


def px(value: float) -> str:
    """A pixel coordinate as printed in the SVG."""
    return fixed(value, 2)


def esc(text: str) -> str:
    """Text escaped for SVG/HTML content and attributes."""
    return html.escape(text, quote=True)


def nice_ticks(lo: float, hi: float, count: int = 5) -> tuple[list[float], int]:
    """Round tick values covering ``[lo, hi]`` and the decimals their labels need.

    Args:
        lo: lower end of the data.
        hi: upper end of the data.
        count: about how many ticks.

    Returns:
        (ticks, decimals): ticks are multiples of 1, 2 or 5 × 10^k; the first is
        ``<= lo`` and the last ``>= hi``.
    """
    if not hi > lo:
        pad = abs(lo) * 0.1 or 1.0
        lo, hi = lo - pad, hi + pad
    raw = (hi - lo) / max(count, 1)
    power = 10.0 ** math.floor(math.log10(raw))
    step = next(m * power for m in (1.0, 2.0, 5.0, 10.0) if m * power >= raw * (1 - 1e-9))
    first, last = math.floor(lo / step + 1e-9), math.ceil(hi / step - 1e-9)
    decimals = max(0, -math.floor(math.log10(step) + 1e-9))
    return [k * step for k in range(first, last + 1)], decimals


@dataclass(frozen=True, slots=True)
class Frame:
    """Data → pixel mapping of one plot.

    Attributes:
        width: total width, px.
        height: total height, px.
        x_lim: data range along x (left, right).
        y_lim: data range along y (bottom, top).
        margin: left, right, top, bottom margins, px.
    """

    width: float
    height: float
    x_lim: tuple[float, float]
    y_lim: tuple[float, float]
    margin: tuple[float, float, float, float] = (58.0, 16.0, 28.0, 42.0)

    def x(self, value: float) -> float:
        """Pixel x of a data x."""
        left, right = self.margin[0], self.width - self.margin[1]
        lo, hi = self.x_lim
        return left + (value - lo) / (hi - lo) * (right - left)

    def y(self, value: float) -> float:
        """Pixel y of a data y."""
        top, bottom = self.margin[2], self.height - self.margin[3]
        lo, hi = self.y_lim
        return bottom - (value - lo) / (hi - lo) * (bottom - top)


def svg_open(width: float, height: float, label: str) -> str:
    """The ``<svg>`` start tag of a plot ``width`` × ``height`` px."""
    return (f'<svg class="plot" viewBox="0 0 {px(width)} {px(height)}" width="{px(width)}" '
            f'height="{px(height)}" role="img" aria-label="{esc(label)}">')


def text(x: float, y: float, content: str, *, anchor: str = "middle", size: int = FONT,
         extra: str = "") -> str:
    """A ``<text>`` element."""
    return (f'<text x="{px(x)}" y="{px(y)}" font-size="{size}" text-anchor="{anchor}"'
            f'{extra}>{esc(content)}</text>')


def line(x1: float, y1: float, x2: float, y2: float, stroke: str, *, width: float = 1.0,
         extra: str = "") -> str:
    """A ``<line>`` element."""
    return (f'<line x1="{px(x1)}" y1="{px(y1)}" x2="{px(x2)}" y2="{px(y2)}" '
            f'stroke="{stroke}" stroke-width="{fixed(width, 2)}"{extra}/>')


def axes(frame: Frame, x_ticks: tuple[Sequence[float], int],
         y_ticks: tuple[Sequence[float], int], *, title: str, x_label: str,
         y_label: str) -> list[str]:
    """Grid, tick labels, axis labels and title of a cartesian plot."""
    out = [text(frame.width / 2, 17, title, size=13, extra=' font-weight="bold"')]
    top, bottom = frame.margin[2], frame.height - frame.margin[3]
    left, right = frame.margin[0], frame.width - frame.margin[1]
    for value in x_ticks[0]:
        x = frame.x(value)
        out.append(line(x, top, x, bottom, GRID))
        out.append(text(x, bottom + 15, fixed(value, x_ticks[1])))
    for value in y_ticks[0]:
        y = frame.y(value)
        out.append(line(left, y, right, y, GRID))
        out.append(text(left - 6, y + 4, fixed(value, y_ticks[1]), anchor="end"))
    out.append(f'<rect x="{px(left)}" y="{px(top)}" width="{px(right - left)}" '
               f'height="{px(bottom - top)}" fill="none" stroke="{INK}"/>')
    out.append(text((left + right) / 2, frame.height - 8, x_label))
    cy = (top + bottom) / 2
    out.append(text(14, cy, y_label, extra=f' transform="rotate(-90 14 {px(cy)})"'))
    return out


def framed(width: float, height: float, xs: Sequence[float], ys: Sequence[float],
           *, x_ticks: tuple[list[float], int] | None = None, zero: bool = False,
           ) -> tuple[Frame, tuple[list[float], int], tuple[list[float], int]]:
    """A frame whose ranges are the nice tick ranges around the data.

    Args:
        width: plot width, px.
        height: plot height, px.
        xs: x data (ignored when ``x_ticks`` is given).
        ys: y data.
        x_ticks: fixed x ticks and their decimals; the x range is first to last.
        zero: include 0 in the y range.

    Returns:
        (frame, x_ticks, y_ticks).
    """
    xt = x_ticks if x_ticks else nice_ticks(min(xs), max(xs))
    yt = nice_ticks(min([*ys, 0.0] if zero else ys), max([*ys, 0.0] if zero else ys))
    frame = Frame(width, height, (xt[0][0], xt[0][-1]), (yt[0][0], yt[0][-1]))
    return frame, xt, yt
