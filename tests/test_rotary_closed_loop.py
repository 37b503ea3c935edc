"""Method M4 closed loop: plant rotary errors in the virtual machine, run the programs,
read the DPRNT log, identify, compare with the truth."""

from __future__ import annotations

import functools
import re
from pathlib import Path

import numpy as np
import pytest
from conftest import REPO
from fuzzing import examples
from hypothesis import given, settings
from hypothesis import strategies as st
from mutations import mutate
from scipy import stats

from probegen.calibrate.rotary import M4Result, PivotResult, identify_m4, identify_pivot
from probegen.dialects import get_dialect
from probegen.errors import CalibrationError, ProbegenError
from probegen.machine.errors_model import ErrorModel, RotaryErrors
from probegen.machine.kinematics import Machine, Topology
from probegen.machine.probe_model import Lobing, ProbeModel
from probegen.planning.rotary import RotaryPlan, compensation_program, plan_rotary
from probegen.planning.rotary_spec import load_rotary_spec
from probegen.results.dprnt import parse_dprnt
from probegen.sim.contact import PlacedPart
from probegen.sim.macrob.machine import FreeMachine, RunResult, Settings, run_program
from probegen.sim.vm import VirtualMachine, run_text

UM, URAD = 1e-3, 1e-6
ERRORS = ErrorModel(
    b=RotaryErrors(np.array([6.0, 0.0, -8.0]) * UM, np.array([12.0, 0.0, -20.0]) * URAD),
    c=RotaryErrors(np.array([-12.0, -4.0, 0.0]) * UM, np.array([10.0, -15.0, 0.0]) * URAD))
"""Planted: C 12 um off the B axis along X (M4's delta), the other location errors."""
LENGTH = 0.1 * UM
ANGLE = 1.0 * URAD


def plan(name: str) -> RotaryPlan:
    return plan_rotary(load_rotary_spec(REPO / f"samples/rotary/{name}.toml"))


def run(p: RotaryPlan, *, errors: ErrorModel = ERRORS, lobing: Lobing | None = None,
        noise: float = 0.0, seed: int = 0, work_offset: tuple[float, float, float] = (0, 0, 0),
        text: str | None = None) -> str:
    spec = p.spec
    vm = VirtualMachine(
        PlacedPart.from_spheres([spec.sphere_centre], [spec.sphere_radius]),
        ProbeModel(spec.machine.probe.ball_radius, lobing or Lobing(), noise_sigma=noise,
                   seed=seed),
        Machine(Topology.FIVE_AXIS_BC, errors, spec.pivot_length))
    program = text if text is not None else get_dialect("fanuc").generate(p.program)
    res = run_text(program, vm, kind="macrob", work_offset=work_offset)
    assert res.alarm is None, res.alarm
    return res.output


def m4(p: RotaryPlan, **kwargs: object) -> M4Result:
    return identify_m4(p, parse_dprnt(run(p, **kwargs), strict=True))  # type: ignore[arg-type]


def pivot(p: RotaryPlan, **kwargs: object) -> PivotResult:
    return identify_pivot(p, parse_dprnt(run(p, **kwargs), strict=True))  # type: ignore[arg-type]


def truth(errors: ErrorModel) -> dict[str, float]:
    b, c = errors.b, errors.c
    return {"EX0C": c.position[0], "EY0C": c.position[1], "EA0C": c.tilt[0],
            "EB0C": c.tilt[1], "EX0B": b.position[0], "EZ0B": b.position[2],
            "EA0B": b.tilt[0], "EC0B": b.tilt[2]}


def values(r: PivotResult) -> dict[str, tuple[float, float]]:
    return {n: (v, u) for a in (r.c, r.b)
            for n, v, u in zip(a.names, a.values, a.uncertainties, strict=True)}


# --------------------------------------------------------------------------- M4 (seed)


def test_m4_recovers_delta_and_epsilon_without_noise() -> None:
    lobing = Lobing(lateral=0.004, axial=0.0015)
    r = m4(plan("m4"), lobing=lobing)
    delta = ERRORS.b.position[0] - ERRORS.c.position[0]  # 18 um: B axis vs C axis along X
    epsilon = lobing.lateral - lobing.axial + ERRORS.b.position[2]
    assert abs(r.delta - delta) < LENGTH
    assert abs(r.epsilon - epsilon) < LENGTH
    assert r.delta_rigid == pytest.approx(r.delta - r.epsilon, abs=1e-12)
    assert r.compensation == (-r.delta, 0.0, 0.0)


def test_m4_rigid_solution_is_exact_for_a_rigid_system() -> None:
    errors = ErrorModel(c=RotaryErrors(np.array([-7.0, 0.0, 0.0]) * UM, np.zeros(3)))
    r = m4(plan("m4"), errors=errors, lobing=Lobing(0.002, 0.002))
    assert abs(r.delta_rigid - 7.0 * UM) < LENGTH and abs(r.delta - 7.0 * UM) < LENGTH
    assert abs(r.epsilon) < LENGTH


def test_m4_compensation_closes_the_loop() -> None:
    """Run the compensation program on the control, then the test again: delta is gone."""
    p = plan("m4")
    first = m4(p)
    comp = get_dialect("fanuc").generate(compensation_program(p.spec, first.compensation))
    res = run_program(comp, FreeMachine())
    assert res.alarm is None
    offset = (res.variables.get(5221, 0.0), res.variables.get(5222, 0.0), 0.0)
    assert offset[0] == pytest.approx(-first.delta, abs=1e-4)
    again = m4(p, work_offset=offset)
    assert abs(again.delta) < LENGTH


def test_m4_missing_touch_is_a_calibration_error() -> None:
    p = plan("m4")
    log = "\n".join(line for line in run(p).splitlines() if "BM90 2 " not in line)
    with pytest.raises(CalibrationError, match="touches 1-3 of BM90, missing 2"):
        identify_m4(p, parse_dprnt(log))


# ----------------------------------------------------------------- pivot calibration


def test_pivot_recovers_every_location_error_without_noise() -> None:
    r = pivot(plan("pivot"))
    found, want = values(r), truth(ERRORS)
    for name, value in want.items():
        limit = LENGTH if name[1] in "XYZ" else ANGLE
        assert abs(found[name][0] - value) < limit, (name, found[name][0], value)
    assert r.compensation == pytest.approx((-12.0 * UM, -4.0 * UM, 0.0), abs=LENGTH)
    assert r.b.circle.radius == pytest.approx(150.0 - 8.0 * UM, abs=1e-4)  # l1 + EZ0B
    assert max(abs(v) for res in r.c.residuals for v in res) < 0.2 * UM


def test_pivot_compensation_puts_the_work_offset_on_the_c_axis() -> None:
    p = plan("pivot")
    first = pivot(p)
    again = pivot(p, work_offset=first.compensation)
    assert abs(again.c.values[0]) < LENGTH and abs(again.c.values[1]) < LENGTH
    assert abs(again.c.values[2] - first.c.values[2]) < ANGLE


def test_pivot_is_blind_to_probe_pretravel() -> None:
    """An isotropic pre-travel only shrinks every fitted sphere: the centres stay."""
    r = pivot(plan("pivot"), lobing=Lobing(0.003, 0.003))
    found = values(r)
    for name, value in truth(ERRORS).items():
        assert abs(found[name][0] - value) < (LENGTH if name[1] in "XYZ" else ANGLE)


@pytest.mark.parametrize("name", ["pivot", "m4"])
def test_reported_uncertainty_matches_the_noise(name: str) -> None:
    """Over seeds, the errors of the identified values divided by their reported standard
    uncertainties have an RMS near 1 (the uncertainty is consistent with the planted
    trigger noise), and the reported touch sigma matches the planted one."""
    p = plan(name)
    sigma = 0.001  # 1 um trigger noise
    z: list[float] = []
    for seed in range(8):
        if name == "pivot":
            result = pivot(p, noise=sigma, seed=seed)
            found, want = values(result), truth(ERRORS)
            z += [(found[k][0] - v) / found[k][1] for k, v in want.items()]
            assert 0.6 * sigma < result.c.sigma < 1.4 * sigma
            assert 0.6 * sigma < result.b.sigma < 1.4 * sigma
        else:
            r = m4(p, noise=sigma, seed=seed)
            z.append((r.delta - (ERRORS.b.position[0] - ERRORS.c.position[0])) / r.u_delta)
            assert 0.4 * sigma < r.sigma < 2.0 * sigma
    rms = float(np.sqrt(np.mean(np.square(z))))
    assert 0.5 < rms < 2.0, rms


def test_pivot_missing_station_is_a_calibration_error(tmp_path: Path) -> None:
    p = plan("pivot")
    log = "\n".join(line for line in run(p).splitlines() if " C3 " not in line)
    with pytest.raises(CalibrationError, match="of C3, missing 1, 2"):
        identify_pivot(p, parse_dprnt(log))


# ------------------------------------------------------------------ CLI and bad logs


def test_cli_plan_sim_identify(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from probegen.cli.app import main

    spec = str(REPO / "samples/rotary/m4.toml")
    assert main(["-q", "rotary", "plan", spec, "-o", str(tmp_path)]) == 0
    program = tmp_path / "m4.nc"
    log = tmp_path / "run.log"
    assert main(["rotary", "sim", str(program), "--spec", spec, "--errors",
                 str(REPO / "samples/machines/five-axis-bc.toml"), "-o", str(log)]) == 0
    comp = tmp_path / "comp.nc"
    capsys.readouterr()
    assert main(["rotary", "identify", str(log), "--spec", spec, "--compensation",
                 str(comp)]) == 0
    out = capsys.readouterr().out
    assert "delta compliant" in out and "G91 G10 L2 P1 X-" in comp.read_text()
    # few samples: the 95 % intervals use Student's t on the repeatability's dof
    found = re.search(r"Student t = ([0-9.]+) for (\d+) dof", out)
    assert found is not None, out
    assert float(found[1]) == pytest.approx(float(stats.t.ppf(0.975, int(found[2]))),
                                            abs=1e-3)
    assert float(found[1]) > 2.0  # a handful of samples: wider than the normal 1.96
    assert main(["rotary", "plan", spec, "-d", "dmis", "-o", str(tmp_path)]) == 5


@functools.cache
def m4_log() -> str:
    return run(plan("m4"))


@st.composite
def mutated_log(draw: st.DrawFn) -> str:
    return mutate(draw, m4_log(), "0123456789.- XYZ\n", most=4)


@settings(max_examples=examples(60))
@given(mutated_log())
def test_mutated_logs_end_in_a_result_or_a_probegen_error(text: str) -> None:
    try:
        identify_m4(plan("m4"), parse_dprnt(text))
    except ProbegenError:
        pass


# ------------------------------------------------------------- the virtual machine


def run_bare(text: str, vm: VirtualMachine) -> RunResult:
    return run_program(text, vm, settings=Settings(home=(0.0, 0.0, 500.0)))


def bare_vm(centre: tuple[float, float, float]) -> VirtualMachine:
    return VirtualMachine(PlacedPart.from_spheres([centre], [12.5]), ProbeModel(3.0),
                          Machine(Topology.FIVE_AXIS_BC, pivot_length=150.0))


def test_vm_turns_the_part_with_the_c_table() -> None:
    """C = 90 carries the sphere at table (100, 0) to work (0, -100): found from above."""
    text = "G0 Z100.\nG53 C90.\nG0 X0 Y-100.\nG31 Z0 F100.\n#1=#5063\nM30\n"
    res = run_bare(text, bare_vm((100.0, 0.0, 30.0)))
    assert res.alarm is None and res.variables[1] == pytest.approx(45.5, abs=1e-9)


def test_vm_tilt_moves_the_ball_and_probes_along_the_stylus() -> None:
    """At B = -90 the ball is L to +X of the commanded point and L higher; a touch along
    the stylus gets the axial pre-travel."""
    vm = bare_vm((0.0, 0.0, 30.0))
    vm.probe = ProbeModel(3.0, Lobing(lateral=0.004, axial=0.001))
    text = "G0 X-200. Z100.\nG53 B-90.\nG0 Z-120.\nG31 X-150. F100.\n#1=#5061\nM30\n"
    res = run_bare(text, vm)
    assert res.alarm is None
    assert res.variables[1] == pytest.approx(-150.0 - 15.5 + 0.001, abs=1e-9)


def test_vm_rotary_move_into_the_part_is_a_collision() -> None:
    text = "G0 X-17. Z100.\nG1 Z30. F1000.\nG53 B-20.\nM30\n"
    res = run_bare(text, bare_vm((0.0, 0.0, 30.0)))
    assert res.alarm is not None and res.alarm.number == 9100
    assert "ROTARY" in res.alarm.message and res.alarm.line == 3
