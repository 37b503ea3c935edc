"""The machine table under the part in the collision check (planning/table.py).

The part stands on the table at its lowest point; below that plane is steel.  A disc of
our own making (D40 x 10 mm, standing on the table at z = 0) with the CMM sample profile
(margin 0.3 mm; the rack's smallest ball D1):

* the disc's outside measured 9.9 mm below its top (the ball's centre at z = 0.1: every
  ball of the rack reaches below the table) is refused, the message naming the table;
  with ``[part] raised = 2`` (parallels) it is planned; at 5 mm below its top it is
  planned on the table, no point of any stylus within the margin of it;
* a move that passes under the part's lowest point, which the part's mesh alone clears,
  is refused by the exact check and not cleared by the fast one (heightmap);
* the table's distance to a ball and to a cylinder along the frame's +Z, with the frame
  turned, against points sampled on their surfaces (hypothesis).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from conftest import REPO
from hypothesis import given
from hypothesis import strategies as st

from probegen import cad, ir
from probegen.errors import ProbegenError
from probegen.machine.profile import load_profile
from probegen.planning import part_of, plan_program
from probegen.planning.collision import check_program, obstacle_for, probe_stylus, swept
from probegen.planning.heightmap import clear_segments
from probegen.planning.table import NAME, Table
from probegen.spec.model import load_spec

CMM = REPO / "samples/machines/cmm.toml"
MARGIN = 0.3
"""The CMM sample's margin, mm."""

SPEC = '''[part]
model = "{model}"
raised = {raised}

[machine]
profile = "{profile}"

[program]
number = 7
name = "DISC"

[[feature]]
id = "OD"
kind = "circle"
at = [20.0, 0.0, 5.0]
sections = [{depth}]
points = 6
'''


@pytest.fixture(scope="module")
def disc(tmp_path_factory: pytest.TempPathFactory) -> Path:
    from build123d import Align, Cylinder, export_step

    path = tmp_path_factory.mktemp("table") / "disc.step"
    export_step(Cylinder(20.0, 10.0, align=(Align.CENTER, Align.CENTER, Align.MIN)),
                str(path))
    return path


def _plan(disc: Path, depth: float, raised: float = 0.0) -> ir.Program:
    spec_path = disc.parent / f"disc_{depth}_{raised}.toml"
    spec_path.write_text(SPEC.format(model=disc, profile=CMM, depth=depth, raised=raised))
    spec = load_spec(spec_path)
    return plan_program(spec, runtime_variables=False, part=part_of(spec)).program


def test_a_section_whose_ball_reaches_below_the_table_is_refused_naming_it(
        disc: Path) -> None:
    with pytest.raises(ProbegenError, match=NAME) as info:
        _plan(disc, 9.9)
    assert "cuts" in str(info.value) or "within" in str(info.value), info.value


def test_raised_on_parallels_the_same_section_is_planned(disc: Path) -> None:
    """``[part] raised = 2``: the table 2 mm below the disc, the D1 ball's (0.5 mm)
    lowest point 0.1 - 0.5 + 2 = 1.6 mm above it; the stylus taken is the one that
    fits the section with the margin (the section 0.1 mm above the disc's bottom)."""
    program = _plan(disc, 9.9, raised=2.0)
    assert sum(isinstance(n, ir.Touch) for n in ir.walk(program.body)) == 6


def test_a_part_loaded_at_another_height_than_the_spec_says_is_refused(disc: Path) -> None:
    """The spec says where the table is (``[part] raised``); a part handed to
    ``plan_program`` that stands elsewhere would put the table of the collision check
    elsewhere: refused, naming both heights."""
    spec_path = disc.parent / "disc_mismatch.toml"
    spec_path.write_text(SPEC.format(model=disc, profile=CMM, depth=9.9, raised=2.0))
    spec = load_spec(spec_path)
    with pytest.raises(ProbegenError, match=r"raised = 2 mm.* stands 0 mm above the table"):
        plan_program(spec, runtime_variables=False, part=cad.load_part(disc))


def test_raised_must_not_be_negative(disc: Path) -> None:
    with pytest.raises(ProbegenError, match=r"raised.*(at least|>=|minimum)"):
        _plan(disc, 5.0, raised=-1.0)


def test_a_section_above_the_table_keeps_every_stylus_clear_of_it(disc: Path) -> None:
    """Every segment of the program (no orientation: work coordinates) keeps the ball
    of the stylus it takes the margin above the table: its centre ``ball + margin``
    above z = 0 (the shank and body stand above the ball)."""
    program = _plan(disc, 5.0)
    taken = [n for n in program.body if isinstance(n, ir.SelectStylus)]
    ball = (taken[-1].ball_diameter if taken else load_profile(CMM).probe.ball_diameter) / 2.0
    part = cad.load_part(disc)  # on the table (raised 0)
    report = check_program(program, obstacle_for(part, []), [], load_profile(CMM), part=part)
    assert len(report.segments) > 12
    lowest = min(min(s.start[2], s.end[2]) for s in report.segments)
    assert lowest - ball >= MARGIN - 1e-9
    assert lowest == pytest.approx(5.0, abs=1e-6)  # the section's touches


def test_a_move_under_the_part_is_refused_by_both_checks(disc: Path) -> None:
    part = cad.load_part(disc)
    obstacle = obstacle_for(part, [])
    stylus = probe_stylus(load_profile(CMM), 1.5)
    # beside the disc (5 mm off its side), from above the table to 1 mm under it
    a, b = np.array([26.5, -30.0, 3.0]), np.array([26.5, 30.0, 0.5])
    ball, shank, worst = swept(obstacle, a, b, 0.0, 0.0, stylus, MARGIN, bound=True)
    assert ball - MARGIN == pytest.approx(0.5 - 1.5 - MARGIN, abs=0.01)
    assert shank > ball
    assert obstacle.name_at(worst - np.array([0.0, 0.0, 2.0])) == NAME
    assert not clear_segments([[(a, b)]], obstacle, stylus, MARGIN)[0]
    # the same move 10 mm higher is cleared by both
    up = np.array([0.0, 0.0, 10.0])
    ball, shank, _ = swept(obstacle, a + up, b + up, 0.0, 0.0, stylus, MARGIN)
    assert min(ball, shank) >= MARGIN
    assert clear_segments([[(a + up, b + up)]], obstacle, stylus, MARGIN)[0]


def test_clearance_asks_the_table_first_and_agrees_with_each_element(disc: Path) -> None:
    """``MeshObstacle.clearance`` skips the part's query of an element the table puts at
    least as deep as that query can report: its figures are those of each element's own
    distance (the part's or the table's, the lesser: ``clearance_of``), on a grid of
    centres beside, over and under the disc's foot; and ``face_of`` names the table for
    an element in it and clear of the part (no distance query)."""
    from probegen.planning.intrusion import elements

    part = cad.load_part(disc)
    obstacle = obstacle_for(part, [])
    stylus = probe_stylus(load_profile(CMM), 0.5, 0.35, 20.0)  # D1, with the body
    ball, shank, body = elements(stylus.ball, stylus.cylinders())
    in_table = 0
    for x in (21.0, 24.0, 30.0):
        for z in (-30.0, -20.5, -3.0, -0.2, 0.4, 2.0, 12.0):
            c = np.array([x, 0.0, z])
            got = obstacle.clearance(c, stylus)
            want = (obstacle.clearance_of(c, ball),
                    min(obstacle.clearance_of(c, shank), obstacle.clearance_of(c, body)))
            assert got == pytest.approx(want, abs=1e-9), (c, got, want)
            in_table += got[0] < -1.0
    assert in_table >= 4  # the shortcut was taken
    c = np.array([40.0, 0.0, -25.0])  # the body's lower end 5 mm into the table, 13 mm off
    assert obstacle.face_of(c, body) == NAME
    assert obstacle.face_of(np.array([20.3, 0.0, 5.0]), ball).startswith("face ")


def test_the_grown_body_test_keeps_the_table_figure(disc: Path) -> None:
    """The disc turned a quarter about X (the table a wall beside the probe): the body,
    far from the part, is settled by its grown collision test (``collision.GROWN_FIRST``)
    and its clearance is then the table's, nearer than the shank's: the figures are each
    element's own (``clearance_of``)."""
    from probegen.planning.intrusion import elements

    part = cad.load_part(disc).turned(((1.0, 0.0, 0.0), (0.0, 0.0, -1.0), (0.0, 1.0, 0.0)))
    obstacle = obstacle_for(part, [])
    stylus = probe_stylus(load_profile(CMM), 0.5, 0.35, 20.0)  # D1, with the body
    ball, shank, body = elements(stylus.ball, stylus.cylinders())
    for centre in ((60.0, 12.0, 0.0), (60.0, 8.0, -30.0), (25.0, 14.0, 5.0),
                   (45.0, 30.0, -10.0)):
        c = np.array(centre)
        got = obstacle.clearance(c, stylus)
        want = (obstacle.clearance_of(c, ball),
                min(obstacle.clearance_of(c, shank), obstacle.clearance_of(c, body)))
        assert got == pytest.approx(want, abs=1e-9), (c, got, want)
    # the table (frame y = 0) is the body's nearest: 12 - 6.6 mm
    assert obstacle.clearance(np.array([60.0, 12.0, 0.0]), stylus)[1] == pytest.approx(5.4)


_unit = st.tuples(*[st.floats(-1.0, 1.0)] * 3).filter(
    lambda v: 0.1 < math.hypot(*v) <= 1.0)


@given(n=_unit, centre=st.tuples(*[st.floats(-50.0, 50.0)] * 3),
       radius=st.floats(0.1, 10.0), low=st.floats(0.0, 40.0), length=st.floats(0.5, 60.0))
def test_table_distance_is_the_least_over_the_surface(
        n: tuple[float, float, float], centre: tuple[float, float, float], radius: float,
        low: float, length: float) -> None:
    unit = np.asarray(n) / math.hypot(*n)
    table = Table((float(unit[0]), float(unit[1]), float(unit[2])), 2.0)
    c = np.asarray(centre)
    # the ball: its lowest point along the normal
    assert table.clearance(c, radius) == pytest.approx(float(c @ unit) - radius - 2.0,
                                                       abs=1e-9)
    # the cylinder along +Z from low to low + length: its two rims, sampled
    angles = np.linspace(0.0, 2.0 * math.pi, 3601)
    rim = np.stack([radius * np.cos(angles), radius * np.sin(angles),
                    np.zeros_like(angles)], axis=1)
    points = np.concatenate([c + rim + [0.0, 0.0, z] for z in (low, low + length)])
    sampled = float(np.min(points @ unit)) - 2.0
    found = table.clearance(c, radius, low, low + length)
    assert found <= sampled + 1e-9
    assert found >= sampled - radius * (1.0 - math.cos(math.pi / 3600)) - 1e-9
