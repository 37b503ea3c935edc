"""The report's colours, one place for the 3-D views, the SVG plots and the legends."""

from __future__ import annotations

PATH = {
    "rapid": "#d62728",
    "protected": "#1f77b4",
    "touch": "#2ca02c",
    "other": "#9467bd",
}
"""Stylus path segments by group (``model.Segment.group``)."""

REFERENCE = "#c4c4c4"
"""Wireframe of the nominal sphere."""

POINT = "#111111"
"""Measured contact points."""

LIGHT = "#f2d492"
"""Error balls and bars for a positive residual: material outside the surface (along
the outward material normal; docs/results.md), whatever the kind."""

LIGHT_EDGE = "#9c7a22"

DARK = "#2e3a59"
"""Error balls and bars for a negative residual: material missing (inside the surface)."""

DARK_EDGE = "#11182a"

LINE = "#1f77b4"
"""Line plots of calibration functions."""


def by_sign(value: float) -> tuple[str, str]:
    """(fill, edge) for a signed residual: light when positive, dark otherwise."""
    return (LIGHT, LIGHT_EDGE) if value > 0 else (DARK, DARK_EDGE)

TOLERANCE = "#d62728"
"""Tolerance limits (LSL, USL) of the trend charts."""

CONTROL = "#ff7f0e"
"""Control limits (LCL, UCL) of the trend charts, and points in a run or trend."""

CENTRE = "#2ca02c"
"""The centre line of the trend charts."""

OUT_OF_CONTROL = "#d62728"
"""A point beyond the control limits."""

MUTED = "#9a9a9a"
"""Single values behind subgroup means, NOT EVALUATED runs."""
