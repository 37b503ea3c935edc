"""A drill point: the 118° cone at the bottom of a D2.46 drilled hole, measured with the
CMM sample's D1 stylus (issue 17: NIST FTC 10's six drill points were left out with
"too few touches").

The point is 0.739 mm long; its normal leans 59° out of the section plane, so with a
retract ``d`` a section of radius ``R`` has a safe circle of ``R - (0.5 + d)·cos 59°``.
Its default sections (radius 0.307 and 0.922) do not serve the D1 ball: the lower one has
no safe circle with the least retract (0.45 mm), the upper one brings the ball within
0.15 mm of the hole's wall.  The alternative sections at 0.4 and 0.6 of its length
(radius 0.492 and 0.738) do, with the least retract: the retract the planner tries there
is the largest that fits them (``revolved_plan._fitting``), not the one that served the
default sections.  The program runs on the virtual CMM with the part placed off by a
planted offset, and the measured cone's apex and angle are the planted ones to 1 µm.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from conftest import REPO

from probegen import cad
from probegen.cli.app import main
from probegen.dialects import get_dialect
from probegen.errors import PlanningError
from probegen.machine.profile import load_profile
from probegen.planning import plan_program
from probegen.planning.revolved import PathKind
from probegen.results import parse_dmis_output
from probegen.spec.model import load_spec

PROFILE = REPO / "samples/machines/cmm.toml"
RADIUS = 1.23
"""The drilled hole's radius, mm (FTC 10's D2.46)."""
HALF = math.radians(59.0)
"""The drill point's half angle (118° included)."""
TIP = 4.0 - RADIUS / math.tan(HALF)
"""The point's tip, z mm: the hole runs from the top (z 10) down to z 4."""
OFFSET = (0.004, -0.003, 0.002)
"""The planted placement error, mm."""


@pytest.fixture(scope="module")
def model(tmp_path_factory: pytest.TempPathFactory) -> Path:
    from build123d import Align, Box, Cone, Cylinder, Pos, export_step

    point = RADIUS / math.tan(HALF)
    hole = (Pos(0, 0, 4) * Cylinder(RADIUS, 6.0, align=(Align.CENTER, Align.CENTER, Align.MIN))
            + Pos(0, 0, TIP) * Cone(0.0, RADIUS, point,
                                    align=(Align.CENTER, Align.CENTER, Align.MIN)))
    block = Box(20, 20, 10, align=(Align.CENTER, Align.CENTER, Align.MIN)) - hole
    path = tmp_path_factory.mktemp("drill") / "drill_point.step"
    export_step(block, path)
    return path


def _spec(model: Path, tmp_path: Path, extra: str = "") -> Path:
    at = RADIUS / 2.0, 0.0, TIP + RADIUS / 2.0 / math.tan(HALF)  # halfway up the point
    spec = tmp_path / "drill_point.toml"
    spec.write_text(f'[part]\nmodel = "{model.as_posix()}"\n\n[machine]\nprofile = '
                    f'"{PROFILE.as_posix()}"\n\n[[feature]]\nid = "TIP"\nkind = "cone"\n'
                    f'at = [{at[0]}, {at[1]}, {at[2]}]\nstylus = "D1"\npoints = 8\n{extra}')
    return spec


def test_a_drill_point_is_measured_in_two_sections_with_the_least_retract(
        model: Path, tmp_path: Path) -> None:
    planned = plan_program(load_spec(_spec(model, tmp_path)), runtime_variables=False)
    (tip,) = planned.revolved
    sections = tip.plan.sections
    assert len(sections) == 2 and len(tip.normals) == 16  # nothing dropped
    assert [s.retract for s in sections] == pytest.approx([0.45, 0.45])  # 1.5 margins
    assert sorted(s.section.radius for s in sections) == pytest.approx([0.492, 0.738],
                                                                        abs=1e-3)
    assert all(s.safe_radius > 0.0 for s in sections)
    assert any(n.startswith("default sections lose touches") for n in tip.notes)
    assert planned.clearance.minimum >= 0.0  # the program's check clears every move
    targets = [p for p in tip.plan.path if p.kind is PathKind.TARGET]
    assert len(targets) == 16


def test_the_spec_s_retract_is_kept(model: Path, tmp_path: Path) -> None:
    """A spec that gives the retract gets it at every choice of sections, never a smaller
    one: with 0.5 mm the sections at 55/90 % plan (the upper one's touches dropped), and
    the lower one at 40 % has no safe circle (0.492 - 1.0 x cos 59° < 0), so the drill
    point keeps one section: refused, not planned with 0.45 mm."""
    spec = load_spec(_spec(model, tmp_path, "retract = 0.5\n"))
    with pytest.raises(PlanningError, match="too few touches"):
        plan_program(spec, runtime_variables=False)


def test_the_drill_point_measured_on_the_virtual_cmm_is_the_planted_one(
        model: Path, tmp_path: Path) -> None:
    spec = load_spec(_spec(model, tmp_path))
    planned = plan_program(spec, runtime_variables=False)
    program, out = tmp_path / "drill_point.dmi", tmp_path / "drill_point.out"
    program.write_text(get_dialect("dmis").generate(planned.program))
    code = main(["sim", str(program), "--part", str(model), "--machine", str(PROFILE),
                 "--offset", *map(str, OFFSET), "-o", str(out)])
    assert code == 0
    cone = parse_dmis_output(out.read_text(), strict=True).feature("TIP")
    assert cone.type == "CONE"
    assert cone.angle == pytest.approx(118.0, abs=1e-3)
    assert cone.direction is not None and abs(cone.direction[2]) == pytest.approx(1.0)
    # the reported point is the tip moved by the offset
    tip = np.array([0.0, 0.0, TIP]) + np.asarray(OFFSET)
    assert np.linalg.norm(np.asarray(cone.position) - tip) < 1e-3


def test_the_part_loads(model: Path) -> None:
    part = cad.load_part(model)
    assert part.bbox_max[2] == pytest.approx(10.0)
    assert load_profile(PROFILE).margin == pytest.approx(0.3)
