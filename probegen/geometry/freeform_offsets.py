"""Where the extra touches of free-form compensation go (method M3, 2-D and micro-plane).

The planner (``planning/freeform.py``) puts the extra touches here and the compensation
(``evaluate/compensate_freeform.py``) expects them here, so plan and compensation agree:

* 2-D: two touches at ``∓spacing`` along the slope direction (the nominal normal's part
  ⟂ ``d``) around each guide point;
* micro-plane: ``count`` touches on a circle of radius ``ρ`` ⟂ ``d`` around the guide line.

Frames and units: part frame, mm; ``d`` (``probe_direction``) is the unit direction the
ball travels while probing (``(0, 0, −1)`` probing straight down).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from probegen.errors import ProbegenError
from probegen.geometry.frames import FloatArray, orthonormal_basis, unit

DOWN = (0.0, 0.0, -1.0)
"""Probing straight down (−Z), the seed's 3-axis setting."""

TWO_D_SPACING = 0.5
"""Default offset of the 2-D method's extra touches along the slope, mm (the seed's 0.5)."""

MICRO_PLANE_RADIUS = 0.5
"""Default radius of the micro-plane circle, mm: the top of the seed's 0.05–0.5 mm range,
which divides the noise amplification ``σ/ρ`` most."""

DEGENERATE = 1e-12
"""A cross product (mm²) or a chord (mm) shorter than this cannot give a normal."""


def finite_rows(values: ArrayLike, shape: tuple[int, ...], what: str) -> FloatArray:
    """``values`` as a finite float array of ``shape`` (``-1`` = any count)."""
    try:
        array = np.asarray(values, dtype=np.float64).reshape(shape)
    except (TypeError, ValueError) as exc:
        raise ProbegenError(f"{what}: expected an array of shape {shape}, {exc}") from None
    if not np.all(np.isfinite(array)):
        raise ProbegenError(f"{what}: expected finite numbers, found NaN or infinity")
    return array


def travel_direction(probe_direction: ArrayLike) -> FloatArray:
    """The unit travel direction ``d`` of a probing move."""
    return unit(probe_direction, what="probe direction")


def slope_directions(nominal_normals: ArrayLike, *,
                     probe_direction: ArrayLike = DOWN) -> FloatArray:
    """Unit direction of steepest slope ⟂ ``d`` at each point: the normal's part ⟂ ``d``.

    Where the normal is parallel to ``d`` (no slope) the first axis of
    ``orthonormal_basis(d)`` is used (+X probing down).  Returns ``(m, 3)``.
    """
    n = finite_rows(nominal_normals, (-1, 3), "slope directions: normals")
    d = travel_direction(probe_direction)
    across = n - np.outer(n @ d, d)
    length = np.linalg.norm(across, axis=1)
    fallback = orthonormal_basis(d)[0]
    flat = length < DEGENERATE
    out = np.where(flat[:, None], fallback, across / np.where(flat, 1.0, length)[:, None])
    return np.asarray(out)


def two_d_offsets(nominal_normals: ArrayLike, *, spacing: float = TWO_D_SPACING,
                  probe_direction: ArrayLike = DOWN) -> FloatArray:
    """Where the 2-D method's extra touches go: ``(m, 2, 3)`` offsets ``∓spacing·slope``.

    Add them to the guide points (or guide-line origins); probe along the same ``d``.
    """
    if not (math.isfinite(spacing) and spacing > 0.0):
        raise ProbegenError(f"2-D spacing: expected a positive length in mm, found {spacing!r}")
    s = slope_directions(nominal_normals, probe_direction=probe_direction)
    return np.asarray(np.stack([-spacing * s, spacing * s], axis=1))


def micro_plane_offsets(*, radius: float = MICRO_PLANE_RADIUS, count: int = 3,
                        phase: float = 0.0, probe_direction: ArrayLike = DOWN) -> FloatArray:
    """Where the micro-plane touches go: ``(count, 3)`` offsets on a circle ⟂ ``d``.

    Args:
        radius: circle radius ``ρ``, mm (the seed uses 0.05–0.5 mm).
        count: touches, equally spaced (3: the seed; 4 cancels the quadratic aliasing).
        phase: angle of the first touch from the first axis of ``orthonormal_basis(d)``, rad.
        probe_direction: travel direction ``d``.
    """
    if not (math.isfinite(radius) and radius > 0.0):
        raise ProbegenError(f"micro-plane radius: expected a positive length in mm, found "
                            f"{radius!r}")
    if isinstance(count, bool) or not isinstance(count, int) or count < 3:
        raise ProbegenError(f"micro-plane touches: expected an integer >= 3, found {count!r}")
    basis = orthonormal_basis(travel_direction(probe_direction))
    angles = phase + np.arange(count) * 2.0 * math.pi / count
    return np.asarray(radius * (np.outer(np.cos(angles), basis[0])
                                + np.outer(np.sin(angles), basis[1])))
