"""Synthetic tests of the least-squares fits and the frame helpers.

Noise-free points must give back the generating shape to 1e-9.  With seeded Gaussian
noise of standard deviation ``SIGMA`` along the surface normal, every parameter must lie
within 3 standard deviations of the truth, the standard deviations being the linearised
least-squares ones, ``SIGMA * sqrt(diag((J^T J)^-1))``, with ``J`` the Jacobian of an
independent orthogonal-distance function (finite differences, written here) at the
truth.  Parameters are expressed in the true shape's local frame (axis along +Z) so
that they are unique: axis tilt ``(a, b)`` (axis along ``(a, b, 1)``) and the axis
point where the axis meets the local plane ``z = 0``.
"""

from __future__ import annotations

import dataclasses
import math
import warnings
from collections.abc import Callable
from typing import Any

import numpy as np
import pytest
from fuzzing import examples
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from probegen.errors import ProbegenError
from probegen.geometry import fits
from probegen.geometry.frames import orthonormal_basis, rotation_to_z, unit

SIGMA = 0.002
EXACT = 1e-9
ORIGIN = np.array([120.0, -45.0, 310.0])
ROT = rotation_to_z([0.3, -0.5, 0.8])  # rows e1, e2, axis of the true shapes
AXIS = ROT[2]

Params = np.ndarray
DistanceFn = Callable[[np.ndarray, Params], np.ndarray]

# ------------------------------------------------------------------ generators


def ring(angles: np.ndarray, radius: np.ndarray | float, z: np.ndarray | float) -> np.ndarray:
    """Local points ``(n, 3)`` at the given angles, radii and heights (broadcast)."""
    return np.column_stack(np.broadcast_arrays(radius * np.cos(angles),
                                               radius * np.sin(angles), z))


def to_world(local: np.ndarray) -> np.ndarray:
    return ORIGIN + local @ ROT


def grid(span_deg: float, count: int, heights: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Angles (``count`` over ``span_deg``, rad) by heights, flattened."""
    span = math.radians(span_deg)
    ang = np.linspace(0.0, span, count, endpoint=span_deg < 360.0)
    a, h = np.meshgrid(ang, heights)
    return a.ravel(), h.ravel()


def noisy(points: np.ndarray, normals: np.ndarray, seed: int) -> np.ndarray:
    """Points moved along unit ``normals`` by seeded N(0, SIGMA) noise."""
    rng = np.random.default_rng(seed)
    return points + normals * rng.normal(0.0, SIGMA, len(points))[:, None]


# ------------------------------------- independent distances and parameters


def _local(points: np.ndarray) -> np.ndarray:
    return (points - ORIGIN) @ ROT.T


def _axis_frame(q: np.ndarray, origin: np.ndarray, a: float, b: float
                ) -> tuple[np.ndarray, np.ndarray]:
    """Distance from and height along the axis ``origin + t (a, b, 1)``."""
    d = np.array([a, b, 1.0]) / math.sqrt(1.0 + a * a + b * b)
    rel = q - origin
    z = rel @ d
    return np.linalg.norm(rel - np.outer(z, d), axis=1), z


def dist_cylinder(q: np.ndarray, p: Params) -> np.ndarray:
    rho, _ = _axis_frame(q, np.array([p[0], p[1], 0.0]), p[2], p[3])
    return rho - p[4]


def dist_cone(q: np.ndarray, p: Params) -> np.ndarray:
    rho, z = _axis_frame(q, np.array([p[0], p[1], 0.0]), p[2], p[3])
    return rho * math.cos(p[4]) - z * math.sin(p[4]) - p[5]


def dist_torus(q: np.ndarray, p: Params) -> np.ndarray:
    rho, z = _axis_frame(q, p[:3], p[3], p[4])
    return np.hypot(rho - p[5], z) - p[6]


def _local_axis(axis: tuple[float, ...], point: tuple[float, ...]
                ) -> tuple[np.ndarray, np.ndarray]:
    """A fitted axis in the true local frame, oriented to +Z, and its point there."""
    d = ROT @ np.asarray(axis)
    d = d if d[2] > 0 else -d
    return d, _local(np.asarray(point)[None, :])[0]


def params_cylinder(f: fits.CylinderFit) -> Params:
    d, p = _local_axis(f.axis, f.point)
    p0 = p - p[2] / d[2] * d
    return np.array([p0[0], p0[1], d[0] / d[2], d[1] / d[2], f.radius])


def params_cone(f: fits.ConeFit) -> Params:
    d = ROT @ np.asarray(f.axis)
    assert d[2] > 0, "cone axis must point to increasing radius"
    p = _local(np.asarray(f.point)[None, :])[0]
    t = -p[2] / d[2]
    p0 = p + t * d
    radius = f.radius + t * math.tan(f.half_angle)
    return np.array([p0[0], p0[1], d[0] / d[2], d[1] / d[2], f.half_angle,
                     radius * math.cos(f.half_angle)])


def params_torus(f: fits.TorusFit) -> Params:
    d, c = _local_axis(f.axis, f.centre)
    return np.array([c[0], c[1], c[2], d[0] / d[2], d[1] / d[2], f.major_radius,
                     f.minor_radius])


def linearised_std(dist: DistanceFn, q: np.ndarray, truth: Params) -> np.ndarray:
    """Standard deviations of the least-squares parameters for noise SIGMA."""
    h = 1e-6
    cols = [(dist(q, truth + h * e) - dist(q, truth - h * e)) / (2 * h)
            for e in np.eye(len(truth))]
    jac = np.column_stack(cols)
    return np.asarray(SIGMA * np.sqrt(np.diag(np.linalg.inv(jac.T @ jac))))


def check_truth(found: Params, truth: Params, tol: float | np.ndarray) -> None:
    err = np.abs(found - truth)
    assert np.all(err <= tol), f"errors {err} above {tol}"


# ---------------------------------------------------------------- shape cases


def cylinder_case(span_deg: float) -> tuple[np.ndarray, np.ndarray, Params]:
    ang, z = grid(span_deg, 24, np.linspace(-20.0, 30.0, 6))
    normals = ring(ang, 1.0, 0.0)
    return to_world(ring(ang, 12.5, z)), normals @ ROT, np.array([0, 0, 0, 0, 12.5])


def cone_case(span_deg: float, psi_deg: float) -> tuple[np.ndarray, np.ndarray, Params]:
    psi = math.radians(psi_deg)
    ang, z = grid(span_deg, 24, np.linspace(-5.0, 15.0, 5))
    radius = 10.0 + z * math.tan(psi)
    normals = ring(ang, math.cos(psi), -math.sin(psi))
    truth = np.array([0, 0, 0, 0, psi, 10.0 * math.cos(psi)])
    return to_world(ring(ang, radius, z)), normals @ ROT, truth


def torus_case(tube_from: float, tube_to: float) -> tuple[np.ndarray, np.ndarray, Params]:
    major, minor = 40.0, 6.0
    theta, phi = grid(360.0, 36, np.radians(np.linspace(tube_from, tube_to, 9)))
    radius, z = major + minor * np.cos(phi), minor * np.sin(phi)
    normals = ring(theta, np.cos(phi), np.sin(phi))
    return to_world(ring(theta, radius, z)), normals @ ROT, np.array([0, 0, 0, 0, 0,
                                                                      major, minor])


Case = tuple[np.ndarray, np.ndarray, Params]
AXIAL: dict[str, tuple[Case, Callable[[np.ndarray], Any], Callable[[Any], Params], DistanceFn]] = {
    "cylinder full": (cylinder_case(360), fits.fit_cylinder, params_cylinder, dist_cylinder),
    "cylinder half": (cylinder_case(180), fits.fit_cylinder, params_cylinder, dist_cylinder),
    "cone 30deg": (cone_case(360, 30), fits.fit_cone, params_cone, dist_cone),
    "cone quarter": (cone_case(90, 12), fits.fit_cone, params_cone, dist_cone),
    "cone 117deg": (cone_case(360, 58.7), fits.fit_cone, params_cone, dist_cone),
    "cone 1deg": (cone_case(360, 0.6), fits.fit_cone, params_cone, dist_cone),
    "torus full": (torus_case(0, 360), fits.fit_torus, params_torus, dist_torus),
    "torus outer half": (torus_case(-90, 90), fits.fit_torus, params_torus, dist_torus),
    "torus fillet": (torus_case(180, 270), fits.fit_torus, params_torus, dist_torus),
}


@pytest.mark.parametrize("name", AXIAL)
def test_axial_exact(name: str) -> None:
    (points, _, truth), fit, params, _ = AXIAL[name]
    result = fit(points)
    check_truth(params(result), truth, EXACT)
    assert result.rms < EXACT and result.n == len(points)


@pytest.mark.parametrize("name", AXIAL)
def test_axial_noisy(name: str) -> None:
    (points, normals, truth), fit, params, dist = AXIAL[name]
    noisy_points = noisy(points, normals, seed=7)
    std = linearised_std(dist, _local(points), truth)
    check_truth(params(fit(noisy_points)), truth, 3 * std)


# ------------------------------------------------------- circles and spheres


def circle_points(span_deg: float, count: int) -> tuple[np.ndarray, np.ndarray]:
    ang = np.radians(np.linspace(0.0, span_deg, count, endpoint=span_deg < 360))
    return np.column_stack([np.cos(ang), np.sin(ang)]), ang


def dist_circle(q: np.ndarray, p: Params) -> np.ndarray:
    return np.linalg.norm(q[:, :2] - p[:2], axis=1) - p[2]


@pytest.mark.parametrize("span", [360.0, 60.0, 10.0])
def test_circle_2d(span: float) -> None:
    unit_xy, _ = circle_points(span, 40)
    truth = np.array([-7.5, 1200.25, 33.0])
    pts = truth[:2] + truth[2] * unit_xy
    f = fits.fit_circle_2d(pts)
    check_truth(np.array([*f.centre, f.radius]), truth, EXACT)
    noisy_pts = pts + unit_xy * np.random.default_rng(3).normal(0, SIGMA, len(pts))[:, None]
    g = fits.fit_circle_2d(noisy_pts)
    std = linearised_std(dist_circle, pts, truth)
    check_truth(np.array([*g.centre, g.radius]), truth, 3 * std)


@pytest.mark.parametrize("span", [360.0, 60.0])
def test_circle_3d(span: float) -> None:
    unit_xy, _ = circle_points(span, 30)
    local = np.column_stack([25.0 * unit_xy, np.zeros(len(unit_xy))])
    f = fits.fit_circle_3d(to_world(local))
    check_truth(np.array(f.centre), ORIGIN, EXACT)
    assert abs(f.radius - 25.0) < EXACT and abs(abs(np.dot(f.normal, AXIS)) - 1) < 1e-15


def sphere_points(cap_deg: float) -> np.ndarray:
    """Unit vectors spread over a polar cap of half-angle ``cap_deg`` (Fibonacci)."""
    k = np.arange(200) + 0.5
    cos_t = 1.0 - k / 200 * (1.0 - math.cos(math.radians(cap_deg)))
    ang = k * math.pi * (3.0 - math.sqrt(5.0))
    return ring(ang, np.sqrt(1.0 - cos_t**2), cos_t)


def dist_sphere(q: np.ndarray, p: Params) -> np.ndarray:
    return np.linalg.norm(q - p[:3], axis=1) - p[3]


@pytest.mark.parametrize("cap", [180.0, 90.0, 30.0])
def test_sphere(cap: float) -> None:
    unit_pts = sphere_points(cap)
    truth = np.array([*ORIGIN, 9.525])
    pts = truth[:3] + truth[3] * unit_pts
    f = fits.fit_sphere(pts)
    check_truth(np.array([*f.centre, f.radius]), truth, EXACT)
    noisy_pts = noisy(pts, unit_pts, seed=11)
    g = fits.fit_sphere(noisy_pts)
    check_truth(np.array([*g.centre, g.radius]), truth, 3 * linearised_std(dist_sphere, pts, truth))


# ------------------------------------------------------------ lines and planes


def test_line_and_plane_exact() -> None:
    t = np.linspace(-50, 80, 7)
    line = ORIGIN + np.outer(t, AXIS)
    f = fits.fit_line_3d(line)
    assert abs(abs(np.dot(f.direction, AXIS)) - 1) < 1e-15 and f.form < EXACT
    g = fits.fit_line_2d(line[:, :2])
    assert g.form < EXACT and abs(np.dot(g.direction, g.normal)) < 1e-15
    xy = np.random.default_rng(1).uniform(-30, 30, (9, 2))
    p = fits.fit_plane(to_world(np.column_stack([xy, np.zeros(9)])))
    assert abs(abs(np.dot(p.normal, AXIS)) - 1) < 1e-14 and p.form < EXACT


def test_line_2d_noisy_slope() -> None:
    x = np.linspace(0, 100, 51)
    rng = np.random.default_rng(5)
    y = 0.25 * x + 3 + rng.normal(0, SIGMA, x.size) * math.hypot(1, 0.25)
    f = fits.fit_line_2d(np.column_stack([x, y]))
    slope_std = SIGMA * math.hypot(1, 0.25) / math.sqrt(np.sum((x - x.mean()) ** 2))
    assert abs(f.direction[1] / f.direction[0] - 0.25) < 3 * slope_std


# ------------------------------------------------------------------ conventions


def test_residual_signs_and_form() -> None:
    pts = np.array([[1.1, 0, 0], [0, 1, 0], [-1, 0, 0], [0, -0.9, 0], [0, 0, 1], [0, 0, -1]])
    f = fits.fit_sphere(pts)
    assert f.residuals[0] > 0 > f.residuals[3]
    assert math.isclose(f.form, max(f.residuals) - min(f.residuals))
    assert math.isclose(f.rms, math.sqrt(np.mean(np.square(f.residuals))))
    plane = fits.fit_plane([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.1]])
    assert plane.normal[2] > 0 and plane.residuals[3] > 0


def test_direction_sign_rule_and_axis_point() -> None:
    points, _, _ = cylinder_case(180)  # half cylinder: the centroid is off the axis
    f = fits.fit_cylinder(points)
    k = int(np.argmax(np.abs(f.axis)))
    assert f.axis[k] > 0
    offset = points.mean(axis=0) - np.asarray(f.point)
    assert np.linalg.norm(offset) > 1.0 and abs(np.dot(offset, f.axis)) < EXACT
    assert np.linalg.norm(_local(np.asarray([f.point]))[0, :2]) < EXACT  # on the true axis


def test_cone_outputs() -> None:
    points, _, _ = cone_case(360, 30)
    f = fits.fit_cone(points)
    flipped = fits.fit_cone(2 * ORIGIN - points)  # point reflection turns the axis
    assert np.allclose(flipped.axis, -np.asarray(f.axis), atol=1e-12)
    assert math.isclose(f.apex_angle, math.radians(60), abs_tol=EXACT)
    assert math.isclose(f.distance, f.radius * math.cos(f.half_angle))
    apex_local = _local(np.asarray([f.apex]))[0]
    check_truth(apex_local, np.array([0, 0, -10.0 / math.tan(math.radians(30))]), 1e-8)


def test_records_are_frozen_plain_floats() -> None:
    f = fits.fit_sphere(sphere_points(180) * 3)
    with pytest.raises(dataclasses.FrozenInstanceError):
        f.radius = 1.0  # type: ignore[misc]
    assert not hasattr(f, "__dict__")
    assert type(f.radius) is float and all(type(c) is float for c in f.centre)
    assert all(type(r) is float for r in f.residuals) and type(f.n) is int


# ------------------------------------------------------------------- bad input

LINE_PTS = np.outer(np.arange(8.0), [1.0, 2.0, 3.0]) + 5.0
PLANE_PTS = np.column_stack([np.cos(np.arange(8.0)), np.sin(np.arange(8.0)), np.full(8, 2.0)])

NAMES: dict[Callable[[Any], object], str] = {
    fits.fit_sphere: "sphere", fits.fit_circle_3d: "3-D circle", fits.fit_circle_2d: "2-D circle",
    fits.fit_plane: "plane", fits.fit_cylinder: "cylinder", fits.fit_cone: "cone",
    fits.fit_torus: "torus", fits.fit_line_3d: "3-D line", fits.fit_line_2d: "2-D line",
}

BAD = [
    (fits.fit_sphere, PLANE_PTS, "coplanar"),
    (fits.fit_sphere, np.ones((3, 3)), "at least 4 points"),
    (fits.fit_sphere, np.ones((9, 3)), "coincident"),
    (fits.fit_circle_3d, LINE_PTS, "collinear"),
    (fits.fit_circle_2d, LINE_PTS[:, :2], "collinear"),
    (fits.fit_plane, LINE_PTS, "collinear"),
    (fits.fit_cylinder, LINE_PTS, "collinear"),
    (fits.fit_cone, LINE_PTS, "collinear"),
    (fits.fit_torus, LINE_PTS, "collinear"),
    (fits.fit_cylinder, PLANE_PTS[:4], "at least 5 points"),
    (fits.fit_line_3d, [[1.0, 2.0, 3.0]], "at least 2 points"),
    (fits.fit_line_2d, LINE_PTS, "shape (8, 3)"),
    (fits.fit_plane, [[0, 0, 0], [1, 0, math.nan], [0, 1, 0]], "finite"),
    (fits.fit_sphere, np.vstack([PLANE_PTS, [[0, 0, math.inf]]]), "row 8"),
    (fits.fit_cone, "not points", "array"),
    (fits.fit_plane, [[0, 0, 0], [1, 0]], "array"),
]


@pytest.mark.parametrize(("fit", "pts", "found"), BAD, ids=[str(i) for i in range(len(BAD))])
def test_bad_input(fit: Callable[[Any], object], pts: Any, found: str) -> None:
    with pytest.raises(ProbegenError, match="expected") as info:
        fit(pts)
    assert found in str(info.value)
    assert str(info.value).startswith(NAMES[fit] + " fit: expected")


def _degenerate(draw: st.DrawFn) -> np.ndarray:
    n = draw(st.integers(0, 12))
    coords = st.floats(allow_nan=False, allow_infinity=False, width=64) | st.sampled_from(
        [0.0, 1e-300, -1e-300, 1e300, -1e300, 1.0, 5e-324])
    pts = draw(arrays(np.float64, (n, 3), elements=coords))
    kind = draw(st.sampled_from(["raw", "dup", "line", "plane", "tiny", "huge"]))
    if kind == "dup" and n:
        pts[:] = pts[0]
    elif kind == "line":
        with np.errstate(over="ignore"):
            pts = np.outer(np.arange(n, dtype=float), pts[0] if n else np.ones(3))
    elif kind == "plane":
        pts[:, 2] = pts[0, 2] if n else 0.0
    elif kind in ("tiny", "huge"):
        rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
        pts = rng.normal(size=(n, 3)) * (1e-200 if kind == "tiny" else 1e200)
    return np.asarray(pts)


FITS_3D = [fits.fit_line_3d, fits.fit_plane, fits.fit_circle_3d, fits.fit_sphere,
           fits.fit_cylinder, fits.fit_cone, fits.fit_torus]
FITS_2D = [fits.fit_line_2d, fits.fit_circle_2d]


@settings(max_examples=examples(120), suppress_health_check=[HealthCheck.too_slow])
@given(st.composite(_degenerate)())
def test_any_finite_input_fits_or_raises(pts: np.ndarray) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for fit, arg in [(f, pts) for f in FITS_3D] + [(f, pts[:, :2]) for f in FITS_2D]:
            try:
                result = fit(arg)
            except ProbegenError:
                continue
            record: Any = result
            values = [v for v in dataclasses.astuple(record) if isinstance(v, float)]
            assert all(math.isfinite(v) for v in values), (fit.__name__, result)


# ---------------------------------------------------------------------- frames


@pytest.mark.parametrize("v", [[0, 0, 2.0], [0, 0, -3.0], [1e-300, 0, -1], [0.3, -0.5, 0.8],
                               [1, 0, 0], [-2e-9, 1e-9, -1.0], [1e200, 1e200, -1e200]])
def test_rotation_to_z(v: list[float]) -> None:
    rot = rotation_to_z(v)
    assert np.allclose(rot @ unit(v), [0, 0, 1], atol=1e-15)
    assert np.allclose(rot @ rot.T, np.eye(3), atol=1e-15)
    assert math.isclose(np.linalg.det(rot), 1.0)
    assert np.allclose(orthonormal_basis(v)[2], unit(v), atol=1e-15)


def test_rotation_to_z_special_cases() -> None:
    assert np.array_equal(rotation_to_z([0, 0, 5]), np.eye(3))
    assert np.array_equal(rotation_to_z([0, 0, -5]), np.diag([1.0, -1.0, -1.0]))
    for bad in ([0, 0, 0], [0, math.nan, 1], [math.inf, 0, 0]):
        with pytest.raises(ProbegenError, match="expected"):
            rotation_to_z(bad)
