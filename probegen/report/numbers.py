"""Number formatting for the report: fixed decimals, never ``-0``, never an exponent.

Every number the report prints (table cells, SVG coordinates, tick labels, the 3-D
scene's JSON) goes through :func:`fixed`, so the same results give the same bytes.
"""

from __future__ import annotations

import math


def fixed(value: float, decimals: int) -> str:
    """``value`` with exactly ``decimals`` decimals; ``-0.000`` is printed as ``0.000``.

    Args:
        value: a finite number.
        decimals: digits after the point (0 prints an integer).

    Returns:
        The text, e.g. ``fixed(-0.00001, 3) == "0.000"``.
    """
    if not math.isfinite(value):
        return "0" if decimals == 0 else "0." + "0" * decimals
    text = f"{value:.{decimals}f}"
    if text.startswith("-") and text.strip("-0.") == "":
        text = text[1:]
    return text


def signed(value: float, decimals: int) -> str:
    """Like :func:`fixed` with an explicit ``+`` on positive values (zero has none)."""
    text = fixed(value, decimals)
    return text if text.startswith("-") or text.strip("0.") == "" else "+" + text


def compact(value: float, decimals: int) -> str:
    """Fixed decimals with trailing zeros (and a bare point) removed: ``1.5000 -> 1.5``."""
    text = fixed(value, decimals)
    if "." in text:
        text = text.rstrip("0").rstrip(".")
    return "0" if text in ("", "-0") else text
