"""Closed loop: plan → emit → virtual machine → log → ingest/evaluate, against known truth.

The expected results are computed without the simulator's contact code: a touch along
the planned normal ``n`` ends with the ball centre at ``C + (R + r − δ(−n))·n`` (first
contact plus the probe's pre-travel ``δ`` along the motion), so the compensated point is
``C + (R − δ)·n``; the expected sphere is the least-squares fit of those points.  With
machine errors, the control reports the commanded position whose actual tool point is
that ball centre (inverted here by fixed-point iteration on the kinematics), which is
what a real machine measures into the part; compensating the reported points with the
same known model gives the part truth back.

Tolerance: 1e-4 mm (0.1 um, noise-free): the DPRNT log prints 4 decimals.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from conftest import REPO, SHARED

from probegen import cad
from probegen.dialects import get_dialect
from probegen.evaluate.ingest import ingest
from probegen.geometry.fits import fit_sphere
from probegen.machine.calibration import compensate
from probegen.machine.kinematics import Machine, load_machine
from probegen.machine.probe_model import Lobing, ProbeModel
from probegen.planning import plan_program
from probegen.results import parse_dmis_output, parse_dprnt
from probegen.sim.contact import PlacedPart
from probegen.sim.vm import VirtualMachine, run_text
from probegen.spec.model import load_spec

TOL = 1e-4
LOBING = Lobing(0.0012, 0.0008, 0.0005)
OFFSET = np.array([1.2, -0.9, 0.4])


@pytest.fixture(scope="module")
def sphere_model() -> cad.Model:
    return cad.load_step(REPO / "samples/sphere25/sphere25.step")


def program_text(spec_name: str, dialect: str) -> tuple[str, object]:
    spec = load_spec(Path("samples/sphere25") / spec_name)
    d = get_dialect(dialect)
    planned = plan_program(spec, runtime_variables=d.RUNTIME_VARIABLES)
    return d.generate(planned.program), planned


def expected_fit(centre: np.ndarray, radius: float, directions: np.ndarray,
                 probe: ProbeModel) -> tuple[np.ndarray, float, float]:
    delta = np.array([probe.trigger_offset(-n) for n in directions])
    pts = centre + (radius - delta)[:, None] * directions
    f = fit_sphere(pts)
    radial = np.linalg.norm(pts - np.array(f.centre), axis=1)
    return np.array(f.centre), 2 * f.radius, float(radial.max() - radial.min())


@pytest.mark.parametrize(("spec_name", "touches"),
                         [("sphere_test.toml", 31), ("sphere_test_cap.toml", 36)])
def test_fanuc_sphere_test_on_the_model(in_repo: Path, sphere_model: cad.Model,
                                        tmp_path: Path, spec_name: str, touches: int) -> None:
    text, planned = program_text(spec_name, "fanuc")
    probe = ProbeModel(3.0, LOBING)
    c, s = np.cos(np.radians(0.5)), np.sin(np.radians(0.5))
    rot = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1.0]])
    vm = VirtualMachine(PlacedPart.from_model(sphere_model, rotation=rot, translation=OFFSET),
                        probe)
    res = run_text(text, vm, kind="macrob")
    assert res.alarm is None and res.touches == touches
    log = tmp_path / "run.log"
    log.write_text(res.output)
    (r,) = ingest(log, load_spec(Path("samples/sphere25") / spec_name)).results
    dirs = np.array(planned.sphere_tests[0].directions)
    centre, diameter, form = expected_fit(OFFSET, 12.5, dirs, probe)
    assert np.allclose(r.fit.centre, centre, atol=TOL)
    assert 2 * r.fit.radius == pytest.approx(diameter, abs=TOL)
    assert r.p_ftu == pytest.approx(form, abs=TOL)
    assert form > 0.0005  # the lobing is really there


def test_dmis_sphere_test_on_the_virtual_cmm(in_repo: Path, sphere_model: cad.Model) -> None:
    text, planned = program_text("sphere_test.toml", "dmis")
    probe = ProbeModel(3.0, LOBING)
    vm = VirtualMachine(PlacedPart.from_model(sphere_model, translation=OFFSET), probe)
    res = run_text(text, vm, kind="dmis")
    assert res.alarm is None
    out = parse_dmis_output(res.output, strict=True)
    located = out.feature("SPH1L")
    assert np.allclose(located.position, OFFSET, atol=2e-3)  # 5 touches, with lobing
    sph = out.feature("SPH1")
    dirs = np.array(planned.sphere_tests[0].directions)
    centre, diameter, _ = expected_fit(OFFSET, 12.5, dirs, probe)
    # FA(SPH1) is reported in the frame translated onto the located centre
    assert np.allclose(np.array(sph.position) + np.array(located.position), centre, atol=TOL)
    assert sph.diameter == pytest.approx(diameter, abs=TOL)


@pytest.mark.parametrize("planted_diameter", [25.0, 25.0037])
def test_iso_layout_recovers_planted_size(in_repo: Path, planted_diameter: float,
                                          tmp_path: Path) -> None:
    text, planned = program_text("sphere_test_iso.toml", "fanuc")
    probe = ProbeModel(3.0, LOBING)
    part = PlacedPart.from_spheres([[0.0, 0.0, 0.0]], [planted_diameter / 2])
    res = run_text(text, VirtualMachine(part, probe), kind="macrob")
    assert res.alarm is None
    log = tmp_path / "run.log"
    log.write_text(res.output)
    (r,) = ingest(log, load_spec(Path("samples/sphere25/sphere_test_iso.toml"))).results
    dirs = np.array(planned.sphere_tests[0].directions)
    centre, diameter, form = expected_fit(np.zeros(3), planted_diameter / 2, dirs, probe)
    assert np.allclose(r.fit.centre, centre, atol=TOL)
    assert 2 * r.fit.radius == pytest.approx(diameter, abs=TOL)
    assert r.p_ftu == pytest.approx(form, abs=TOL)


def invert(kin: Machine, targets: np.ndarray) -> np.ndarray:
    """Commanded positions whose actual tool points are ``targets`` (fixed point)."""
    cmd = targets.copy()
    for _ in range(20):
        cmd = cmd - (np.asarray(kin.actual_tool_point(cmd, np.zeros(3))) - targets)
    return cmd


def test_machine_errors_are_measured_into_the_part(in_repo: Path, sphere_model: cad.Model,
                                                   tmp_path: Path) -> None:
    work = np.array([400.0, 250.0, 100.0])  # where G54 puts the part on the machine
    kin = load_machine(REPO / "samples/machines/errors-example.toml")
    text, planned = program_text("sphere_test.toml", "fanuc")
    probe = ProbeModel(3.0, LOBING)
    vm = VirtualMachine(PlacedPart.from_model(sphere_model, translation=work + OFFSET), probe,
                        kin)
    res = run_text(text, vm, kind="macrob", work_offset=tuple(work))
    assert res.alarm is None
    log = tmp_path / "run.log"
    log.write_text(res.output)
    spec = load_spec(Path("samples/sphere25/sphere_test.toml"))
    (r,) = ingest(log, spec).results
    dirs = np.array(planned.sphere_tests[0].directions)
    delta = np.array([probe.trigger_offset(-n) for n in dirs])
    balls = work + OFFSET + (12.5 + 3.0 - delta)[:, None] * dirs
    reported = invert(kin, balls) - work
    expected = fit_sphere(reported - 3.0 * dirs)
    assert np.allclose(r.fit.centre, expected.centre, atol=TOL)
    assert r.fit.radius == pytest.approx(expected.radius, abs=TOL)
    # the machine errors really moved the result ...
    truth_centre, truth_d, _ = expected_fit(OFFSET, 12.5, dirs, probe)
    assert np.linalg.norm(np.array(r.fit.centre) - truth_centre) > 5 * TOL
    # ... and compensating the reported points with the known model gives the truth back
    touches = {t.index: t.xyz for t in parse_dprnt(res.output).touches if t.kind == "PT"}
    measured = np.array([touches[k] for k in range(1, 26)]) + work
    actual = np.asarray(kin.actual_tool_point(measured, np.zeros(3))) - work
    fixed = fit_sphere(compensate(actual, dirs, 3.0))
    assert np.allclose(fixed.centre, truth_centre, atol=TOL)
    assert 2 * fixed.radius == pytest.approx(truth_d, abs=TOL)


def test_missed_trigger_raises_the_programs_alarm(in_repo: Path) -> None:
    text, _ = program_text("sphere_test_iso.toml", "fanuc")
    part = PlacedPart.from_spheres([[0.0, 0.0, 0.0]], [12.5 - 3.0])  # far smaller: no touch
    res = run_text(text, VirtualMachine(part, ProbeModel(3.0)), kind="macrob")
    assert res.alarm is not None and res.alarm.startswith("3001 PROBE DID NOT TOUCH")
    assert "ERR NOTOUCH SPH1 1" in res.output


def test_unexpected_contact_on_a_protected_move(in_repo: Path) -> None:
    text, _ = program_text("sphere_test_iso.toml", "fanuc")
    part = PlacedPart.from_spheres([[0.0, 0.0, 0.0], [0.0, 0.0, 40.0]], [12.5, 5.0])
    res = run_text(text, VirtualMachine(part, ProbeModel(3.0)), kind="macrob")
    assert res.alarm is not None and res.alarm.startswith("3002 UNEXPECTED PROBE TRIGGER")
    assert "ERR COLLISION SPH1 1" in res.output


def test_unexpected_contact_on_a_plain_move_is_a_collision(in_repo: Path) -> None:
    text = "%\nO0001\nG21\nG90 G54\nG0 Z50.\nG1 X0. Y0. Z5. F500.\nM30\n%\n"
    part = PlacedPart.from_spheres([[0.0, 0.0, 0.0]], [12.5])
    res = run_text(text, VirtualMachine(part, ProbeModel(3.0)), kind="macrob")
    assert res.alarm is not None and res.alarm.startswith("9100 STYLUS COLLISION (G1)")
    assert res.alarm.endswith("(line 6)")


def test_nist_dcx_program_on_the_dcx_model() -> None:
    model = cad.load_step(SHARED / "ref/nist-ippdme/DCXpart/STEP_AP214/"
                                   "DaimlerChryslerTestPartAP214.stp")
    part = PlacedPart.from_model(model, translation=(355.0, 91.0, -80.0))
    vm = VirtualMachine(part, ProbeModel(2.0))
    text = (SHARED / "ref/nist-ippdme/DCXpart/DMIS/IMTS_M_clean.dmi").read_text()
    res = run_text(text, vm, kind="dmis", source="IMTS_M_clean.dmi",
                   home=(355.0, 91.0, 150.0))
    assert res.alarm is None, res.alarm
    out = parse_dmis_output(res.output, strict=True)
    cyl1, cyl2 = out.feature("CYL1"), out.feature("CYL2")
    assert cyl1.diameter == pytest.approx(31.0, abs=1e-4)
    assert cyl2.diameter == pytest.approx(12.5, abs=1e-4)
    assert np.allclose(cyl1.position[:2], (0.0, 0.0), atol=1e-4)
    assert np.allclose(cyl2.position[:2], (0.0, 0.0), atol=1e-4)
    for name, normal, axis, value in (("PLN1", (0, 0, 1), 2, 30.0),
                                      ("PLN2", (0, -1, 0), 1, -52.0),
                                      ("PLN3", (-1, 0, 0), 0, -86.0)):
        plane = out.feature(name)
        assert np.allclose(np.abs(plane.direction), np.abs(normal), atol=1e-6)
        assert plane.position[axis] == pytest.approx(value, abs=1e-4)
    assert all(t.intol for t in out.tolerances)
