"""Links over obstacles (issue 17 item 4, planning/travel.py and planning/reroute.py): a
move between two touches of a feature, or between two features, that would pass through
a boss or a wall goes over it at the lowest local height the collision check clears,
below the clearance plane, instead of failing or climbing to the clearance plane.

Parts are built here with build123d; the profile is the sample VMC (ball r = 3, shank
4.5 x 50, margin 0.5: the ball's centre must pass at least r + margin/2 = 3.25 above
whatever lies under the way).
"""

from __future__ import annotations

from pathlib import Path

import pytest
from conftest import REPO

from probegen import ir
from probegen.planning import plan_program
from probegen.spec.model import load_spec

PROFILE = REPO / "samples/machines/vmc-fanuc.toml"
CLEARANCE_Z = 100.0
ABOVE = 3.0 + 0.25
"""The least height of the ball centre above an obstacle under the way, mm."""


def _spec(tmp_path: Path, shape: object, features: str) -> Path:
    from build123d import export_step

    model = tmp_path / "part.step"
    export_step(shape, model)
    spec = tmp_path / "part.toml"
    spec.write_text(f'[part]\nmodel = "{model.as_posix()}"\n\n[machine]\nprofile = '
                    f'"{PROFILE.as_posix()}"\nclearance_z = {CLEARANCE_Z}\n\n{features}')
    return spec


def _moves(block: ir.Node) -> list[ir.Move]:
    assert isinstance(block, ir.FeatureBlock)
    return [n for n in block.body if isinstance(n, ir.Move)]


def _run_on_vm(planned: object, model: Path) -> None:
    """The Fanuc program runs on the virtual machine without an alarm, every touch made."""
    from probegen import cad
    from probegen.dialects import get_dialect
    from probegen.machine.probe_model import ProbeModel
    from probegen.sim.contact import PlacedPart
    from probegen.sim.vm import VirtualMachine, run_text

    program = planned.program  # type: ignore[attr-defined]
    text = get_dialect("fanuc").generate(program)
    vm = VirtualMachine(PlacedPart.from_model(cad.load_step(model)), ProbeModel(3.0))
    result = run_text(text, vm, kind="macrob", source=model.name)
    assert result.alarm is None
    touches = sum(isinstance(n, ir.Touch) for n in ir.walk(program.body))
    assert result.touches == touches


def test_plane_contacts_on_both_sides_of_a_boss_are_linked_over_it(tmp_path: Path) -> None:
    from build123d import Align, Box, Cylinder, Pos

    # a plate (top z = 10) with a boss of diameter 20 up to z = 30 in the middle
    plate = Box(100, 40, 10, align=(Align.CENTER, Align.CENTER, Align.MIN))
    boss = Pos(0, 0, 10) * Cylinder(10, 20, align=(Align.CENTER, Align.CENTER, Align.MIN))
    spec = _spec(tmp_path, plate + boss,
                 '[[feature]]\nid = "TOP"\nkind = "plane"\nat = [-40.0, 0.0, 10.0]\n'
                 'contacts = [[-40.0, 0.0, 10.0], [40.0, 5.0, 10.0], [40.0, -10.0, 10.0]]\n'
                 'retract = 4.0\n')
    planned = plan_program(load_spec(spec), runtime_variables=True)
    (block,) = [n for n in planned.program.body if isinstance(n, ir.FeatureBlock)]
    moves = _moves(block)
    # touch 1 at x = -40, then over the boss: up, across at a local height, down
    start1, start2 = (-40.0, 0.0, 17.0), (40.0, 5.0, 17.0)
    k = [m.target for m in moves].index(start2)
    up, across = moves[k - 2].target, moves[k - 1].target
    height = up[2]
    assert up[:2] == start1[:2] and across[:2] == start2[:2] and across[2] == height
    assert 30.0 + ABOVE <= height <= 30.0 + ABOVE + 0.5 < CLEARANCE_Z
    # the contacts beside each other on one side keep their straight move
    assert moves[-3].target == (40.0, -10.0, 17.0)
    assert moves[-4].mode is ir.MoveMode.RETRACT and moves[-4].target == start2
    assert planned.clearance.minimum >= 0.0
    _run_on_vm(planned, tmp_path / "part.step")


def test_two_bores_separated_by_a_wall_are_linked_over_the_wall(tmp_path: Path) -> None:
    from build123d import Align, Box, Cylinder, Pos

    # a block (top z = 30) with two through bores of diameter 16, 40 mm apart: the wall
    # between them is the block's top
    block = Box(80, 40, 30, align=(Align.CENTER, Align.CENTER, Align.MIN))
    bores = [Pos(x, 0, 0) * Cylinder(8, 30, align=(Align.CENTER, Align.CENTER, Align.MIN))
             for x in (-20.0, 20.0)]
    features = "".join(
        f'[[feature]]\nid = "{name}"\nkind = "cylinder"\nat = [{x + 8.0}, 0.0, 15.0]\n'
        f'sections = [5.0, 20.0]\npoints = 4\n\n' for name, x in (("A", -20.0), ("B", 20.0)))
    spec = _spec(tmp_path, block - bores[0] - bores[1], features)
    planned = plan_program(load_spec(spec), runtime_variables=True)
    blocks = [n for n in planned.program.body if isinstance(n, ir.FeatureBlock)]
    assert len(blocks) == 2
    # no rapid at the clearance plane between the features: the second block opens with
    # the link from the first one's last safe point, over the wall
    rapids = [n for n in planned.program.body if isinstance(n, ir.Move)]
    assert len(rapids) == 1  # above the first feature only
    first, second = _moves(blocks[0]), _moves(blocks[1])
    assert first[-1].target[2] < 30.0  # left inside the first bore
    link = second[:3]
    height = max(m.target[2] for m in link)
    assert 30.0 + ABOVE <= height <= 30.0 + ABOVE + 0.5 < CLEARANCE_Z
    assert link[0].target[:2] == first[-1].target[:2]  # straight up out of the first bore
    assert planned.clearance.minimum >= 0.0
    _run_on_vm(planned, tmp_path / "part.step")


def test_the_lift_is_the_lowest_local_height_the_check_clears(tmp_path: Path) -> None:
    from build123d import Align, Box, Cylinder, Pos

    from probegen import cad
    from probegen.machine.profile import load_profile
    from probegen.planning.collision import obstacle_for
    from probegen.planning.reroute import Sweeper

    plate = Box(100, 40, 10, align=(Align.CENTER, Align.CENTER, Align.MIN))
    boss = Pos(0, 0, 10) * Cylinder(10, 20, align=(Align.CENTER, Align.CENTER, Align.MIN))
    model = tmp_path / "part.step"
    from build123d import export_step

    export_step(plate + boss, model)
    machine = load_profile(PROFILE)
    sweeper = Sweeper(obstacle_for(cad.load_part(model), []), machine, 3.0)
    a, b = (-40.0, 0.0, 17.0), (40.0, 0.0, 17.0)
    assert sweeper.move(a, b) is not None  # straight through the boss
    local = sweeper.local_height(a, b)
    assert local is not None and 30.0 + ABOVE <= local <= 30.0 + ABOVE + 0.5
    assert sweeper.lift(a, b, CLEARANCE_Z) == (a, (a[0], a[1], local), (b[0], b[1], local), b)
    # beside the boss nothing is higher than the plate: the move across is level
    c = (40.0, 30.0, 17.0)
    assert sweeper.local_height(b, c) == pytest.approx(10.0 + ABOVE, abs=0.5)
    # a ceiling at or below the local height: no lift (the caller takes the clearance plane)
    assert sweeper.lift(a, b, local) is None


class _Walls:
    """A stand-in sweeper: every straight move is refused, every lift at z = 5 clears."""

    def __init__(self) -> None:
        from probegen.machine.profile import Feeds

        self.feeds = Feeds(rapid=24000.0, position=2000.0, probe=300.0)
        self.ceilings: list[float] = []

    def refused(self, a: object, b: object) -> bool:
        return True

    def lift(self, a: tuple[float, float, float], b: tuple[float, float, float],
             ceiling: float) -> tuple[tuple[float, float, float], ...] | None:
        from probegen.planning.reroute import lift_points

        self.ceilings.append(ceiling)
        return lift_points(a, b, 5.0) if 5.0 < ceiling else None


def test_a_feature_link_is_taken_only_when_quicker_than_the_clearance_plane() -> None:
    from probegen.planning.order import Stop
    from probegen.planning.travel import Linker, clearance_travel, travel_time

    walls = _Walls()
    near, far = (50.0, 0.0, 0.0), (1000.0, 0.0, 0.0)
    origin = (0.0, 0.0, 0.0)
    linker = Linker(walls, [Stop(origin, origin), Stop(near, near), Stop(far, far)],  # type: ignore[arg-type]
                    CLEARANCE_Z)
    # 50 mm: up 5, across, down 5 at 2000 mm/min (1.8 s) beats the clearance plane
    # (200 mm up and down at 2000 mm/min and 50 mm at the rapid rate: 6.125 s)
    assert linker.route(origin, near) == (origin, (0.0, 0.0, 5.0), (50.0, 0.0, 5.0), near)
    assert travel_time(linker.route(origin, near), CLEARANCE_Z, walls.feeds) == (  # type: ignore[arg-type]
        pytest.approx(1.8))
    assert travel_time(clearance_travel(origin, near, CLEARANCE_Z), CLEARANCE_Z,
                       walls.feeds) == pytest.approx(6.125)
    # the lift was looked for only below the height where it stops being quicker
    assert walls.ceilings == [pytest.approx(CLEARANCE_Z - 50.0 * (1.0 - 2000.0 / 24000.0) / 2)]
    # 1000 mm: the clearance plane (6 s + 2.5 s) beats even the straight move (30 s): no
    # link is looked for
    assert linker.route(origin, far) is None
    assert len(walls.ceilings) == 1
