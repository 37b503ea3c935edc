"""Evaluation of revolved features (``evaluate_revolved``) on synthetic ball centres.

Ball centres are built by hand on the offset surface of a known feature, placed off
nominal (shifted and, where the kind allows, tilted), with planted form errors; the
evaluation must give back the truth to 1e-6 mm (exact data: only the fits' own
convergence limits it).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest
from conftest import REPO
from fuzzing import examples
from hypothesis import given, settings
from hypothesis import strategies as st

from probegen.errors import ProbegenError, SpecError
from probegen.evaluate.revolved import Nominal, evaluate_revolved
from probegen.geometry.frames import rotation_to_z
from probegen.spec.model import load_spec

R_BALL = 3.0
EXACT = 1e-6


@dataclass(frozen=True)
class Limits:
    diameter: tuple[float, float] | None = (-0.01, 0.01)
    position: float | None = 0.05
    form: float | None = 0.01
    roundness: float | None = 0.003
    taper: float | None = 0.005
    angle: tuple[float, float] | None = (-0.05, 0.05)
    # the exact values below are least-squares ranges (ptp of the sampled lobes);
    # test_minimum_zone.py checks the default, the minimum zone
    form_method: str = "least_squares"


def chars(result: object) -> dict[str, object]:
    return {c.name: c for c in result.characteristics}  # type: ignore[attr-defined]


def placed(points: np.ndarray, shift: np.ndarray, tilt: np.ndarray | None) -> np.ndarray:
    """Points of a feature built about +Z at the origin, tilted onto ``tilt``, moved."""
    rot = np.eye(3) if tilt is None else rotation_to_z(tilt).T
    return points @ rot.T + shift


def ring(n: int, phase: float = 0.1) -> np.ndarray:
    return phase + 2.0 * math.pi * np.arange(n) / n


def test_cylinder_taper_roundness_position() -> None:
    # bore R 25, sections at z = 10 and 40; δ = 0.004 + 2e-4·z + 0.002·cos 3θ
    theta, z = np.tile(ring(8), 2), np.repeat([40.0, 10.0], 8)
    delta = 0.004 + 2e-4 * z + 0.002 * np.cos(3 * theta)
    rho = 25.0 + delta - R_BALL  # the ball is inside the bore
    pts = np.column_stack([rho * np.cos(theta), rho * np.sin(theta), z])
    shift = np.array([50.3, 49.8, 0.0])
    c = placed(pts, shift, None)
    nominal = Nominal("cylinder", (50.0, 50.0, 25.0), (0.0, 0.0, 1.0), 50.0, True,
                      (((50.0, 50.0, 40.0), 50.0), ((50.0, 50.0, 10.0), 50.0)))
    res = evaluate_revolved("B", nominal, c, np.repeat([0, 1], 8), ball_radius=R_BALL,
                            limits=Limits())
    ch = chars(res)
    # 8 equally spaced points: the 3-lobe is orthogonal to the circle's terms
    assert ch["D_S1"].measured == pytest.approx(50.0 + 2 * (0.004 + 0.008), abs=EXACT)
    assert ch["D_S2"].measured == pytest.approx(50.0 + 2 * (0.004 + 0.002), abs=EXACT)
    assert ch["TAPER"].measured == pytest.approx(2 * 2e-4 * 30.0, abs=EXACT)
    assert ch["TAPER"].ok is False  # 0.012 against ±0.005
    sampled = 0.002 * np.cos(3 * ring(8))
    assert ch["RON_S1"].measured == pytest.approx(np.ptp(sampled), abs=EXACT)
    assert ch["RON_S1"].ok is False  # 0.0037 > 0.003
    assert ch["D"].measured == pytest.approx(50.0 + 2 * (0.004 + 0.005), abs=EXACT)
    assert ch["POS"].measured == pytest.approx(2 * math.hypot(0.3, 0.2), abs=EXACT)
    assert ch["TILT"].measured == pytest.approx(0.0, abs=1e-6)
    assert res.kind == "cylinder" and res.diameter == ch["D"].measured
    # the contact points lie on the surface: r from the ball centres, away from the axis
    radial = np.hypot(*(np.array(res.points)[:, :2] - shift[:2]).T)
    assert np.allclose(radial, 25.0 + delta, atol=EXACT)


def cone_centres(apex_radius_at_0: float, alpha: float, heights: np.ndarray,
                 theta: np.ndarray, delta: np.ndarray, outer: bool) -> np.ndarray:
    """Ball centres on a cone about +Z (radius ``R0 + z·tan α`` of the surface at
    ``z``, plus δ), the ball touching along the normal from outside (``outer``)."""
    sign = 1.0 if outer else -1.0
    e = np.column_stack([np.cos(theta), np.sin(theta), np.zeros_like(theta)])
    n = sign * (math.cos(alpha) * e - math.sin(alpha) * np.array([0.0, 0.0, 1.0]))
    surf = (apex_radius_at_0 + heights * math.tan(alpha) + delta)[:, None] * e
    surf[:, 2] = heights
    return surf + R_BALL * n


@pytest.mark.parametrize("outer", [True, False])
def test_cone_gauge_diameters_angle_and_roundness(outer: bool) -> None:
    alpha = math.atan(0.2)  # 11.31 degrees; surface radius 8 + 0.2·z, axis +Z up
    theta = np.tile(ring(8), 2)
    h = np.repeat([5.0, 15.0], 8)
    lobes = 0.003 * np.cos(3 * theta + 0.4)
    c = cone_centres(8.0, alpha, h, theta, 0.005 + lobes, outer)
    tilt = np.array([0.01, -0.02, 1.0])
    shift = np.array([25.3, 74.8, 30.0])
    c = placed(c, shift, tilt)
    axis = tuple(tilt / np.linalg.norm(tilt))
    apex = tuple(shift - 40.0 * np.asarray(axis))
    sections = tuple((tuple(shift + z * np.asarray(axis)), 2 * (8 + 0.2 * z)) for z in (5.0, 15.0))
    nominal = Nominal("cone", apex, axis, 0.0, not outer, sections, half_angle=alpha)  # type: ignore[arg-type]
    res = evaluate_revolved("C", nominal, c, np.repeat([0, 1], 8), ball_radius=R_BALL,
                            limits=Limits())
    ch = chars(res)
    # second order in the lobes (δ²/R ~ 1e-6 mm) moves the least-squares angle a little
    assert ch["ANGLE"].measured == pytest.approx(math.degrees(alpha), abs=1e-5)
    assert ch["D_S1"].measured == pytest.approx(18.0 + 0.01, abs=EXACT)
    assert ch["D_S2"].measured == pytest.approx(22.0 + 0.01, abs=EXACT)
    assert ch["RON_S1"].measured == pytest.approx(np.ptp(lobes[:8]), abs=EXACT)
    assert ch["POS"].measured == pytest.approx(0.0, abs=EXACT)
    assert res.half_angle == pytest.approx(alpha, abs=1e-7)
    # the surface's apex moves by δ/tan α along the axis (a radius δ larger everywhere)
    want = np.asarray(apex) - 0.005 / math.tan(alpha) * np.asarray(axis)
    assert np.allclose(res.apex, want, atol=1e-5)
    radial_dev = np.asarray(res.residuals) / math.cos(alpha)
    assert np.ptp(radial_dev) == pytest.approx(np.ptp(lobes), abs=EXACT)


@pytest.mark.parametrize("inside", [False, True])
def test_sphere_centre_and_diameter(inside: bool) -> None:
    rng = np.random.default_rng(3)
    theta = np.tile(ring(8), 2)
    polar = np.repeat([0.6, 1.3], 8)
    u = np.column_stack([np.sin(polar) * np.cos(theta), np.sin(polar) * np.sin(theta),
                         np.cos(polar)])
    r_ball = 15.0 + 0.004 + (-R_BALL if inside else R_BALL)
    centre = np.array([75.2, 74.9, 30.05])
    c = centre + r_ball * u + 0.0 * rng.normal(size=u.shape)
    nominal = Nominal("sphere", (75.0, 75.0, 30.0), (0.0, 0.0, 1.0), 30.0, inside,
                      (((75.0, 75.0, 40.0), 22.4), ((75.0, 75.0, 33.0), 29.4)))
    res = evaluate_revolved("S", nominal, c, np.repeat([0, 1], 8), ball_radius=R_BALL,
                            limits=Limits())
    ch = chars(res)
    assert ch["D"].measured == pytest.approx(30.008, abs=EXACT)
    assert ch["POS"].measured == pytest.approx(2 * math.sqrt(0.04 + 0.01 + 0.0025), abs=EXACT)
    assert ch["FORM"].measured == pytest.approx(0.0, abs=EXACT)
    assert np.allclose(np.linalg.norm(np.array(res.points) - centre, axis=1), 15.004,
                       atol=EXACT)


@pytest.mark.parametrize("ball_in_tube", [False, True])
def test_torus_tube_and_major_diameter(ball_in_tube: bool) -> None:
    theta = np.tile(ring(8), 3)
    phi = np.repeat([0.2, 0.7, 1.2], 8)  # tube angles from the equator
    major, minor = 19.0, 4.0 + 0.003
    tube = minor - R_BALL if ball_in_tube else minor + R_BALL
    e = np.column_stack([np.cos(theta), np.sin(theta), np.zeros_like(theta)])
    # the inner half of the tube (towards the axis), as the rounded top edge of a bore
    n = -np.cos(phi)[:, None] * e + np.sin(phi)[:, None] * np.array([0.0, 0.0, 1.0])
    centre = np.array([25.1, 24.9, 26.0])
    c = centre + major * e + tube * n
    nominal = Nominal("torus", (25.0, 25.0, 26.0), (0.0, 0.0, 1.0), 8.0, ball_in_tube,
                      tuple(((25.0, 25.0, 26.0 + 4 * math.sin(p)), 30.0) for p in
                            (0.2, 0.7, 1.2)), major_diameter=38.0)
    res = evaluate_revolved("T", nominal, c, np.repeat([0, 1, 2], 8), ball_radius=R_BALL,
                            limits=Limits())
    ch = chars(res)
    assert ch["D"].measured == pytest.approx(8.006, abs=EXACT)
    assert ch["DMAJ"].measured == pytest.approx(38.0, abs=EXACT)
    assert ch["POS"].measured == pytest.approx(2 * math.hypot(0.1, 0.1), abs=EXACT)
    assert res.major_diameter == pytest.approx(38.0, abs=EXACT)


def test_too_few_sections_is_an_error() -> None:
    theta = ring(8)
    c = np.column_stack([22 * np.cos(theta), 22 * np.sin(theta), np.full(8, 10.0)])
    nominal = Nominal("cylinder", (0.0, 0.0, 25.0), (0.0, 0.0, 1.0), 50.0, True,
                      (((0.0, 0.0, 40.0), 50.0), ((0.0, 0.0, 10.0), 50.0)))
    with pytest.raises(ProbegenError, match="at least 2 sections, found 1"):
        evaluate_revolved("B", nominal, c, np.zeros(8, dtype=int), ball_radius=R_BALL,
                          limits=Limits())


KINDS = {
    "circle": Nominal("circle", (0.0, 0.0, 10.0), (0.0, 0.0, 1.0), 50.0, True,
                      (((0.0, 0.0, 10.0), 50.0),)),
    "cylinder": Nominal("cylinder", (0.0, 0.0, 25.0), (0.0, 0.0, 1.0), 50.0, True,
                        (((0.0, 0.0, 40.0), 50.0), ((0.0, 0.0, 10.0), 50.0))),
    "cone": Nominal("cone", (0.0, 0.0, -40.0), (0.0, 0.0, 1.0), 0.0, False,
                    (((0.0, 0.0, 15.0), 22.0), ((0.0, 0.0, 5.0), 18.0)),
                    half_angle=math.atan(0.2)),
    "sphere": Nominal("sphere", (0.0, 0.0, 0.0), (0.0, 0.0, 1.0), 30.0, False,
                      (((0.0, 0.0, 10.0), 22.4), ((0.0, 0.0, 3.0), 29.4))),
    "torus": Nominal("torus", (0.0, 0.0, 0.0), (0.0, 0.0, 1.0), 8.0, False,
                     (((0.0, 0.0, 3.0), 32.0), ((0.0, 0.0, 2.0), 33.0),
                      ((0.0, 0.0, 1.0), 34.0)), major_diameter=38.0),
}


@settings(max_examples=examples(120))
@given(st.sampled_from(sorted(KINDS)), st.integers(3, 24),
       st.lists(st.floats(-60.0, 60.0, allow_nan=False), min_size=72, max_size=72),
       st.integers(0, 3))
def test_any_touches_give_a_result_or_a_clear_error(kind: str, n: int, coords: list[float],
                                                     mode: int) -> None:
    """Random ball centres (anywhere, on the axis, repeated, or on the nominal rings with
    up to 0.6 mm of scatter): a finite result or a ProbegenError, never another
    exception or a NaN."""
    c = np.array(coords[: 3 * n]).reshape(-1, 3)
    k = np.arange(len(c)) % len(KINDS[kind].sections)
    if mode == 3:  # scattered about the nominal rings
        angle = 2.0 * math.pi * np.arange(len(c)) / len(c)
        ring = np.array([KINDS[kind].sections[j][0] for j in k])
        radius = np.array([KINDS[kind].sections[j][1] / 2.0 - R_BALL for j in k])
        c = ring + np.column_stack([radius * np.cos(angle), radius * np.sin(angle),
                                    np.zeros(len(c))]) + c / 100.0
    if mode == 1:  # on the axis
        c[:, :2] = 0.0
    elif mode == 2:  # coincident
        c[:] = c[0]
    try:
        res = evaluate_revolved("F", KINDS[kind], c, k, ball_radius=R_BALL, limits=Limits())
    except ProbegenError:
        return
    assert all(math.isfinite(ch.measured) for ch in res.characteristics)
    assert np.all(np.isfinite(res.points))


SPEC = """\
[part]
model = "{model}"
units = "{units}"
[machine]
profile = "{profile}"
[[feature]]
id = "C"
kind = "cone"
face = 7
sections = [0.2, 0.6]
tolerance = {{ diameter = [-0.001, 0.001], roundness = 0.0002, taper = 0.0004, angle = {angle} }}
"""


@pytest.mark.parametrize("units, scale", [("mm", 1.0), ("inch", 25.4)])
def test_spec_tolerance_keys(tmp_path: Path, units: str, scale: float) -> None:
    path = tmp_path / "spec.toml"
    path.write_text(SPEC.format(model=REPO / "samples/revolved_block/revolved_block.step",
                                profile=REPO / "samples/machines/vmc-fanuc.toml",
                                units=units, angle="[-0.05, 0.1]"))
    tol = load_spec(path).features[0].tolerance  # type: ignore[union-attr]
    assert tol.roundness == pytest.approx(0.0002 * scale)
    assert tol.taper == pytest.approx(0.0004 * scale)
    assert tol.angle == (-0.05, 0.1)  # degrees, whatever the units


def test_spec_angle_limits_in_order(tmp_path: Path) -> None:
    path = tmp_path / "spec.toml"
    path.write_text(SPEC.format(model=REPO / "samples/revolved_block/revolved_block.step",
                                profile=REPO / "samples/machines/vmc-fanuc.toml",
                                units="mm", angle="[0.1, -0.1]"))
    with pytest.raises(SpecError, match=r"feature\[0\].tolerance.angle: expected \[lower, upper\]"):
        load_spec(path)
