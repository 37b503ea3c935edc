"""Least-squares (Gaussian, orthogonal distance) fits of the features probegen measures.

Line (2-D and 3-D) and plane fits are closed form (principal directions of the centred
points).  Circle, sphere, cylinder, cone and torus fits start from algebraic fits and
are refined by Levenberg-Marquardt to the orthogonal-distance optimum; the 3-D circle
follows NIST: least-squares plane, projection, least-squares circle in that plane.

Every fit takes ``points : (n, 3) float`` (``(n, 2)`` for the 2-D line and circle),
returns a frozen record of plain Python floats (``probegen.geometry.fits_results``
documents the residual sign, direction sign and axis-point conventions), and raises
``ProbegenError`` naming the fit, what it needed and what it found for input it cannot
use: too few points, NaN/inf, coincident, collinear or (sphere) coplanar points.

The implementation is validated against the NIST least-squares reference pairs
(``tests/test_fits_nist.py``).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from probegen.geometry.fits_axial import fit_cone, fit_cylinder, fit_torus
from probegen.geometry.fits_conditioning import assess_model, assess_plane, line_condition
from probegen.geometry.fits_initial import algebraic_circle, algebraic_sphere
from probegen.geometry.fits_results import (
    Circle2dFit,
    Circle3dFit,
    ConeFit,
    CylinderFit,
    Line2dFit,
    Line3dFit,
    PlaneFit,
    SphereFit,
    TorusFit,
)
from probegen.geometry.fits_solver import (
    FloatArray,
    Model,
    Normalised,
    Pose,
    as_points,
    canonical,
    check_finite,
    columns,
    fit_error,
    guarded,
    inverse,
    jacobian_at,
    normalise,
    norms,
    polish,
    require_rank,
    step_tolerance,
    subsample,
    summary,
    vec2,
    vec3,
)
from probegen.geometry.frames import orthonormal_basis

__all__ = [
    "Circle2dFit",
    "Circle3dFit",
    "ConeFit",
    "CylinderFit",
    "Line2dFit",
    "Line3dFit",
    "PlaneFit",
    "SphereFit",
    "TorusFit",
    "fit_circle_2d",
    "fit_circle_3d",
    "fit_cone",
    "fit_cylinder",
    "fit_line_2d",
    "fit_line_3d",
    "fit_plane",
    "fit_sphere",
    "fit_torus",
]

# ------------------------------------------------------------------ closed form


@guarded("2-D line")
def fit_line_2d(points: ArrayLike) -> Line2dFit:
    """Least-squares line in the plane.

    Args:
        points: ``(n, 2)`` float, ``n >= 2``, not all the same point.

    Returns:
        The fit: centroid, direction (largest-magnitude component positive), normal
        (direction turned +90 degrees) and residuals signed along the normal.

    Raises:
        ProbegenError: too few, non-finite or coincident points.
    """
    data = normalise(as_points(points, fit="2-D line", dim=2, minimum=2), fit="2-D line")
    direction = canonical(data.directions[0])
    normal = np.array([-direction[1], direction[0]])
    residuals, rms, form = summary("2-D line", data.points @ normal * data.scale)
    return Line2dFit(vec2(data.centre), vec2(direction), vec2(normal),
                     residuals, rms, form, len(residuals), line_condition(data))


@guarded("3-D line")
def fit_line_3d(points: ArrayLike) -> Line3dFit:
    """Least-squares line in space.

    Args:
        points: ``(n, 3)`` float, ``n >= 2``, not all the same point.

    Returns:
        The fit: centroid, direction (largest-magnitude component positive) and the
        unsigned distance of each point from the line.

    Raises:
        ProbegenError: too few, non-finite or coincident points.
    """
    data = normalise(as_points(points, fit="3-D line", dim=3, minimum=2), fit="3-D line")
    direction = canonical(data.directions[0])
    across = data.points - np.outer(data.points @ direction, direction)
    dist = np.sqrt(np.sum(across * across, axis=1)) * data.scale
    residuals, rms, _ = summary("3-D line", dist)
    form = 2.0 * float(np.max(dist))
    check_finite("3-D line", form)
    return Line3dFit(vec3(data.centre), vec3(direction), residuals, rms, form, len(residuals),
                     line_condition(data))


def _plane(points: ArrayLike, fit: str) -> tuple[Normalised, FloatArray, float]:
    """Normalised points (at least 3, not collinear), their unit plane normal and the
    plane's condition number."""
    data = normalise(as_points(points, fit=fit, dim=3, minimum=3), fit=fit)
    require_rank(data, 2, fit=fit, expected="at least 3 points not all collinear")
    normal = canonical(data.directions[2])
    return data, normal, assess_plane(fit, data, normal, data.points @ normal)


@guarded("plane")
def fit_plane(points: ArrayLike) -> PlaneFit:
    """Least-squares plane.

    Args:
        points: ``(n, 3)`` float, ``n >= 3``, not all collinear.

    Returns:
        The fit: centroid, normal (largest-magnitude component positive) and residuals
        signed along the normal.

    Raises:
        ProbegenError: too few, non-finite or collinear points.
    """
    data, normal, condition = _plane(points, "plane")
    residuals, rms, form = summary("plane", data.points @ normal * data.scale)
    return PlaneFit(vec3(data.centre), vec3(normal), residuals, rms, form, len(residuals),
                    condition)


# -------------------------------------------------------------------- iterative


def _circle_residuals(q: FloatArray, shape: FloatArray) -> FloatArray:
    return np.asarray(np.hypot(q[:, 0], q[:, 1]) - shape[0])


def _circle_jacobian(q: FloatArray, shape: FloatArray) -> FloatArray:
    inv = inverse(np.hypot(q[:, 0], q[:, 1]))
    return columns(len(q), -q[:, 0] * inv, -q[:, 1] * inv, -1.0)


def _sphere_residuals(q: FloatArray, shape: FloatArray) -> FloatArray:
    return np.asarray(norms(q) - shape[0])


def _sphere_jacobian(q: FloatArray, shape: FloatArray) -> FloatArray:
    inv = inverse(norms(q))
    return columns(len(q), -q[:, 0] * inv, -q[:, 1] * inv, -q[:, 2] * inv, -1.0)


CIRCLE = Model("circle", (0, 1), _circle_residuals, _circle_jacobian)
SPHERE = Model("sphere", (0, 1, 2), _sphere_residuals, _sphere_jacobian)


def _circle(xy: FloatArray, data: Normalised,
            fit: str) -> tuple[FloatArray, float, FloatArray, float]:
    """Fit a circle to normalised in-plane points ``xy : (n, 2)``.

    Returns:
        ``(centre (2,), radius, residuals (n,))`` in normalised units, and the condition
        number.
    """
    flat = np.column_stack([xy, np.zeros(len(xy))])
    sample = subsample(flat)
    start = algebraic_circle(sample[:, :2])
    if start is None:
        raise fit_error(fit, "points on a circle", "no algebraic circle through them")
    pose, shape = Pose(np.append(start[0], 0.0), np.eye(3)), np.array([start[1]])
    sol = polish(CIRCLE, flat, sample, pose, shape, step_tol=step_tolerance(data))
    jac = jacobian_at(CIRCLE, flat, sol)
    condition = assess_model(fit, CIRCLE, jac, sol.residuals, data)
    return sol.pose.origin[:2], float(sol.shape[0]), sol.residuals, condition


@guarded("2-D circle")
def fit_circle_2d(points: ArrayLike) -> Circle2dFit:
    """Least-squares circle in the plane.

    Args:
        points: ``(n, 2)`` float, ``n >= 3``, not all collinear.

    Returns:
        The fit; residuals are ``+`` outside.

    Raises:
        ProbegenError: too few, non-finite or collinear points.
    """
    fit = "2-D circle"
    data = normalise(as_points(points, fit=fit, dim=2, minimum=3), fit=fit)
    require_rank(data, 2, fit=fit, expected="at least 3 points not all collinear")
    centre, radius, res, condition = _circle(data.points, data, fit)
    world, radius = data.to_world(centre), radius * data.scale
    check_finite(fit, world, radius)
    residuals, rms, form = summary(fit, res * data.scale)
    return Circle2dFit(vec2(world), radius, residuals, rms, form, len(residuals), condition)


@guarded("3-D circle")
def fit_circle_3d(points: ArrayLike) -> Circle3dFit:
    """Least-squares circle in space: least-squares plane, projection onto it, then the
    least-squares circle of the projected points (the NIST convention).

    Args:
        points: ``(n, 3)`` float, ``n >= 3``, not all collinear.

    Returns:
        The fit; the normal has its largest-magnitude component positive; residuals are
        the in-plane radial deviations of the projected points, ``+`` outside.

    Raises:
        ProbegenError: too few, non-finite or collinear points.
    """
    fit = "3-D circle"
    data, normal, flatness = _plane(points, fit)
    basis = orthonormal_basis(normal)[:2]
    centre, radius, res, roundness = _circle(data.points @ basis.T, data, fit)
    world, radius = data.to_world(centre @ basis), radius * data.scale
    check_finite(fit, world, radius)
    residuals, rms, form = summary(fit, res * data.scale)
    return Circle3dFit(vec3(world), vec3(normal), radius, residuals, rms, form, len(residuals),
                       max(flatness, roundness))


@guarded("sphere")
def fit_sphere(points: ArrayLike) -> SphereFit:
    """Least-squares sphere.

    Args:
        points: ``(n, 3)`` float, ``n >= 4``, not all coplanar.

    Returns:
        The fit; residuals are ``+`` outside.

    Raises:
        ProbegenError: too few, non-finite or coplanar points.
    """
    data = normalise(as_points(points, fit="sphere", dim=3, minimum=4), fit="sphere")
    require_rank(data, 3, fit="sphere", expected="at least 4 points not all coplanar")
    sample = subsample(data.points)
    start = algebraic_sphere(sample)
    if start is None:
        raise fit_error("sphere", "points on a sphere", "no algebraic sphere through them")
    pose, shape = Pose(start[0], np.eye(3)), np.array([start[1]])
    sol = polish(SPHERE, data.points, sample, pose, shape, step_tol=step_tolerance(data))
    centre, radius = data.to_world(sol.pose.origin), float(sol.shape[0]) * data.scale
    check_finite("sphere", centre, radius)
    jac = jacobian_at(SPHERE, data.points, sol)
    condition = assess_model("sphere", SPHERE, jac, sol.residuals, data)
    residuals, rms, form = summary("sphere", sol.residuals * data.scale)
    return SphereFit(vec3(centre), radius, residuals, rms, form, len(residuals), condition)
