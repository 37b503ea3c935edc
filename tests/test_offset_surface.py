"""The offset-surface solver (M3 theoretical ball centres) and the B-spline surface.

Closed forms: a plane, a sphere (outside and inside) and a cylinder as parametric surfaces,
where the ball centre is where the guide line meets the plane/sphere/cylinder offset by r.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pytest
from fuzzing import examples
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from numpy.typing import ArrayLike
from scipy.interpolate import NdBSpline

from probegen.errors import ModelError, PlanningError, ProbegenError
from probegen.geometry.bspline import BSplineSurface, clamped_knots, height_field
from probegen.geometry.offset_surface import (
    Domain,
    Status,
    SurfaceJet,
    ball_centre,
    ball_centres,
    differential,
)

TWO_PI = 2.0 * math.pi


@dataclass(frozen=True)
class Plane:
    """``S = p + u·a + v·b`` on ``[-50, 50]²``."""

    p: np.ndarray
    a: np.ndarray
    b: np.ndarray
    domain: Domain = ((-50.0, 50.0), (-50.0, 50.0))

    def evaluate(self, u: ArrayLike, v: ArrayLike) -> np.ndarray:
        return self.derivatives(u, v).point

    def derivatives(self, u: ArrayLike, v: ArrayLike) -> SurfaceJet:
        uu, vv = np.broadcast_arrays(np.ravel(u), np.ravel(v))
        m = len(uu)
        zero = np.zeros((m, 3))
        return SurfaceJet(self.p + np.outer(uu, self.a) + np.outer(vv, self.b),
                          np.tile(self.a, (m, 1)), np.tile(self.b, (m, 1)), zero, zero, zero)


@dataclass(frozen=True)
class Sphere:
    """``S = c + R·(cos v cos u, cos v sin u, sin v)``; ``S_u × S_v`` points outward."""

    c: np.ndarray
    radius: float
    domain: Domain = ((-TWO_PI, TWO_PI), (-math.pi / 2, math.pi / 2))

    def evaluate(self, u: ArrayLike, v: ArrayLike) -> np.ndarray:
        return self.derivatives(u, v).point

    def derivatives(self, u: ArrayLike, v: ArrayLike) -> SurfaceJet:
        uu, vv = np.broadcast_arrays(np.ravel(u), np.ravel(v))
        cu, su, cv, sv = np.cos(uu), np.sin(uu), np.cos(vv), np.sin(vv)
        z = np.zeros_like(uu)
        r = self.radius

        def col(*parts: np.ndarray) -> np.ndarray:
            return r * np.stack(parts, axis=1)

        return SurfaceJet(self.c + col(cv * cu, cv * su, sv), col(-cv * su, cv * cu, z),
                          col(-sv * cu, -sv * su, cv), col(-cv * cu, -cv * su, z),
                          col(sv * su, -sv * cu, z), col(-cv * cu, -cv * su, -sv))


@dataclass(frozen=True)
class Cylinder:
    """``S = (R cos u, R sin u, v)``, axis Z; ``S_u × S_v`` points outward."""

    radius: float
    domain: Domain = ((-TWO_PI, TWO_PI), (-100.0, 100.0))

    def evaluate(self, u: ArrayLike, v: ArrayLike) -> np.ndarray:
        return self.derivatives(u, v).point

    def derivatives(self, u: ArrayLike, v: ArrayLike) -> SurfaceJet:
        uu, vv = np.broadcast_arrays(np.ravel(u), np.ravel(v))
        r, z, one = self.radius, np.zeros_like(uu), np.ones_like(uu)
        c, s = np.cos(uu), np.sin(uu)
        zero = np.zeros((len(uu), 3))
        return SurfaceJet(np.stack([r * c, r * s, vv], 1), np.stack([-r * s, r * c, z], 1),
                          np.stack([z, z, one], 1), np.stack([-r * c, -r * s, z], 1), zero,
                          zero)


def line_sphere(o: np.ndarray, d: np.ndarray, c: np.ndarray, radius: float,
                nearer: bool = True) -> np.ndarray:
    """Intersection of the line ``o + t·d`` (unit ``d``) with a sphere: t values (m,)."""
    w = o - c
    b = np.einsum("ij,ij->i", w, d)
    disc = b * b - (np.einsum("ij,ij->i", w, w) - radius ** 2)
    root = np.sqrt(disc)
    return -b - root if nearer else -b + root


def random_units(rng: np.random.Generator, m: int) -> np.ndarray:
    v = rng.normal(size=(m, 3))
    return v / np.linalg.norm(v, axis=1, keepdims=True)


# --- closed forms ---------------------------------------------------------------------------

def test_plane_matches_closed_form_in_one_step() -> None:
    rng = np.random.default_rng(1)
    a, b = random_units(rng, 2)
    b = b - (a @ b) * a
    b /= np.linalg.norm(b)
    plane = Plane(np.array([1.0, 2.0, 3.0]), a, b)
    n = np.cross(a, b)
    m, r = 200, 3.0
    uv = rng.uniform(-20, 20, (m, 2))
    d = random_units(rng, m)
    d[np.abs(d @ n) < 0.2] = -n  # keep the lines well off parallel
    d[d @ n > 0] *= -1.0  # the ball travels towards the surface
    o = plane.evaluate(uv[:, 0], uv[:, 1]) + r * n + rng.uniform(-30, 30, (m, 1)) * d
    res = ball_centres(plane, o, d, r, uv + rng.uniform(-5, 5, (m, 2)))
    centre_plane_t = ((plane.p + r * n - o) @ n) / (d @ n)
    assert res.ok.all()
    np.testing.assert_allclose(res.t, centre_plane_t, atol=1e-9)
    np.testing.assert_allclose(res.centre - res.contact, r * np.tile(n, (m, 1)), atol=1e-9)
    assert res.iterations.max() <= 2  # linear: Newton is exact in one step


def test_sphere_outside_matches_closed_form() -> None:
    rng = np.random.default_rng(2)
    sphere = Sphere(np.array([5.0, -3.0, 2.0]), 12.5)
    r, m = 3.0, 300
    target = random_units(rng, m)
    target = target[np.abs(target[:, 2]) < 0.95]  # away from the poles of (u, v)
    m = len(target)
    d = -random_units(rng, m)
    d[np.einsum("ij,ij->i", d, target) > -0.3] = -target[
        np.einsum("ij,ij->i", d, target) > -0.3]
    o = sphere.c + (sphere.radius + r) * target - 40.0 * d
    u = np.arctan2(target[:, 1], target[:, 0])
    v = np.arcsin(target[:, 2])
    seeds = np.column_stack([u, v]) + rng.uniform(-0.05, 0.05, (m, 2))
    res = ball_centres(sphere, o, d, r, seeds, strict=True)
    expected = line_sphere(o, d, sphere.c, sphere.radius + r)
    np.testing.assert_allclose(res.t, expected, atol=1e-9)
    radial = (res.centre - sphere.c) / (sphere.radius + r)
    np.testing.assert_allclose(res.normal, radial, atol=1e-9)
    np.testing.assert_allclose(res.contact, sphere.c + sphere.radius * radial, atol=1e-9)


def test_sphere_inside_concave_matches_closed_form() -> None:
    sphere = Sphere(np.zeros(3), 20.0)
    r = 3.0
    o = np.array([[1.0, 2.0, 0.0], [0.0, 0.0, 0.0], [-4.0, 1.0, 5.0]])
    d = np.array([[1.0, 0.2, -0.5], [0.3, -1.0, 0.1], [0.0, 0.6, -1.0]])
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    t = line_sphere(o, d, sphere.c, sphere.radius - r, nearer=False)
    hit = o + t[:, None] * d
    seeds = np.column_stack([np.arctan2(hit[:, 1], hit[:, 0]),
                             np.arcsin(hit[:, 2] / np.linalg.norm(hit, axis=1))]) + 0.1
    res = ball_centres(sphere, o, d, r, seeds, normal_sign=-1.0, strict=True)
    np.testing.assert_allclose(res.t, t, atol=1e-9)
    np.testing.assert_allclose(res.normal, -hit / np.linalg.norm(hit, axis=1, keepdims=True),
                               atol=1e-9)
    np.testing.assert_allclose(res.kappa_max, 1.0 / sphere.radius, rtol=1e-9)


def test_cylinder_matches_closed_form() -> None:
    cyl = Cylinder(8.0)
    r = 2.5
    angles = np.linspace(0.0, 5.0, 11)
    heights = np.linspace(-20.0, 20.0, 11)
    d = -np.column_stack([np.cos(angles), np.sin(angles), np.full(11, 0.3)])
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    o = np.column_stack([30 * np.cos(angles), 30 * np.sin(angles), heights])
    res = ball_centres(cyl, o, d, r, np.column_stack([angles + 0.2, heights]), strict=True)
    np.testing.assert_allclose(np.hypot(res.centre[:, 0], res.centre[:, 1]), cyl.radius + r,
                               atol=1e-9)
    # the centre lies on the line: compare with the 2-D circle intersection
    dxy = d[:, :2] / np.linalg.norm(d[:, :2], axis=1, keepdims=True)
    along = line_sphere(np.column_stack([o[:, :2], np.zeros(11)]),
                        np.column_stack([dxy, np.zeros(11)]), np.zeros(3), cyl.radius + r)
    t = along / np.linalg.norm(d[:, :2], axis=1)
    np.testing.assert_allclose(res.t, t, atol=1e-9)
    np.testing.assert_allclose(res.normal[:, 2], 0.0, atol=1e-12)


def test_zero_radius_is_the_line_surface_intersection() -> None:
    sphere = Sphere(np.zeros(3), 10.0)
    res = ball_centre(sphere, (0.0, 0.0, 50.0), (0.1, 0.0, -1.0), 0.0, (0.0, 1.2))
    assert math.isclose(float(np.linalg.norm(res.contact)), 10.0, abs_tol=1e-10)
    np.testing.assert_allclose(res.centre, res.contact, atol=1e-9)


def test_record_fields_are_consistent() -> None:
    surf = height_field(np.outer(np.linspace(0, 3, 6), np.ones(6)), x=(0, 10), y=(0, 10))
    rec = ball_centre(surf, (4.0, 5.0, 50.0), (0.0, 0.0, -1.0), 1.5, (4.0, 5.0))
    assert rec.residual <= 1e-10 and 1 <= rec.iterations <= 10
    assert math.isclose(math.dist(rec.centre, rec.contact), 1.5, abs_tol=1e-9)
    np.testing.assert_allclose(np.subtract(rec.centre, rec.contact) / 1.5, rec.normal,
                               atol=1e-9)
    assert rec.normal[2] > 0  # S_u x S_v of a height field points up
    assert rec.centre[0] == 4.0 and rec.centre[1] == 5.0  # on the vertical guide line
    assert isinstance(rec.uv[0], float) and isinstance(rec.t, float)


def test_batch_equals_single_lines() -> None:
    rng = np.random.default_rng(3)
    surf = height_field(rng.normal(scale=2.0, size=(8, 9)), x=(0, 40), y=(-10, 30))
    xy = rng.uniform([3, -7], [37, 27], (40, 2))
    o = np.column_stack([xy, np.full(40, 15.0)])
    d = np.array([0.1, -0.05, -1.0])
    batch = ball_centres(surf, o, d, 2.0, xy, strict=True)
    for i in (0, 17, 39):
        one = ball_centre(surf, o[i], d, 2.0, xy[i])
        np.testing.assert_allclose(one.centre, batch.centre[i], atol=1e-12)


# --- convergence from seeds ----------------------------------------------------------------

@pytest.mark.parametrize("offset", [0.0, 0.3, 0.8, 1.2])
def test_newton_converges_from_distant_seeds(offset: float) -> None:
    sphere = Sphere(np.zeros(3), 25.0)
    o = np.array([[3.0, -2.0, 100.0]])
    d = np.array([0.0, 0.0, -1.0])
    res = ball_centres(sphere, o, d, 3.0, np.array([[0.0, math.pi / 2 - 0.2 - offset]]))
    expected = line_sphere(o, np.array([d]), sphere.c, 28.0)
    assert res.ok[0], res.message(0)
    assert abs(res.t[0] - expected[0]) < 1e-9
    assert res.iterations[0] < 40


def test_seed_on_the_far_side_is_reported_not_returned() -> None:
    sphere = Sphere(np.zeros(3), 25.0)
    res = ball_centres(sphere, [[3.0, -2.0, 100.0]], (0, 0, -1), 3.0, [0.0, -1.1])
    assert res.status[0] == Status.BACK_SIDE  # Newton found the bottom of the sphere
    assert "from behind" in res.message(0)
    wrong_sign = ball_centres(sphere, [[3.0, -2.0, 100.0]], (0, 0, -1), 3.0, [0.0, 1.2],
                              normal_sign=-1.0)
    assert wrong_sign.status[0] != Status.OK


def test_converges_quadratically_on_a_bspline() -> None:
    rng = np.random.default_rng(4)
    surf = height_field(rng.normal(scale=1.0, size=(10, 10)), x=(0, 50), y=(0, 50))
    xy = rng.uniform(5, 45, (500, 2))
    res = ball_centres(surf, np.column_stack([xy, np.full(500, 40.0)]), (0, 0, -1), 3.0,
                       xy + rng.uniform(-2, 2, xy.shape), strict=True)
    assert res.residual.max() <= 1e-10
    assert res.iterations.max() <= 8


# --- failures ------------------------------------------------------------------------------

def test_line_off_the_face_is_outside_domain() -> None:
    plane = Plane(np.zeros(3), np.array([1.0, 0, 0]), np.array([0, 1.0, 0]),
                  domain=((0.0, 10.0), (0.0, 10.0)))
    res = ball_centres(plane, [[15.0, 5.0, 20.0]], (0, 0, -1), 3.0, [5.0, 5.0])
    assert res.status[0] == Status.OUTSIDE_DOMAIN
    with pytest.raises(PlanningError, match="outside the surface's parameter domain"):
        ball_centre(plane, (15.0, 5.0, 20.0), (0, 0, -1), 3.0, (5.0, 5.0))


def test_concave_radius_too_large_is_self_intersecting() -> None:
    sphere = Sphere(np.zeros(3), 2.0)
    with pytest.raises(PlanningError, match=r"self-intersecting: ball radius 3 mm >= radius "
                                            r"of curvature 2 mm"):
        ball_centre(sphere, (0.1, 0.0, 0.0), (0.0, 0.3, -1.0), 3.0, (0.0, -1.0),
                    normal_sign=-1.0)


def test_fold_on_a_concave_bspline_valley_is_reported() -> None:
    x = np.linspace(-10, 10, 9)
    heights = np.outer(0.25 * x ** 2, np.ones(6))  # a valley, radius of curvature ~2 mm
    surf = height_field(heights, x=(-10, 10), y=(0, 10))
    res = ball_centres(surf, [[0.0, 5.0, 50.0]], (0, 0, -1), 5.0, [0.0, 5.0])
    assert res.status[0] == Status.SELF_INTERSECTING
    assert "use a smaller ball" in res.message(0)
    assert res.kappa_max[0] > 1.0 / 5.0
    ok = ball_centres(surf, [[0.0, 5.0, 50.0]], (0, 0, -1), 0.5, [0.0, 5.0])
    assert ok.ok[0]


def test_line_parallel_to_the_surface_is_tangent() -> None:
    plane = Plane(np.zeros(3), np.array([1.0, 0, 0]), np.array([0, 1.0, 0]))
    res = ball_centres(plane, [[0.0, 0.0, 5.0]], (1.0, 0.0, 0.0), 3.0, [0.0, 0.0])
    assert res.status[0] == Status.TANGENT
    assert "tangent" in res.message(0)


def test_singular_parametrisation_is_degenerate() -> None:
    flat = Plane(np.zeros(3), np.array([1.0, 0, 0]), np.array([2.0, 0, 0]))  # S_u || S_v
    res = ball_centres(flat, [[0.0, 0.0, 30.0]], (0, 0, -1), 1.0, [0.0, 0.0])
    assert res.status[0] == Status.DEGENERATE
    assert "degenerate" in res.message(0)


def test_strict_names_first_failure_and_count() -> None:
    plane = Plane(np.zeros(3), np.array([1.0, 0, 0]), np.array([0, 1.0, 0]),
                  domain=((0.0, 10.0), (0.0, 10.0)))
    o = [[5.0, 5.0, 9.0], [50.0, 5.0, 9.0], [5.0, 70.0, 9.0]]
    with pytest.raises(PlanningError, match=r"guide line 1: .*\(2 of 3 lines failed\)"):
        ball_centres(plane, o, (0, 0, -1), 1.0, [5.0, 5.0], strict=True)
    res = ball_centres(plane, o, (0, 0, -1), 1.0, [5.0, 5.0])
    assert res.ok.tolist() == [True, False, False]
    assert res.record(0).centre == (5.0, 5.0, 1.0)
    with pytest.raises(PlanningError):
        res.record(1)


@pytest.mark.parametrize(("kwargs", "match"), [
    ({"radius": -1.0}, "radius >= 0"),
    ({"radius": float("nan")}, "radius >= 0"),
    ({"direction": (0.0, 0.0, 0.0)}, "direction is zero"),
    ({"origin": (0.0, float("inf"), 1.0)}, "finite"),
    ({"normal_sign": 0.0}, "normal_sign"),
    ({"origin": "abc"}, "expected origins"),
])
def test_bad_arguments_raise_planning_error(kwargs: dict[str, object], match: str) -> None:
    plane = Plane(np.zeros(3), np.array([1.0, 0, 0]), np.array([0, 1.0, 0]))
    args: dict[str, object] = {"origin": (0.0, 0.0, 5.0), "direction": (0, 0, -1),
                               "radius": 1.0, "normal_sign": 1.0}
    args.update(kwargs)
    with pytest.raises(PlanningError, match=match):
        ball_centre(plane, args["origin"], args["direction"], args["radius"],  # type: ignore[arg-type]
                    (0.0, 0.0), normal_sign=args["normal_sign"])  # type: ignore[arg-type]


# --- the B-spline surface ------------------------------------------------------------------

def test_bspline_matches_scipy_ndbspline() -> None:
    rng = np.random.default_rng(5)
    nu, nv, pu, pv = 7, 6, 3, 2
    ku = np.r_[np.zeros(pu), np.linspace(0, 1, nu - pu + 1) ** 1.3, np.ones(pu)]
    kv = np.r_[np.zeros(pv), [0.0, 0.5, 0.5, 1.2, 2.0], 2 * np.ones(pv)]  # a double knot
    poles = rng.normal(size=(nu, nv, 3))
    surf = BSplineSurface(poles, ku, kv, pu, pv)
    reference = NdBSpline((ku, kv), poles, (pu, pv))
    uv = np.vstack([rng.uniform([0, 0], [1, 2], (60, 2)), [[1, 2], [0, 0], [0.3, 0.5]]])
    jet = surf.derivatives(uv[:, 0], uv[:, 1])
    for name, nu_ in [("point", (0, 0)), ("su", (1, 0)), ("sv", (0, 1)), ("suu", (2, 0)),
                      ("suv", (1, 1)), ("svv", (0, 2))]:
        np.testing.assert_allclose(getattr(jet, name), reference(uv, nu=nu_), atol=1e-11,
                                   err_msg=name)
    assert surf.domain == ((0.0, 1.0), (0.0, 2.0))


def test_rational_bspline_is_an_exact_cylinder() -> None:
    w = math.sqrt(0.5)  # quarter circle as a rational quadratic
    radius = 7.0
    arc = np.array([[radius, 0.0], [radius, radius], [0.0, radius]])
    poles = np.array([[[x, y, z] for z in (0.0, 10.0)] for x, y in arc])
    weights = np.array([[1.0, 1.0], [w, w], [1.0, 1.0]])
    surf = BSplineSurface(poles, [0, 0, 0, 1, 1, 1], [0, 0, 1, 1], 2, 1, weights)
    u = np.linspace(0, 1, 25)
    v = np.linspace(0, 1, 25)
    jet = surf.derivatives(u, v)
    np.testing.assert_allclose(np.hypot(jet.point[:, 0], jet.point[:, 1]), radius, atol=1e-12)
    diff = differential(jet, 1.0)  # S_u x S_v points outward here
    np.testing.assert_allclose(diff.kappa_max, 0.0, atol=1e-12)  # convex: κ = -1/R, 0
    inward = differential(jet, -1.0).kappa_max  # seen from inside: concave, κ = +1/R
    np.testing.assert_allclose(inward, 1.0 / radius, rtol=1e-10)
    cyl = Cylinder(radius)
    o = np.array([[20.0, 15.0, 4.0]])
    d = np.array([-1.0, -0.7, 0.1])
    res = ball_centres(surf, o, d, 2.0, [0.5, 0.4], strict=True)
    ref = ball_centres(cyl, o, d, 2.0, [0.7, 4.0], strict=True)
    np.testing.assert_allclose(res.centre, ref.centre, atol=1e-9)


def test_height_field_is_a_graph() -> None:
    surf = height_field(np.arange(30.0).reshape(5, 6), x=(-2.0, 8.0), y=(1.0, 4.0), degree=2)
    pts = surf.evaluate([-2.0, 0.5, 8.0], [1.0, 2.5, 4.0])
    np.testing.assert_allclose(pts[:, :2], [[-2.0, 1.0], [0.5, 2.5], [8.0, 4.0]], atol=1e-12)
    knots = clamped_knots(6, 3, 0.0, 1.0)
    assert knots.tolist() == [0, 0, 0, 0, 1 / 3, 2 / 3, 1, 1, 1, 1]


@pytest.mark.parametrize(("kwargs", "match"), [
    ({"poles": np.zeros((4, 4))}, "expected an \\(nu, nv, 3\\) array"),
    ({"knots_u": [0, 0, 1, 1]}, "expected 8 knots"),
    ({"knots_u": [0, 0, 0, 0, 1, 1, 1, 0]}, "non-decreasing"),
    ({"knots_u": [0, 0, 0, 0, 0, 0, 0, 0]}, "is empty"),
    ({"degree_u": 0}, "integer >= 1"),
    ({"degree_u": True}, "integer >= 1"),
    ({"weights": np.zeros((4, 4))}, "positive"),
    ({"poles": np.full((4, 4, 3), np.nan)}, "finite"),
    ({"knots_v": ["a"] * 8}, "expected numbers"),
])
def test_bad_bspline_raises_model_error(kwargs: dict[str, object], match: str) -> None:
    args: dict[str, object] = {"poles": np.zeros((4, 4, 3)),
                               "knots_u": [0, 0, 0, 0, 1, 1, 1, 1],
                               "knots_v": [0, 0, 0, 0, 1, 1, 1, 1], "degree_u": 3,
                               "degree_v": 3, "weights": None}
    args.update(kwargs)
    with pytest.raises(ModelError, match=match):
        BSplineSurface(**args)  # type: ignore[arg-type]


def test_knot_multiplicity_above_degree_plus_one_is_rejected() -> None:
    with pytest.raises(ModelError, match="repeats more than"):
        BSplineSurface(np.zeros((6, 4, 3)), [0, 0, 0, 0, 0.5, 0.5, 0.5, 0.5, 0.5, 1],
                       [0, 0, 0, 0, 1, 1, 1, 1], 3, 3)


# --- properties ----------------------------------------------------------------------------

finite = st.floats(-1e3, 1e3, allow_nan=False)


@st.composite
def problems(draw: st.DrawFn) -> tuple[BSplineSurface, np.ndarray, np.ndarray, float,
                                       np.ndarray]:
    nu, nv = draw(st.integers(4, 7)), draw(st.integers(4, 7))
    degree = draw(st.integers(1, 3))
    scale = draw(st.sampled_from([0.01, 1.0, 10.0, 100.0]))
    seed = draw(st.integers(0, 2 ** 32 - 1))
    rng = np.random.default_rng(seed)
    surf = height_field(rng.normal(scale=scale, size=(nu, nv)), x=(0.0, 20.0), y=(0.0, 20.0),
                        degree=degree)
    m = draw(st.integers(1, 6))
    origins = rng.uniform(-10, 30, (m, 3)) * [1, 1, draw(st.sampled_from([1.0, 10.0]))]
    directions = rng.normal(size=(m, 3))
    if draw(st.booleans()):
        directions[:, :2] *= 0.05
    radius = draw(st.sampled_from([0.0, 0.5, 3.0, 50.0]))
    seeds = rng.uniform(-5, 25, (m, 2))
    return surf, origins, directions, radius, seeds


@settings(max_examples=examples(80), suppress_health_check=[HealthCheck.too_slow])
@given(problems(), st.sampled_from([1.0, -1.0]))
def test_solver_ends_in_a_result_or_a_probegen_error(
        problem: tuple[BSplineSurface, np.ndarray, np.ndarray, float, np.ndarray],
        sign: float) -> None:
    surf, origins, directions, radius, seeds = problem
    try:
        res = ball_centres(surf, origins, directions, radius, seeds, normal_sign=sign)
    except ProbegenError:
        return
    assert set(res.status.tolist()) <= {int(s) for s in Status}
    d = directions / np.linalg.norm(directions, axis=1, keepdims=True)
    for i in np.flatnonzero(res.ok):
        rec = res.record(i)
        assert rec.residual <= 1e-10
        np.testing.assert_allclose(np.subtract(rec.centre, rec.contact),
                                   radius * np.asarray(rec.normal), atol=1e-9)
        np.testing.assert_allclose(rec.centre, origins[i] + rec.t * d[i], atol=1e-9)
    for i in np.flatnonzero(~res.ok):
        assert res.message(i).startswith(f"guide line {i}: ")


@settings(max_examples=examples(100))
@given(st.lists(finite, min_size=0, max_size=30), st.integers(-1, 4), st.integers(-1, 6))
def test_bspline_constructor_ends_in_a_surface_or_a_model_error(
        values: list[float], degree: int, n: int) -> None:
    knots = sorted(values[:n + degree + 1]) if n > 0 else values
    try:
        surf = BSplineSurface(np.zeros((max(n, 0), 4, 3)), knots, [0, 0, 0, 0, 1, 1, 1, 1],
                              degree, 3)
    except ModelError:
        return
    (u0, u1), _ = surf.domain
    assert u1 > u0
    assert np.all(np.isfinite(surf.evaluate([u0, u1], [0.5, 0.5])))


@settings(max_examples=examples(60), suppress_health_check=[HealthCheck.too_slow])
@given(st.integers(0, 2 ** 32 - 1), st.integers(1, 3), st.booleans(),
       st.sampled_from([0.0, 1.0, 5.0]))
def test_solver_on_random_rational_surfaces(seed: int, degree: int, rational: bool,
                                            radius: float) -> None:
    """Arbitrary poles (folds, cusps, near-degenerate patches) and weights: a result with a
    status for every line, or a ProbegenError, never another exception."""
    rng = np.random.default_rng(seed)
    n = degree + 1 + int(rng.integers(0, 3))
    poles = rng.normal(scale=10.0, size=(n, n, 3))
    if rng.random() < 0.2:
        poles[:, 0] = poles[0, 0]  # a collapsed edge (a pole of the parametrisation)
    weights = rng.uniform(0.2, 5.0, (n, n)) if rational else None
    knots = clamped_knots(n, degree, 0.0, 1.0)
    surf = BSplineSurface(poles, knots, knots, degree, degree, weights)
    m = 8
    seeds = rng.uniform(-0.2, 1.2, (m, 2))
    target = surf.evaluate(np.clip(seeds[:, 0], 0, 1), np.clip(seeds[:, 1], 0, 1))
    d = rng.normal(size=(m, 3))
    origins = target - 30.0 * d / np.linalg.norm(d, axis=1, keepdims=True)
    try:
        res = ball_centres(surf, origins, d, radius, seeds, normal_sign=1.0)
    except ProbegenError:
        return
    assert len(res.status) == m
    for i in range(m):
        if res.ok[i]:
            rec = res.record(i)
            assert math.isclose(math.dist(rec.centre, rec.contact), radius, abs_tol=1e-8)
        else:
            with pytest.raises(PlanningError):
                res.record(i)
