"""Stated uncertainty (geometry.uncertainty, evaluate.uncertainty) and ISO 14253-1 decisions.

The coverage test simulates 200 noisy repeats of a bore (a cylinder, 3 sections of 8
touches) and of a sphere test: Gaussian noise on the ball centres and, for the bore, a
calibration error of the effective radius drawn from the stated ``u_radius``; the
stated ``U`` (k = 2) must cover the truth 95 % ± 3 % of the time.
"""

from __future__ import annotations

import dataclasses
import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest
from conftest import REPO
from fuzzing import examples
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from mutations import mutate

from probegen.cli.app import main
from probegen.errors import ExitCode, ProbegenError, SpecError
from probegen.evaluate.characteristics import Characteristic
from probegen.evaluate.ingest import ingest
from probegen.evaluate.revolved import Nominal, evaluate_revolved
from probegen.evaluate.sphere_test import evaluate_sphere_test
from probegen.geometry.uncertainty import Budget, decide, few_dof_note, verdict
from probegen.machine.calibration import load_calibration
from probegen.machine.profile import load_profile
from probegen.spec.model import load_spec

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
    sphere_truth = {"X": 1.0, "Y": 2.0, "Z": 3.0, "D": 25.0, "POS": 2 * math.sqrt(14.0)}
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
    # every output says so
    sphere = ingest(SAMPLE / "sphere_test.log", load_spec(SAMPLE / "sphere_test.toml"))
    notes = dataclasses.replace(sphere, revolved=(none,)).uncertainty_notes
    assert ("uncertainty: feature C: 5 touches for 3 fit parameters leave 2 degrees of "
            "freedom (< 5): the residual sigma is unreliable; u uses it or nothing: state "
            "the profile's [uncertainty] probe") in notes
    assert not any("feature SPH1" in n for n in notes)  # 25 touches: 21 dof
    assert few_dof_note("C", "circle", 5, Budget(probe=0.001)) is not None
    assert few_dof_note("C", "circle", 8, Budget()) is None


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


SAMPLE = REPO / "samples/sphere25"


def _stated_spec(tmp_path: Path, extra: str = "", tolerance: str = "") -> Path:
    """The sphere-test sample spec with a profile that states its uncertainty."""
    profile = tmp_path / "vmc.toml"
    profile.write_text((REPO / "samples/machines/vmc-fanuc.toml").read_text()
                       + "\n[uncertainty]\nmachine = 0.002\nprobe = 0.001\n")
    text = (SAMPLE / "sphere_test.toml").read_text()
    text = text.replace('"../machines/vmc-fanuc.toml"', f'"{profile}"')
    text = text.replace('"sphere25.step"', f'"{SAMPLE / "sphere25.step"}"')
    text = text.replace("[program]", extra + "[program]")
    spec = tmp_path / "spec.toml"
    spec.write_text(text + tolerance)
    return spec


def test_stated_contributions_reach_every_output(tmp_path: Path,
                                                 capsys: pytest.CaptureFixture[str]) -> None:
    spec = _stated_spec(tmp_path)
    cal = tmp_path / "probe.toml"
    assert main(["ingest", str(SAMPLE / "sphere_test.log"), "--spec", str(spec), "-o",
                 str(tmp_path), "--write-calibration", str(cal)]) == ExitCode.OK
    out = capsys.readouterr().out
    header = next(line for line in out.splitlines() if line.startswith("feature"))
    assert header.split()[-3:] == ["U", "decision", "method"]
    assert "was not stated" not in out
    doc = json.loads((tmp_path / "results.json").read_text())
    assert doc["uncertainty"] == {"k": 2.0, "decision_rule": "simple", "u_radius": 0.0,
                                  "machine": 0.002, "probe": 0.001, "notes": []}
    chars = {c["name"]: c for c in doc["features"][0]["characteristics"]}
    # the machine's 2 µm dominates every length; the form uses the probe's 1 µm
    assert 0.002 < chars["D"]["u"] < 0.0021 and chars["D"]["U"] == pytest.approx(
        2 * chars["D"]["u"], abs=2e-7)
    assert chars["P_FTU"]["u"] == pytest.approx(math.sqrt(2) * 0.001, abs=1e-7)
    rows = (tmp_path / "results.csv").read_text().splitlines()
    assert ",status,u,U,decision," in rows[0]
    # the calibration carries the effective radius's u; an old file reads as 0
    written = load_calibration(cal)
    assert written.u_radius == pytest.approx(chars["R_EFF"]["u"], abs=1e-7)
    old = tmp_path / "old.toml"
    old.write_text("\n".join(ln for ln in cal.read_text().splitlines()
                             if not ln.startswith("u_radius")))
    assert load_calibration(old).u_radius == 0.0
    again = ingest(SAMPLE / "sphere_test.log", load_spec(spec), calibration=written)
    assert again.budget.radius == written.u_radius


def test_guard_band_refuses_an_undecided_value(tmp_path: Path,
                                               capsys: pytest.CaptureFixture[str]) -> None:
    # P_STU -0.8 µm against ±2 µm with U ≈ 4 µm: OK by simple acceptance, undecided,
    # so NOT OK when guard-banded (option or the spec's [evaluation] table)
    tol = "tolerance = { size = 0.002 }\n"
    log = str(SAMPLE / "sphere_test.log")
    simple = _stated_spec(tmp_path, tolerance=tol)
    assert main(["ingest", log, "--spec", str(simple), "-o", str(tmp_path)]) == ExitCode.OK
    doc = json.loads((tmp_path / "results.json").read_text())
    d = {c["name"]: c for c in doc["features"][0]["characteristics"]}["D"]
    assert (d["ok"], d["decision"]) == (True, "undecided")
    assert main(["ingest", log, "--spec", str(simple), "-o", str(tmp_path),
                 "--decision-rule", "guard_band"]) == ExitCode.NOT_OK
    doc = json.loads((tmp_path / "results.json").read_text())
    d = {c["name"]: c for c in doc["features"][0]["characteristics"]}["D"]
    assert (d["ok"], d["decision"], doc["features"][0]["ok"]) == (False, "undecided", False)
    banded = _stated_spec(tmp_path, '[evaluation]\ndecision_rule = "guard_band"\n\n', tol)
    assert load_spec(banded).decision_rule == "guard_band"
    assert main(["ingest", log, "--spec", str(banded), "-o", str(tmp_path)]) == ExitCode.NOT_OK
    assert "decision rule guard_band" in capsys.readouterr().out


def test_bad_uncertainty_settings_name_the_key(tmp_path: Path) -> None:
    bad = _stated_spec(tmp_path, '[evaluation]\ndecision_rule = "lenient"\n\n')
    with pytest.raises(SpecError, match=r"evaluation\.decision_rule"):
        load_spec(bad)
    profile = tmp_path / "vmc.toml"
    profile.write_text(profile.read_text().replace("machine = 0.002", "machine = -1"))
    with pytest.raises(SpecError, match=r"uncertainty\.machine: expected a number >= 0"):
        load_profile(profile)


PROFILE_TEXT = (REPO / "samples/machines/vmc-fanuc.toml").read_text()
STATED = "\n[uncertainty]\nmachine = 0.002\nprobe = 0.001\n"
CALIBRATION = ("[calibration]\nball_radius = 3.0\neffective_radius = 2.9996\n"
               "directions = [[0.0, 0.0, 1.0]]\nradii = [2.9996]\nu_radius = 0.0002\n")
EVALUATION = '\n[evaluation]\ndecision_rule = "guard_band"\n'


@st.composite
def _mutated(draw: st.DrawFn) -> tuple[str, str]:
    which = draw(st.sampled_from(["profile", "calibration", "evaluation"]))
    base = {"profile": STATED, "calibration": CALIBRATION, "evaluation": EVALUATION}[which]
    text = mutate(draw, base, '[]="=.,-0123456789e_abcdgilnmoprstuvx \n')
    return which, PROFILE_TEXT + text if which == "profile" else text


@settings(max_examples=examples(120),
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(_mutated())
def test_mutated_uncertainty_inputs_end_in_a_result_or_an_error(
        tmp_path: Path, case: tuple[str, str]) -> None:
    which, text = case
    path = tmp_path / "in.toml"
    path.write_text(text, encoding="utf-8")
    try:
        if which == "profile":
            stated = load_profile(path).uncertainty
            assert all(v is None or 0.0 <= v <= 1.0 for v in (stated.machine, stated.probe))
        elif which == "calibration":
            assert 0.0 <= load_calibration(path).u_radius <= 1.0
        else:
            spec = _stated_spec(tmp_path, text)
            assert load_spec(spec).decision_rule in ("simple", "guard_band")
    except ProbegenError:
        pass
