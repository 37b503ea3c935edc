"""Ball centre → contact point, along the nominal surface normal.

A touch-trigger probe reports the ball centre ``O`` at the trigger; the contact point is
``P = O − r·n`` with ``n`` the outward unit normal of the surface and ``r`` the ball's
effective radius.  Compensating along the move axis instead of the normal is the classic
error of open probing macros (tens of micrometres on a slope); here it is always the
normal.

The effective radius is either one number (the nominal ball radius, or the mean effective
radius of a probe calibration) or a ``ProbeCalibration``: effective radii measured in a set
of directions by the sphere test (method M1), interpolated between them by inverse-distance
weighting on the unit sphere (exact at the measured directions).

Calibration file (TOML, written by ``probegen ingest --write-calibration``)::

    [calibration]
    ball_radius = 3.0            # nominal, mm
    effective_radius = 2.9981    # mean effective radius, mm
    source = "run.log"
    directions = [[0.0, 0.0, 1.0], ...]    # unit vectors, probe frame
    radii = [2.9979, ...]                  # effective radius in each direction, mm
    u_radius = 0.0002            # standard uncertainty of the effective radius, mm
                                 # (optional, 0 when absent: files before it)
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from probegen.errors import SpecError
from probegen.tomlread import Table, load_toml

IDW_POWER = 4.0
"""Power of the inverse-distance weights: high enough that a direction's own radius
dominates near it, low enough to blend smoothly between the measured directions."""


@dataclass(frozen=True, slots=True)
class ProbeCalibration:
    """Effective stylus radii by direction (from the sphere test).

    Attributes:
        ball_radius: nominal ball radius, mm.
        effective_radius: mean effective radius, mm.
        directions: unit vectors where the radius was measured.
        radii: the effective radius in each direction, mm.
        source: where the calibration came from.
        u_radius: standard uncertainty of the effective radius, mm (from the sphere
            test's fit; 0 when the file does not state it).
    """

    ball_radius: float
    effective_radius: float
    directions: tuple[tuple[float, float, float], ...]
    radii: tuple[float, ...]
    source: str = ""
    u_radius: float = 0.0

    def radius(self, normals: ArrayLike) -> NDArray[np.float64]:
        """Effective radius for each approach normal ``normals : (n, 3)``; returns (n,)."""
        n = np.asanyarray(normals, dtype=np.float64).reshape(-1, 3)
        if not self.directions:
            return np.full(len(n), self.effective_radius)
        d = np.asarray(self.directions)
        r = np.asarray(self.radii)
        dist = np.linalg.norm(n[:, None, :] - d[None, :, :], axis=2)
        exact = dist < 1e-12
        w = 1.0 / np.maximum(dist, 1e-12) ** IDW_POWER
        w = np.where(exact.any(axis=1, keepdims=True), exact.astype(float), w)
        return np.asarray((w @ r) / w.sum(axis=1))


def compensate(centres: ArrayLike, normals: ArrayLike,
               radius: float | ProbeCalibration) -> NDArray[np.float64]:
    """Contact points ``P = O − r(n)·n``.

    Args:
        centres: (n, 3) ball centres reported at the trigger.
        normals: (n, 3) outward unit surface normals (nominal, or estimated).
        radius: effective ball radius, or a calibration giving it by direction.

    Returns:
        (n, 3) float contact points.
    """
    o = np.asanyarray(centres, dtype=np.float64).reshape(-1, 3)
    n = np.asanyarray(normals, dtype=np.float64).reshape(-1, 3)
    n = n / np.linalg.norm(n, axis=1, keepdims=True)
    r = radius.radius(n) if isinstance(radius, ProbeCalibration) else np.full(len(n), radius)
    return np.asarray(o - r[:, None] * n)


def load_calibration(path: str | Path) -> ProbeCalibration:
    """Read a calibration file (see the module docstring); errors name file and key."""
    file = str(path)
    root = Table(load_toml(path), file, "")
    t = root.table("calibration", required=True)
    directions = t.get_any("directions", [])
    radii = t.get_any("radii", [])
    cal = ProbeCalibration(
        ball_radius=t.get_float("ball_radius", required=True, positive=True) or 0.0,
        effective_radius=t.get_float("effective_radius", required=True, positive=True) or 0.0,
        directions=_directions(t, directions),
        radii=_radii(t, radii),
        source=t.get_str("source", "") or "",
        u_radius=t.get_float("u_radius", 0.0, minimum=0.0, maximum=1.0) or 0.0,
    )
    if len(cal.directions) != len(cal.radii):
        raise SpecError(f"{t.where('radii')}: expected one radius per direction "
                        f"({len(cal.directions)}), found {len(cal.radii)}")
    t.done()
    root.done()
    return cal


def _directions(t: Table, value: object) -> tuple[tuple[float, float, float], ...]:
    out = []
    if not isinstance(value, list):
        raise t.fail("directions", "an array of [x, y, z] unit vectors")
    for v in value:
        ok = isinstance(v, list) and len(v) == 3 and all(
            isinstance(c, int | float) and not isinstance(c, bool) for c in v)
        if not ok or abs(math.hypot(*v) - 1.0) > 1e-6:
            raise t.fail("directions", "an array of [x, y, z] unit vectors")
        out.append((float(v[0]), float(v[1]), float(v[2])))
    return tuple(out)


def _radii(t: Table, value: object) -> tuple[float, ...]:
    ok = isinstance(value, list) and all(
        isinstance(c, int | float) and not isinstance(c, bool) and c > 0 for c in value)
    if not ok:
        raise t.fail("radii", "an array of positive numbers")
    assert isinstance(value, list)
    return tuple(float(c) for c in value)


def calibration_toml(cal: ProbeCalibration) -> str:
    """The calibration as TOML text (fixed decimals, repeatable)."""
    dirs = ",\n    ".join(f"[{x:.9f}, {y:.9f}, {z:.9f}]" for x, y, z in cal.directions)
    radii = ", ".join(f"{r:.7f}" for r in cal.radii)
    return (
        "# Probe calibration written by probegen (sphere test, method M1).\n"
        "[calibration]\n"
        f"ball_radius = {cal.ball_radius:.7f}\n"
        f"effective_radius = {cal.effective_radius:.7f}\n"
        f"source = {_quote(cal.source)}\n"
        f"directions = [\n    {dirs},\n]\n"
        f"radii = [{radii}]\n"
        f"u_radius = {cal.u_radius:.7f}\n"
    )


def _quote(text: str) -> str:
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"') + '"'
