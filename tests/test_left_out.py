"""What is left out is left out for a reason the user can act on (issue 17, item 5).

A block made here with three bores the 6 mm ball cannot measure, each for its own
reason: a D2 through bore (the stylus is too large), a D20 bore 2 mm deep (blind,
shallower than the ball needs), a D8 bore along X (not along the probe).  Each reason is
checked word for word in ``plan --all-revolved`` (the table), in the program header
``plan -o`` writes (Fanuc, LinuxCNC and DMIS: comments the controls accept) and in the
skeleton ``init`` writes.
"""

from __future__ import annotations

import re
from dataclasses import replace
from pathlib import Path

import pytest
from build123d import Align, Box, Cylinder, Pos, Rot, export_step
from conftest import REPO

from probegen import cad
from probegen.cli.app import main
from probegen.errors import ExitCode
from probegen.machine.profile import load_profile
from probegen.planning.left_out import header_comments
from probegen.planning.revolved_spec import all_revolved_spec, smallest_bore

MACHINE = REPO / "samples/machines/vmc-fanuc.toml"
C, MIN, MAX = Align.CENTER, Align.MIN, Align.MAX
REASONS = [
    "R1 bore D2.000 (cylinder, faces 7): bore D2.000: the stylus ball D6.000 needs D8.000 or "
    "more, the ball and 1.000 mm each side for the retract and safe circle: a smaller "
    "stylus",
    "R2 bore D20.000 (cylinder, faces 8): blind, depth 2.000 mm: the ball reaches no section "
    "(it needs 3.500 mm below one: radius 3.000 + margin 0.500): a smaller stylus [no touch "
    "can be reached safely: touch 1 dropped: its approach from (6.000, 0.000, 19.000) to "
    "(6.730, 0.000, 19.000): the stylus ball cuts 2.000 mm into face 10; 7 more touches "
    "dropped]",
    "R3 bore D8.000 (cylinder, faces 9): axis (1.0000, 0.0000, 0.0000) is 90.0 deg from Z, "
    "not along the probe: needs an orientation or a setup",
]


@pytest.fixture(scope="module")
def model(tmp_path_factory: pytest.TempPathFactory) -> Path:
    part = Box(80, 40, 20, align=(C, C, MIN))
    part -= Pos(-25, 0, 20) * Cylinder(1.0, 20, align=(C, C, MAX))  # D2 through
    part -= Pos(0, 0, 20) * Cylinder(10, 2, align=(C, C, MAX))  # D20, 2 deep, blind
    part -= Pos(25, 0, 10) * Rot(0, 90, 0) * Cylinder(4, 40)  # D8 along X
    path = tmp_path_factory.mktemp("left_out") / "block.step"
    export_step(part, path)
    return path


def test_each_reason_names_the_numbers_and_the_remedy(model: Path) -> None:
    spec, notes = all_revolved_spec(cad.load_part(model), load_profile(MACHINE))
    assert spec.features == ()
    assert list(notes) == REASONS


def test_smallest_bore_is_what_the_planner_takes() -> None:
    """The profile: ball 6, margin 0.5: a bore needs r + 1.5 margins + 0.25 core = 4 mm
    in radius; the bore sample's planning refuses below it."""
    machine = load_profile(MACHINE)
    assert smallest_bore(machine) == pytest.approx(8.0)


def test_the_plan_table_lists_them(model: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["-q", "plan", "--all-revolved", str(model), "--machine",
                 str(MACHINE)]) == ExitCode.OK
    out = capsys.readouterr().out.splitlines()
    at = out.index("left out (3 recognised features; the reason and what would make each "
                   "measurable):")
    assert out[at + 1:] == [f"  {r}" for r in REASONS]


@pytest.mark.parametrize(("dialect", "ext", "open_", "close"), [
    ("fanuc", "nc", "(", ")"), ("linuxcnc", "ngc", "(", ")"), ("dmis", "dmi", "$$ ", "")])
def test_the_program_header_lists_them(model: Path, tmp_path: Path, dialect: str, ext: str,
                                       open_: str, close: str) -> None:
    assert main(["-q", "plan", "--all-revolved", str(model), "--machine", str(MACHINE),
                 "-d", dialect, "-o", str(tmp_path)]) == ExitCode.OK
    lines = (tmp_path / f"block.{ext}").read_text(encoding="ascii").splitlines()
    at = lines.index(f"{open_}LEFT OUT 3 RECOGNISED FEATURES:{close}")
    block = lines[at + 1:at + 10]
    text = " ".join(line.removeprefix(open_).removesuffix(close).strip() for line in block)
    assert "R1 BORE D2.000 CYLINDER, FACES 7: BORE D2.000: THE STYLUS BALL D6.000 NEEDS " \
           "D8.000 OR MORE, THE BALL AND 1.000 MM EACH SIDE FOR THE RETRACT AND SAFE " \
           "CIRCLE: A SMALLER STYLUS" in text
    assert "R2 BORE D20.000 CYLINDER, FACES 8: BLIND, DEPTH 2.000 MM" in text
    assert "R3 BORE D8.000 CYLINDER, FACES 9: AXIS 1.0000, 0.0000, 0.0000 IS 90.0 DEG FROM " \
           "Z, NOT ALONG THE PROBE: NEEDS AN ORIENTATION OR A SETUP" in text
    assert all(len(line) <= 80 for line in lines)
    assert not any(re.search(r"\(.*\(|\).*\)", line) for line in block)  # nothing nested


def test_header_comments_fit_a_fanuc_block() -> None:
    long = "R9 " + "word " * 60
    comments = header_comments((long.strip(), "R10 x (y) [detail dropped]"))
    assert comments[0].text == "LEFT OUT 2 RECOGNISED FEATURES:"
    assert all(len(c.text) <= 72 for c in comments)
    assert comments[-1].text == "R10 X Y"
    assert header_comments(()) == ()


def test_the_skeleton_lists_them(model: Path, tmp_path: Path) -> None:
    spec = tmp_path / "block.toml"
    assert main(["-q", "init", str(model), "--machine", str(MACHINE), "-o",
                 str(spec)]) == ExitCode.OK
    text = spec.read_text(encoding="ascii")
    for reason in REASONS:
        assert f"\n#   {reason}\n" in text


FIVE = REPO / "samples/machines/vmc-5axis-fanuc.toml"


@pytest.fixture(scope="module")
def shallow(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A D4 bore 1 mm deep: wide enough for the rack's smallest stylus (D2 takes D4 and
    more), too shallow for its ball."""
    part = Box(40, 40, 20, align=(C, C, MIN))
    part -= Pos(0, 0, 20) * Cylinder(2.0, 1.0, align=(C, C, MAX))
    path = tmp_path_factory.mktemp("shallow") / "shallow.step"
    export_step(part, path)
    return path


def test_a_rack_leaves_out_for_the_smallest_styluss_own_reason(shallow: Path) -> None:
    """Every stylus fails: D6 and D3 because the bore is narrower than they take, D2
    because the bore is too shallow.  The line says the last (what the user acts on);
    neither the largest ball's "R > r + d" nor the profile approach's (a 2 mm retract
    does not fit a D4 bore with a D2 ball, 0.75 mm does)."""
    from probegen.errors import PlanningError
    from probegen.planning.revolved_spec import plan_revolved
    from probegen.planning.styli import stylus_named
    from probegen.spec.model import RevolvedSpec

    sample = load_profile(FIVE)   # its rack without D1: D2 the smallest, as described
    machine = replace(sample, rack=tuple(s for s in sample.rack if s.label != "D1"))
    part = cad.load_part(shallow)
    assert smallest_bore(machine.with_stylus(stylus_named(machine, "D2", "x"))) == 4.0
    spec, notes = all_revolved_spec(part, machine)
    assert spec.features == ()
    bore = next(n for n in notes if n.startswith("R1 bore D4.000"))
    assert "blind, depth 1.000 mm: the ball reaches no section (it needs 1.500 mm below " \
           "one: radius 1.000 + margin 0.500): a smaller stylus" in bore
    assert "where it is measured" not in bore and "D6" not in bore
    feature = RevolvedSpec("B", "spec.toml: feature[0]", "circle", int(bore.split(
        "faces ")[1].split(")")[0]), None, None, 8, None)
    d2 = machine.with_stylus(stylus_named(machine, "D2", "x"))
    with pytest.raises(PlanningError) as info:
        plan_revolved(feature, part, d2, 40.0)
    assert "R > r + d" not in str(info.value)
    assert "no touch can be reached safely" in str(info.value)


def test_the_smallest_styluss_own_reason_is_read_not_what_the_others_said() -> None:
    """A pick_stylus message: the smallest stylus collides, a larger one's "R > r + d"
    and "end margin" texts come after it; the reason is the collision."""
    from types import SimpleNamespace

    from probegen.planning.left_out import revolved_left_out
    from probegen.planning.styli import NONE_PLANS

    machine = load_profile(FIVE)
    problem = (
        "part.step: revolved feature 4: no touch can be reached safely: touch 1 dropped: "
        "its approach from (0.000, 0.000, 5.000) to (1.000, 0.000, 5.000): the stylus shank "
        "cuts 0.015 mm into face 12 (with D2, " + NONE_PLANS + "D6 (ball 6 mm): inner radius "
        "2.500 mm: the safe circle R - r - d = -2.500 mm: expected R > r + d = 5.000 mm; D3 "
        "(ball 3 mm): expected an accessible arc longer than twice the end margin 2.000 mm, "
        "found arcs of 3.100 mm; D2 (ball 2 mm): no touch can be reached safely ...)")
    bore = SimpleNamespace(id=4, type="cylinder", inner=True, radius=2.5, minor_radius=None,
                           faces=(7,), axis=(0.0, 0.0, 1.0), length=10.0,
                           extent=(0.0, 10.0), centre_at=lambda h: (0.0, 0.0, h))
    through = SimpleNamespace(exact=SimpleNamespace(inside=lambda p: False))
    line = revolved_left_out(bore, through, machine, problem, 4.0)  # type: ignore[arg-type]
    assert line.startswith("R4 bore D5.000 (cylinder, faces 7): no touch can be reached "
                           "safely: no room: the stylus shank meets face 12 (a smaller or "
                           "longer stylus, or another orientation) [")
    assert "where it is measured" not in line and "arc too short" not in line


def test_a_shank_collision_names_the_face_the_shank_meets(tmp_path: Path) -> None:
    """The ball 2 mm over a floor, the shank up through a roof 8 mm higher: a face of the
    roof is named, not the floor (the face nearest the ball centre)."""
    import numpy as np

    from probegen.planning.collision import Stylus, describe, obstacle_for

    part = Box(40, 40, 5, align=(C, C, MIN)) + Pos(10, 0, 15) * Box(20, 40, 5,
                                                                   align=(C, C, MIN))
    path = tmp_path / "roof.step"
    export_step(part, path)
    loaded = cad.load_part(path)
    floor = f"face {cad.face_at(loaded.model, (-10.0, 0.0, 5.0)).id}"
    roof = {f"face {cad.face_at(loaded.model, (10.0, 0.0, z)).id}" for z in (15.0, 20.0)}
    assert floor not in roof
    obstacle, stylus, centre = obstacle_for(loaded, []), Stylus(1.0, 0.7, 30.0), \
        np.array([10.0, 0.0, 7.0])
    ball, shank = obstacle.clearance(centre, stylus)
    assert ball > 0.5 and shank < 0.0
    said = describe(obstacle, ball - 0.25, shank - 0.25, 0.25, centre, stylus)
    # the depth measured: the roof (z 15-20) crosses the shank's axis and reaches 12 mm
    # above its lower end (the ball's top, z = 8)
    assert said.startswith("the stylus shank cuts 0.700 mm (across its axis, 12.000 mm up "
                           "from its lower end) into face ")
    assert said.split(" into ")[1].split(";")[0] in roof
    assert floor in describe(obstacle, ball - 0.25, shank - 0.25, 0.25, centre)
