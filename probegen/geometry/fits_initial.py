"""Starting guesses for the iterative fits: algebraic (linear) fits and candidate axes.

All functions take *normalised* points (centroid at the origin, RMS norm 1, see
``fits_solver.normalise``) and return ``None`` when the data do not give a guess, so a
caller can try the next candidate.
"""

from __future__ import annotations

import math

import numpy as np

from probegen.geometry.fits_solver import FloatArray

#: Two candidate axes closer than this (|cos| above 1 - PARALLEL) are one candidate.
PARALLEL = 1e-6
#: Fewest points for the general-quadric axis guess (it has 9 degrees of freedom).
QUADRIC_MINIMUM = 10


def _lstsq(lhs: FloatArray, rhs: FloatArray) -> FloatArray:
    """Least-squares solution of ``lhs @ x = rhs``."""
    return np.asarray(np.linalg.lstsq(lhs, rhs, rcond=None)[0], dtype=np.float64)


def algebraic_circle(xy: FloatArray) -> tuple[FloatArray, float] | None:
    """Kasa's algebraic circle: ``|p|^2 = 2 c . p + k`` solved linearly.

    Args:
        xy: ``(n, 2)`` points.

    Returns:
        ``(centre (2,), radius)`` or ``None`` if the points give no circle.
    """
    lhs = np.column_stack([2.0 * xy, np.ones(len(xy))])
    sol = _lstsq(lhs, np.sum(xy * xy, axis=1))
    r2 = sol[2] + sol[:2] @ sol[:2]
    if not (np.isfinite(r2) and r2 > 0.0):
        return None
    return sol[:2], math.sqrt(r2)


def algebraic_sphere(points: FloatArray) -> tuple[FloatArray, float] | None:
    """Algebraic sphere ``|p|^2 = 2 c . p + k`` for ``points : (n, 3)``.

    Returns:
        ``(centre (3,), radius)`` or ``None``.
    """
    lhs = np.column_stack([2.0 * points, np.ones(len(points))])
    sol = _lstsq(lhs, np.sum(points * points, axis=1))
    r2 = sol[3] + sol[:3] @ sol[:3]
    if not (np.isfinite(r2) and r2 > 0.0):
        return None
    return sol[:3], math.sqrt(r2)


def algebraic_cone(q: FloatArray) -> tuple[FloatArray, float, float] | None:
    """Cone about +Z with radius linear in z, from ``x^2 + y^2 = 2 x0 x + 2 y0 y + c0 +
    c1 z + c2 z^2`` solved linearly (``(r0 + k z)^2 = c0 + x0^2 + y0^2 + c1 z + c2 z^2``).

    Args:
        q: ``(n, 3)`` points in a frame whose +Z is the candidate axis.

    Returns:
        ``(centre (2,) at z = 0, radius r0 at z = 0, slope k = dr/dz)`` or ``None``.
    """
    x, y, z = q.T
    lhs = np.column_stack([2.0 * x, 2.0 * y, np.ones(len(q)), z, z * z])
    sol = _lstsq(lhs, x * x + y * y)
    r2 = sol[2] + sol[:2] @ sol[:2]
    if not (np.isfinite(r2) and r2 > 0.0):
        return None
    slope = math.copysign(math.sqrt(max(float(sol[4]), 0.0)), float(sol[3]))
    return sol[:2], math.sqrt(r2), slope


def _quadric_axes(points: FloatArray) -> FloatArray | None:
    """Eigenvectors (rows, ``(3, 3)``) of the quadratic part of the algebraic quadric
    through ``points : (n, 3)``; a cylinder's or cone's axis is one of them."""
    if len(points) < QUADRIC_MINIMUM:
        return None
    x, y, z = points.T
    design = np.column_stack([x * x, y * y, z * z, x * y, x * z, y * z, x, y, z,
                              np.ones(len(points))])
    coef = np.linalg.svd(design, full_matrices=False)[2][-1]
    quad = np.array([[coef[0], coef[3] / 2, coef[4] / 2],
                     [coef[3] / 2, coef[1], coef[5] / 2],
                     [coef[4] / 2, coef[5] / 2, coef[2]]])
    if not np.all(np.isfinite(quad)):
        return None
    vectors: FloatArray = np.linalg.eigh(quad)[1].T
    return vectors


def candidate_axes(points: FloatArray, directions: FloatArray) -> list[FloatArray]:
    """Distinct candidate axes for a surface of revolution.

    Args:
        points: ``(n, 3)`` normalised points.
        directions: ``(3, 3)`` principal directions of the points (rows).

    Returns:
        Unit ``(3,)`` vectors: the principal directions (a long cylinder's axis is the
        first, a disc's or a torus' the last) and the quadric's eigenvectors.
    """
    pool = [directions]
    quadric = _quadric_axes(points)
    if quadric is not None:
        pool.append(quadric)
    found: list[FloatArray] = []
    for axis in np.vstack(pool):
        if all(abs(float(axis @ other)) < 1.0 - PARALLEL for other in found):
            found.append(axis)
    return found
