"""Closed loop for the in-process decisions (docs/actions.md): the bore_block setup
program (samples/bore_block/bore_block_actions.toml) runs on the virtual machine against
a part placed off and rotated, and the control's own arithmetic must leave the right work
offset, rotation, tool wear and alarms.

Planted truth: the part sits at the G54 origin plus (1.234, -0.8, 0.3) mm, turned 0.5
degrees about Z through its origin.  The program aligns on the front edge (G68 about
the bore's nominal centre), sets G54 X/Y from the bore and Z from the top face, so that
afterwards ``G54 + R(G68) (p - c) + c`` must be where the part's point ``p`` really is
(noise-free: within 1 um, the angle within 1 urad).  The bore planted 0.03 mm oversize
corrects tool 12's radius wear by +0.015 mm; a bore 0.08 mm oversize (limit +0.05)
stops the program with alarm 3010 before any offset is written; a boss out of its
diameter limits sets the flag #510 and the program runs on.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from conftest import REPO, sample_script

from probegen import cad
from probegen.dialects import get_dialect
from probegen.errors import UnsupportedError
from probegen.evaluate.ingest import ingest
from probegen.evaluate.outputs import to_table
from probegen.machine.probe_model import ProbeModel
from probegen.planning import plan_program
from probegen.results import parse_dmis_output
from probegen.sim.contact import PlacedPart
from probegen.sim.vm import SimResult, VirtualMachine, control_state, run_text
from probegen.spec.model import load_spec

SPEC = Path("samples/bore_block/bore_block_actions.toml")
CMM_SPEC = Path("samples/bore_block/bore_block_cmm.toml")
WORK = np.array([300.0, 200.0, -100.0])   # G54 before the run
SHIFT = np.array([1.234, -0.8, 0.3])      # where the part really is, from G54
ANGLE = math.radians(0.5)
UM, URAD = 1e-3, 1e-6
D_WEAR_12 = 12012                          # memory C: D wear of offset 12


def rot_z(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


@pytest.fixture(scope="module")
def models(tmp_path_factory: pytest.TempPathFactory) -> dict[str, cad.Model]:
    make = sample_script("bore_block")
    out = {"nominal": cad.load_step(REPO / "samples/bore_block/bore_block.step")}
    for name, bore, boss in (("bore+0.03", 50.03, 20.0), ("bore+0.08", 50.08, 20.0),
                             ("boss+0.05", 50.0, 20.05)):
        path = tmp_path_factory.mktemp("variant") / f"{name}.step"
        make.main(path, bore_diameter=bore, boss_diameter=boss)
        out[name] = cad.load_step(path)
    return out


@pytest.fixture(scope="module")
def fanuc_text() -> str:
    spec = load_spec(REPO / SPEC)
    planned = plan_program(spec, runtime_variables=True)
    assert planned.clearance.minimum >= 0.0
    return get_dialect("fanuc").generate(planned.program)


def run(text: str, model: cad.Model, angle: float = ANGLE) -> SimResult:
    part = PlacedPart.from_model(model, rotation=rot_z(angle), translation=WORK + SHIFT)
    return run_text(text, VirtualMachine(part, ProbeModel(3.0)), kind="macrob",
                    work_offset=tuple(WORK))


def g54(res: SimResult) -> np.ndarray:
    return np.array([res.variables.get(5221 + i, 0.0) for i in range(3)])


def test_part_off_and_rotated_ends_with_the_right_offset_and_rotation(
        fanuc_text: str, models: dict[str, cad.Model]) -> None:
    res = run(fanuc_text, models["nominal"])
    assert res.alarm is None, res.alarm
    assert res.rotation is not None
    cx, cy, degrees = res.rotation
    assert (cx, cy) == (50.0, 50.0)                      # the bore's nominal centre
    assert math.radians(degrees) == pytest.approx(ANGLE, abs=URAD)
    assert res.variables[520] == degrees                 # the angle for the part program
    offset = g54(res)
    c = np.array([cx, cy, 0.0])
    truth = rot_z(ANGLE)
    for p in ([0.0, 0.0, 0.0], [100.0, 100.0, 50.0], [50.0, 50.0, 25.0], [20.0, 20.0, 70.0]):
        p = np.array(p)
        programmed = rot_z(math.radians(degrees)) @ (p - c) + c + offset
        assert np.allclose(programmed, truth @ p + WORK + SHIFT, atol=UM), p
    # not a tautology: the offset really moved by the planted shift and rotation
    assert np.linalg.norm(offset - WORK) > 0.5
    assert D_WEAR_12 not in res.variables                # nominal bore: no correction
    assert res.variables[510] == 0.0                     # boss in tolerance
    assert control_state(res) == [                       # what probegen sim prints
        "G54 X300.7958 Y199.6344 Z-99.7000", "G68 X50.0000 Y50.0000 R0.500000"]


def test_oversize_bore_corrects_the_tool_radius(fanuc_text: str,
                                                models: dict[str, cad.Model]) -> None:
    res = run(fanuc_text, models["bore+0.03"])
    assert res.alarm is None, res.alarm
    # a bore 0.03 too big: the tool cut 0.015 too deep on each side -> radius wear +0.015
    assert res.variables[D_WEAR_12] == pytest.approx(0.015, abs=1e-6)
    assert "RES BORE T12 C.0150" in res.output
    assert "T12 D wear 0.0150" in control_state(res)


def test_out_of_tolerance_bore_stops_before_writing_offsets(
        fanuc_text: str, models: dict[str, cad.Model]) -> None:
    res = run(fanuc_text, models["bore+0.08"])
    assert res.alarm is not None and res.alarm.startswith("3010 BORE OUT OF TOL")
    assert "ERR OUTTOL BORE 1" in res.output
    assert np.array_equal(g54(res), WORK)                # nothing written
    assert D_WEAR_12 not in res.variables and res.rotation is None


def test_flagged_boss_runs_on(fanuc_text: str, models: dict[str, cad.Model]) -> None:
    res = run(fanuc_text, models["boss+0.05"])
    assert res.alarm is None
    assert res.variables[510] == 1.0
    assert "NG1" in res.output.split("RES BOSS")[1].splitlines()[0]


def test_edge_beyond_its_angle_raises_the_alarm(fanuc_text: str,
                                                models: dict[str, cad.Model]) -> None:
    res = run(fanuc_text, models["nominal"], angle=math.radians(1.2))  # limit 1 degree
    assert res.alarm is not None and res.alarm.startswith("3010 EDGE OUT OF TOL")


@pytest.mark.parametrize("variant", ["nominal", "bore+0.03", "boss+0.05"])
def test_offline_decisions_agree_with_the_machine(fanuc_text: str, tmp_path: Path,
                                                  models: dict[str, cad.Model],
                                                  variant: str) -> None:
    res = run(fanuc_text, models[variant])
    log = tmp_path / "run.log"
    log.write_text(res.output)
    ing = ingest(log, load_spec(REPO / SPEC))
    by_key = {(d.feature, d.key): d for d in ing.decisions}
    assert set(by_key) == {("EDGE", k) for k in ("P", "A", "NG")} | {
        ("TOP", k) for k in ("P", "NG")} | {
        (f, k) for f in ("BORE", "BOSS") for k in ("X", "Y", "D", "F", "NG")} | {
        ("BORE", "C")}
    assert all(d.agrees for d in ing.decisions), [d for d in ing.decisions if not d.agrees]
    # the offline values are right on their own too
    assert by_key["EDGE", "A"].offline == pytest.approx(0.5, abs=2e-4)
    assert by_key["BORE", "C"].offline == pytest.approx(
        {"bore+0.03": 0.015}.get(variant, 0.0), abs=2e-4)
    assert by_key["BOSS", "NG"].offline == (1.0 if variant == "boss+0.05" else 0.0)
    table = to_table(ing)
    assert "BORE     C" in table or "BORE C" in " ".join(table.split())


def test_offline_check_catches_a_wrong_machine_value(fanuc_text: str, tmp_path: Path,
                                                     models: dict[str, cad.Model]) -> None:
    res = run(fanuc_text, models["nominal"])
    log = tmp_path / "run.log"
    log.write_text(res.output.replace("RES BORE X50.7958", "RES BORE X50.7968"))
    ing = ingest(log, load_spec(REPO / SPEC))
    bad = [(d.feature, d.key) for d in ing.decisions if d.agrees is False]
    assert bad == [("BORE", "X")]


def test_dmis_part_frame_puts_the_measured_part_at_nominal(
        models: dict[str, cad.Model]) -> None:
    spec = load_spec(REPO / CMM_SPEC)
    text = get_dialect("dmis").generate(plan_program(spec, runtime_variables=False).program)
    part = PlacedPart.from_model(models["bore+0.03"], rotation=rot_z(ANGLE), translation=SHIFT)
    res = run_text(text, VirtualMachine(part, ProbeModel(3.0)), kind="dmis")
    assert res.alarm is None, res.alarm
    out = parse_dmis_output(res.output, strict=True)
    # reported again in the part frame: the bore at its nominal centre, the top at
    # z = 50, the edge along +X ...
    bore, top, edge = out.feature("BORE"), out.feature("TOP"), out.feature("EDGE")
    assert np.allclose(bore.position[:2], (50.0, 50.0), atol=1e-4)
    assert top.position[2] == pytest.approx(50.0, abs=1e-4)
    assert np.allclose(edge.direction, (1.0, 0.0, 0.0), atol=1e-6)
    # ... and the boss, 42 mm from the bore, where the part says: the rotation is right
    assert np.allclose(out.feature("BOSS").position[:2], (20.0, 20.0), atol=1e-4)
    tols = {t.name: t for t in out.tolerances}
    assert tols["BORE_D"].value == pytest.approx(0.03, abs=1e-4) and tols["BORE_D"].intol
    assert tols["BOSS_P"].intol is False                 # about (20, 20) of the machine
    assert tols["TOP_P"].intol                            # 0.3 mm off, zone 1.0


def test_dmis_cannot_stop_or_correct_tools() -> None:
    spec = load_spec(REPO / SPEC)
    with pytest.raises(UnsupportedError, match="on_out_of_tolerance = 'alarm'"):
        get_dialect("dmis").generate(plan_program(spec, runtime_variables=False).program)


def tweaked_text(tmp: Path, old: str, new: str, *more: tuple[str, str]) -> str:
    """The Fanuc program of the sample spec with edits (paths made absolute)."""
    text = (REPO / SPEC).read_text()
    for a, b in ((old, new), *more):
        assert a in text
        text = text.replace(a, b)
    text = text.replace(
        '"../machines/vmc-fanuc.toml"', f'"{REPO}/samples/machines/vmc-fanuc.toml"').replace(
        '"bore_block.step"', f'"{REPO}/samples/bore_block/bore_block.step"')
    path = tmp / "spec.toml"
    path.write_text(text)
    planned = plan_program(load_spec(path), runtime_variables=True)
    return get_dialect("fanuc").generate(planned.program)


def test_correction_beyond_its_maximum_stops_without_writing(
        tmp_path: Path, models: dict[str, cad.Model]) -> None:
    text = tweaked_text(tmp_path, "max = 0.1", "max = 0.01")
    res = run(text, models["bore+0.03"])
    assert res.alarm is not None and res.alarm.startswith("3011 BORE TOOL CORR TOO BIG")
    assert "ERR BIGCORR BORE 12" in res.output and D_WEAR_12 not in res.variables


def test_a_long_feature_id_keeps_its_alarm_within_26_characters(
        tmp_path: Path, models: dict[str, cad.Model]) -> None:
    """``HOUSINGBORE1 TOOL CORR TOO BIG`` (30 characters) would not fit a Fanuc alarm:
    the text takes its short form, the id stays whole (docs/actions.md)."""
    text = tweaked_text(tmp_path, "max = 0.1", "max = 0.01",
                        ('id = "BORE"', 'id = "HOUSINGBORE1"'))
    assert "#3000=11(HOUSINGBORE1 BIGCORR)" in text
    res = run(text, models["bore+0.03"])
    assert res.alarm is not None and res.alarm.startswith("3011 HOUSINGBORE1 BIGCORR")
    assert "ERR BIGCORR HOUSINGBORE1 12" in res.output


@pytest.mark.parametrize(("feedback", "dead_band", "wear"),
                         [("0.5", "0.005", 0.0075), ("1.0", "0.02", None)])
def test_feedback_and_dead_band(tmp_path: Path, models: dict[str, cad.Model],
                                feedback: str, dead_band: str, wear: float | None) -> None:
    text = tweaked_text(tmp_path, "dead_band = 0.005, max = 0.1, feedback = 1.0",
                        f"dead_band = {dead_band}, max = 0.1, feedback = {feedback}")
    res = run(text, models["bore+0.03"])
    assert res.alarm is None
    if wear is None:                                    # 0.015 inside a 0.02 dead band
        assert D_WEAR_12 not in res.variables and "RES BORE T12 C.0000" in res.output
    else:
        assert res.variables[D_WEAR_12] == pytest.approx(wear, abs=1e-6)


def test_stop_reaction_ends_the_run_with_a_message(tmp_path: Path,
                                                   models: dict[str, cad.Model]) -> None:
    text = tweaked_text(tmp_path, 'on_out_of_tolerance = "alarm"\nset_work_offset = { '
                        'offset = "G54", axes = "XY" }', 'on_out_of_tolerance = "stop"\n'
                        'set_work_offset = { offset = "G54", axes = "XY" }')
    assert "#3006=1(BORE OUT OF TOL)" in text
    res = run(text, models["bore+0.08"])
    assert res.alarm is None and "ERR OUTTOL BORE 1" in res.output
    assert "PGEND" not in res.output and np.array_equal(g54(res), WORK)


def test_sphere_centre_sets_g55(in_repo: Path) -> None:
    spec = load_spec(Path("samples/sphere25/sphere_setup.toml"))
    text = get_dialect("fanuc").generate(plan_program(spec, runtime_variables=True).program)
    centre = WORK + np.array([1.234, -0.9, 0.4])
    part = PlacedPart.from_spheres([centre.tolist()], [12.5])
    res = run_text(text, VirtualMachine(part, ProbeModel(3.0)), kind="macrob",
                   work_offset=tuple(WORK))
    assert res.alarm is None, res.alarm
    g55 = np.array([res.variables[5241 + i] for i in range(3)])
    assert np.allclose(g55, centre, atol=UM)      # the sphere's centre is G55's origin
    assert np.array_equal(g54(res), WORK)         # the running offset is left alone


def test_high_face_shortens_the_tool_length(tmp_path: Path,
                                             models: dict[str, cad.Model]) -> None:
    text = tweaked_text(tmp_path, 'set_work_offset = { offset = "G54", axes = "Z" }',
                        'update_tool = { tool = 5, offset = "length", max = 0.5 }')
    res = run(text, models["nominal"])
    assert res.alarm is None, res.alarm
    # the top is 0.3 mm high: the tool must cut 0.3 deeper, its H wear drops by 0.3
    assert res.variables[10005] == pytest.approx(-0.3, abs=1e-6)


@pytest.mark.parametrize(("old", "new", "first"), [
    ('offset = "G54", axes = "XY" }\nupdate', 'offset = "G54.1 P3", axes = "XY" }\nupdate',
     14041),                                          # G54.1 P3: #14041-, via G10 L20 P3
    ('kind = "circle"\nat = [75.0, 50.0, 25.0]\nsections = [25.0]',
     'kind = "cylinder"\nat = [75.0, 50.0, 25.0]\nsections = [10.0, 40.0]', 5221),
])
def test_extended_offset_and_cylinder_bore(tmp_path: Path, models: dict[str, cad.Model],
                                           old: str, new: str, first: int) -> None:
    text = tweaked_text(tmp_path, old, new)
    res = run(text, models["nominal"], angle=0.0)
    assert res.alarm is None, res.alarm
    xy = np.array([res.variables[first], res.variables[first + 1]])
    assert np.allclose(xy, WORK[:2] + SHIFT[:2], atol=UM)
