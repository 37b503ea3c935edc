"""M5 closed loop: plant the errors, run the grating programs on the virtual machine,
read the virtual grating's CSV, identify, compare with the truth.

Layout facts the assertions rest on (docs/m5.md, "Identifiability"): on ``vmc-xyfz``
the seed's plan (one setup per plane) determines EXX, EYY, EZZ, EBX, ECX, EAY, EZY and
the three plane squareness values; the rolls EAX, EBY are confounded with the
straightness EYX, EZX, EXY; the Z axis' pitch and yaw (EAZ, EBZ) act only through the
head's length and are confounded with EYZ, EXZ; ECY and ECZ do not move a read point on
the spindle axis at all.  A riser per plane separates the rolls (no combination is left
over on this layout), a second head length the Z angles.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from conftest import REPO

from probegen.calibrate.grating_io import (
    GratingReading,
    LevelReading,
    format_readings,
    read_readings,
)
from probegen.calibrate.grating_out import summary
from probegen.calibrate.identify import (
    Identification,
    axis_ranges,
    identify_global,
    raw_parameters,
    truth,
)
from probegen.calibrate.identify_model import FUNCTIONS, VolumetricModel, analyse, design, setup_of
from probegen.calibrate.identify_stepwise import identify_stepwise
from probegen.cli.grating import readings_of, simulate_readings
from probegen.geometry.orthopoly import evaluate, rms, rms_difference
from probegen.machine.kinematics import Machine, load_machine
from probegen.planning.grating import GratingSpec, plan_setup, setups

SEED = {"EXX", "EYY", "EZZ", "EBX", "ECX", "EAY", "EZY"}
RISER = SEED | {"EAX", "EBY", "EYX", "EZX", "EXY"}
HEAD = RISER | {"EAZ", "EBZ", "EXZ", "EYZ"}
ALL = {f.name for f in FUNCTIONS}


@pytest.fixture(scope="module")
def machine() -> Machine:
    return load_machine(REPO / "samples" / "grating" / "machine-errors.toml")


def through_csv(readings: list[GratingReading], tmp: Path) -> list[GratingReading]:
    """Write the virtual grating's CSV and read it back, as a user would."""
    path = tmp / "readings.csv"
    path.write_text(format_readings(readings), encoding="ascii")
    return read_readings(path)


@pytest.fixture(scope="module")
def seed_readings(machine: Machine, tmp_path_factory: pytest.TempPathFactory
                  ) -> list[GratingReading]:
    return through_csv(simulate_readings(GratingSpec(), machine),
                       tmp_path_factory.mktemp("seed"))


@pytest.fixture(scope="module")
def riser_readings(machine: Machine, tmp_path_factory: pytest.TempPathFactory
                   ) -> list[GratingReading]:
    return through_csv(simulate_readings(GratingSpec(), machine, second_offset=True),
                       tmp_path_factory.mktemp("riser"))


def planted(machine: Machine, readings: list[GratingReading]) -> Identification:
    return truth(machine.errors, axis_ranges(readings),
                 list(dict.fromkeys(setup_of(r) for r in readings)))


def relative_errors(found: Identification, true: Identification) -> dict[str, float]:
    """RMS over the range of (found − truth) / RMS of the truth, per determined function
    and squareness value."""
    out = {}
    for f, t in zip(found.functions, true.functions, strict=True):
        if f.coefficients is None:
            continue
        assert t.coefficients is not None
        out[f.function.name] = (rms_difference(f.range, f.coefficients, t.coefficients)
                                / rms(t.range, t.coefficients))
    for s, ts in zip(found.squareness, true.squareness, strict=True):
        if s.value is not None and ts.value is not None:
            out[s.name] = abs(s.value - ts.value) / abs(ts.value)
    return out


def determined(result: Identification) -> set[str]:
    return {f.function.name for f in result.functions if f.determined}


def test_linear_model_matches_the_exact_kinematic_chain(machine: Machine) -> None:
    """The identification's first-order model against the VM's full transforms."""
    rng = np.random.default_rng(1)
    q = np.column_stack([rng.uniform(-100, 100, 50), rng.uniform(-100, 100, 50),
                         rng.uniform(-200, 0, 50)])
    t = np.tile([0.0, 0.0, -100.0], (50, 1))
    ranges = axis_ranges(simulate_readings(GratingSpec(), Machine()))
    model = VolumetricModel(ranges, 5)
    raw = raw_parameters(machine.errors, model)
    linear = model.sensitivity(q, t) @ raw
    exact = machine.volumetric_error(q, t[0]) * 1e3
    assert np.max(np.abs(linear - exact)) < 2e-4  # µm: second-order terms only
    assert np.max(np.abs(exact)) > 5.0


def test_seed_plan_noise_free(machine: Machine, seed_readings: list[GratingReading]) -> None:
    found = identify_global(seed_readings)
    assert determined(found) == SEED
    errors = relative_errors(found, planted(machine, seed_readings))
    assert set(errors) == SEED | {"S_XY", "S_XZ", "S_YZ"}
    assert max(errors.values()) < 0.01, errors
    assert max(errors.values()) < 1e-3  # in fact the CSV's rounding (1e-5 um) is all
    rolls = {f.function.name: f for f in found.functions if f.function.kind == "roll"}
    assert all(f.coefficients is None for f in rolls.values())
    assert set(rolls["EAX"].partners) >= {"EYX", "EZX"}
    assert "EXY" in rolls["EBY"].partners
    text = summary(found)
    for name in ALL - SEED:  # reported as not identifiable, with no number on the line
        (line,) = [ln for ln in text if ln.strip().startswith(name + " ")]
        assert "NOT IDENTIFIABLE" in line and "rms" not in line


def test_two_offsets_recover_the_rolls(machine: Machine,
                                       riser_readings: list[GratingReading]) -> None:
    found = identify_global(riser_readings)
    assert determined(found) == RISER
    errors = relative_errors(found, planted(machine, riser_readings))
    assert set(errors) >= {"EAX", "EBY", "EYX", "EZX", "EXY"}
    assert max(errors.values()) < 0.01, errors
    # the undetermined rest: the Z angles (with the Z straightness) and ECY, ECZ
    assert {f.function.name for f in found.functions if not f.determined} == ALL - RISER


def test_second_head_recovers_the_z_angles(machine: Machine, tmp_path: Path) -> None:
    readings = through_csv(simulate_readings(GratingSpec(), machine, second_offset=True,
                                             second_head=True), tmp_path)
    found = identify_global(readings)
    assert determined(found) == HEAD
    errors = relative_errors(found, planted(machine, readings))
    assert max(errors.values()) < 0.01, errors
    ecy, ecz = found.function("ECY"), found.function("ECZ")
    assert ecy.coefficients is None and ecz.coefficients is None
    assert ecy.partners == () and ecz.partners == ()  # no effect on the read point


def test_level_readings_instead_of_risers(machine: Machine,
                                          seed_readings: list[GratingReading]) -> None:
    true = planted(machine, seed_readings)
    level = []
    for name, axis in (("EAX", "X"), ("EBY", "Y")):
        f = true.function(name)
        assert f.coefficients is not None
        for q in np.linspace(f.range.lo, f.range.hi, 11):
            roll = float(evaluate(f.range, [q], f.coefficients, 1)[0]) + 3.0  # level zero
            level.append(LevelReading(axis, float(q), roll))
    found = identify_global(seed_readings, level)
    assert determined(found) == RISER
    assert max(relative_errors(found, true).values()) < 0.01
    stepwise = identify_stepwise(seed_readings, level)
    assert determined(stepwise) == RISER
    assert max(relative_errors(stepwise, true).values()) < 0.01


def test_stepwise_and_global_agree_noise_free(machine: Machine,
                                              riser_readings: list[GratingReading]) -> None:
    true = planted(machine, riser_readings)
    glob = identify_global(riser_readings)
    step = identify_stepwise(riser_readings)
    assert determined(step) == RISER  # the stepwise method never reaches the Z angles
    for result in (glob, step):
        assert max(relative_errors(result, true).values()) < 0.01
    for name in RISER:
        a, b = glob.function(name), step.function(name)
        assert a.coefficients is not None and b.coefficients is not None
        assert rms_difference(a.range, a.coefficients, b.coefficients) < 1e-3 * rms(
            a.range, a.coefficients), name


NOISE = 0.05  # µm, one reading


@pytest.fixture(scope="module")
def noisy(machine: Machine) -> list[GratingReading]:
    return simulate_readings(GratingSpec(), machine, second_offset=True, noise=NOISE,
                             seed=11)


def test_dispersion_reported_matches_the_noise(noisy: list[GratingReading]) -> None:
    found = identify_global(noisy)
    # 2 × 366 readings: the estimate of sigma is good to a few per cent
    assert found.dispersion == pytest.approx(NOISE, rel=0.1)
    assert 2 <= found.degree <= 4  # planted cubics; noise may cost the top degree


def test_stepwise_and_global_with_noise(machine: Machine,
                                        noisy: list[GratingReading]) -> None:
    """With noise the two differ: the stepwise method uses four lines per setup through
    differences (a yaw from two lines 200 mm apart: σ·√2/200 mm ≈ 0.35 µrad per point),
    the global fit all lines, the diagonals included, at once.  Both stay close to the
    truth; the differences are of the size of that noise propagation."""
    true = planted(machine, noisy)
    glob, step = identify_global(noisy), identify_stepwise(noisy)
    eg, es = relative_errors(glob, true), relative_errors(step, true)
    translations = {"EXX", "EYY", "EZZ"}
    assert max(eg[n] for n in translations) < 0.02
    assert max(es[n] for n in translations) < 0.02
    for name in ("ECX", "EBX", "EAY"):  # angles from two parallel lines
        f = true.function(name)
        assert f.coefficients is not None
        allowed = 3 * NOISE * np.sqrt(2) / 200.0 * 1e3  # µrad, 3 sigma of one point
        for result in (glob, step):
            g = result.function(name)
            assert g.coefficients is not None
            assert rms_difference(f.range, g.coefficients, f.coefficients) < allowed, (
                name, result.method)
    # The rolls differ most: the stepwise method takes their linear terms from slope
    # changes between the setups divided by the 50 mm riser (one slope of a difference of
    # two 11-stop lines: σ·√2/√(Σ(x − x̄)²) = 0.34 µrad; through the two planes ≈ 0.4 µrad
    # RMS over ±100 mm, 1 σ) while the global fit uses every line.  Measured here:
    # about 1.7 µrad RMS for EBY (stepwise) against 0.3 µrad (global).
    for name in ("EAX", "EBY"):
        f = true.function(name)
        assert f.coefficients is not None
        for result, allowed in ((glob, 1.0), (step, 3.0)):
            g = result.function(name)
            assert g.coefficients is not None
            assert rms_difference(f.range, g.coefficients, f.coefficients) < allowed, (
                name, result.method)


def test_riser_in_xy_only_leaves_one_combination_of_the_roll_slopes() -> None:
    """The XY riser alone: straightness separated, the rolls but for the sum of their
    slopes (their difference is determined); the XZ riser determines the sum."""
    spec = GratingSpec()
    readings = []
    for s in setups(spec, second_offset=True):
        if s.riser and s.plane != "XY":
            continue
        plan = plan_setup(spec, s)
        readings += readings_of(plan, [(tuple(p), 0.0, 0.0) for p in plan.stops])
    model = VolumetricModel(axis_ranges(readings), 3)
    ident = analyse(design(model, readings))
    names = {f.name: k for k, f in enumerate(FUNCTIONS)}
    for name in ("EYX", "EZX", "EXY"):
        assert ident.determined(model.function_selector(names[name]))
    slope = {}
    for name in ("EAX", "EBY"):
        sel = model.function_selector(names[name])
        assert not ident.determined(sel)
        assert ident.determined(sel[1:])  # degrees 2..d: the nonlinear part
        slope[name] = sel[0] / ((model.ranges[FUNCTIONS[names[name]].axis].hi
                                 - model.ranges[FUNCTIONS[names[name]].axis].lo) / 2)
    assert ident.determined(slope["EBY"] - slope["EAX"])
    assert not ident.determined(slope["EBY"] + slope["EAX"])


def test_stepwise_ignores_second_head_setups_for_the_rolls(machine: Machine,
                                                           tmp_path: Path) -> None:
    """A second head changes no roll's lever arm: without risers the stepwise rolls stay
    undetermined, as in the global fit."""
    readings = through_csv(simulate_readings(GratingSpec(), machine, second_head=True),
                           tmp_path)
    step = identify_stepwise(readings)
    assert determined(step) == SEED
    glob = identify_global(readings)
    assert determined(glob) == SEED | {"EAZ", "EBZ", "EXZ", "EYZ"}


def test_stepwise_needs_the_seed_lines(seed_readings: list[GratingReading]) -> None:
    import dataclasses

    from probegen.errors import CalibrationError

    renamed = [dataclasses.replace(r, line="P" + r.line[1:]) if r.plane == "XZ" else r
               for r in seed_readings]
    with pytest.raises(CalibrationError, match=r"XZ Y=50 head 100: expected the seed's line"):
        identify_stepwise(renamed)
    assert determined(identify_global(renamed)) == SEED  # the global fit needs no names


def test_xy_riser_only_reports_the_roll_curvature_and_slope_combinations(
        machine: Machine, riser_readings: list[GratingReading]) -> None:
    """What the XY riser alone determines of the rolls is reported, and the one
    combination of their slopes it leaves is reported as not identifiable."""
    readings = [r for r in riser_readings if r.offset == 0.0 or r.plane == "XY"]
    found = identify_global(readings)
    true = planted(machine, readings)
    assert determined(found) == SEED | {"EYX", "EZX", "EXY"}
    slopes = {}
    for name in ("EAX", "EBY"):
        f, t = found.function(name), true.function(name)
        assert f.coefficients is None and f.curvature is not None
        assert t.coefficients is not None
        assert rms_difference(f.range, f.curvature, t.coefficients[1:], 2) < 0.01 * rms(
            t.range, t.coefficients[1:], 2)
        slopes[name] = t.coefficients[0] * 2000.0 / (t.range.hi - t.range.lo)
    known = [c for c in found.slopes if c.value is not None]
    unknown = [c for c in found.slopes if c.value is None]
    assert len(known) == 1 and len(unknown) == 1
    (k,) = known
    assert dict(k.terms) == pytest.approx({"EAX": 1.0, "EBY": -1.0})
    assert k.value == pytest.approx(slopes["EAX"] - slopes["EBY"], rel=1e-3)
    assert dict(unknown[0].terms) == pytest.approx({"EAX": 1.0, "EBY": 1.0})
    text = "\n".join(summary(found))
    assert "+1*slope(EAX) +1*slope(EBY): NOT IDENTIFIABLE" in text
    assert "+1*slope(EAX) -1*slope(EBY) = " in text


def test_confidence_bands_cover_the_planted_functions(machine: Machine, tmp_path: Path) -> None:
    """The 95 % bands (Student t × the least-squares standard uncertainty of each
    function, from the covariance of its Legendre coefficients) hold the planted
    function at about 95 % of the positions over three noisy runs; the CSV tables and
    the plots carry them."""
    from probegen.cli.grating import write_outputs

    hits = total = 0
    for seed in range(3):
        readings = simulate_readings(GratingSpec(), machine, second_offset=True, noise=NOISE,
                                     seed=seed)
        found = identify_global(readings, degree=3)  # the planted cubics: no model bias
        true = planted(machine, readings)
        assert found.dof > 700 and found.k95 == pytest.approx(1.963, abs=1e-3)
        for f, t in zip(found.functions, true.functions, strict=True):
            if f.coefficients is None:
                continue
            assert t.coefficients is not None
            q = np.linspace(f.range.lo, f.range.hi, 5)
            error = (evaluate(f.range, q, f.coefficients, f.function.lowest)
                     - evaluate(t.range, q, t.coefficients, t.function.lowest))
            band = f.band(q, found.k95)
            assert band is not None and np.all(band > 0.0)
            hits += int(np.sum(np.abs(error) <= band))
            total += len(q)
    assert 0.85 <= hits / total <= 0.99, hits / total
    write_outputs(tmp_path, found, None, 100.0)
    table = (tmp_path / "errors_x.csv").read_text(encoding="utf-8").splitlines()
    header = next(ln for ln in table if ln.startswith("position_mm"))
    assert "EXX_um,EXX_um_ci95" in header
    assert any(ln.startswith("# ci95: half width of the 95 % confidence band, Student t 1.96")
               for ln in table)
    row = table[-1].split(",")
    assert all(cell != "" for cell in row)
    svg = (tmp_path / "plot_EXX.svg").read_text(encoding="utf-8")
    assert '<polygon class="band"' in svg
