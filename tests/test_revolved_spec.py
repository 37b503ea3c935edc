"""Revolved features in specs (M2 wired): spec keys, resolution, planning, CLI."""

from __future__ import annotations

from pathlib import Path

import pytest
from conftest import REPO

from probegen import ir
from probegen.cli.app import ExitCode, main
from probegen.errors import PlanningError, SpecError
from probegen.planning import plan_program
from probegen.spec.model import RevolvedSpec, RevolvedTolerance, load_spec

PROFILE = REPO / "samples/machines/vmc-fanuc.toml"


def write_spec(tmp_path: Path, model: Path, feature: str) -> Path:
    path = tmp_path / "spec.toml"
    path.write_text(f'[part]\nmodel = "{model.as_posix()}"\n\n[machine]\n'
                    f'profile = "{PROFILE.as_posix()}"\n\n[[feature]]\n{feature}\n')
    return path


def test_sample_spec_loads(in_repo: Path) -> None:
    spec = load_spec("samples/bore_block/bore_block.toml")
    bore, boss = spec.features
    assert isinstance(bore, RevolvedSpec) and isinstance(boss, RevolvedSpec)
    assert (bore.kind, bore.sections, bore.points, bore.at) == (
        "cylinder", (10.0, 40.0), 8, (75.0, 50.0, 25.0))
    assert bore.tolerance == RevolvedTolerance((0.0, 0.025), 0.05, 0.01)
    assert (boss.kind, boss.face, boss.sections, boss.points) == ("circle", 7, (10.0,), 6)


def test_plan_dispatches_and_orders(in_repo: Path) -> None:
    planned = plan_program(load_spec("samples/bore_block/bore_block.toml"),
                           runtime_variables=True)
    # the boss on top first, then straight across and down into the bore (a clear link
    # below the clearance plane: no climb to z = 100 between them)
    assert [p.spec.id for p in planned.revolved] == ["BOSS", "BORE"]
    assert planned.tour is not None and planned.tour.order == (1, 0)
    blocks = [n for n in planned.program.body if isinstance(n, ir.FeatureBlock)]
    assert [type(b.feature) for b in blocks] == [ir.CircleDef, ir.CylinderDef]
    bore = blocks[1].feature
    assert isinstance(bore, ir.CylinderDef)
    assert (bore.centre, bore.diameter, bore.length, bore.inner) == (
        (50.0, 50.0, 25.0), 50.0, 50.0, True)
    boss_last = planned.revolved[0].plan.path[-2].position
    link = [n.target for n in blocks[1].body[:3] if isinstance(n, ir.Move)]
    assert all(z < 100.0 for _, _, z in link)  # never up to the clearance plane
    assert max(z for _, _, z in link) <= boss_last[2] + 15.0
    # sections by depth below the top (z = 50): 10 -> z 40, 40 -> z 10, top first
    zs = [s.section.centre[2] for s in planned.revolved[1].plan.sections]
    assert zs == pytest.approx([40.0, 10.0])
    (boss_section,) = planned.revolved[0].plan.sections
    assert boss_section.section.centre[2] == pytest.approx(60.0)
    touches = [n for n in ir.walk(planned.program.body) if isinstance(n, ir.Touch)]
    # 6 + 16 planned, less the bore's touch at 225 deg in its 40 mm deep section: the
    # OMP40-like body of vmc-fanuc.toml (40 mm across, 50 mm above the ball, z 60..110)
    # would meet the 20 mm boss (up to z = 70) there
    assert len(touches) == 21
    assert planned.clearance.minimum >= 0.0


def test_default_sections(tmp_path: Path) -> None:
    model = REPO / "samples/bore_block/bore_block.step"
    spec = load_spec(write_spec(tmp_path, model, 'id = "B"\nkind = "cylinder"\nface = 8'))
    (p,) = plan_program(spec, runtime_variables=True).revolved
    # the default sections (a quarter of the 50 mm bore from each end: z 37.5, 12.5) lose
    # touches to the body (z 62.5.. beside the boss, up to z = 70): the next candidate
    # sections that keep all 16 are higher
    assert [s.section.centre[2] for s in p.plan.sections] == pytest.approx([45.0, 27.5])
    assert any("default sections lose touches" in n for n in p.notes)
    assert len(p.normals) == 16
    spec = load_spec(write_spec(tmp_path, model, 'id = "C"\nkind = "circle"\nface = 8'))
    (p,) = plan_program(spec, runtime_variables=True).revolved
    assert [s.section.centre[2] for s in p.plan.sections] == pytest.approx([25.0])


def test_inaccessible_feature_names_the_reason(tmp_path: Path) -> None:
    from build123d import Box, Cylinder, Rot, export_step

    part = Box(60, 40, 40) - Rot(0, 90, 0) * Cylinder(8, 80)
    model = tmp_path / "side_bore.step"
    export_step(part, model)
    spec = load_spec(write_spec(tmp_path, model,
                                'id = "SIDE"\nkind = "cylinder"\nat = [30.0, 0.0, 8.0]'))
    with pytest.raises(PlanningError, match=r"feature\[0\]: revolved feature \d+ "
                       r"\(cylinder, faces [\d,]+\) is not accessible: .+"):
        plan_program(spec, runtime_variables=True)


@pytest.mark.parametrize(("feature", "message"), [
    ('id = "B"\nkind = "cylinder"\nface = 8\nsections = [-1.0]', "feature[0].sections"),
    ('id = "B"\nkind = "cylinder"\nface = 8\npoints = 2', "feature[0].points"),
    ('id = "B"\nkind = "cylinder"\nface = 8\nat = [0.0, 0.0, 0.0]', "feature[0].face"),
    ('id = "B"\nkind = "cylinder"\nface = 8\ntolerance = { diameter = [0.1, 0.0] }',
     "feature[0].tolerance.diameter"),
    ('id = "B"\nkind = "cylinder"\nface = 8\nlayout = "iso"', "layout"),
])
def test_bad_revolved_keys(tmp_path: Path, feature: str, message: str) -> None:
    model = REPO / "samples/bore_block/bore_block.step"
    with pytest.raises(SpecError, match=message.replace("[", r"\[").replace("]", r"\]")):
        load_spec(write_spec(tmp_path, model, feature))


def test_cli_features_revolved(in_repo: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["features", "--revolved", "samples/bore_block/bore_block.step"]) == ExitCode.OK
    rows = capsys.readouterr().out.splitlines()
    assert rows[1].split()[:4] == ["1", "cylinder", "outer", "7"]
    assert rows[4].split()[:4] == ["2", "cylinder", "inner", "8"]


def test_cli_plan_all_revolved(in_repo: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code = main(["plan", "samples/bore_block/bore_block.step", "--all-revolved",
                 "--machine", "samples/machines/vmc-fanuc.toml"])
    out = capsys.readouterr().out.splitlines()
    assert code == ExitCode.OK
    assert out[0].split()[:5] == ["feature", "kind", "side", "sect", "pts"]
    r1, r2, total = (row.split() for row in out[1:4])
    assert r1[:5] == ["R1", "cylinder", "outer", "2", "16"]
    assert r2[:5] == ["R2", "cylinder", "inner", "2", "16"]
    for row in (r1, r2):
        plan, baseline, bound = float(row[5]), float(row[7]), float(row[9])
        assert bound <= plan + 1e-6 < baseline
    assert total[:3] == ["total", "4", "32"]
    assert out[-2].startswith("collision check:")
    assert out[-1] == ("rerouted: R2: default sections lose touches; measured at "
                       "z = 45.000, 27.500")


def test_cli_plan_spec(in_repo: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["plan", "samples/bore_block/bore_block.toml"]) == ExitCode.OK
    out = capsys.readouterr().out
    # 15 of 16: the body would meet the boss at the bore's 40 mm deep section (above)
    assert "BORE     cylinder inner    2   15" in out
    assert "order: BOSS BORE" in out


def test_cli_plan_all_revolved_needs_machine(in_repo: Path) -> None:
    assert main(["plan", "samples/bore_block/bore_block.step", "--all-revolved"]) != 0
