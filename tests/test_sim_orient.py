"""The virtual machine executes a tilted working plane and stylus changes (issue 17).

Hand-written Macro B programs, as the control reads them, probe a bore in the +X side
face of a block (built here with build123d) under ``G68.2`` with the frame's Z along
+X (``ir.frames.frame_for``) on a trunnion table; ``#5061``-``#5063`` are in the feature
coordinate system.  The same with a planted part offset, a tool change to a 2 mm
stylus of the rack, the Haas forms, and the alarms.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest
from build123d import Align, Box, Cylinder, Pos, Rot, export_step
from fuzzing import examples
from hypothesis import given, settings
from hypothesis import strategies as st

from probegen import cad
from probegen.ir import frames
from probegen.machine.probe_model import ProbeModel
from probegen.machine.profile import Stylus, load_profile
from probegen.results import parse_dmis_output
from probegen.sim.contact import PlacedPart
from probegen.sim.macrob.tilt import FeatureFrame
from probegen.sim.vm import UNKNOWN_TOOL, WRONG_LENGTH, VirtualMachine, run_text

BORE_AXIS_YZ = (30.0, 20.0)
"""The side bore's axis (along X) at work Y 30, Z 20; D20, 25 deep from the face X 80."""
BORE_RADIUS = 10.0
FACE_X = 80.0
WORK = (0.0, 0.0, -400.0)
"""G54: machine Z0 (G53 Z0) is 400 mm above the work origin; the table pivots there."""
RACK = (Stylus("D6", 6.0, 4.5, 50.0, 20), Stylus("D2", 2.0, 1.4, 30.0, 21))
AXIS = (1.0, 0.0, 0.0)
ROTATION = frames.frame_for(AXIS)
EULER = frames.euler_zxz(ROTATION)
ORIGIN = (FACE_X, *BORE_AXIS_YZ)


@pytest.fixture(scope="module")
def side_bore(tmp_path_factory: pytest.TempPathFactory) -> cad.Part:
    block = Box(80.0, 60.0, 40.0, align=(Align.MIN, Align.MIN, Align.MIN))
    hole = Pos(FACE_X, *BORE_AXIS_YZ) * Rot(0, 90, 0) * Cylinder(
        BORE_RADIUS, 50.0, align=(Align.CENTER, Align.CENTER, Align.CENTER))
    path = tmp_path_factory.mktemp("side") / "side_bore.step"
    export_step(block - hole, str(path))
    return cad.load_part(str(path))


def machine(part: cad.Part, shift: tuple[float, float, float] = (0.0, 0.0, 0.0),
            rack: tuple[Stylus, ...] = RACK) -> VirtualMachine:
    placed = PlacedPart.from_model(part, translation=np.add(WORK, shift))
    profile = load_profile("samples/machines/vmc-fanuc.toml")
    styli = dataclasses.replace(profile, rack=rack).styli() if rack else ()
    return VirtualMachine(placed, ProbeModel(3.0), rack=styli, pivot=WORK)


def program(*, tool: int = 20, g682: str = "G68.2", g531: str | None = "G53.1",
            g69: str = "G69") -> str:
    """Probe the side bore at frame depth -10 along frame +X, -X, +Y, -Y; keep each
    skip position at full precision in #101- and print it."""
    touches = []
    for n, (x, y) in enumerate(((12.0, 0.0), (-12.0, 0.0), (0.0, 12.0), (0.0, -12.0))):
        v = 101 + 3 * n
        touches.append(f"G31 X{x:.1f} Y{y:.1f} F200.\n#{v}=#5061\n#{v + 1}=#5062\n"
                       f"#{v + 2}=#5063\nDPRNT[PT*X#5061[44]*Y#5062[44]*Z#5063[44]]\n"
                       "G1 X0. Y0. F1000.\n")
    tilt = "" if g531 is None else g531 + "\n"
    return (f"%\nO1000(SIDE BORE)\nG21\nG90 G17 G40 G49 G80 G94 G69\nT{tool} M6\nG54\n"
            f"G0 G43 H{tool} Z100.\nG53 Z0.\n"
            f"{g682} X{ORIGIN[0]:.1f} Y{ORIGIN[1]:.1f} Z{ORIGIN[2]:.1f} "
            f"I{EULER[0]:.4f} J{EULER[1]:.4f} K{EULER[2]:.4f}\n{tilt}"
            "G0 X0. Y0. Z30.\nG1 Z-10. F1000.\nPOPEN\n" + "".join(touches) +
            f"G0 Z30.\nG53 Z0.\n{g682} X0. Y0. Z0. I0. J0. K0.\n{tilt}{g69}\n"
            "PCLOS\nM30\n%\n")


def skip_points(result_variables: dict[int, float]) -> np.ndarray:
    return np.array([[result_variables[101 + 3 * n + i] for i in range(3)]
                     for n in range(4)])


def in_frame(work_point: np.ndarray) -> np.ndarray:
    return np.array(frames.to_frame(_orient(), tuple(work_point)))


def _orient() -> frames.ir.Orient:
    return frames.ir.Orient("TILT1", ROTATION, ORIGIN)


def test_skip_positions_are_in_the_frame_and_on_the_bore(side_bore: cad.Part) -> None:
    assert EULER == (90.0, 90.0, 0.0)
    vm = machine(side_bore)
    res = run_text(program(), vm, kind="macrob", work_offset=WORK)
    assert res.alarm is None, res.alarm
    assert res.touches == 4
    points = skip_points(res.variables)
    # the ball centre at each trigger (table frame = machine at A0 C0 = work + G54)
    for printed, hit in zip(points, vm.touches, strict=True):
        centre = np.asarray(hit.centre) - WORK
        assert np.allclose(printed, in_frame(centre), atol=1e-9, rtol=0.0)
        work = np.array(frames.to_work(_orient(), tuple(printed)))
        radial = np.hypot(work[1] - BORE_AXIS_YZ[0], work[2] - BORE_AXIS_YZ[1])
        assert radial == pytest.approx(BORE_RADIUS - 3.0, abs=1e-9)  # on the bore, ball 3
        assert work[0] == pytest.approx(FACE_X - 10.0, abs=1e-9)
        assert np.asarray(hit.point)[0] - WORK[0] == pytest.approx(FACE_X - 10.0, abs=1e-9)
    assert points[0] == pytest.approx((7.0, 0.0, -10.0), abs=1e-9)
    assert "PT X7.0000 Y.0000 Z-10.0000" in res.output
    assert vm.table == {"A": 0.0, "C": 0.0}  # turned back by the last G68.2 + G53.1


def test_planted_part_offset_is_recovered_in_the_frame(side_bore: cad.Part) -> None:
    shift = (0.05, -0.03, 0.02)
    res = run_text(program(), machine(side_bore, shift), kind="macrob", work_offset=WORK)
    assert res.alarm is None, res.alarm
    p = skip_points(res.variables)
    centre = ((p[0, 0] + p[1, 0]) / 2.0, (p[2, 1] + p[3, 1]) / 2.0)
    expected = frames.apply_t(ROTATION, shift)  # (-0.03, 0.02, 0.05): Y, Z, X of work
    assert centre == pytest.approx(expected[:2], abs=1e-6)
    work = frames.direction_to_work(_orient(), (*centre, 0.0))
    assert work == pytest.approx((0.0, shift[1], shift[2]), abs=1e-6)


def test_tool_change_to_the_2mm_stylus_changes_the_contact(side_bore: cad.Part) -> None:
    vm = machine(side_bore)
    res = run_text(program(tool=21), vm, kind="macrob", work_offset=WORK)
    assert res.alarm is None, res.alarm
    assert vm.stylus == RACK[1]
    p = skip_points(res.variables)
    assert p[0] == pytest.approx((9.0, 0.0, -10.0), abs=1e-9)  # ball centre 1 mm off
    for hit in vm.touches:
        assert np.linalg.norm(np.asarray(hit.centre) - hit.point) == pytest.approx(1.0)


def test_haas_g268_g253_g269_run_as_g682(side_bore: cad.Part) -> None:
    fanuc = run_text(program(), machine(side_bore), kind="macrob", work_offset=WORK)
    haas = run_text(program(g682="G268", g531="G253", g69="G269"), machine(side_bore),
                    kind="macrob", work_offset=WORK, control="haas")
    assert haas.alarm is None, haas.alarm
    assert haas.output == fanuc.output
    wrong = run_text(program(), machine(side_bore), kind="macrob", work_offset=WORK,
                     control="haas")
    assert wrong.alarm is not None and wrong.alarm.startswith("10 IMPROPER G-CODE (G68.2)")
    assert run_text(program(g682="G268"), machine(side_bore), kind="macrob",
                    work_offset=WORK).alarm.startswith("10 ")  # type: ignore[union-attr]


def test_unknown_tool_is_an_alarm_naming_it(side_bore: cad.Part) -> None:
    res = run_text(program(tool=7), machine(side_bore), kind="macrob", work_offset=WORK)
    assert res.alarm is not None
    assert res.alarm.startswith(f"{UNKNOWN_TOOL} TOOL T7 IS NOT IN THE RACK")
    assert "(T20 D6 BALL 6, T21 D2 BALL 2)" in res.alarm and res.touches == 0
    # without a rack the probe never changes (programs before issue 17)
    free = run_text(program(tool=7), machine(side_bore, rack=()), kind="macrob",
                    work_offset=WORK)
    assert free.alarm is None and skip_points(free.variables)[0][0] == pytest.approx(7.0)


def test_length_offset_of_another_tool_is_an_alarm(side_bore: cad.Part) -> None:
    text = program(tool=21).replace("G43 H21", "G43 H20")
    res = run_text(text, machine(side_bore), kind="macrob", work_offset=WORK)
    assert res.alarm is not None and res.alarm.startswith(f"{WRONG_LENGTH} G43 H20 WITH T21")


def test_g682_without_g531_before_probing_is_an_alarm(side_bore: cad.Part) -> None:
    vm = machine(side_bore)
    text = program(g531=None).replace("G0 X0. Y0. Z30.\nG1 Z-10. F1000.",
                                      "G0 X0. Y0. Z300.")
    res = run_text(text, vm, kind="macrob", work_offset=WORK)
    assert res.alarm is not None and res.alarm.startswith("9020 PROBING UNDER G68.2 I90 J90 K0")
    assert "G53.1 MISSING" in res.alarm and res.touches == 0


def test_probing_with_the_table_turned_and_no_frame_is_an_alarm(side_bore: cad.Part) -> None:
    text = program().replace("G0 X0. Y0. Z30.\nG1 Z-10. F1000.",
                             "G69\nG0 X200. Y200. Z0.", 1)
    res = run_text(text, machine(side_bore), kind="macrob", work_offset=WORK)
    assert res.alarm is not None and res.alarm.startswith("9021 PROBING WITH THE TABLE TURNED")


def test_g53_moves_under_a_frame_are_machine_moves(side_bore: cad.Part) -> None:
    from probegen.sim.macrob.machine import FreeMachine, run_program

    text = ("G90 G54\nG68.2 X80. Y30. Z20. I90. J90. K0.\nG53.1\nG53 X10. Y20. Z0.\n"
            "#101=#5021\n#102=#5022\n#103=#5023\n#104=#5041\n#105=#5042\n#106=#5043\n"
            "G0 X0. Y0. Z30.\n#107=#5021\n#108=#5022\n#109=#5023\nM30\n")
    free = FreeMachine(record=True)
    res = run_program(text, free, variables={5223: WORK[2]})
    v = res.variables
    assert (v[101], v[102], v[103]) == (10.0, 20.0, 0.0)
    # the frame point (0, 0, 30) is work (110, 30, 20): table (110, 30, -380) turned
    # about the pivot at machine 0 (Settings default) by Rx(-90)·Rz(-90): (y, z, x)
    assert (v[107], v[108], v[109]) == pytest.approx((30.0, -380.0, 110.0), abs=1e-12)
    # #5041-: machine (10, 20, 0) is table (0, 10, 20), work (0, 10, 420), frame R^T(w - o)
    assert (v[104], v[105], v[106]) == pytest.approx((-20.0, 400.0, -80.0), abs=1e-12)
    assert free.turns == [({"A": 0.0, "C": 0.0}, {"A": -90.0, "C": -90.0})]




DMIS = """DMISMN/'SIDE BORE',05.0
UNITS/MM,ANGDEC
S(D6A0B0)=SNSDEF/PROBE,INDEX,POL,0,0,0,0,-1,50.0000,6.0000
S(D2A90BM90)=SNSDEF/PROBE,INDEX,POL,90,-90,0,0,-1,30.0000,2.0000
SNSLCT/S(D6A0B0)
SNSET/APPRCH,2.0000
SNSET/RETRCT,2.0000
SNSET/SEARCH,2.0000
GOTO/40.0000,30.0000,100.0000
F(TOP)=FEAT/POINT,CART,40.0000,30.0000,40.0000,0.000000,0.000000,1.000000
MEAS/POINT,F(TOP),1
  PTMEAS/CART,40.0000,30.0000,40.0000,0.000000,0.000000,1.000000
ENDMES
OUTPUT/FA(TOP)
GOTO/150.0000,30.0000,100.0000
SNSLCT/S(D2A90BM90)
GOTO/150.0000,30.0000,20.0000
GOTO/70.0000,30.0000,20.0000
F(WALL)=FEAT/POINT,CART,70.0000,40.0000,20.0000,0.000000,-1.000000,0.000000
MEAS/POINT,F(WALL),1
  PTMEAS/CART,70.0000,40.0000,20.0000,0.000000,-1.000000,0.000000
ENDMES
OUTPUT/FA(WALL)
F(BORE)=FEAT/CIRCLE,INNER,CART,70.0000,30.0000,20.0000,1.000000,0.000000,0.000000,20.0000
MEAS/CIRCLE,F(BORE),4
  PTMEAS/CART,70.0000,40.0000,20.0000,0.000000,-1.000000,0.000000
  PTMEAS/CART,70.0000,30.0000,30.0000,0.000000,0.000000,-1.000000
  PTMEAS/CART,70.0000,20.0000,20.0000,0.000000,1.000000,0.000000
  PTMEAS/CART,70.0000,30.0000,10.0000,0.000000,0.000000,1.000000
ENDMES
OUTPUT/FA(BORE)
GOTO/150.0000,30.0000,20.0000
ENDFIL
"""


@pytest.mark.parametrize("shift", [(0.0, 0.0, 0.0), (0.05, -0.03, 0.02)])
def test_cmm_two_sensors_and_a_tilted_head_measure_the_side_bore(
        side_bore: cad.Part, shift: tuple[float, float, float]) -> None:
    vm = VirtualMachine(PlacedPart.from_model(side_bore, translation=shift), ProbeModel(3.0),
                        rack=RACK)
    res = run_text(DMIS, vm, kind="dmis")
    assert res.alarm is None, res.alarm
    assert res.touches == 6 and not res.report
    assert vm.stylus == RACK[1] and vm.stylus_axis == pytest.approx((1.0, 0.0, 0.0))
    for hit in vm.touches[1:]:  # the 2 mm ball, on the bore
        assert np.linalg.norm(np.asarray(hit.centre) - hit.point) == pytest.approx(1.0)
    found = {f.name: f for f in parse_dmis_output(res.output, strict=True).features}
    dx, dy, dz = shift
    assert found["TOP"].position == pytest.approx((40.0, 30.0, 40.0 + dz), abs=1e-5)
    wall = found["WALL"].position
    assert wall[0] == pytest.approx(70.0, abs=1e-5)
    axis = (BORE_AXIS_YZ[0] + dy, BORE_AXIS_YZ[1] + dz)  # the planted bore axis
    assert np.hypot(wall[1] - axis[0], wall[2] - axis[1]) == pytest.approx(
        BORE_RADIUS, abs=1e-5)  # on the bore surface, compensated with the 2 mm ball
    assert found["BORE"].position == pytest.approx((70.0, *axis), abs=1e-5)
    assert found["BORE"].diameter == pytest.approx(20.0, abs=1e-4)


def test_cmm_sensor_whose_ball_is_not_in_the_rack_is_an_alarm(side_bore: cad.Part) -> None:
    vm = VirtualMachine(PlacedPart.from_model(side_bore), ProbeModel(3.0), rack=RACK)
    res = run_text(DMIS.replace("30.0000,2.0000", "30.0000,1.5000"), vm, kind="dmis")
    assert res.alarm is not None
    assert res.alarm.startswith(f"{UNKNOWN_TOOL} SENSOR S(D2A90BM90) D1.5: NO STYLUS")


def test_head_direction_convention() -> None:
    from probegen.sim.cmm.sensors import head_direction

    assert head_direction(0.0, 0.0) == pytest.approx((0.0, 0.0, -1.0))
    assert head_direction(90.0, 0.0) == pytest.approx((0.0, -1.0, 0.0))
    assert head_direction(90.0, 90.0) == pytest.approx((1.0, 0.0, 0.0))
    assert head_direction(90.0, -90.0) == pytest.approx((-1.0, 0.0, 0.0))
    assert head_direction(45.0, 180.0) == pytest.approx((0.0, 0.5 ** 0.5, -(0.5 ** 0.5)))


TOOL_CHANGE = """%
O1001(TOP FACE)
G21
G90 G17 G40 G49 G80 G94 G69
T{tool} M6
G54
G0 G43 H{tool} Z100.
G0 X40. Y30. Z60.
POPEN
G31 Z30. F200.
DPRNT[PT*X#5061[44]*Y#5062[44]*Z#5063[44]]
G0 Z100.
PCLOS
M30
%
"""


@pytest.mark.parametrize(("tool", "z"), [(20, "43.0000"), (21, "41.0000")])
def test_cli_sim_takes_the_stylus_of_the_profile_rack(
        side_bore: cad.Part, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, tool: int,
        z: str) -> None:
    """``probegen sim --machine`` hands the profile's rack to the virtual machine."""
    from probegen.cli.app import main
    from probegen.machine import profile as profiles

    real = profiles.load_profile
    monkeypatch.setattr(profiles, "load_profile",
                        lambda path: dataclasses.replace(real(path), rack=RACK))
    nc, log = tmp_path / "top.nc", tmp_path / "top.log"
    nc.write_text(TOOL_CHANGE.format(tool=tool))
    part = side_bore.model.path
    assert main(["sim", str(nc), "--part", part, "--machine",
                 "samples/machines/vmc-fanuc.toml", "-o", str(log)]) == 0
    assert log.read_text() == f"%\nPT X40.0000 Y30.0000 Z{z}\n%\n"
    nc.write_text(TOOL_CHANGE.format(tool=9))
    assert main(["sim", str(nc), "--part", part, "--machine",
                 "samples/machines/vmc-fanuc.toml", "-o", str(log)]) != 0


@pytest.mark.parametrize(("tool", "z"), [(20, 43.0), (21, 41.0)])
def test_linuxcnc_tool_change_takes_the_rack_stylus(side_bore: cad.Part, tool: int,
                                                    z: float) -> None:
    text = (f"G21 G90\nT{tool} M6\nG43 H{tool}\nG0 X40 Y30 Z60\nG38.2 Z30 F200\n"
            "#<z> = #5063\n(LOG,Z#<z>)\nM2\n")
    vm = VirtualMachine(PlacedPart.from_model(side_bore), ProbeModel(3.0), rack=RACK)
    res = run_text(text, vm, kind="ngc")
    assert res.alarm is None, res.alarm
    assert vm.touches[0].centre[2] == pytest.approx(z)
    bad = run_text(text.replace(f"T{tool} M6", "T5 M6").replace(f"H{tool}", "H5"),
                   VirtualMachine(PlacedPart.from_model(side_bore), ProbeModel(3.0),
                                  rack=RACK), kind="ngc")
    assert bad.alarm is not None and f"{UNKNOWN_TOOL} TOOL T5 IS NOT IN THE RACK" in bad.alarm
    wrong = run_text(text.replace(f"H{tool}", "H5"),
                     VirtualMachine(PlacedPart.from_model(side_bore), ProbeModel(3.0),
                                    rack=RACK), kind="ngc")
    assert wrong.alarm is not None and f"{WRONG_LENGTH} G43 H5 WITH T{tool}" in wrong.alarm


@pytest.mark.parametrize(("axis", "travel", "expected"), [
    ("A", None, {"A": -90.0, "C": -90.0}),
    ("A", (-30.0, 110.0), {"A": 90.0, "C": 90.0}),
    ("B", None, {"B": -90.0, "C": 0.0}),
    ("B", (-10.0, 100.0), {"B": 90.0, "C": 180.0}),
])
def test_g531_picks_the_trunnion_solution_within_the_travel(
        side_bore: cad.Part, axis: str, travel: tuple[float, float] | None,
        expected: dict[str, float]) -> None:
    """Both solutions bring the frame's Z up: the skip positions in the frame agree."""
    vm = machine(side_bore)
    vm.tilt_axis, vm.tilt_range = axis, travel
    turns: list[dict[str, float]] = []
    tilt = vm.tilt
    vm.tilt = lambda start, end, at: (turns.append(end), tilt(start, end, at))  # type: ignore[method-assign]
    res = run_text(program(), vm, kind="macrob", work_offset=WORK)
    assert res.alarm is None, res.alarm
    assert turns[0] == pytest.approx(expected, abs=1e-12)
    assert skip_points(res.variables)[0] == pytest.approx((7.0, 0.0, -10.0), abs=1e-9)


def test_g531_out_of_the_tilt_travel_is_an_alarm(side_bore: cad.Part) -> None:
    vm = machine(side_bore)
    vm.tilt_range = (-30.0, 60.0)
    res = run_text(program(), vm, kind="macrob", work_offset=WORK)
    assert res.alarm is not None
    assert res.alarm.startswith("9022 G53.1: NO A WITHIN -30..60 (THE TILT AXIS'S TRAVEL)")


def test_cli_sim_runs_a_tilted_program_on_a_trunnion_profile(
        side_bore: cad.Part, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A profile with ``[tilt]``: machine Z0 is the start height, the work origin and the
    pivot 500 mm below it; the frame's skip positions are those of the test machine."""
    from probegen.cli.app import main
    from probegen.machine import profile as profiles

    real = profiles.load_profile
    monkeypatch.setattr(profiles, "load_profile", lambda path: dataclasses.replace(
        real(path), rack=RACK, tilt=profiles.Tilt(tilt_range=(-110.0, 110.0))))
    nc, log = tmp_path / "side.nc", tmp_path / "side.log"
    nc.write_text(program(tool=21))
    assert main(["sim", str(nc), "--part", side_bore.model.path, "--machine",
                 "samples/machines/vmc-fanuc.toml", "-o", str(log)]) == 0
    expected = run_text(program(tool=21), machine(side_bore), kind="macrob", work_offset=WORK)
    assert log.read_text() == expected.output
    assert "PT X9.0000 Y.0000 Z-10.0000" in expected.output


angle = st.floats(-180.0, 180.0, allow_nan=False).map(lambda a: round(a, 3))
coordinate = st.floats(-200.0, 200.0, allow_nan=False).map(lambda a: round(a, 4))


@settings(max_examples=examples(60))
@given(euler=st.tuples(angle, st.floats(0.0, 180.0).map(lambda a: round(a, 3)), angle),
       origin=st.tuples(coordinate, coordinate, coordinate),
       point=st.tuples(coordinate, coordinate, coordinate),
       axis=st.sampled_from(["A", "B"]))
def test_g682_round_trip_and_tool_axis(euler: tuple[float, float, float],
                                       origin: tuple[float, float, float],
                                       point: tuple[float, float, float], axis: str) -> None:
    """Any frame: a move to a frame point reads back as that point (#5041-, #5061-), the
    machine goes to ``pivot + T·(origin + R·p + G54 - pivot)``, and G53.1 brings the tool
    along the frame's Z on either trunnion (the G31 that follows raises no alarm)."""
    from probegen.sim.macrob.machine import FreeMachine, Settings, run_program
    from probegen.sim.macrob.tilt import along_frame, table_rotation

    words = (f"X{origin[0]:.4f} Y{origin[1]:.4f} Z{origin[2]:.4f} I{euler[0]:.3f} "
             f"J{euler[1]:.3f} K{euler[2]:.3f}")
    p = f"X{point[0]:.4f} Y{point[1]:.4f} Z{point[2]:.4f}"
    text = (f"G90 G54\nG68.2 {words}\nG53.1\nG0 {p}\n#101=#5041\n#102=#5042\n#103=#5043\n"
            f"G31 Z{point[2] - 1.0:.4f} F100.\n#104=#5061\nM30\n")
    free = FreeMachine(record=True)
    res = run_program(text, free, variables={5223: -400.0},
                      settings=Settings(table_pivot=(5.0, -3.0, -400.0), tilt_axis=axis))
    assert res.alarm is None, res.alarm
    v = res.variables
    assert (v[101], v[102], v[103]) == pytest.approx(point, abs=1e-9)
    assert v[104] == pytest.approx(point[0], abs=1e-9)
    rotation = frames.from_euler_zxz(*euler)
    end = free.turns[-1][1] if free.turns else {axis: 0.0, "C": 0.0}
    frame = FeatureFrame.of(origin, euler)
    assert along_frame(frame, table_rotation(end))
    # the machine point of the G0: pivot + T·(origin + R·p + G54 - pivot)
    work = np.add(origin, frames.apply(rotation, point)) + (0.0, 0.0, -400.0)
    machine_point = np.add((5.0, -3.0, -400.0), np.asarray(table_rotation(end)) @ (
        work - (5.0, -3.0, -400.0)))
    assert free.moves[0][2] == pytest.approx(tuple(machine_point), abs=1e-9)


def test_a_program_after_one_that_left_the_table_turned_starts_there(
        side_bore: cad.Part) -> None:
    """The control reads where its rotary axes stand: a second program that probes
    without a frame is alarm 9021, one that sets the same frame needs no G53.1 turn."""
    vm = machine(side_bore)
    first = program().split("G0 Z30.\nG53 Z0.\n")[0] + "G0 Z30.\nG53 Z0.\nPCLOS\nM30\n%\n"
    assert run_text(first, vm, kind="macrob", work_offset=WORK).alarm is None
    assert vm.table == {"A": -90.0, "C": -90.0}
    again = run_text(program(g531=None).replace("I0. J0. K0.\nG69", "I0. J0. K0.\nG53.1\nG69"),
                     vm, kind="macrob", work_offset=WORK)
    assert again.alarm is None, again.alarm
    assert skip_points(again.variables)[0] == pytest.approx((7.0, 0.0, -10.0), abs=1e-9)


@pytest.mark.parametrize("block", ["G68.2 X0. Y0. Z0. I0. J90. K0. G31 Z-5. F100.",
                                   "G53.1 G31 Z-5. F100.", "G31 G53.1 Z-5. F100."])
def test_tilt_codes_with_a_skip_in_one_block_are_an_alarm(block: str) -> None:
    from probegen.sim.macrob.machine import FreeMachine, run_program

    res = run_program(f"G90 G54\nG68.2 X0. Y0. Z0. I0. J90. K0.\n{block}\nM30\n",
                      FreeMachine())
    assert res.alarm is not None and res.alarm.number == 9010
    assert "IN ONE BLOCK" in res.alarm.message and "G31" in res.alarm.message


@pytest.mark.parametrize(("snsdef", "axis"), [
    ("INDEX,POL,0,0,0,0,-1,50,2", (0.0, 0.0, 1.0)),
    ("INDEX,POL,90,90,0,0,1,50,2", (-1.0, 0.0, 0.0)),
    ("INDEX,POL,90,0,0,0,-1,50,2", (0.0, 1.0, 0.0)),
    ("INDEX,POL,90,0,1,0,0,50,2", None),            # a horizontal mount
    ("INDEX,VEC,0,0,1,0,0,-1,40,2", (0.0, 0.0, 1.0)),
    ("FIXED,CART,0,0,30,0,0,-1,2", (0.0, 0.0, 1.0)),
    ("FIXED,CART,250,0,-50,0,0,1,2", None),         # a tip offset from the quill
])
def test_sensor_axes(side_bore: cad.Part, snsdef: str,
                     axis: tuple[float, float, float] | None) -> None:
    from probegen.sim.cmm.interpreter import run_dmis
    from probegen.sim.vm import CmmAdapter

    vm = VirtualMachine(PlacedPart.from_model(side_bore), ProbeModel(3.0), rack=RACK)
    text = f"DMISMN/'S',05.0\nUNITS/MM,ANGDEC\nS(X)=SNSDEF/PROBE,{snsdef}\nSNSLCT/S(X)\nENDFIL\n"
    res = run_dmis(text, CmmAdapter(vm), skip_unsupported=True)
    if axis is None:
        assert [s.text for s in res.skipped] == ["SNSLCT/S(X)"]
        assert "stylus direction" in res.skipped[0].reason
    else:
        assert not res.skipped and vm.stylus == RACK[1]
        assert vm.stylus_axis == pytest.approx(axis, abs=1e-15)


sensor_word = st.one_of(
    st.sampled_from(["PROBE", "INDEX", "FIXED", "POL", "CART", "VEC", "VIDEO", "X"]),
    st.floats(-400.0, 400.0, allow_nan=False).map(lambda v: f"{v:.3f}"),
    st.integers(-3, 200).map(str))


@settings(max_examples=examples(80))
@given(prefix=st.sampled_from([[], ["PROBE", "INDEX", "POL"], ["PROBE", "FIXED", "CART"],
                                ["PROBE", "INDEX", "VEC"]]),
       words=st.lists(sensor_word, max_size=9))
def test_random_sensors_on_a_cmm_with_a_head_end_in_a_result_or_an_error(
        prefix: list[str], words: list[str]) -> None:
    """Any SNSDEF/SNSLCT on the rack CMM: a run result (perhaps an alarm or a skipped
    statement) or a ProbegenError, never another exception."""
    from probegen.errors import ProbegenError
    from probegen.sim.cmm.interpreter import run_dmis
    from probegen.sim.vm import CmmAdapter

    vm = VirtualMachine(PlacedPart.from_spheres([(0.0, 0.0, 0.0)], [5.0]), ProbeModel(3.0),
                        rack=RACK)
    text = (f"DMISMN/'S',05.0\nUNITS/MM,ANGDEC\nS(X)=SNSDEF/{','.join(prefix + words)}\n"
            "SNSLCT/S(X)\nENDFIL\n")
    try:
        res = run_dmis(text, CmmAdapter(vm), skip_unsupported=True)
    except ProbegenError:
        return
    assert res.alarm is None or res.alarm.number == UNKNOWN_TOOL
    if res.alarm is None and not res.skipped and vm.stylus is not None:
        assert np.linalg.norm(vm.stylus_axis) == pytest.approx(1.0)


def test_g531_does_not_turn_when_the_tool_is_along_the_frame_already() -> None:
    from probegen.sim.macrob.machine import FreeMachine, run_program

    free = FreeMachine(record=True)
    res = run_program("G90 G54\nG68.2 X10. Y0. Z0. I30. J0. K0.\nG53.1\nG0 X1. Y0. Z5.\n"
                      "#101=#5021\n#102=#5022\nM30\n", free)
    assert res.alarm is None and free.turns == []
    # frame X is work (cos 30, sin 30, 0): the frame point (1, 0, 5) is work (10.866, 0.5, 5)
    assert (res.variables[101], res.variables[102]) == pytest.approx(
        (10.0 + 3 ** 0.5 / 2, 0.5), abs=1e-12)


@pytest.mark.parametrize(("a", "b", "alarm"), [
    ("90", "-90", None), ("105", "172.5", None), ("112.5", "0", "A112.5 B0"),
    ("10", "0", "A10 B0"), ("90", "-187.5", "A90 B-187.5")])
def test_cmm_head_indexes_only_its_angles(side_bore: cad.Part, a: str, b: str,
                                          alarm: str | None) -> None:
    from probegen.machine.profile import Head
    from probegen.sim.vm import HEAD_INDEX

    vm = VirtualMachine(PlacedPart.from_model(side_bore), ProbeModel(3.0), rack=RACK,
                        head=Head())
    text = (f"DMISMN/'S',05.0\nUNITS/MM,ANGDEC\nS(X)=SNSDEF/PROBE,INDEX,POL,{a},{b},0,0,-1,"
            "30,2\nSNSLCT/S(X)\nENDFIL\n")
    res = run_text(text, vm, kind="dmis")
    if alarm is None:
        assert res.alarm is None and vm.stylus == RACK[1]
    else:
        assert res.alarm is not None
        assert res.alarm.startswith(f"{HEAD_INDEX} SENSOR S(X) {alarm}: NOT AN INDEX OF THE "
                                    "HEAD (A 0..105, B -180..180, STEP 7.5)")


def test_g53_turns_the_table_back_after_g69(side_bore: cad.Part) -> None:
    """The dialect's way back to the vertical: ``G69`` leaves the table turned, ``G53 A0
    C0`` turns it to zero; a vertical probing move after it runs (no alarm 9021), and
    ``G53`` naming a table axis with a linear axis, or a tilt outside the travel, is an
    alarm."""
    back = program().replace("G53 Z0.\nG68.2 X0. Y0. Z0. I0. J0. K0.\nG53.1\nG69\n",
                             "G53 Z0.\nG69\nG53 A0 C0\nG0 X-20. Y-20.\nG0 Z5.\n"
                             "G31 Z-5. F200.\n")
    assert back != program()
    vm = machine(side_bore)
    res = run_text(back, vm, kind="macrob", work_offset=WORK)
    assert res.alarm is None, res.alarm
    assert res.touches == 4  # the vertical G31 beside the block ends in the air
    left = run_text(back.replace("G53 A0 C0\n", ""), machine(side_bore), kind="macrob",
                    work_offset=WORK)
    assert left.alarm is not None and left.alarm.startswith("9021 ")
    mixed = run_text(back.replace("G53 A0 C0", "G53 A0 C0 Z0"), machine(side_bore),
                     kind="macrob", work_offset=WORK)
    assert mixed.alarm is not None and mixed.alarm.startswith("9010 ")
    vm = machine(side_bore)
    vm.tilt_range = (-110.0, 110.0)
    far = run_text(back.replace("G53 A0 C0", "G53 A-120. C0"), vm, kind="macrob",
                   work_offset=WORK)
    assert far.alarm is not None and far.alarm.startswith("9022 G53 A-120")
