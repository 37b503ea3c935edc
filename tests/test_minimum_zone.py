"""One convention for all kinds (issue 15, item 7): ISO 1101 minimum-zone form with least
squares as an option, residuals + where material is outside the nominal surface, position
as the zone diameter."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from fuzzing import examples
from hypothesis import given, settings
from hypothesis import strategies as st

from probegen.errors import SpecError
from probegen.evaluate.revolved import Nominal, evaluate_revolved
from probegen.evaluate.sphere_test import evaluate_sphere_test
from probegen.geometry import minimum_zone as mz
from probegen.geometry.fits import (
    fit_circle_2d,
    fit_cylinder,
    fit_line_2d,
    fit_line_3d,
    fit_plane,
    fit_sphere,
)
from probegen.spec.model import RevolvedTolerance, load_spec

R_BALL = 2.0


def lobed(n_even: int = 6, extra: int = 40, amplitude: float = 0.01,
          radius: float = 10.0) -> np.ndarray:
    """A three-lobed section ``r = R + a cos 3θ`` with its six extremes sampled and
    ``extra`` points crowded on one quarter (which pulls the least-squares centre
    off the lobes' centre): its minimum zone is exactly ``2 a``."""
    theta = np.radians(np.concatenate([np.arange(0.0, 360.0, 360.0 / n_even),
                                       np.linspace(5.0, 85.0, extra)]))
    r = radius + amplitude * np.cos(3 * theta)
    return np.column_stack([r * np.cos(theta), r * np.sin(theta)])


def test_minimum_zone_roundness_of_lobed_points_is_the_known_zone() -> None:
    points = lobed()
    ls = fit_circle_2d(points)
    zone = mz.roundness(points, ls.centre)
    assert zone == pytest.approx(0.02, abs=1e-9)
    assert ls.form > zone + 0.005  # least squares is wider here (0.038)


def test_minimum_zone_cylindricity_flatness_sphericity_straightness() -> None:
    ring = lobed()
    tube = np.vstack([np.column_stack([ring, np.full(len(ring), z)]) for z in (0, 10, 20)])
    cyl = fit_cylinder(tube)
    assert mz.cylindricity(tube, cyl.point, cyl.axis) == pytest.approx(0.02, abs=1e-8)
    assert cyl.form > 0.03
    # a plane with one 5 um bump among many points, and a tilt: zone 0.005 exactly
    rng = np.random.default_rng(0)
    xy = rng.uniform(-10.0, 10.0, (200, 2))
    z = 0.001 * xy[:, 0] + np.where(np.arange(200) == 7, 0.005, 0.0)
    plane = np.column_stack([xy, z])
    ls = fit_plane(plane)
    flat = mz.flatness(plane, ls.point, ls.normal)
    assert flat == pytest.approx(0.005 / math.hypot(1.0, 0.001), abs=1e-9)
    assert flat <= ls.form
    # a sphere with points on two shells 10 um apart
    dirs = rng.normal(size=(60, 3))
    dirs /= np.linalg.norm(dirs, axis=1)[:, None]
    shell = dirs * (5.0 + 0.01 * (np.arange(60) % 2))[:, None]
    sph = fit_sphere(shell)
    assert mz.sphericity(shell, sph.centre) == pytest.approx(0.01, abs=1e-9)
    # a 2-D line: a step of 3 um in the middle of a tilted line
    u = np.linspace(0.0, 50.0, 51)
    line = np.column_stack([u, 0.01 * u + np.where(abs(u - 25.0) < 3.0, 0.003, 0.0)])
    l2 = fit_line_2d(line)
    assert mz.straightness_2d(line, l2.point, l2.direction) == pytest.approx(
        0.003 / math.hypot(1.0, 0.01), abs=1e-9)
    assert mz.straightness_2d(line, l2.point, l2.direction) <= l2.form
    # a 3-D line: points on a helix of radius 2 um about a tilted axis: cylinder D 4 um
    t = np.linspace(0.0, 4.0 * math.pi, 80)
    helix = np.column_stack([0.002 * np.cos(t), 0.002 * np.sin(t), 3.0 * t])
    l3 = fit_line_3d(helix)
    assert mz.straightness_3d(helix, l3.point, l3.direction) == pytest.approx(0.004, abs=1e-8)
    assert mz.straightness_3d(helix, l3.point, l3.direction) <= l3.form + 1e-12


def bore_centres(deltas: np.ndarray, radius: float = 15.0) -> np.ndarray:
    """Ball centres in a bore (ball inside) of the given radial surface deviations
    (+ away from the axis), at two heights."""
    theta = 0.1 + 2.0 * math.pi * np.arange(len(deltas) // 2) / (len(deltas) // 2)
    theta = np.tile(theta, 2)
    z = np.repeat([20.0, 5.0], len(deltas) // 2)
    rho = radius + deltas - R_BALL
    return np.column_stack([rho * np.cos(theta), rho * np.sin(theta), z])


BORE = Nominal("cylinder", (0.0, 0.0, 12.5), (0.0, 0.0, 1.0), 30.0, True,
               (((0.0, 0.0, 20.0), 30.0), ((0.0, 0.0, 5.0), 30.0)))


def test_a_bore_with_material_added_reads_a_positive_residual() -> None:
    deltas = np.zeros(16)
    deltas[3] = -0.005  # the surface 5 um nearer the axis: material where air should be
    res = evaluate_revolved("B", BORE, bore_centres(deltas), np.repeat([0, 1], 8),
                            ball_radius=R_BALL, limits=RevolvedTolerance())
    assert int(np.argmax(res.residuals)) == 3
    # the least-squares cylinder absorbs about a third of a lone 5 um bump
    assert res.residuals[3] > 0.003
    assert max(abs(r) for i, r in enumerate(res.residuals) if i != 3) < 0.0015
    # ... and a boss with material added too (the ball outside, the surface further out)
    theta = 0.1 + 2.0 * math.pi * np.arange(8) / 8
    rho = 15.0 + np.where(np.arange(8) == 5, 0.005, 0.0) + R_BALL
    boss = np.column_stack([np.tile(rho * np.cos(theta), 2), np.tile(rho * np.sin(theta), 2),
                            np.repeat([20.0, 5.0], 8)])
    outer = Nominal("cylinder", (0.0, 0.0, 12.5), (0.0, 0.0, 1.0), 30.0, False, BORE.sections)
    res = evaluate_revolved("P", outer, boss, np.repeat([0, 1], 8), ball_radius=R_BALL,
                            limits=RevolvedTolerance())
    assert {int(np.argmax(res.residuals)) % 8} == {5}
    assert max(res.residuals) > 0.002


def test_form_characteristics_name_their_method_and_minimum_zone_is_narrower() -> None:
    lobes = 0.002 * np.cos(3 * (0.1 + 2.0 * math.pi * np.arange(8) / 8))
    centres = bore_centres(np.tile(lobes, 2))
    k = np.repeat([0, 1], 8)
    zone = evaluate_revolved("B", BORE, centres, k, ball_radius=R_BALL, limits=RevolvedTolerance())
    ls = evaluate_revolved("B", BORE, centres, k, ball_radius=R_BALL,
                           limits=RevolvedTolerance(form_method="least_squares"))
    for name in ("FORM", "RON_S1", "RON_S2"):
        mz_c = next(c for c in zone.characteristics if c.name == name)
        ls_c = next(c for c in ls.characteristics if c.name == name)
        assert (mz_c.method, ls_c.method) == ("minimum zone", "least squares")
        assert mz_c.measured <= ls_c.measured + 1e-12
    assert next(c for c in ls.characteristics if c.name == "RON_S1").measured == pytest.approx(
        float(np.ptp(lobes)), abs=1e-6)
    assert all(c.method == "" for c in zone.characteristics
               if c.name in ("X", "Y", "Z", "POS", "D"))


def test_sphere_test_position_is_the_zone_diameter() -> None:
    dirs = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1],
                     [0.6, 0.0, 0.8], [0.0, 0.6, 0.8], [-0.6, 0.0, 0.8]], dtype=float)
    offset = np.array([0.003, -0.004, 0.0])  # 5 um from the nominal centre
    points = offset + 12.5 * dirs
    res = evaluate_sphere_test("S", points, dirs, nominal_centre=(0.0, 0.0, 0.0),
                               calibrated_diameter=25.0, ball_radius=R_BALL, position=0.009)
    pos = next(c for c in res.characteristics if c.name == "POS")
    assert pos.measured == pytest.approx(0.010, abs=1e-9)
    assert pos.ok is False  # a 0.009 zone does not hold a centre 5 um off
    p_ftu = next(c for c in res.characteristics if c.name == "P_FTU")
    assert p_ftu.method == "least squares"  # ISO 10360-5 defines it so


def test_form_method_spec_key(tmp_path: Path) -> None:
    root = Path(__file__).resolve().parent.parent / "samples" / "bore_block"
    text = (root / "bore_block.toml").read_text()
    spec = tmp_path / "spec.toml"

    def load(body: str):  # type: ignore[no-untyped-def]
        for key in ("profile", "model"):
            body = body.replace(f'{key} = "', f'{key} = "{root}/')
        spec.write_text(body)
        return load_spec(spec)

    default = load(text)
    revolved = [f for f in default.features if hasattr(f, "tolerance")
                and hasattr(f.tolerance, "form_method")]
    assert revolved and all(f.tolerance.form_method == "minimum_zone" for f in revolved)
    ls = load(text + '\n[evaluation]\nform_method = "least_squares"\n')
    assert all(f.tolerance.form_method == "least_squares" for f in ls.features
               if hasattr(f.tolerance, "form_method"))
    with pytest.raises(SpecError, match="form_method"):
        load(text + '\n[evaluation]\nform_method = "chebyshev"\n')


def test_a_displaced_cone_gives_the_same_gauge_diameters() -> None:
    """Gauge planes follow the feature: a cone moved across its axis, or tilted about
    its top gauge point, gives the gauge diameters of the cone in place (the planes are
    square to the fitted axis, at their nominal spacing from the top one).  A move
    along the axis is a size error for a cone measured alone (docs/results.md)."""
    from test_evaluate_revolved import R_BALL as CONE_BALL
    from test_evaluate_revolved import cone_centres, placed

    alpha = math.atan(0.2)
    theta = np.tile(0.1 + 2.0 * math.pi * np.arange(8) / 8, 2)
    h = np.repeat([15.0, 5.0], 8)
    c = cone_centres(8.0, alpha, h, theta, np.full(16, 0.004), False)
    sections = (((0.0, 0.0, 15.0), 22.0), ((0.0, 0.0, 5.0), 18.0))
    nominal = Nominal("cone", (0.0, 0.0, -40.0), (0.0, 0.0, 1.0), 0.0, True, sections,
                      half_angle=alpha)
    k = np.repeat([0, 1], 8)

    def gauges(points: np.ndarray) -> list[float]:
        res = evaluate_revolved("C", nominal, points, k, ball_radius=CONE_BALL,
                                limits=RevolvedTolerance())
        return [c.measured for c in res.characteristics if c.name.startswith("D_S")]

    home = gauges(c)
    assert home == pytest.approx([22.008, 18.008], abs=1e-6)
    across = gauges(c + np.array([0.4, -0.3, 0.0]))
    assert across == pytest.approx(home, abs=1e-6)
    tilt = np.array([0.002, -0.001, 1.0])  # 0.13 degrees about the top gauge point
    top = np.array([0.0, 0.0, 15.0])
    tilted = gauges(placed(c - top, top, tilt))
    assert tilted == pytest.approx(home, abs=1e-9)


@settings(max_examples=examples(40))
@given(st.lists(st.floats(-0.01, 0.01), min_size=5, max_size=40),
       st.floats(0.0, 2.0 * math.pi))
def test_minimum_zone_roundness_is_never_wider_than_least_squares(
        deviations: list[float], phase: float) -> None:
    n = len(deviations)
    theta = phase + 2.0 * math.pi * np.arange(n) / n
    r = 10.0 + np.asarray(deviations)
    points = np.column_stack([r * np.cos(theta), r * np.sin(theta)])
    ls = fit_circle_2d(points)
    zone = mz.roundness(points, ls.centre)
    assert 0.0 <= zone <= ls.form + 1e-12
    assert zone <= float(np.ptp(r)) + 1e-9  # the zone about the origin is one candidate
