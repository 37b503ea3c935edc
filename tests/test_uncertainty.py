"""Stated uncertainty (probegen.uncertainty, evaluate_uncertainty) and ISO 14253-1 decisions.

The coverage test simulates 200 noisy repeats of a bore (a cylinder, 3 sections of 8
touches) and of a sphere test: Gaussian noise on the ball centres and, for the bore, a
calibration error of the effective radius drawn from the stated ``u_radius``; the
stated ``U`` (k = 2) must cover the truth 95 % ± 3 % of the time.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pytest

from probegen.evaluate import Characteristic, evaluate_sphere_test
from probegen.evaluate_revolved import Nominal, evaluate_revolved
from probegen.uncertainty import Budget, decide, verdict

REPEATS = 200
NOISE = 0.002  # mm, per coordinate of each ball centre
U_RADIUS = 0.001  # mm, the calibration's stated effective-radius uncertainty
R_BALL = 3.0


@dataclass(frozen=True)
class Limits:
    diameter: tuple[float, float] | None = (-0.02, 0.02)
    position: float | None = 0.2
    form: float | None = 0.05
    roundness: float | None = None
    taper: float | None = None
    angle: tuple[float, float] | None = None


BORE = Nominal("cylinder", (50.0, 40.0, -15.0), (0.0, 0.0, 1.0), 30.0, True,
               (((50.0, 40.0, -5.0), 30.0), ((50.0, 40.0, -15.0), 30.0),
                ((50.0, 40.0, -25.0), 30.0)))
SHIFT = np.array([0.04, -0.03, 0.0])  # the bore's true axis is off nominal by this
D_TRUE = 30.006


def bore_centres(rng: np.random.Generator, r_true: float) -> tuple[np.ndarray, np.ndarray]:
    """Ball centres of the bore touched with a ball of effective radius ``r_true``."""
    theta = 0.2 + 2.0 * math.pi * np.arange(8) / 8
    rho = D_TRUE / 2.0 - r_true
    pts, secs = [], []
    for j, (centre, _) in enumerate(BORE.sections):
        for t in theta:
            pts.append(np.array(centre) + SHIFT + [rho * math.cos(t), rho * math.sin(t), 0.0])
            secs.append(j)
    return np.array(pts) + rng.normal(0.0, NOISE, (len(pts), 3)), np.array(secs)


def sphere_points(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Contact points of a 25 mm sphere test at (1, 2, 3) (5 rings of 5 and the pole)."""
    dirs = [(0.0, 0.0, 1.0)]
    for polar in (0.3, 0.7, 1.1, 1.4, 1.57):
        for k in range(5):
            a = 2.0 * math.pi * k / 5 + polar
            dirs.append((math.cos(a) * math.sin(polar), math.sin(a) * math.sin(polar),
                         math.cos(polar)))
    d = np.array(dirs)
    return np.array([1.0, 2.0, 3.0]) + 12.5 * d + rng.normal(0.0, NOISE, d.shape), d


def covered(c: Characteristic, truth: float) -> bool:
    assert c.U is not None
    return abs(c.measured - truth) <= c.U


def test_stated_u_covers_the_truth_95_percent() -> None:
    rng = np.random.default_rng(20261126)
    truth = {"X": 50.04, "Y": 39.97, "D": D_TRUE, "D_S2": D_TRUE,
             "POS": 2 * math.hypot(0.04, 0.03)}
    sphere_truth = {"X": 1.0, "Y": 2.0, "Z": 3.0, "D": 25.0, "POS": math.sqrt(14.0)}
    hits = {f"bore {k}": 0 for k in truth} | {f"sphere {k}": 0 for k in sphere_truth}
    for _ in range(REPEATS):
        r_true = R_BALL + rng.normal(0.0, U_RADIUS)
        centres, secs = bore_centres(rng, r_true)
        res = evaluate_revolved("B", BORE, centres, secs, ball_radius=R_BALL,
                                limits=Limits(), budget=Budget(radius=U_RADIUS))
        chars = {c.name: c for c in res.characteristics}
        for name, value in truth.items():
            hits[f"bore {name}"] += covered(chars[name], value)
        pts, dirs = sphere_points(rng)
        st = evaluate_sphere_test("S", pts, dirs, nominal_centre=(0.0, 0.0, 0.0),
                                  calibrated_diameter=25.0, ball_radius=R_BALL)
        schars = {c.name: c for c in st.characteristics}
        for name, value in sphere_truth.items():
            hits[f"sphere {name}"] += covered(schars[name], value)
    rates = {k: v / REPEATS for k, v in hits.items()}
    assert all(0.92 <= r <= 0.98 for r in rates.values()), rates


def test_u_is_the_least_squares_standard_error_for_exact_noise() -> None:
    # 24 touches, σ = 2 µm on every coordinate: the fitted radius's standard error is
    # σ/√n (residuals along the normal), the diameter's twice that; the centre's
    # √(2/n)σ per coordinate; the stated u agrees within the estimate's own spread.
    rng = np.random.default_rng(3)
    us = []
    for _ in range(20):
        centres, secs = bore_centres(rng, R_BALL)
        res = evaluate_revolved("B", BORE, centres, secs, ball_radius=R_BALL, limits=Limits())
        chars = {c.name: c for c in res.characteristics}
        us.append((chars["D"].u, chars["X"].u))
    u_d, u_x = np.mean(us, axis=0)
    assert u_d == pytest.approx(2 * NOISE / math.sqrt(24), rel=0.15)
    assert u_x == pytest.approx(NOISE * math.sqrt(2 / 24), rel=0.15)


def test_calibration_and_machine_contributions_add_in_quadrature() -> None:
    centres, secs = bore_centres(np.random.default_rng(1), R_BALL)
    bare = evaluate_revolved("B", BORE, centres, secs, ball_radius=R_BALL, limits=Limits())
    full = evaluate_revolved("B", BORE, centres, secs, ball_radius=R_BALL, limits=Limits(),
                             budget=Budget(radius=0.003, machine=0.004))
    b = {c.name: c.u for c in bare.characteristics}
    f = {c.name: c.u for c in full.characteristics}
    assert f["D"] == pytest.approx(math.sqrt(b["D"] ** 2 + 0.006**2 + 0.004**2))
    assert f["X"] == pytest.approx(math.hypot(b["X"], 0.004))  # a centre ignores the radius
    assert f["POS"] == pytest.approx(2 * math.hypot(b["POS"] / 2, 0.004))


def test_few_degrees_of_freedom_use_the_stated_probe_contribution() -> None:
    # a circle of 5 exact touches: n − p = 2, residual σ 0; the probe's 1 µm is used
    theta = 2 * math.pi * np.arange(5) / 5
    c = np.column_stack([7 * np.cos(theta), 7 * np.sin(theta), np.zeros(5)])
    nominal = Nominal("circle", (0.0, 0.0, 0.0), (0.0, 0.0, 1.0), 20.0, True,
                      (((0.0, 0.0, 0.0), 20.0),))
    none = evaluate_revolved("C", nominal, c, np.zeros(5), ball_radius=3.0, limits=Limits())
    probe = evaluate_revolved("C", nominal, c, np.zeros(5), ball_radius=3.0, limits=Limits(),
                              budget=Budget(probe=0.001))
    d0 = {ch.name: ch for ch in none.characteristics}["D"]
    d1 = {ch.name: ch for ch in probe.characteristics}["D"]
    assert d0.u == pytest.approx(0.0, abs=1e-9)
    assert d1.u == pytest.approx(2 * 0.001 / math.sqrt(5), rel=1e-3)


@pytest.mark.parametrize("deviation, u, expected", [
    (0.000, 0.001, "conforming"),       # well inside
    (0.009, 0.001, "undecided"),        # inside, within U = 0.002 of the upper limit
    (0.011, 0.001, "undecided"),        # outside, within U
    (0.013, 0.001, "non-conforming"),   # outside the limits widened by U
    (-0.0125, 0.001, "non-conforming"),
    (0.009, None, "conforming"),        # no uncertainty: the value decides
    (0.011, 0.0, "non-conforming"),
    (0.0, 0.006, "undecided"),          # U wider than half the tolerance: never proven
])
def test_iso_14253_decision(deviation: float, u: float | None, expected: str) -> None:
    assert decide(deviation, -0.01, 0.01, u) == expected
    c = Characteristic("D", 20 + deviation, 20.0, deviation, -0.01, 0.01, u)
    assert c.decision == expected
    assert c.accepted("simple") is c.ok  # simple acceptance: the value alone
    assert c.accepted("guard_band") is (expected == "conforming")


def test_untoleranced_has_no_decision_and_u_gives_U() -> None:
    c = Characteristic("X", 1.0, 1.0, 0.0, u=0.0015)
    assert c.decision is None and c.accepted("guard_band") is None
    assert c.U == pytest.approx(0.003)
    assert Characteristic("X", 1.0, 1.0, 0.0).U is None
    assert verdict(None, None, "guard_band") is None
    one_sided = Characteristic("FORM", 0.0095, 0.0, 0.0095, None, 0.01, 0.001)
    assert one_sided.decision == "undecided" and one_sided.ok is True
