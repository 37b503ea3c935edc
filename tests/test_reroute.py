"""The reroute (planning/reroute.py): a revolved feature's path made safe against the
whole part by dropping only the touches that cannot be reached, lifting over what a
move along the safe circle would hit, and entering where the way down is clear.

Each model is a 20 mm boss (z 0..10) on a plate with one obstacle beside it, measured
in one section at z = 5 with 8 points (ball r = 3, retract d = 2: the safe circle has
radius 15 and the touches start at 0°, 45°, ...).
"""

from __future__ import annotations

from pathlib import Path

import pytest
from conftest import REPO

from probegen.errors import CollisionError
from probegen.planning import plan_program
from probegen.planning.revolved import PathKind
from probegen.spec.model import load_spec

PROFILE = REPO / "samples/machines/vmc-fanuc.toml"


def _plan(tmp_path: Path, obstacle: object,  # type: ignore[no-untyped-def]
          profile: Path = PROFILE):
    from build123d import Align, Box, Cylinder, Pos, export_step

    base = Pos(0, 0, -5) * Box(80, 80, 5, align=(Align.CENTER, Align.CENTER, Align.MIN))
    boss = Cylinder(10, 10, align=(Align.CENTER, Align.CENTER, Align.MIN))
    model = tmp_path / "boss.step"
    export_step(base + boss + obstacle, model)
    spec = tmp_path / "boss.toml"
    spec.write_text(f'[part]\nmodel = "{model.as_posix()}"\n\n[machine]\nprofile = '
                    f'"{profile.as_posix()}"\nclearance_z = 100.0\n\n[[feature]]\nid = "B"\n'
                    f'kind = "circle"\nat = [10.0, 0.0, 5.0]\nsections = [5.0]\npoints = 8\n')
    return plan_program(load_spec(spec), runtime_variables=True)


def _box(x0: float, x1: float, y0: float, y1: float, z0: float, z1: float) -> object:
    from build123d import Align, Box, Pos

    return Pos(x0, y0, z0) * Box(x1 - x0, y1 - y0, z1 - z0, align=Align.MIN)


def test_a_touch_the_ball_cannot_reach_is_dropped_alone(tmp_path: Path) -> None:
    # a wall 4.6 mm from the boss at 0°: the 6 mm ball does not fit in between
    planned = _plan(tmp_path, _box(14.6, 30.0, -3.0, 3.0, 0.0, 30.0))
    (b,) = planned.revolved
    assert len(b.normals) == 7  # 8 planned, the one at 0° dropped
    assert any("touch 1 dropped" in n and "face" in n for n in b.notes)
    targets = [p for p in b.plan.path if p.kind is PathKind.TARGET]
    assert [p.index for p in targets] == list(range(1, 8))  # renumbered
    assert min(abs(p.azimuth or 0.0) for p in targets) > 0.5  # none at 0°
    assert planned.clearance.minimum >= 0.0  # the program check clears every move


def test_a_move_along_the_safe_circle_that_hits_a_pin_is_lifted(tmp_path: Path) -> None:
    from build123d import Align, Cylinder, Pos

    # a pin of radius 1 up to z = 6 on the safe circle between the touches at 0° and 45°
    pin = Pos(13.858, 5.740, 0) * Cylinder(1.0, 6.0, align=(Align.CENTER, Align.CENTER,
                                                              Align.MIN))
    planned = _plan(tmp_path, pin)
    (b,) = planned.revolved
    assert len(b.normals) == 8  # nothing dropped
    lifts = [p for p in b.plan.path if p.kind is PathKind.LIFT]
    assert lifts and all(p.position[2] == pytest.approx(10.0) for p in lifts)
    assert any("lifted to z = 10.000" in n for n in b.notes)
    assert planned.clearance.minimum >= 0.0


def test_no_way_down_above_the_first_touch_enters_elsewhere(tmp_path: Path) -> None:
    # a bridge over the first safe point, higher than the 50 mm shank reaches from the
    # section (z 60..63), carried by a column far away: no way down there, but the
    # station itself is clear
    # (a probe without a stated body: the OMP40's 40 mm body of vmc-fanuc.toml, right
    # above the shank, would meet the bridge from most of the stations)
    sample = PROFILE.read_text()
    assert sample.count("\nbody_diameter = 40.0\n") == 1
    bodiless = tmp_path / "vmc-fanuc-no-body.toml"
    bodiless.write_text(sample.replace("\nbody_diameter = 40.0\n", "\n")
                        .replace("\nbody_length = 50.0\n", "\n"))
    bridge = _box(12.0, 40.0, -2.0, 2.0, 60.0, 63.0) + _box(36.0, 40.0, -2.0, 2.0, 0.0, 60.0)
    planned = _plan(tmp_path, bridge, bodiless)
    (b,) = planned.revolved
    assert len(b.normals) == 8
    first_safe = b.plan.path[1]
    assert first_safe.kind is PathKind.SAFE
    assert abs(first_safe.azimuth or 0.0) > 0.5  # not the station under the bridge
    assert planned.clearance.minimum >= 0.0


def test_a_feature_with_no_safe_touch_names_the_move_and_the_face(tmp_path: Path) -> None:
    # a ring around the boss, 1 mm off it, higher than the boss: no touch fits
    from build123d import Align, Cylinder

    ring = (Cylinder(25, 20, align=(Align.CENTER, Align.CENTER, Align.MIN))
            - Cylinder(11, 20, align=(Align.CENTER, Align.CENTER, Align.MIN)))
    with pytest.raises(CollisionError, match=r"feature B: no touch can be reached safely: "
                       r"touch 1 dropped: its approach from \(.+\) to \(.+\): the stylus "
                       r"(ball|shank) .+ face \d+"):
        _plan(tmp_path, ring)


@pytest.mark.parametrize(("diameter", "retract"), [(9.0, 1.25), (8.4, 1.0)])
def test_a_bore_too_small_for_the_usual_retract_gets_a_shorter_one(
        tmp_path: Path, diameter: float, retract: float) -> None:
    """r + d = 5 mm does not fit a 9 mm or an 8.4 mm bore: the 9 mm bore takes the
    largest retract that leaves a safe circle of 0.25 mm (1.25 mm, more than the 1 mm
    fallback), the 8.4 mm bore the fallback (0.95 mm would be the smaller)."""
    from build123d import Align, Box, Cylinder, export_step

    block = (Box(40, 40, 20, align=(Align.CENTER, Align.CENTER, Align.MIN))
             - Cylinder(diameter / 2.0, 20, align=(Align.CENTER, Align.CENTER, Align.MIN)))
    model = tmp_path / "small_bore.step"
    export_step(block, model)
    spec = tmp_path / "small_bore.toml"
    spec.write_text(f'[part]\nmodel = "{model.as_posix()}"\n\n[machine]\nprofile = '
                    f'"{PROFILE.as_posix()}"\nclearance_z = 100.0\n\n[[feature]]\nid = "H"\n'
                    f'kind = "cylinder"\nat = [{diameter / 2.0}, 0.0, 10.0]\npoints = 6\n')
    planned = plan_program(load_spec(spec), runtime_variables=True)
    (h,) = planned.revolved
    assert [s.retract for s in h.plan.sections] == pytest.approx([retract, retract])
    assert len(h.normals) == 12
    assert planned.clearance.minimum >= 0.0


def test_what_a_refused_move_ran_into_is_measured_when_first_read(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """``Sweeper.move`` describes a refused move (``collision.describe``: how deep the
    stylus cuts into which face) only when its text is first read, once; the text is
    the one made at once before (the planner drops most such texts unread)."""
    from build123d import Align, Box, Cylinder, Pos, export_step

    from probegen import cad
    from probegen.machine.profile import load_profile
    from probegen.planning import reroute
    from probegen.planning.collision import obstacle_for

    model = tmp_path / "boss.step"
    export_step(Pos(0, 0, -5) * Box(80, 80, 5, align=(Align.CENTER, Align.CENTER, Align.MIN))
                + Cylinder(10, 10, align=(Align.CENTER, Align.CENTER, Align.MIN)), model)
    machine = load_profile(PROFILE)
    sweeper = reroute.Sweeper(obstacle_for(cad.load_part(model), []), machine,
                              machine.probe.ball_radius)
    calls: list[int] = []
    describe = reroute.describe

    def counted(*args: object, **kw: object) -> str:
        calls.append(1)
        return describe(*args, **kw)  # type: ignore[arg-type]

    monkeypatch.setattr(reroute, "describe", counted)
    assert sweeper.move((30.0, 0.0, 5.0), (30.0, 0.0, 20.0)) is None  # clear of the boss
    why = sweeper.move((30.0, 0.0, 5.0), (0.0, 0.0, 5.0))  # through the boss
    assert why is not None and calls == []  # refused, not yet described
    note = reroute.Text.format("touch {} dropped: its approach {}", 3, why)
    assert calls == []
    text = str(note)
    assert text.startswith("touch 3 dropped: its approach from (30.000, 0.000, 5.000) to "
                           "(0.000, 0.000, 5.000): the stylus ball comes within ")
    assert " mm of face " in text and calls == [1]
    assert f"{why}" == str(why) == text.split("its approach ", 1)[1] and calls == [1]
