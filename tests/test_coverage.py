"""Features left out where the planner, not the part, was the limit (issue 17, lane coverage).

Parts made here reproduce what the NIST models showed:

* a "C" engraved in a block, 3 mm deep: the concave wall of the groove is an inner
  cylinder whose section centre lies on the island, in material (NIST CTC 1's letters on
  its side, FTC 8's).  The probe reaches the wall where its arc is, beside it: the
  feature is measured with the CMM sample profile, the program runs on the virtual CMM,
  every touch lies on the wall's face with the outward normal;
* the same "C" 0.6 mm deep: shallower than the smallest ball needs (NIST CTC 3's 0.635 mm
  engraving): the part's limit, said so (``blind, depth``), for the groove's wall (a bore)
  and its island (a boss) alike, not a bare collision;
* a pocket whose outline has a rounded corner of R3 between two sides 157 deg apart: an
  arc of 1.19 mm, shorter than the 1 mm ball's end margins (its radius and the margin at
  each end, 1.6 mm), though the sides continue the arc and leave the ball room (MetalBoop's
  front plate: the rounded corners of its profile): measured with the margin alone at
  each end.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from build123d import Align, Box, Cylinder, Polygon, Pos, export_step, extrude, fillet
from conftest import REPO

from probegen import cad, ir
from probegen.cad.revolved import revolved_features
from probegen.machine.profile import load_profile
from probegen.planning import plan_program
from probegen.planning.revolved_spec import all_revolved_spec

CMM = REPO / "samples/machines/cmm.toml"
C, MIN, MAX = Align.CENTER, Align.MIN, Align.MAX
OUTER, INNER = 7.0, 3.0
"""The radii of the engraved "C" groove's walls, mm."""


def engraved(path: Path, depth: float) -> Path:
    """A 40 x 40 x 10 block with a "C" engraved ``depth`` deep in its top: the ring
    between :data:`INNER` and :data:`OUTER` round (0, 0), open over the +X quarter."""
    ring = Pos(0, 0, 10) * (Cylinder(OUTER, depth, align=(C, C, MAX))
                            - Cylinder(INNER, depth, align=(C, C, MAX)))
    opening = Pos(0, 0, 10) * Pos(OUTER / 2.0 + 0.5, 0, 0) * Box(
        OUTER + 1.0, OUTER * math.sqrt(2.0), depth, align=(C, C, MAX))
    block = Box(40, 40, 10, align=(C, C, MIN)) - (ring - opening)
    export_step(block, path)
    return path


@pytest.fixture(scope="module")
def deep(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return engraved(tmp_path_factory.mktemp("coverage") / "deep_c.step", 3.0)


@pytest.fixture(scope="module")
def shallow(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return engraved(tmp_path_factory.mktemp("coverage") / "shallow_c.step", 0.6)


def _wall(part: cad.Part) -> object:
    """The groove's outer wall: the inner cylinder of radius :data:`OUTER`."""
    return next(f for f in revolved_features(part)
                if f.type == "cylinder" and f.inner and abs(f.radius - OUTER) < 1e-6)


def test_the_wall_round_an_island_is_reached_beside_its_arc(deep: Path) -> None:
    part = cad.load_part(deep)
    wall = _wall(part)
    centre = np.asarray(wall.sections[0].centre)  # type: ignore[attr-defined]
    assert part.exact.inside(centre)  # the island: the old test refused it here
    assert wall.accessible, wall.reason  # type: ignore[attr-defined]
    assert wall.sections[0].arcs != ()  # type: ignore[attr-defined]


def _measured_on_the_cmm(model: Path, part: cad.Part, feature: object, tmp_path: Path
                         ) -> list[ir.Touch]:
    """``plan --all-revolved`` of ``model`` with the CMM sample measures ``feature`` (a
    recognised revolved feature); its program runs on the virtual CMM; every touch of
    the feature lies on its face.  Its touches."""
    from probegen.cli.app import main
    from probegen.dialects import get_dialect

    spec, notes = all_revolved_spec(part, load_profile(CMM))
    face = feature.faces[0]  # type: ignore[attr-defined]
    assert [f.face for f in spec.features if f.face == face] == [face], notes
    planned = plan_program(spec, runtime_variables=False, part=part)
    touches = [n for n in ir.walk(planned.program.body)
               if isinstance(n, ir.Touch) and n.feature == f"R{feature.id}"]  # type: ignore[attr-defined]
    assert all(part.exact.contains(face - 1, np.asarray(t.contact)) for t in touches)
    program = tmp_path / "program.dmi"
    program.write_text(get_dialect("dmis").generate(planned.program), encoding="ascii")
    assert main(["sim", str(program), "--part", str(model), "--machine", str(CMM),
                 "-o", str(tmp_path / "out.txt")]) == 0
    return touches


def test_the_wall_round_an_island_is_measured_on_the_virtual_cmm(
        deep: Path, tmp_path: Path) -> None:
    part = cad.load_part(deep)
    touches = _measured_on_the_cmm(deep, part, _wall(part), tmp_path)
    assert len(touches) >= 4  # of 8: a circle needs 3, spread over the arc
    spread = [math.atan2(t.contact[1], t.contact[0]) % (2 * math.pi) for t in touches]
    assert max(spread) - min(spread) > math.radians(90.0)
    for t in touches:  # the normal towards the axis: out of the material
        radial = np.asarray(t.contact[:2]) / np.linalg.norm(t.contact[:2])
        assert float(np.dot(t.normal[:2], radial)) == pytest.approx(-1.0, abs=1e-6)


def test_a_rounded_corner_of_a_profile_is_measured_with_the_margin_at_its_ends(
        tmp_path: Path) -> None:
    outline = fillet(Polygon((-15, -8), (15, -8), (15, 4), (0, 7), (-15, 4),
                             align=None).vertices(), radius=3.0)
    model = tmp_path / "corner.step"
    export_step(Box(50, 40, 10, align=(C, C, MIN)) - Pos(0, 0, 10) * extrude(
        outline, amount=-5), model)
    part = cad.load_part(model)
    corner = next(f for f in revolved_features(part) if f.sections[0].arcs
                  and f.sections[0].arcs[0][1] - f.sections[0].arcs[0][0] < math.radians(30))
    arc = corner.sections[0].arcs[0]
    assert 3.0 * (arc[1] - arc[0]) == pytest.approx(1.19, abs=0.01)  # under 1.6 mm
    touches = _measured_on_the_cmm(model, part, corner, tmp_path)
    assert len(touches) == 16  # two sections of 8, none dropped
    margin = load_profile(CMM).margin
    for t in touches:  # each at least the margin (arc length) inside the arc's ends
        phi = math.atan2(t.contact[1] - corner.origin[1], t.contact[0] - corner.origin[0])
        assert arc[0] + margin / 3.0 - 1e-9 <= phi % (2 * math.pi) <= arc[1] - margin / 3.0 + 1e-9


def test_a_shallow_engraving_is_the_parts_limit_said_plainly(shallow: Path) -> None:
    part, machine = cad.load_part(shallow), load_profile(CMM)
    spec, notes = all_revolved_spec(part, machine)
    assert spec.features == ()
    walls = [n for n in notes if n.startswith(("R", )) and "cylinder" in n]
    assert len(walls) == 2  # the groove's wall (a bore) and its island (a boss)
    for note in walls:
        assert ": blind, depth 0.600 mm: the ball reaches no section (it needs 0.800 mm " \
               "below one: radius 0.500 + margin 0.300): a smaller stylus [" in note, note


def test_a_short_inner_arc_is_judged_on_the_ball_centres_the_cmm_fits() -> None:
    """8 touches over 6 deg of a D6 bore with a D3 ball (what the margin alone at the
    ends of a short arc can give: MetalBoop's front plate, R100): the contacts are off one
    line, the ball centres (radius 1.5) are not, and the virtual CMM refuses the circle on
    them; the planner refuses it first."""
    from types import SimpleNamespace

    from probegen.geometry.determined import undetermined
    from probegen.planning.revolved import PathKind, PathPoint
    from probegen.planning.well_posed import ill_posed

    phi = np.radians(np.linspace(15.0, 21.0, 8))
    ring = np.column_stack([np.cos(phi), np.sin(phi), np.zeros(8)])
    contacts, normals, ball = 3.0 * ring, -ring, 1.5
    z = (0.0, 0.0, 1.0)
    assert undetermined("circle", contacts, z) == ""
    assert "on one line" in undetermined("circle", contacts + ball * normals, z)
    path = tuple(PathPoint(PathKind.TARGET, tuple(c + ball * n), 0, 0.0, k + 1, tuple(c),
                           tuple(n)) for k, (c, n) in enumerate(zip(contacts, normals,
                                                                    strict=True)))
    plan = SimpleNamespace(path=path, sections=(SimpleNamespace(ball=ball),))
    assert "on one line" in ill_posed("circle", SimpleNamespace(axis=z), plan)  # type: ignore[arg-type]
