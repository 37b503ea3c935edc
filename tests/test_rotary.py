"""Method M4 planning: rotary test specs, programs (goldens), dialects and collision checks."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest
import test_linuxcnc
from conftest import REPO, assert_golden
from fuzzing import examples
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from mutations import mutate
from test_linuxcnc import log_text, motions, run_rs274

from probegen import ir
from probegen.dialects import get_dialect
from probegen.errors import CollisionError, ProbegenError, SpecError, UnsupportedError
from probegen.machine.kinematics import head_shift
from probegen.planning.rotary import (
    check_rotary,
    compensation_program,
    plan_rotary,
    stylus_direction,
    table_point,
)
from probegen.planning.rotary_spec import load_rotary_spec
from probegen.results import parse_dprnt
from probegen.sim.macrob.machine import FreeMachine, run_program

SAMPLES = ("m4", "pivot")
rs274 = test_linuxcnc.rs274
"""The ``rs274`` fixture (LinuxCNC's standalone interpreter; skips without it, fails in CI)."""
PROFILE = str(REPO / "samples/machines/vmc-fanuc.toml")


def spec_text(name: str) -> str:
    text = (REPO / f"samples/rotary/{name}.toml").read_text(encoding="utf-8")
    return text.replace('"../machines/vmc-fanuc.toml"', repr(PROFILE).replace("'", '"'))


def load_text(tmp_path: Path, text: str) -> object:
    path = tmp_path / "spec.toml"
    path.write_text(text, encoding="utf-8", errors="surrogatepass")
    return load_rotary_spec(path)


@pytest.mark.parametrize("name", SAMPLES)
def test_program_matches_golden(in_repo: Path, name: str) -> None:
    plan = plan_rotary(load_rotary_spec(f"samples/rotary/{name}.toml"))
    text = get_dialect("fanuc").generate(plan.program)
    assert text == get_dialect("fanuc").generate(plan.program)
    assert_golden(REPO / "tests/golden/rotary" / f"{name}.nc", text)


def test_compensation_program_matches_golden(in_repo: Path) -> None:
    spec = load_rotary_spec("samples/rotary/m4.toml")
    text = get_dialect("fanuc").generate(compensation_program(spec, (-0.018, 0.0, 0.0)))
    assert "G91 G10 L2 P1 X-0.0180 Y0.0000 Z0.0000\nG90\n" in text
    assert_golden(REPO / "tests/golden/rotary/compensation/m4.nc", text)


def test_dmis_refuses_rotary_programs(in_repo: Path) -> None:
    plan = plan_rotary(load_rotary_spec("samples/rotary/m4.toml"))
    with pytest.raises(UnsupportedError, match="Rotary.*no rotary axes"):
        get_dialect("dmis").generate(plan.program)


@pytest.mark.parametrize("name", SAMPLES)
def test_rs274_runs_the_linuxcnc_rotary_program(in_repo: Path, rs274: str, tmp_path: Path,
                                                name: str) -> None:
    """LinuxCNC's own interpreter runs the program; every touch goes to its planned ball
    centre less the head shift, with B and C where the station wants them."""
    plan = plan_rotary(load_rotary_spec(f"samples/rotary/{name}.toml"))
    text = get_dialect("linuxcnc").generate(plan.program)
    assert_golden(REPO / "tests/golden/rotary" / f"{name}.ngc", text)
    run = run_rs274(rs274, text, tmp_path)
    assert run.returncode == 0, run.output
    probes = [[float(v) for v in args.split(",")[:6]] for cmd, args in run.commands
              if cmd == "STRAIGHT_PROBE"]
    touches = [p for p, m in zip(probes, (m for m in motions(run)
                                          if m[0] == "STRAIGHT_PROBE"), strict=True)
               if m[2] == plan.spec.machine.feeds.probe]
    spec = plan.spec
    k = spec.sphere_radius + spec.machine.probe.ball_radius - spec.machine.probe.overtravel
    expected = [[*(np.array(st_.sphere) + k * np.array(n) - head_shift(st_.b, 150.0)), st_.b,
                 st_.c] for st_ in plan.stations for n in st_.directions]
    np.testing.assert_allclose(np.array(touches)[:, [0, 1, 2, 4, 5]], expected, atol=1e-4)
    log = parse_dprnt(log_text(run), strict=True)
    assert len(log.touches) == len(expected)


def test_linuxcnc_compensation_adds_to_the_offset(in_repo: Path) -> None:
    spec = load_rotary_spec("samples/rotary/m4.toml")
    text = get_dialect("linuxcnc").generate(compensation_program(spec, (-0.018, 0.0, 0.0)))
    assert "G10 L2 P1 X[#5221-0.0180] Y[#5222+0.0000] Z[#5223+0.0000]\n" in text


def test_commanded_points_undo_the_head_shift(in_repo: Path) -> None:
    """Run the program on a free control: every skip move's target, plus the head shift of
    the B angle in force, is the planned ball-centre end point of its touch."""
    plan = plan_rotary(load_rotary_spec("samples/rotary/pivot.toml"))
    free = FreeMachine(record=True)
    res = run_program(get_dialect("fanuc").generate(plan.program), free)
    assert res.alarm is not None and res.alarm.number == 3001  # no part: nothing touched
    # the first touch of the first station: B = 0, straight down onto the pole
    station = plan.stations[0]
    r = plan.spec.machine.probe.ball_radius
    over = plan.spec.machine.probe.overtravel
    n = np.array(station.directions[0])
    end = np.array(station.sphere) + (plan.spec.sphere_radius + r - over) * n
    skips = [m for m in free.moves if m[0] == "skip"]
    np.testing.assert_allclose(skips[-1][2], end, atol=1e-4)
    assert free.turns[0][1] == {"B": 0.0, "C": 0.0}


def test_tilted_touch_targets(in_repo: Path) -> None:
    """At B = +90 the commanded point is the ball centre less (-L, 0, L)."""
    plan = plan_rotary(load_rotary_spec("samples/rotary/m4.toml"))
    text = get_dialect("fanuc").generate(plan.program)
    tail = text[text.index("G53 B90.0000"):]
    shift = head_shift(90.0, 150.0)
    ball_x = 12.5 + 3.0 - plan.spec.machine.probe.overtravel
    assert f"#190={ball_x - shift[0]:.4f}\n#191=0.0000\n#192={30.0 - shift[2]:.4f}" in tail


def test_every_planned_move_is_clear(in_repo: Path) -> None:
    for name in SAMPLES:
        plan = plan_rotary(load_rotary_spec(f"samples/rotary/{name}.toml"))
        assert plan.clearance >= 0.0
        assert check_rotary(plan.program, plan.spec) == plan.clearance


def test_collision_check_catches_a_move_through_the_sphere(in_repo: Path) -> None:
    plan = plan_rotary(load_rotary_spec("samples/rotary/m4.toml"))
    body = (*plan.program.body[:3], ir.Move((0.0, 0.0, 40.0), ir.MoveMode.PROTECTED))
    with pytest.raises(CollisionError, match="reference sphere"):
        check_rotary(dataclasses.replace(plan.program, body=body), plan.spec)


def test_collision_check_follows_a_tilt_into_the_sphere(in_repo: Path) -> None:
    """Ball beside the sphere at its equator, B = 0: tilting to +90 swings the ball up and
    over in an arc of radius L about the pivot, into the sphere."""
    spec = load_rotary_spec("samples/rotary/m4.toml")
    body = (ir.Move((0.0, 0.0, 100.0), ir.MoveMode.RAPID),
            ir.Rotary(0.0, 0.0),
            ir.Move((-17.0, 0.0, 100.0), ir.MoveMode.RAPID),
            ir.Move((-17.0, 0.0, 30.0), ir.MoveMode.PROTECTED),
            ir.Rotary(-20.0, None, head_shift(-20.0, 150.0)))
    program = ir.Program(compensation_program(spec, (0.0, 0.0, 0.0)).setup, body)
    with pytest.raises(CollisionError, match="turn to B-20"):
        check_rotary(program, spec)


def test_pose_helpers() -> None:
    np.testing.assert_allclose(stylus_direction(90.0), [1.0, 0.0, 0.0], atol=1e-15)
    np.testing.assert_allclose(table_point((80.0, 0.0, 30.0), 90.0), [0.0, -80.0, 30.0],
                               atol=1e-12)
    np.testing.assert_allclose(head_shift(-90.0, 150.0), [150.0, 0.0, 150.0], atol=1e-12)


def test_stations(in_repo: Path) -> None:
    plan = plan_rotary(load_rotary_spec("samples/rotary/pivot.toml"))
    names = [s.feature for s in plan.stations]
    assert names == [f"C{k}" for k in range(1, 9)] + [f"B{k}" for k in range(1, 6)]
    for st_ in plan.stations:
        pole = stylus_direction(st_.b)
        assert np.dot(st_.directions[0], pole) == pytest.approx(1.0)
        assert min(np.dot(d, pole) for d in st_.directions) >= np.cos(np.radians(50.0)) - 1e-9


# ------------------------------------------------------------------------ bad specs


@pytest.mark.parametrize(("edit", "message"), [
    (('clearance_z = 100.0', 'clearance_z = 40.0'), "machine.clearance_z: expected at least"),
    (('b_positions = [-90, -45, 0, 45, 90]', 'b_positions = [-90, 45, 90]'),
     "B = 0 among the stations"),
    (('b_positions = [-90, -45, 0, 45, 90]', 'b_positions = [-120, 0, 90]'),
     r"within \[-90, 90\]"),
    (('c_positions = [0, 45, 90', 'c_positions = [0, 0, 90'), "distinct"),
    (('kind = "pivot"', 'kind = "pivit"'), "test.kind: expected one of"),
    (('points = 9', 'points = 9\nrepeats = 3'), "test.repeats: unknown key"),
])
def test_bad_pivot_specs(tmp_path: Path, edit: tuple[str, str], message: str) -> None:
    text = spec_text("pivot")
    assert edit[0] in text
    with pytest.raises(SpecError, match=message):
        load_text(tmp_path, text.replace(*edit, 1))


def test_m4_sphere_must_sit_on_the_c_axis(tmp_path: Path) -> None:
    text = spec_text("m4").replace("centre = [0.0, 0.0, 30.0]", "centre = [5.0, 0.0, 30.0]")
    with pytest.raises(SpecError, match="sphere.centre: expected the sphere on the C axis"):
        load_text(tmp_path, text)


@st.composite
def mutated(draw: st.DrawFn) -> str:
    return mutate(draw, spec_text(draw(st.sampled_from(SAMPLES))), '[]="=.,-0123456789az \n')


@settings(max_examples=examples(100),
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(mutated())
def test_mutated_specs_end_in_a_plan_or_a_probegen_error(tmp_path: Path, text: str) -> None:
    try:
        plan_rotary(load_text(tmp_path, text))  # type: ignore[arg-type]
    except ProbegenError:
        pass
