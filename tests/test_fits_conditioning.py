"""Fit conditioning: the ``condition`` figure, refusals with clear messages for points that
cannot determine the shape, and the large-data paths (subsample start, normal equations)
giving the same fits as the small-data ones."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np
import pytest

from probegen.errors import ProbegenError
from probegen.geometry import fits, fits_axial, fits_solver
from probegen.geometry.fits_conditioning import CONDITION_LIMIT, conditioning
from probegen.geometry.fits_solver import Pose, as_points, jacobian_at, normalise
from probegen.geometry.frames import orthonormal_basis

SIGMA = 0.002
CENTRE = np.array([-7.5, 120.0, 40.0])


def arc(
    span_deg: float, count: int, *, radius: float = 33.0, sigma: float = SIGMA, seed: int = 3
) -> np.ndarray:
    """``(count, 2)`` points on an arc of ``span_deg`` degrees, radial noise ``sigma``."""
    ang = np.radians(np.linspace(0.0, span_deg, count))
    rho = radius + np.random.default_rng(seed).normal(0.0, sigma, count)
    return CENTRE[:2] + rho[:, None] * np.column_stack([np.cos(ang), np.sin(ang)])


def cap(
    cap_deg: float, count: int = 200, *, radius: float = 9.525, sigma: float = SIGMA
) -> np.ndarray:
    """``(count, 3)`` points spread over a polar cap of half-angle ``cap_deg``."""
    k = np.arange(count) + 0.5
    cos_t = 1.0 - k / count * (1.0 - math.cos(math.radians(cap_deg)))
    ang = k * math.pi * (3.0 - math.sqrt(5.0))
    sin_t = np.sqrt(1.0 - cos_t**2)
    unit = np.column_stack([sin_t * np.cos(ang), sin_t * np.sin(ang), cos_t])
    rho = radius + np.random.default_rng(1).normal(0.0, sigma, count)
    return CENTRE + rho[:, None] * unit


def cylinder(
    span_deg: float,
    count: int,
    *,
    heights: tuple[float, float] = (-20.0, 20.0),
    sigma: float = SIGMA,
    seed: int = 5,
) -> np.ndarray:
    """``(count, 3)`` random points on a cylinder sector (axis tilted, radius 8)."""
    rng = np.random.default_rng(seed)
    ang = rng.uniform(0.0, math.radians(span_deg), count)
    z = rng.uniform(*heights, count)
    rho = 8.0 + rng.normal(0.0, sigma, count)
    e1, e2, axis = orthonormal_basis([0.3, -0.5, 0.8])
    return (
        CENTRE
        + (rho * np.cos(ang))[:, None] * e1
        + (rho * np.sin(ang))[:, None] * e2
        + z[:, None] * axis
    )


def sphere(count: int, *, sigma: float = SIGMA, seed: int = 5) -> np.ndarray:
    """``(count, 3)`` random points all over a sphere of radius 12.5."""
    rng = np.random.default_rng(seed)
    unit = rng.normal(size=(count, 3))
    unit /= np.linalg.norm(unit, axis=1)[:, None]
    return CENTRE + (12.5 + rng.normal(0.0, sigma, count))[:, None] * unit


def refused(fit: Callable[[Any], object], points: Any) -> str:
    with pytest.raises(ProbegenError) as info:
        fit(points)
    return str(info.value)


# --- the figure ----------------------------------------------------------------------------


def test_every_record_reports_a_finite_condition() -> None:
    line = np.outer(np.linspace(0, 10, 7), [1.0, 2.0, 2.0]) + np.random.default_rng(0).normal(
        0, SIGMA, (7, 3)
    )
    ring = np.column_stack([arc(360, 24), np.full(24, 5.0)])
    records = [
        fits.fit_line_2d(line[:, :2]),
        fits.fit_line_3d(line),
        fits.fit_plane(cap(60)),
        fits.fit_circle_2d(arc(360, 24)),
        fits.fit_circle_3d(ring),
        fits.fit_sphere(cap(90)),
        fits.fit_cylinder(cylinder(360, 200)),
    ]
    for record in records:
        condition = record.condition  # type: ignore[attr-defined]
        assert type(condition) is float and 1.0 <= condition < 1e3, (record, condition)


def test_condition_grows_as_the_arc_shortens() -> None:
    spans = [360.0, 180.0, 60.0, 10.0, 1.0]
    conditions = [fits.fit_circle_2d(arc(s, 40, sigma=0.0)).condition for s in spans]
    assert conditions == sorted(conditions)
    assert conditions[0] < 1.5 and 1e3 < conditions[3] < 3e3 and 1e5 < conditions[4] < 3e5


def test_condition_does_not_depend_on_units_or_placement() -> None:
    points = cylinder(120, 300)
    moved = points * 25.4 + np.array([1e4, -3e3, 250.0])
    a, b = fits.fit_cylinder(points), fits.fit_cylinder(moved)
    assert math.isclose(a.condition, b.condition, rel_tol=1e-6)


def test_uncertainties_are_the_linearised_ones() -> None:
    rng = np.random.default_rng(8)
    jac = rng.normal(size=(50, 3))
    res = rng.normal(0.0, 0.1, 50)
    result = conditioning(jac, res)
    sigma2 = float(res @ res) / (50 - 3)
    expected = np.sqrt(sigma2 * np.diag(np.linalg.inv(jac.T @ jac)))
    assert np.allclose(result.std, expected, rtol=1e-12)
    assert math.isclose(result.condition, float(np.linalg.cond(jac)), rel_tol=1e-12)
    big = np.vstack([jac] * 400)  # many rows: through J^T J
    assert math.isclose(
        conditioning(big, np.tile(res, 400)).condition, result.condition, rel_tol=1e-9
    )


def test_tilts_are_judged_about_the_centroid() -> None:
    """The solver's pivot may sit anywhere on the axis; the figure must not depend on it."""
    points = cylinder(90, 200)
    data = normalise(as_points(points, fit="cylinder", dim=3, minimum=5), fit="cylinder")
    sol = fits_axial._solve(fits_axial.CYLINDER, data, fits_axial._start_cylinder)
    moved = Pose(sol.pose.origin + 3.0 * sol.pose.axis, sol.pose.rot)
    shifted = fits_solver.Solution(moved, sol.shape, sol.residuals, sol.cost)
    jac_a = fits_axial.pivot_at_centroid(
        jacobian_at(fits_axial.CYLINDER, data.points, sol), sol, with_cone=False
    )
    jac_b = fits_axial.pivot_at_centroid(
        jacobian_at(fits_axial.CYLINDER, data.points, shifted), shifted, with_cone=False
    )
    assert np.allclose(jac_a, jac_b, atol=1e-12)


# --- refusals -------------------------------------------------------------------------------

REFUSED = [
    ("5-degree arc, 2 um noise", fits.fit_circle_2d, arc(5, 40), "radius uncertain by +-1.1"),
    ("5-degree arc, 12 points", fits.fit_circle_2d, arc(5, 12), "uncertain by +-3.4"),
    (
        "5-degree arc in space",
        fits.fit_circle_3d,
        np.column_stack([arc(5, 40), np.full(40, 7.0)]),
        "radius uncertain by",
    ),
    (
        "noise-free 0.001-degree arc",
        fits.fit_circle_2d,
        arc(0.001, 40, sigma=0.0),
        "ill-conditioned problem (condition number 1.7e+11, limit 1e+08)",
    ),
    (
        "4 nearly concyclic points",
        fits.fit_sphere,
        np.array([[10.0, 0, 0], [0, 10, 0], [-10, 0, 0], [0, -10, 1e-8]]),
        "ill-conditioned",
    ),
    ("2-degree cylinder sector", fits.fit_cylinder, cylinder(2, 400), "across the axis"),
]


@pytest.mark.parametrize(
    ("fit", "points", "found"), [r[1:] for r in REFUSED], ids=[r[0] for r in REFUSED]
)
def test_points_that_cannot_determine_the_shape_are_refused(
    fit: Callable[[Any], object], points: np.ndarray, found: str
) -> None:
    message = refused(fit, points)
    assert " fit: expected points that determine the shape, found " in message
    assert found in message
    assert "too short an arc, too small a cap, too few points or too much scatter" in message


def test_refusal_names_spread_and_scatter() -> None:
    message = refused(fits.fit_circle_2d, arc(5, 40))
    assert message == (
        "2-D circle fit: expected points that determine the shape, found the radius uncertain"
        " by +-1.1 (more than the 0.85 RMS spread of the points; RMS residual 0.0023): too"
        " short an arc, too small a cap, too few points or too much scatter"
    )


ACCEPTED = [
    ("10-degree arc, 2 um noise", fits.fit_circle_2d, arc(10, 40), 33.0, 0.5),
    ("noise-free 0.1-degree arc", fits.fit_circle_2d, arc(0.1, 40, sigma=0.0), 33.0, 1e-6),
    ("3 points, 120 degrees apart", fits.fit_circle_2d, arc(240, 3, sigma=0.0), 33.0, 1e-9),
    ("30-degree cap", fits.fit_sphere, cap(30), 9.525, 0.01),
    (
        "4 points of a sphere",
        fits.fit_sphere,
        np.array([[10.0, 0, 0], [0, 10, 0], [-10, 0, 0], [0, 0, 10]]),
        10.0,
        1e-9,
    ),
]


@pytest.mark.parametrize(
    ("fit", "points", "radius", "tol"), [a[1:] for a in ACCEPTED], ids=[a[0] for a in ACCEPTED]
)
def test_partial_arcs_and_few_points_converge(
    fit: Callable[[Any], Any], points: np.ndarray, radius: float, tol: float
) -> None:
    result = fit(points)
    assert abs(result.radius - radius) < tol
    assert result.condition <= CONDITION_LIMIT


# --- large data: the fast paths give the small-data answer ------------------------------------


def _same(a: Any, b: Any, tol: float) -> None:
    for name in ("centre", "point", "axis", "radius", "rms", "condition"):
        if hasattr(a, name):
            assert np.allclose(getattr(a, name), getattr(b, name), rtol=tol, atol=tol), name


@pytest.mark.parametrize("fit", [fits.fit_sphere, fits.fit_cylinder, fits.fit_circle_3d])
def test_large_data_paths_agree_with_the_exact_ones(
    fit: Callable[[Any], Any], monkeypatch: pytest.MonkeyPatch
) -> None:
    points = sphere(30_000) if fit is fits.fit_sphere else cylinder(270, 30_000)
    if fit is fits.fit_circle_3d:
        points = points.copy()
        points[:, 2] = 0.01 * np.random.default_rng(2).normal(size=len(points))
        points[:, :2] = (
            CENTRE[:2]
            + 20.0
            * (points[:, :2] - CENTRE[:2])
            / np.linalg.norm(points[:, :2] - CENTRE[:2], axis=1)[:, None]
        )
    fast = fit(points)  # subsample start, normal equations
    monkeypatch.setattr(fits_solver, "SAMPLE_SIZE", 10**9)
    monkeypatch.setattr(fits_solver, "NORMAL_EQUATIONS_FROM", 10**9)
    _same(fast, fit(points), 1e-9)
