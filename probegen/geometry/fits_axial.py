"""Least-squares fits of surfaces of revolution: cylinder, cone, torus.

Each fit starts the solver from every candidate axis (principal directions of the data
and axes of the algebraic quadric; see ``fits_initial.candidate_axes``), with a linear
fit about that axis for the remaining parameters, and keeps the solution of least
cost.  In the local frame of the solver the shape's axis is +Z through the origin; with
``rho`` the distance of a point from the axis and ``z`` its height:

* cylinder, parameters ``(r)``: ``d = rho - r``;
* cone, parameters ``(psi, s)``: ``d = rho cos(psi) - z sin(psi) - s`` with ``psi`` the
  half angle and ``s`` the orthogonal distance from the origin to the surface;
* torus, parameters ``(R, r)``: ``d = hypot(rho - R, z) - r``.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike

from probegen.geometry.fits_conditioning import assess_model
from probegen.geometry.fits_initial import algebraic_circle, algebraic_cone, candidate_axes
from probegen.geometry.fits_results import ConeFit, CylinderFit, TorusFit
from probegen.geometry.fits_solver import (
    FloatArray,
    Model,
    Normalised,
    Pose,
    Solution,
    as_points,
    canonical,
    check_finite,
    columns,
    fit_error,
    guarded,
    inverse,
    jacobian_at,
    multi_start,
    normalise,
    polish,
    require_rank,
    step_tolerance,
    subsample,
    summary,
    vec3,
)
from probegen.geometry.frames import rotation_to_z, unit

# ------------------------------------------------------------------------- models


def _polar(q: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Return ``(rho, x / rho, y / rho)`` for local points ``q : (n, 3)``."""
    rho = np.hypot(q[:, 0], q[:, 1])
    inv = inverse(rho)
    return rho, q[:, 0] * inv, q[:, 1] * inv


def _cylinder_residuals(q: FloatArray, shape: FloatArray) -> FloatArray:
    return np.asarray(np.hypot(q[:, 0], q[:, 1]) - shape[0])


def _cylinder_jacobian(q: FloatArray, shape: FloatArray) -> FloatArray:
    _, ux, uy = _polar(q)
    z = q[:, 2]
    return columns(len(q), -ux, -uy, -ux * z, -uy * z, -1.0)


def _cone_residuals(q: FloatArray, shape: FloatArray) -> FloatArray:
    rho = np.hypot(q[:, 0], q[:, 1])
    return np.asarray(rho * math.cos(shape[0]) - q[:, 2] * math.sin(shape[0]) - shape[1])


def _cone_jacobian(q: FloatArray, shape: FloatArray) -> FloatArray:
    rho, ux, uy = _polar(q)
    x, y, z = q.T
    c, s = math.cos(shape[0]), math.sin(shape[0])
    return columns(len(q), -ux * c, -uy * c, -ux * z * c - x * s, -uy * z * c - y * s,
                   -rho * s - z * c, -1.0)


def _torus_residuals(q: FloatArray, shape: FloatArray) -> FloatArray:
    rho = np.hypot(q[:, 0], q[:, 1])
    return np.asarray(np.hypot(rho - shape[0], q[:, 2]) - shape[1])


def _torus_jacobian(q: FloatArray, shape: FloatArray) -> FloatArray:
    rho, ux, uy = _polar(q)
    x, y, z = q.T
    u = rho - shape[0]
    inv = inverse(np.hypot(u, z))
    cu, cz = u * inv, z * inv
    return columns(len(q), -cu * ux, -cu * uy, -cz, cz * x - cu * ux * z,
                   cz * y - cu * uy * z, -cu, -1.0)


CYLINDER = Model("cylinder", (0, 1, 3, 4), _cylinder_residuals, _cylinder_jacobian)
CONE = Model("cone", (0, 1, 3, 4), _cone_residuals, _cone_jacobian,
             ("half angle", "distance to the surface"), ("half angle",))
TORUS = Model("torus", (0, 1, 2, 3, 4), _torus_residuals, _torus_jacobian,
              ("major radius", "minor radius"))

# ---------------------------------------------------------------- starting guesses


def _start_cylinder(q: FloatArray, axis: FloatArray) -> tuple[Pose, FloatArray] | None:
    """Pose and ``(r,)`` from a circle fitted to the points projected along ``axis``."""
    rot = rotation_to_z(axis)
    circle = algebraic_circle((q @ rot.T)[:, :2])
    if circle is None:
        return None
    centre, radius = circle
    return Pose(rot.T @ np.append(centre, 0.0), rot), np.array([radius])


def _start_cone(q: FloatArray, axis: FloatArray) -> tuple[Pose, FloatArray] | None:
    """Pose and ``(psi, s)`` from the linear cone about ``axis``."""
    rot = rotation_to_z(axis)
    guess = algebraic_cone(q @ rot.T)
    if guess is None:
        return None
    centre, radius, slope = guess
    psi = math.atan(slope)
    return Pose(rot.T @ np.append(centre, 0.0), rot), np.array([psi, radius * math.cos(psi)])


def _start_torus(q: FloatArray, axis: FloatArray) -> tuple[Pose, FloatArray] | None:
    """Pose and ``(R, r)``: centre from the projected circle, then the tube's section
    as a circle in the ``(rho, z)`` half-plane."""
    rot = rotation_to_z(axis)
    local = q @ rot.T
    best: tuple[float, FloatArray, tuple[FloatArray, float]] | None = None
    for centre in _ring_centres(local):
        rho = np.hypot(local[:, 0] - centre[0], local[:, 1] - centre[1])
        meridian = np.column_stack([rho, local[:, 2]])
        tube = algebraic_circle(meridian)
        if tube is None:
            continue
        spread = float(np.ptp(np.hypot(*(meridian - tube[0]).T)))
        if best is None or spread < best[0]:
            best = (spread, centre, tube)
    if best is None:
        return None
    _, centre, ((major, height), minor) = best
    origin = rot.T @ np.array([centre[0], centre[1], height])
    return Pose(origin, rot), np.array([major, minor])


def _ring_centres(local: FloatArray) -> list[FloatArray]:
    """Candidate centres of a torus's rings, its axis along local z: the one circle
    through every point projected (right for full rings), and concentric circles whose
    ``rho^2`` is a quadratic in z (``|p|^2 = 2 c . p + k0 + k1 z + k2 z^2``: exact for
    three or fewer levels; the rings of one torus have different radii, and one circle
    through partial arcs of several puts the centre off the axis)."""
    out = []
    xy, z = local[:, :2], local[:, 2]
    ring = algebraic_circle(xy)
    if ring is not None:
        out.append(ring[0])
    lhs = np.column_stack([2.0 * xy, np.ones(len(z)), z, z * z])
    sol, *_ = np.linalg.lstsq(lhs, np.sum(xy * xy, axis=1), rcond=None)
    if np.all(np.isfinite(sol)):
        out.append(sol[:2])
    return out


Start = Callable[[FloatArray, FloatArray], tuple[Pose, FloatArray] | None]


def _solve(model: Model, data: Normalised, start: Start,
           hint: ArrayLike | None = None, *, nearest: bool = False) -> Solution:
    """Refine from every candidate axis (and the caller's ``hint``, e.g. the nominal
    axis) and keep the best solution; with ``nearest``, refine from the ``hint`` alone
    (the local optimum nearest the nominal, as a CMM does; every candidate axis only
    when the hint gives no start)."""
    q, sample = data.points, subsample(data.points)
    if nearest and hint is not None:
        first = start(sample, unit(hint, what="axis hint"))
        if first is not None:
            return polish(model, q, sample, first[0], first[1],
                          step_tol=step_tolerance(data))
    axes = candidate_axes(sample, data.directions)
    if hint is not None:
        axes.insert(0, unit(hint, what="axis hint"))
    starts = [start(sample, axis) for axis in axes]
    usable = [s for s in starts if s is not None]
    return multi_start(model, q, usable, step_tol=step_tolerance(data))


def _prepare(points: ArrayLike, fit: str, minimum: int) -> Normalised:
    """Check the input, normalise it, and require points not all on one line."""
    data = normalise(as_points(points, fit=fit, dim=3, minimum=minimum), fit=fit)
    require_rank(data, 2, fit=fit, expected=f"at least {minimum} points not all collinear")
    return data


def _assess(fit: str, model: Model, data: Normalised, sol: Solution) -> float:
    """The solution's condition number, or ProbegenError if the points leave it open."""
    jac = jacobian_at(model, data.points, sol)
    if model is TORUS:
        return assess_model(fit, model, jac, sol.residuals, data)
    jac = pivot_at_centroid(jac, sol, with_cone=model is CONE)
    return assess_model(fit, model, jac, sol.residuals, data, sol.pose.axis)


def pivot_at_centroid(jac: FloatArray, sol: Solution, *, with_cone: bool) -> FloatArray:
    """Return the Jacobian of a cylinder (cone) solution for axis tilts about the point
    of the axis nearest the data centroid instead of the solver's pivot ``sol.pose``.

    The solver's pivot may lie anywhere along the axis, and the conditioning of tilts
    depends on it; the centroid's projection makes it a property of the data.  Tilting
    ``(a, b)`` about a pivot ``t`` further along the axis is the same tilt about the old
    pivot and a shift ``(-a t, -b t)``; for a cone the distance to the surface also
    changes by ``t sin(psi)``.  Columns: ``(dx, dy, a, b, shape...)``.
    """
    t = -float(sol.pose.origin @ sol.pose.axis)
    out = np.array(jac, dtype=np.float64, order="F")
    out[:, 2] -= t * out[:, 0]
    out[:, 3] -= t * out[:, 1]
    if with_cone:
        out[:, 4] -= t * math.cos(float(sol.shape[0])) * out[:, 5]
    return out


def _axis_point(data: Normalised, pose: Pose) -> tuple[float, FloatArray]:
    """Return ``(t, point)``: the centroid's height on the axis (normalised units) and
    its projection onto the axis in input units."""
    t = -float(pose.origin @ pose.axis)
    return t, data.to_world(pose.origin + t * pose.axis)


# ------------------------------------------------------------------------- public


@guarded("cylinder")
def fit_cylinder(points: ArrayLike, axis: ArrayLike | None = None, *,
             nearest: bool = False) -> CylinderFit:
    """Least-squares (orthogonal distance) cylinder.

    Args:
        points: ``(n, 3)`` float, ``n >= 5``, not all collinear.
        axis: an approximate axis (the nominal one) to start from as well, or None.
        nearest: start from ``axis`` only and return the optimum nearest it (the
            nominal's), not the best of every start (``fits_nominal`` checks the others).

    Returns:
        The fit; ``point`` is the projection of the centroid onto the axis, ``axis``
        has its largest-magnitude component positive, residuals are ``+`` outside.

    Raises:
        ProbegenError: too few, non-finite or collinear points, or no solution.
    """
    data = _prepare(points, "cylinder", 5)
    sol = _solve(CYLINDER, data, _start_cylinder, axis, nearest=nearest)
    _, point = _axis_point(data, sol.pose)
    radius = float(sol.shape[0]) * data.scale
    check_finite("cylinder", point, radius)
    if not radius > 0.0:
        raise fit_error("cylinder", "points around an axis", f"radius {radius:g}")
    condition = _assess("cylinder", CYLINDER, data, sol)
    residuals, rms, form = summary("cylinder", sol.residuals * data.scale)
    return CylinderFit(vec3(point), vec3(canonical(sol.pose.axis)),
                       radius, residuals, rms, form, len(residuals), condition)


@guarded("cone")
def fit_cone(points: ArrayLike, axis: ArrayLike | None = None, *,
             nearest: bool = False) -> ConeFit:
    """Least-squares (orthogonal distance) cone.

    Args:
        points: ``(n, 3)`` float, ``n >= 6``, not all collinear.
        axis: an approximate axis (the nominal one) to start from as well, or None.
        nearest: start from ``axis`` only and return the optimum nearest it (the
            nominal's), not the best of every start (``fits_nominal`` checks the others).

    Returns:
        The fit; ``point`` is the projection of the centroid onto the axis, ``axis``
        points to increasing radius, ``half_angle`` is in ``[0, pi/2)``, ``radius`` is
        the section radius at ``point``; residuals are ``+`` away from the axis.

    Raises:
        ProbegenError: too few, non-finite or collinear points, or no cone (e.g. the
        solution flattens to a plane).
    """
    data = _prepare(points, "cone", 6)
    sol = _solve(CONE, data, _start_cone, axis, nearest=nearest)
    t, point = _axis_point(data, sol.pose)
    psi, dist = float(sol.shape[0]), float(sol.shape[1]) + t * math.sin(sol.shape[0])
    axis = sol.pose.axis if psi >= 0.0 else -sol.pose.axis
    psi = abs(psi)
    check_finite("cone", point, psi, dist)
    if not psi < math.pi / 2 - 1e-9:
        raise fit_error("cone", "a half angle below 90 degrees", f"{math.degrees(psi):g}")
    condition = _assess("cone", CONE, data, sol)
    residuals, rms, form = summary("cone", sol.residuals * data.scale)
    return ConeFit(vec3(point), vec3(axis), psi,
                   dist * data.scale / math.cos(psi), residuals, rms, form, len(residuals),
                   condition)


@guarded("torus")
def fit_torus(points: ArrayLike, axis: ArrayLike | None = None, *,
             nearest: bool = False) -> TorusFit:
    """Least-squares (orthogonal distance) torus.

    Args:
        points: ``(n, 3)`` float, ``n >= 7``, not all collinear.
        axis: an approximate axis (the nominal one) to start from as well, or None.
        nearest: start from ``axis`` only and return the optimum nearest it (the
            nominal's), not the best of every start (``fits_nominal`` checks the others).

    Returns:
        The fit; ``axis`` has its largest-magnitude component positive, residuals are
        ``+`` outside the tube.

    Raises:
        ProbegenError: too few, non-finite or collinear points, or no solution.
    """
    data = _prepare(points, "torus", 7)
    sol = _solve(TORUS, data, _start_torus, axis, nearest=nearest)
    centre = data.to_world(sol.pose.origin)
    major, minor = (float(v) * data.scale for v in sol.shape)
    check_finite("torus", centre, major, minor)
    if not minor > 0.0:
        raise fit_error("torus", "points around a tube", f"minor radius {minor:g}")
    condition = _assess("torus", TORUS, data, sol)
    residuals, rms, form = summary("torus", sol.residuals * data.scale)
    return TorusFit(vec3(centre), vec3(canonical(sol.pose.axis)),
                    major, minor, residuals, rms, form, len(residuals), condition)
