"""One calibration for everything (issue 15, item 1), closed on the virtual machine.

A lobing, pre-travelling probe (5 µm of pre-travel in every direction, a 3-lobe variation
of ±1.5 µm on sideways touches) first measures the 25 mm sphere (sphere test, M1);
``ingest --write-calibration`` writes its calibration.  Then programs measure the
bore_block (bore as a cylinder, boss), the revolved_block (cone, dome), the free-form
sample and the setup program with in-process actions (front edge, top plane, bore with
work offset and tool wear, boss), every part placed off its nominal place.  With the
calibration every value comes out within 1 µm of the planted truth, offline (``ingest``)
and on the control (the ``RES`` values and offsets the virtual Macro B computed); without
it the pre-travel shows (a bore 10 µm too large, a boss 10 µm too small).

The probe's axial and lateral pre-travel are equal on purpose: a sphere test cannot tell a
pre-travel term linear in the direction from the sphere's position (compensate.py,
docs/results.md), so with unequal ones a plane found from above keeps that term.
``test_unequal_axial_pretravel_keeps_sizes`` shows what still holds then.
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest
from conftest import REGEN, REPO, assert_golden, sample_script

from probegen import cad
from probegen.cli.app import main
from probegen.dialects import get_dialect
from probegen.evaluate.ingest import Ingested, ingest
from probegen.evaluate.outputs import to_csv, to_json, to_table
from probegen.machine.calibration import UNCALIBRATED, ProbeCalibration, load_calibration
from probegen.machine.probe_model import Lobing, ProbeModel
from probegen.planning import plan_program
from probegen.results import read_dprnt
from probegen.sim.contact import PlacedPart
from probegen.sim.vm import SimResult, VirtualMachine, run_text
from probegen.spec.model import Spec, load_spec

UM = 1e-3
LOBING = Lobing(lateral=0.005, axial=0.005, lobe=0.0015, phase=0.3)
NOISE = 0.0001
SAMPLES = REPO / "samples"
SPHERE_SPEC = SAMPLES / "sphere25/sphere_test.toml"
SHIFT = np.array([0.3, -0.2, 0.0])       # every part sits here from its nominal place
# (in Z only the setup program's: a cone's gauge planes are not yet in the part frame)
SETUP_SHIFT = np.array([0.3, -0.2, 0.1])
WORK = np.array([300.0, 200.0, -100.0])  # G54 before the setup program runs
D_WEAR_12 = 12012


def probe(seed: int = 1, lobing: Lobing = LOBING) -> ProbeModel:
    return ProbeModel(3.0, lobing, NOISE, seed)


def spec_with(path: Path, cal: ProbeCalibration | None, keep: tuple[str, ...] = ()) -> Spec:
    spec = load_spec(path)
    if keep:
        spec = dataclasses.replace(spec, features=tuple(f for f in spec.features
                                                        if f.id in keep))
    return dataclasses.replace(spec, machine=dataclasses.replace(spec.machine,
                                                                 calibration=cal))


def run(spec: Spec, model: cad.Model, tmp: Path, name: str, *, seed: int = 1,
        work: np.ndarray | None = None, lobing: Lobing = LOBING,
        shift: np.ndarray = SHIFT) -> tuple[Path, SimResult]:
    text = get_dialect("fanuc").generate(plan_program(spec, runtime_variables=True).program)
    origin = np.zeros(3) if work is None else work
    part = PlacedPart.from_model(model, translation=origin + shift)
    res = run_text(text, VirtualMachine(part, probe(seed, lobing)), kind="macrob",
                   work_offset=tuple(origin))
    assert res.alarm is None, res.alarm
    log = tmp / f"{name}.log"
    log.write_text(res.output)
    return log, res


@pytest.fixture(scope="module")
def tmp(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("calibration")


@pytest.fixture(scope="module")
def models(tmp: Path) -> dict[str, cad.Model]:
    variant = tmp / "bore_50_03.step"
    sample_script("bore_block").main(variant, bore_diameter=50.03)
    return {"sphere": cad.load_step(SAMPLES / "sphere25/sphere25.step"),
            "bore_block": cad.load_step(SAMPLES / "bore_block/bore_block.step"),
            "bore+0.03": cad.load_step(variant),
            "revolved": cad.load_step(SAMPLES / "revolved_block/revolved_block.step"),
            "freeform": cad.load_step(SAMPLES / "freeform/freeform.step")}


@pytest.fixture(scope="module")
def sphere_log(tmp: Path, models: dict[str, cad.Model]) -> Path:
    return run(load_spec(SPHERE_SPEC), models["sphere"], tmp, "sphere")[0]


@pytest.fixture(scope="module")
def cal_file(tmp: Path, sphere_log: Path) -> Path:
    target = tmp / "probe.cal.toml"
    assert main(["-q", "ingest", str(sphere_log), "--spec", str(SPHERE_SPEC), "-o",
                 str(tmp / "sphere_out"), "--write-calibration", str(target),
                 "--calibration-date", "2026-11-26"]) == 0
    return target


@pytest.fixture(scope="module")
def cal(cal_file: Path) -> ProbeCalibration:
    return load_calibration(cal_file)


def test_calibration_file_is_dated_and_repeatable(tmp: Path, sphere_log: Path,
                                                  cal_file: Path,
                                                  cal: ProbeCalibration) -> None:
    again = tmp / "again.cal.toml"
    assert main(["-q", "ingest", str(sphere_log), "--spec", str(SPHERE_SPEC), "-o",
                 str(tmp / "again_out"), "--write-calibration", str(again),
                 "--calibration-date", "2026-11-26"]) == 0
    assert again.read_bytes() == cal_file.read_bytes()
    assert cal.date == "2026-11-26" and cal.source == str(sphere_log)
    assert cal.fingerprint.startswith("C") and len(cal.fingerprint) == 9
    # the effective radius: 3 mm less the 5 µm pre-travel
    assert cal.effective_radius == pytest.approx(3.0 - LOBING.lateral, abs=0.3 * UM)
    old = tmp / "old.cal.toml"  # a file from before the date: still loads
    old.write_text("\n".join(line for line in cal_file.read_text().splitlines()
                             if not line.startswith("date")) + "\n")
    assert load_calibration(old).date == ""
    bad = tmp / "bad.cal.toml"
    assert main(["-q", "ingest", str(sphere_log), "--spec", str(SPHERE_SPEC), "-o",
                 str(tmp / "bad_out"), "--write-calibration", str(bad),
                 "--calibration-date", "yesterday"]) != 0
    assert not bad.exists()


def test_recalibration_keeps_the_map(tmp: Path, sphere_log: Path, cal: ProbeCalibration,
                                     models: dict[str, cad.Model]) -> None:
    spec = load_spec(SPHERE_SPEC)
    first = ingest(sphere_log, spec).results[0]
    again = ingest(sphere_log, spec, calibration=cal).results[0]
    # the re-evaluated test reports the probe's real lobing, not a flattened map
    assert first.p_ftu > 2 * UM
    assert again.p_ftu == pytest.approx(first.p_ftu, abs=1e-9)
    assert np.allclose(again.calibration().radii, cal.radii, atol=1e-7)  # file rounding
    assert again.calibration().ball_radius == cal.ball_radius == 3.0
    # its size is the calibrated one now: the certified diameter within 1 µm
    d = {c.name: c for c in again.characteristics}["D"]
    assert abs(d.deviation) < UM
    assert abs({c.name: c for c in first.characteristics}["D"].deviation) > 5 * UM
    # a second test with other noise: the same map within the noise
    log2, _ = run(spec, models["sphere"], tmp, "sphere2", seed=7)
    second = ingest(log2, spec, calibration=cal).results[0].calibration()
    assert np.abs(np.array(second.radii) - cal.radii).max() < 0.6 * UM
    assert second.radii != cal.radii


def revolved_values(ing: Ingested) -> dict[str, dict[str, float]]:
    return {r.feature: {c.name: c.measured for c in r.characteristics} for r in ing.revolved}


def test_revolved_features_offline(tmp: Path, cal: ProbeCalibration,
                                   models: dict[str, cad.Model]) -> None:
    truth = {
        "BORE": {"X": 50.0, "Y": 50.0, "D": 50.0, "D_S1": 50.0, "D_S2": 50.0},
        "BOSS": {"X": 20.0, "Y": 20.0, "D": 20.0},
        "CONE": {"X": 25.0, "Y": 75.0, "D_S1": 18.0, "D_S2": 22.0},
        "DOME": {"X": 75.0, "Y": 75.0, "Z": 30.0, "D": 30.0},
    }
    found: dict[str, dict[str, float]] = {}
    plain: dict[str, dict[str, float]] = {}
    for path, model, keep in ((SAMPLES / "bore_block/bore_block.toml", "bore_block", ()),
                              (SAMPLES / "revolved_block/revolved_block.toml", "revolved",
                               ("CONE", "DOME"))):
        spec = spec_with(path, None, keep)
        log, _ = run(spec, models[model], tmp, path.stem)
        found |= revolved_values(ingest(log, spec, calibration=cal))
        plain |= revolved_values(ingest(log, spec))
    for fid, values in truth.items():
        for name, value in values.items():
            expected = value + (SHIFT["XYZ".index(name)] if name in "XYZ" else 0.0)
            assert found[fid][name] == pytest.approx(expected, abs=UM), (fid, name)
    # without the calibration: the pre-travel, twice, in every diameter
    assert plain["BORE"]["D"] - 50.0 > 3 * UM + 5 * UM
    assert 20.0 - plain["BOSS"]["D"] > 3 * UM + 5 * UM
    assert abs(plain["CONE"]["D_S1"] - 18.0) > 3 * UM
    assert abs(plain["DOME"]["D"] - 30.0) > 3 * UM


def test_torus_with_the_calibration(tmp: Path, cal: ProbeCalibration,
                                    models: dict[str, cad.Model]) -> None:
    spec = spec_with(SAMPLES / "revolved_block/revolved_block.toml", None, ("RIM",))
    log, _ = run(spec, models["revolved"], tmp, "rim")
    with_cal = revolved_values(ingest(log, spec, calibration=cal))["RIM"]
    without = revolved_values(ingest(log, spec))["RIM"]
    assert abs(with_cal["D"] - 8.0) < UM < 3 * UM < abs(without["D"] - 8.0)


def test_freeform_offline(tmp: Path, cal: ProbeCalibration,
                          models: dict[str, cad.Model]) -> None:
    spec = load_spec(SAMPLES / "freeform/freeform.toml")
    text = get_dialect("fanuc").generate(plan_program(spec, runtime_variables=True).program)
    res = run_text(text, VirtualMachine(PlacedPart.from_model(models["freeform"]), probe()),
                   kind="macrob")
    assert res.alarm is None
    log = tmp / "freeform.log"
    log.write_text(res.output)
    (with_cal,) = ingest(log, spec, calibration=cal).freeform
    (without,) = ingest(log, spec).freeform
    assert np.abs(with_cal.residuals).max() < UM            # the part is nominal
    assert np.abs(without.residuals).max() > 3 * UM


def _machine(log: Path) -> dict[str, dict[str, float]]:
    """The values the control printed (RES lines), by feature and key."""
    out: dict[str, dict[str, float]] = {}
    for r in read_dprnt(log).results:
        out.setdefault(r.feature, {}).update(r.values)
    return out


@pytest.mark.parametrize("calibrated", [True, False])
def test_actions_on_the_control_and_offline(tmp: Path, cal: ProbeCalibration,
                                            models: dict[str, cad.Model],
                                            calibrated: bool) -> None:
    spec = spec_with(SAMPLES / "bore_block/bore_block_actions.toml",
                     cal if calibrated else None)
    log, res = run(spec, models["bore+0.03"], tmp, f"actions_{calibrated}", work=WORK,
                   shift=SETUP_SHIFT)
    g54 = np.array([res.variables[5221 + i] for i in range(3)])
    machine = _machine(log)
    truth = {"BORE D": 50.03, "BOSS D": 20.0, "TOP P": 50.0 + SETUP_SHIFT[2],
             "BORE X": 50.0 + SETUP_SHIFT[0], "BORE Y": 50.0 + SETUP_SHIFT[1]}
    printed = {"BORE D": machine["BORE"]["D"], "BOSS D": machine["BOSS"]["D"],
               "TOP P": machine["TOP"]["P"], "BORE X": machine["BORE"]["X"],
               "BORE Y": machine["BORE"]["Y"]}
    wear = res.variables.get(D_WEAR_12, 0.0)
    ing = ingest(log, spec, calibration=cal if calibrated else None)
    assert all(d.agrees is not False for d in ing.decisions), to_table(ing)
    offline = {(d.feature, d.key): d.offline for d in ing.decisions}
    if calibrated:
        for key, value in truth.items():
            assert printed[key] == pytest.approx(value, abs=UM), key
            assert offline[tuple(key.split())] == pytest.approx(value, abs=UM), key
        assert np.allclose(g54, WORK + SETUP_SHIFT, atol=UM)  # X, Y: the bore; Z: the top
        assert wear == pytest.approx(0.015, abs=UM)         # the bore 0.03 oversize
        assert "DPRNT[PGCAL*" + cal.fingerprint + "]" in get_dialect("fanuc").generate(
            plan_program(spec, runtime_variables=True).program)
    else:
        assert printed["BORE D"] - truth["BORE D"] > 3 * UM + 5 * UM
        assert truth["BOSS D"] - printed["BOSS D"] > 3 * UM + 5 * UM
        assert abs(wear - 0.015) > 3 * UM
        assert abs(g54[2] - WORK[2] - SETUP_SHIFT[2]) > 3 * UM


def test_pgcal_ties_the_log_to_its_calibration(tmp: Path, cal: ProbeCalibration,
                                               cal_file: Path,
                                               models: dict[str, cad.Model]) -> None:
    spec = spec_with(SAMPLES / "bore_block/bore_block_actions.toml", cal)
    log, res = run(spec, models["bore_block"], tmp, "pgcal", work=WORK)
    lines = res.output.splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith("PGSTART"))
    assert lines[start + 1] == f"PGCAL {cal.fingerprint}"
    assert ingest(log, spec, calibration=cal).notes == ()
    plain = load_spec(SAMPLES / "bore_block/bore_block_actions.toml")
    missing = ingest(log, plain)
    assert any("none was given" in n for n in missing.notes)
    assert UNCALIBRATED in to_table(missing) and UNCALIBRATED in to_csv(missing)
    assert json.loads(to_json(missing))["calibration"] == {"state": UNCALIBRATED}
    other = dataclasses.replace(cal, date="2026-11-27")
    assert any(cal.fingerprint in n and other.fingerprint in n
               for n in ingest(log, plain, calibration=other).notes)
    full = json.loads(to_json(ingest(log, plain, calibration=cal)))
    doc = full["calibration"]
    assert (doc["fingerprint"], doc["date"], doc["source"]) == (
        cal.fingerprint, "2026-11-26", cal.source)
    from probegen.report.html import render_report

    assert f"probe {cal.describe()}" in render_report(full)
    assert f"probe {UNCALIBRATED}" in render_report(json.loads(to_json(missing)))
    # the spec's [machine] calibration key does what --calibration does
    keyed = tmp / "keyed.toml"
    text = (SAMPLES / "bore_block/bore_block_actions.toml").read_text()
    keyed.write_text(text.replace('model = "bore_block.step"',
                                  f'model = "{SAMPLES / "bore_block/bore_block.step"}"')
                     .replace('profile = "../machines/vmc-fanuc.toml"',
                              f'profile = "{SAMPLES / "machines/vmc-fanuc.toml"}"\n'
                              f'calibration = "{cal_file.name}"'))
    keyed_spec = load_spec(keyed)
    assert keyed_spec.machine.calibration == cal
    assert ingest(log, keyed_spec).notes == ()
    out = tmp / "compiled.nc"
    assert main(["-q", "compile", str(SAMPLES / "bore_block/bore_block_actions.toml"),
                 "--calibration", str(cal_file), "-o", str(out)]) == 0
    program = out.read_text()
    assert f"(PROBE CALIBRATION {cal.fingerprint} DATED 2026-11-26)" in program
    assert f"DPRNT[PGCAL*{cal.fingerprint}]" in program


def test_unequal_axial_pretravel_keeps_sizes(tmp: Path, models: dict[str, cad.Model]
                                             ) -> None:
    """Axial 3 µm, lateral 5 µm: the sphere test's map lacks the term linear in the
    direction (it is the sphere's position), sizes are still right within 1 µm."""
    lobing = Lobing(lateral=0.005, axial=0.003, lobe=0.0015, phase=0.3)
    spec = load_spec(SPHERE_SPEC)
    log, _ = run(spec, models["sphere"], tmp, "sphere_axial", lobing=lobing)
    cal = ingest(log, spec).results[0].calibration(str(log))
    spec = spec_with(SAMPLES / "bore_block/bore_block.toml", None)
    log, _ = run(spec, models["bore_block"], tmp, "bore_axial", lobing=lobing)
    found = revolved_values(ingest(log, spec, calibration=cal))
    assert found["BORE"]["D"] == pytest.approx(50.0, abs=UM)
    assert found["BOSS"]["D"] == pytest.approx(20.0, abs=UM)


CAL_DATA = REPO / "tests/data/calibration/probe.cal.toml"


def test_calibrated_program_is_golden(in_repo: Path, tmp_path: Path) -> None:
    """The setup program compiled with the sample sphere test's calibration (written
    again here byte for byte): header, PGCAL line and the per-touch corrections."""
    again = tmp_path / "probe.cal.toml"
    assert main(["-q", "ingest", "samples/sphere25/sphere_test.log", "--spec",
                 "samples/sphere25/sphere_test.toml", "-o", str(tmp_path / "out"),
                 "--write-calibration", str(again), "--calibration-date", "2026-11-26"]) == 0
    if REGEN:
        CAL_DATA.write_bytes(again.read_bytes())
    assert again.read_bytes() == CAL_DATA.read_bytes()
    spec = spec_with(SAMPLES / "bore_block/bore_block_actions.toml", load_calibration(again))
    text = get_dialect("fanuc").generate(plan_program(spec, runtime_variables=True).program)
    assert_golden(REPO / "tests/golden/bore_block/bore_block_actions.calibrated.nc", text)


def test_rotary_identify_takes_the_calibration(
        tmp: Path, cal: ProbeCalibration, cal_file: Path,
        capsys: pytest.CaptureFixture[str]) -> None:
    """The pivot test (B tilts the probe: the map is looked up in the probe frame) with
    the lobing probe: with the calibration every location error within 0.5 µm of the
    truth, and the command says which calibration it used."""
    from probegen.calibrate.rotary import identify_pivot
    from probegen.machine.errors_model import ErrorModel, RotaryErrors
    from probegen.machine.kinematics import Machine, Topology
    from probegen.planning.rotary import plan_rotary
    from probegen.planning.rotary_spec import load_rotary_spec

    errors = ErrorModel(b=RotaryErrors(np.array([6.0, 0.0, -8.0]) * UM, np.zeros(3)),
                        c=RotaryErrors(np.array([-12.0, -4.0, 0.0]) * UM, np.zeros(3)))
    spec_path = SAMPLES / "rotary/pivot.toml"
    plan = plan_rotary(load_rotary_spec(spec_path))
    s = plan.spec
    vm = VirtualMachine(PlacedPart.from_spheres([s.sphere_centre], [s.sphere_radius]),
                        probe(), Machine(Topology.FIVE_AXIS_BC, errors, s.pivot_length))
    res = run_text(get_dialect("fanuc").generate(plan.program), vm, kind="macrob")
    assert res.alarm is None
    log = tmp / "pivot.log"
    log.write_text(res.output)
    found = identify_pivot(plan, read_dprnt(log), cal)
    values = dict(zip(found.c.names + found.b.names, found.c.values + found.b.values,
                      strict=True))
    for name, want in (("EX0C", -12.0), ("EY0C", -4.0), ("EX0B", 6.0), ("EZ0B", -8.0)):
        assert values[name] == pytest.approx(want * UM, abs=0.5 * UM), name
    capsys.readouterr()
    assert main(["-q", "rotary", "identify", str(log), "--spec", str(spec_path),
                 "--calibration", str(cal_file)]) == 0
    assert f"probe: {cal.describe()}" in capsys.readouterr().out
    assert main(["-q", "rotary", "identify", str(log), "--spec", str(spec_path)]) == 0
    assert f"probe: {UNCALIBRATED}" in capsys.readouterr().out


NIST_SIMPLE = REPO.parent / "shared/ref/nist-ippdme/IPlusSimplePart"


@pytest.mark.skipif(not NIST_SIMPLE.exists(), reason="NIST simple part not available")
def test_post_ingest_takes_the_calibration(tmp: Path, cal: ProbeCalibration) -> None:
    """NIST's simple part posted for a 4 mm ball, run with the lobing probe: the bore
    (Ø50, 4 touches) within 1 µm with the calibration, 10 µm large without; a
    calibration of the 6 mm ball is refused."""
    ball = 2.0
    small = dataclasses.replace(  # the same pre-travel map on a 4 mm ball
        cal, ball_radius=ball, effective_radius=cal.effective_radius - 1.0,
        radii=tuple(r - 1.0 for r in cal.radii))
    small_file = tmp / "small.cal.toml"
    from probegen.machine.calibration import calibration_toml

    small_file.write_text(calibration_toml(small))
    nc = tmp / "simple.nc"
    model = NIST_SIMPLE / "STEP_Part21_AP203/ipp_simple.stp"
    assert main(["-q", "post", str(NIST_SIMPLE / "DMIS/simple_in.dms"), "--machine",
                 str(SAMPLES / "post/vmc-fanuc-d4.toml"), "--model", str(model),
                 "-o", str(nc)]) == 0
    res = run_text(nc.read_text(), VirtualMachine(PlacedPart.from_model(cad.load_step(model)),
                                                  ProbeModel(ball, LOBING)), kind="macrob")
    assert res.alarm is None
    log = tmp / "simple.log"
    log.write_text(res.output)

    def diameter(*extra: str) -> float:
        out = tmp / "simple.dmo"
        assert main(["-q", "post-ingest", str(log), "--features",
                     str(tmp / "simple.features.json"), "-o", str(out), *extra]) == 0
        line = out.read_text().splitlines()[5]          # the circle's values
        return float(line.split(",")[-1])

    assert diameter("--calibration", str(small_file)) == pytest.approx(50.0, abs=UM)
    assert diameter() - 50.0 > 3 * UM
    cal6 = tmp / "probe6.cal.toml"
    cal6.write_text(calibration_toml(cal))
    assert main(["-q", "post-ingest", str(log), "--features",
                 str(tmp / "simple.features.json"), "-o", str(tmp / "x.dmo"),
                 "--calibration", str(cal6)]) != 0


@pytest.mark.parametrize("calibrated", [True, False])
def test_sphere_setup_work_offset_on_the_control(tmp: Path, cal: ProbeCalibration,
                                                 models: dict[str, cad.Model],
                                                 calibrated: bool) -> None:
    """samples/sphere25/sphere_setup.toml: the control locates the sphere (six touches)
    and sets G55 XYZ from its centre; the calibration corrects each locating touch."""
    spec = spec_with(SAMPLES / "sphere25/sphere_setup.toml", cal if calibrated else None)
    _, res = run(spec, models["sphere"], tmp, f"setup_{calibrated}", work=WORK,
                 shift=SETUP_SHIFT)
    g55 = np.array([res.variables[5241 + i] for i in range(3)])
    error = np.abs(g55 - WORK - SETUP_SHIFT)
    if calibrated:
        assert error.max() < UM, error
    else:
        assert error[2] > 3 * UM                      # Z: the top touch's pre-travel
