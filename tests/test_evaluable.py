"""No feature planned whose result cannot come out (issue 17): the planner refuses, on
every dialect, a revolved feature whose kept touches ingest would leave NOT EVALUATED
(one rule, ``geometry.determined.incomplete``, for both), and the dialect that writes
the program decides the free-fit rule (``planning.well_posed``), not the profile's."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from build123d import Align, Box, Cylinder, Pos, export_step
from conftest import REPO

from probegen import cad
from probegen.cli.app import main
from probegen.errors import ExitCode, PlanningError
from probegen.geometry.determined import incomplete
from probegen.machine.profile import load_profile
from probegen.planning import well_posed
from probegen.planning.oriented import plan_oriented
from probegen.spec.model import RevolvedSpec, load_spec

C, MIN = Align.CENTER, Align.MIN
FANUC = REPO / "samples/machines/vmc-fanuc.toml"
CMM = REPO / "samples/machines/cmm.toml"
BORE_BLOCK = REPO / "samples/bore_block/bore_block.toml"
TWO_LEFT = "2 touches in 1 sections (at least 4 needed)"


def test_the_complete_measurement_rule() -> None:
    """Touches per kind, sections per kind, three touches in each section of a cylinder
    or a cone (its diameter and roundness there); a sphere's sections are not fitted
    one by one."""
    assert incomplete("circle", [0, 0, 0]) == "3 touches in 1 sections (at least 4 needed)"
    assert incomplete("circle", [0, 0, 0, 0]) == ""
    assert incomplete("cylinder", [0] * 8) == \
        "8 touches in 1 sections (at least 6 needed, in 2 sections)"
    assert incomplete("cylinder", [0] * 7 + [1] * 2) == (
        "2 touches in section 2 (at least 3 needed in each section of a cylinder: its "
        "diameter and roundness there)")
    assert incomplete("cylinder", [0, 0, 0, 1, 1, 1]) == ""
    assert incomplete("cone", [0, 0, 0, 1, 1, 1]) != ""  # 7 for a cone
    assert incomplete("sphere", [0, 0, 0, 0, 1]) == ""  # a pole touch: its own section
    assert "in 3 sections" in incomplete("torus", [0] * 8 + [1] * 8)


@pytest.fixture(scope="module")
def slotted(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A D10 boss in a ring wall 1.1 mm off it, the wall cut by one 9 mm slot across:
    a 6 mm ball (and a 1 mm one, with the CMM's 0.3 mm margin) reaches the boss in the
    slot only, two touches of eight."""
    part = Box(60, 60, 10, align=(C, C, MIN))
    part += Pos(0, 0, 10) * Cylinder(12, 10, align=(C, C, MIN))
    part -= Pos(0, 0, 10) * Cylinder(6.1, 10, align=(C, C, MIN))
    part -= Pos(0, 0, 10) * Box(40, 9, 10, align=(C, C, MIN))
    part += Pos(0, 0, 10) * Cylinder(5, 10, align=(C, C, MIN))
    path = tmp_path_factory.mktemp("slotted") / "slotted.step"
    export_step(part, path)
    return path


def _boss(part: cad.Part) -> RevolvedSpec:
    from probegen.cad.revolved import revolved_features

    boss = next(f for f in revolved_features(part) if not f.inner and f.radius == 5.0)
    return RevolvedSpec("BOSS", "test", "circle", boss.faces[0], None, None, 8, None)


@pytest.mark.parametrize("profile", [FANUC, CMM])
def test_two_touches_of_a_circle_are_refused_on_every_dialect(slotted: Path,
                                                              profile: Path) -> None:
    """Fanuc (one stylus) and the CMM to DMIS (every stylus of its rack tried, each
    saying what it kept): two touches are refused, not written for ingest to leave NOT
    EVALUATED."""
    part = cad.load_part(slotted)
    with pytest.raises(PlanningError) as exc:
        plan_oriented(_boss(part), part, load_profile(profile), 100.0)
    text = str(exc.value)
    # with what took the other six: the first touch the collision check dropped, and
    # the face it ran into (the ring wall)
    assert re.search(re.escape(f"circle: too few touches to evaluate it: {TWO_LEFT} (the rest "
                               "dropped by the collision check, e.g. touch 2 dropped: its "
                               "approach from (") + r"[^;]* into face \d+; expected a "
                     r"clearance of at least 0\.\d+ mm\); give more points or sections where "
                     r"the part lets the probe reach them \(points = N, sections = "
                     r"\[\.\.\.\]\), or another stylus, orientation or a setup", text), text
    if profile == CMM:  # what each stylus kept
        assert f"D6 (ball 6 mm): {TWO_LEFT} (the rest dropped by the collision" in text
        assert f"D1 (ball 1 mm): {TWO_LEFT} (the rest dropped by the collision" in text


@pytest.mark.parametrize(("profile", "dialect", "ext"), [(FANUC, "fanuc", ".nc"),
                                                         (CMM, "dmis", ".dmi")])
def test_all_revolved_leaves_it_out_with_the_reason(
        slotted: Path, tmp_path: Path, profile: Path, dialect: str, ext: str,
        capsys: pytest.CaptureFixture[str]) -> None:
    """``plan --all-revolved``: the boss (two touches of each section, as a cylinder or
    as a circle) is in the left-out table and the program's header with the reason, and
    not in the program."""
    out = tmp_path / "out"
    assert main(["plan", str(slotted), "--all-revolved", "--machine", str(profile), "-d",
                 dialect, "-o", str(out), "-q"]) == ExitCode.OK
    printed = capsys.readouterr().out
    left = printed[printed.index("left out ("):]
    line = next(row for row in left.splitlines() if "boss D10.000" in row)
    # measured as a cylinder (two sections, two touches each) and as a circle: refused
    assert "): cylinder: too few touches to evaluate it: 4 touches in 2 sections (at least " \
        "6 needed, in 2 sections) (the rest dropped by the collision check, e.g. touch " in line
    assert "; give more points" in line
    program = (out / f"slotted{ext}").read_text()
    boss = line.split()[0]  # R3
    head = re.sub(r"[\s$()]+", " ", program.upper())  # the comment lines as one text
    assert f"{boss} BOSS D10.000 CYLINDER, FACES 11: CYLINDER: TOO FEW TOUCHES TO EVALUATE " \
        "IT: 4 TOUCHES IN 2 SECTIONS AT LEAST 6 NEEDED, IN 2 SECTIONS THE REST DROPPED BY " \
        "THE COLLISION CHECK, E.G. TOUCH" in head
    assert f"FEATURE {boss} " not in program and f"F({boss})" not in program


@pytest.fixture
def stand_in(monkeypatch: pytest.MonkeyPatch) -> str:
    """Every feature ill posed for a target that fits freely (a stand-in for a CMM's free
    fit refusing it): which dialect's rule the planner applies shows."""
    reason = "a stand-in free-fit refusal"
    monkeypatch.setattr(well_posed, "ill_posed",
                        lambda kind, feature, plan, free=True: reason if free else "")
    return reason


def test_the_dialect_that_writes_the_program_decides(tmp_path: Path, stand_in: str,
                                                     capsys: pytest.CaptureFixture[str]
                                                     ) -> None:
    """bore_block's spec on the Fanuc profile: ``compile -d dmis`` is checked for a CMM's
    free fit (refused, the reason named), ``-d fanuc`` is not."""
    assert main(["compile", str(BORE_BLOCK), "-d", "fanuc", "-o",
                 str(tmp_path / "f")]) == ExitCode.OK
    code = main(["compile", str(BORE_BLOCK), "-d", "dmis", "-o", str(tmp_path / "d")])
    assert code != ExitCode.OK
    assert f"cylinder: {stand_in}: a CMM fits it freely" in capsys.readouterr().err
    assert not (tmp_path / "d").exists()


def test_plan_all_revolved_takes_the_rule_of_every_dialect_it_writes(
        tmp_path: Path, stand_in: str, capsys: pytest.CaptureFixture[str]) -> None:
    """``plan --all-revolved`` on the Fanuc profile: with ``-d dmis`` (alone or with
    ``-d fanuc``) the features are chosen by the free-fit rule, so every one is left out
    with its reason; with ``-d fanuc`` alone, by the evaluation's."""
    model = REPO / "samples/bore_block/bore_block.step"

    def left_out(*dialects: str) -> str:
        args = [a for d in dialects for a in ("-d", d)]
        assert main(["plan", str(model), "--all-revolved", "--machine", str(FANUC), *args,
                     "-o", str(tmp_path / "-".join(dialects)), "-q"]) == ExitCode.OK
        printed = capsys.readouterr().out
        return printed[printed.find("left out ("):] if "left out (" in printed else ""

    assert stand_in not in left_out("fanuc")
    for dialects in (("dmis",), ("fanuc", "dmis")):
        assert stand_in in left_out(*dialects)


def test_a_dprnt_log_is_ingested_as_its_macro_b_program_was_planned() -> None:
    """A spec whose dialect is DMIS compiled with ``-d fanuc``: ingest plans it as Fanuc
    (a DPRNT log comes from a Macro B program), not for a CMM's free fit."""
    from dataclasses import replace

    spec = load_spec(BORE_BLOCK)
    dmis = well_posed.for_dialect(spec, "dmis")
    assert (dmis.dialect, dmis.machine.dialect) == ("dmis", "dmis")
    assert well_posed.for_log(dmis).machine.dialect == "fanuc"
    haas = replace(dmis, machine=replace(dmis.machine, dialect="haas"))
    assert well_posed.for_log(haas).machine.dialect == "haas"
    assert well_posed.for_dialect(spec, "fanuc") is spec
    assert well_posed.strictest(["fanuc", "dmis"], "haas") == "dmis"
    assert well_posed.strictest([], "haas") == "haas"
