"""Form by the ISO 1101 minimum zone (Chebyshev fit): the narrowest zone holding the points.

A form value is the width of a zone between two surfaces of the nominal kind: two
concentric circles (roundness), coaxial cylinders (cylindricity), parallel planes
(flatness), parallel lines in a plane (straightness in a plane), concentric spheres
(sphericity); or the diameter of the thinnest cylinder about a line in space
(straightness of a 3-D line).  ISO 1101 defines it by the *minimum* zone: the pose of
the zone (centre, axis, orientation) that makes it narrowest.  The least-squares zone
(the range of the residuals about the least-squares fit) is never narrower, and is
often 10 to 30 % wider on lobed or tilted data.

Method: start from the least-squares pose; linearise the residuals ``r(p)`` (one per
point: distance from the centre, axis or plane) in the pose parameters ``p``; solve the
linear program

    minimise  u - l   subject to  l <= r_i + J_i s <= u,  |s_k| <= trust_k

(``scipy.optimize.linprog``, HiGHS; for a 3-D line, ``u`` alone with ``r_i + J_i s <=
u``); take the step if the true zone is narrower, else halve the trust region; repeat
until the trust region is below ``STEP`` (relative to the points' spread).  Every
accepted step narrows the zone, so the result is never wider than least squares.  The
Chebyshev problems of the kinds above are convex in the neighbourhood of the least-
squares pose for points spread over the feature, so the iteration reaches the minimum
zone (checked against constructed zones in ``tests/test_minimum_zone.py``).

All lengths are in the points' unit (mm); the pose parameters are scaled internally.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike
from scipy.optimize import linprog

from probegen.geometry.fits_solver import FloatArray
from probegen.geometry.frames import rotation_to_z

LABELS = {"minimum_zone": "minimum zone", "least_squares": "least squares"}
"""How each method is named in the outputs."""

#: Trust region of the first step, relative to the spread of the points.
TRUST = 0.05
#: Stop when the trust region falls below this, relative to the spread.
STEP = 1e-10
#: Most linear programs solved for one zone.
ITERATIONS = 200

Residuals = Callable[[FloatArray], FloatArray]


def _zone(r: FloatArray, one_sided: bool) -> float:
    return float(2.0 * np.max(r)) if one_sided else float(np.max(r) - np.min(r))


def _jacobian(fn: Residuals, p: FloatArray, h: float) -> FloatArray:
    """Central differences of ``fn`` at ``p`` with step ``h``, ``(n, len(p))``."""
    cols = []
    for k in range(len(p)):
        e = np.zeros_like(p)
        e[k] = h
        cols.append((fn(p + e) - fn(p - e)) / (2.0 * h))
    return np.column_stack(cols)


def chebyshev(fn: Residuals, p0: FloatArray, spread: float, *,
              one_sided: bool = False) -> tuple[float, FloatArray]:
    """Narrowest zone of the residuals ``fn(p)`` over pose parameters ``p``.

    Args:
        fn: ``p (k,) -> residuals (n,)``, in length units; ``p`` in length units too
            (angles as tangents times ``spread``; the callers scale them so).
        p0: ``(k,)`` the starting (least-squares) pose.
        spread: the points' spread (length), sets the trust region and the stop.
        one_sided: the zone is ``2 max r`` (a line in space), not ``max r - min r``.

    Returns:
        ``(zone width, pose)``; never wider than at ``p0``.
    """
    p = np.asarray(p0, dtype=np.float64).copy()
    r = fn(p)
    best = _zone(r, one_sided)
    trust = TRUST * spread
    for _ in range(ITERATIONS):
        if trust < STEP * spread or best == 0.0:
            break
        jac = _jacobian(fn, p, max(1e-7 * spread, 1e-12))
        step = _lp_step(r, jac, trust, one_sided)
        if step is None:
            break
        trial = p + step
        r_new = fn(trial)
        zone = _zone(r_new, one_sided)
        if zone < best:
            p, r, best = trial, r_new, zone
            if float(np.max(np.abs(step))) < 0.5 * trust:
                trust *= 0.5  # the linear optimum is inside: it is close
        else:
            trust *= 0.5
    return best, p


def _lp_step(r: FloatArray, jac: FloatArray, trust: float,
             one_sided: bool) -> FloatArray | None:
    """The step of the linearised Chebyshev problem (variables ``s``, ``u``, ``l``)."""
    n, k = jac.shape
    ones = np.ones((n, 1))
    if one_sided:  # minimise u: r + J s <= u
        c = np.concatenate([np.zeros(k), [1.0]])
        a_ub = np.hstack([jac, -ones])
        b_ub = -r
        bounds = [(-trust, trust)] * k + [(None, None)]
    else:  # minimise u - l: r + J s <= u, l <= r + J s
        c = np.concatenate([np.zeros(k), [1.0, -1.0]])
        a_ub = np.vstack([np.hstack([jac, -ones, np.zeros((n, 1))]),
                          np.hstack([-jac, np.zeros((n, 1)), ones])])
        b_ub = np.concatenate([-r, r])
        bounds = [(-trust, trust)] * k + [(None, None), (None, None)]
    out = linprog(c, A_ub=a_ub, b_ub=b_ub, bounds=bounds, method="highs")
    if out.status != 0 or out.x is None:
        return None
    return np.asarray(out.x[:k], dtype=np.float64)


# ----------------------------------------------------------------------- per kind


def _spread(points: FloatArray) -> float:
    centred = points - points.mean(axis=0)
    return max(float(np.sqrt(np.mean(np.sum(centred * centred, axis=1)))), 1e-12)


def roundness(points: ArrayLike, centre: ArrayLike) -> float:
    """Minimum-zone roundness of ``points : (n, 2)`` (in the section's plane) from the
    least-squares ``centre : (2,)``: the radial width of the narrowest annulus."""
    q = np.asarray(points, dtype=np.float64)
    return chebyshev(lambda c: np.hypot(q[:, 0] - c[0], q[:, 1] - c[1]),
                     np.asarray(centre, dtype=np.float64), _spread(q))[0]


def sphericity(points: ArrayLike, centre: ArrayLike) -> float:
    """Minimum-zone sphericity of ``points : (n, 3)`` from the least-squares
    ``centre``: the radial width of the narrowest spherical shell."""
    q = np.asarray(points, dtype=np.float64)
    return chebyshev(lambda c: np.linalg.norm(q - c, axis=1),
                     np.asarray(centre, dtype=np.float64), _spread(q))[0]


def _local(points: ArrayLike, point: ArrayLike, axis: ArrayLike) -> tuple[FloatArray, float]:
    """``points`` in a frame with ``axis`` as +Z through ``point``, and their spread."""
    q = np.asarray(points, dtype=np.float64) - np.asarray(point, dtype=np.float64)
    local = q @ rotation_to_z(np.asarray(axis, dtype=np.float64)).T
    return local, _spread(local)


def _line_distances(q: FloatArray, spread: float) -> Residuals:
    """The distances of local points ``q`` from a line near the local z axis, as a
    function of its 4 pose parameters (a shift in x, y; a tilt in x, y over ``spread``):
    the model of cylindricity and of the straightness of a line in space."""

    def distances(p: FloatArray) -> FloatArray:
        d = np.array([p[2] / spread, p[3] / spread, 1.0])
        d /= np.linalg.norm(d)
        rel = q - np.array([p[0], p[1], 0.0])
        return np.asarray(np.linalg.norm(np.cross(rel, d), axis=1))

    return distances


def cylindricity(points: ArrayLike, point: ArrayLike, axis: ArrayLike) -> float:
    """Minimum-zone cylindricity of ``points : (n, 3)`` from the least-squares axis
    (``point``, unit ``axis``): the radial width of the narrowest coaxial shell."""
    q, spread = _local(points, point, axis)

    distances = _line_distances(q, spread)
    return chebyshev(distances, np.zeros(4), spread)[0]


def flatness(points: ArrayLike, point: ArrayLike, normal: ArrayLike) -> float:
    """Minimum-zone flatness of ``points : (n, 3)`` from the least-squares plane
    (``point``, unit ``normal``): the distance between the closest parallel planes."""
    q, spread = _local(points, point, normal)

    def heights(p: FloatArray) -> FloatArray:
        n = np.array([p[0] / spread, p[1] / spread, 1.0])
        return np.asarray(q @ n / np.linalg.norm(n))

    return chebyshev(heights, np.zeros(2), spread)[0]


def straightness_2d(points: ArrayLike, point: ArrayLike, direction: ArrayLike) -> float:
    """Minimum-zone straightness of ``points : (n, 2)`` from the least-squares line
    (``point``, unit ``direction``): the distance between the closest parallel lines."""
    d = np.asarray(direction, dtype=np.float64)
    normal = np.array([-d[1], d[0]])
    q = np.asarray(points, dtype=np.float64) - np.asarray(point, dtype=np.float64)
    u, v = q @ d, q @ normal
    spread = _spread(q)

    def offsets(p: FloatArray) -> FloatArray:
        return np.asarray((v - (p[0] / spread) * u) / math.hypot(1.0, p[0] / spread))

    return chebyshev(offsets, np.zeros(1), spread)[0]


def straightness_3d(points: ArrayLike, point: ArrayLike, direction: ArrayLike) -> float:
    """Minimum-zone straightness of a line in space, ``points : (n, 3)``, from the
    least-squares line: the diameter of the thinnest cylinder holding the points."""
    q, spread = _local(points, point, direction)

    distances = _line_distances(q, spread)
    return chebyshev(distances, np.zeros(4), spread, one_sided=True)[0]
