"""Orientations and styli (issue 17, item 2): revolved features whose axis is not along +Z
planned in their own frame on the turned part, with the stylus of the rack that fits, on a
block built here with build123d (bores on +X, -Y, +Z and -Z faces, a 3 mm bore, an
inclined hole at 45 deg)."""

from __future__ import annotations

import math
from collections import Counter
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from conftest import REPO
from fuzzing import examples
from hypothesis import given, settings
from hypothesis import strategies as st

from probegen import cad, ir
from probegen.cad import part as part_module
from probegen.errors import CollisionError, PlanningError, SpecError
from probegen.ir import frames
from probegen.machine.profile import Head, MachineProfile, Stylus, Tilt, load_profile
from probegen.planning import PlannedProgram, plan_program
from probegen.planning.collision import check_program, obstacle_for
from probegen.planning.orient import (
    changes,
    head_angles,
    head_direction,
    needs_index,
    order_groups,
    orient_name,
    orientation_for,
)
from probegen.spec.model import RevolvedSpec, Spec

RACK = (Stylus("D1", 1.0, 0.7, 20.0, 21), Stylus("D2", 2.0, 1.4, 30.0, 22),
        Stylus("D3", 3.0, 2.0, 40.0, 23), Stylus("D6", 6.0, 4.5, 50.0, 20))
"""A rack of 1, 2, 3 and 6 mm styli; the 6 mm one is the [probe] stylus (tool 20)."""
FACES = {"-Y": 7, "+Z": 8, "small": 9, "45": 10, "-Z": 11, "+X": 12}
"""The bore face of each direction on :func:`block`'s model."""


def block(path: Path) -> Path:
    """A 60 x 60 x 40 block (bottom at z = 0) with D8 bores 10 deep on +Z, +X and -Z, a D6
    on -Y, a D3 6 deep on +Z and a D6 hole at 45 deg from the top towards -X."""
    from build123d import Align, Box, Cylinder, Pos, Rot, export_step

    shape = Box(60, 60, 40, align=(Align.CENTER, Align.CENTER, Align.MIN))
    for cut in (Pos(-15, -15, 40) * Cylinder(4, 20), Pos(30, 10, 20) * Rot(0, 90, 0) *
                Cylinder(4, 20), Pos(10, -30, 20) * Rot(90, 0, 0) * Cylinder(3, 20),
                Pos(15, -15, 0) * Cylinder(4, 20), Pos(0, 20, 40) * Cylinder(1.5, 12),
                Pos(15, 5, 40) * Rot(0, 45, 0) * Cylinder(3, 24)):
        shape = shape - cut
    export_step(shape, str(path))
    return path


@pytest.fixture(scope="module")
def model(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return block(tmp_path_factory.mktemp("orient") / "block.step")


def profile(kind: str) -> MachineProfile:
    """The VMC sample with a CMM head (DMIS) or a five-axis tilt (Fanuc), the rack, a
    CMM-like margin of 0.1 mm and a TP20-like probe body (13.2 x 65 mm): the sample's
    OMP40 (40 mm across) standing along a side bore's axis would reach 20 mm below it,
    into the table the block stands on (the side bores are 20 mm above it)."""
    base = load_profile(REPO / "samples/machines/vmc-fanuc.toml")
    base = replace(base, probe=replace(base.probe, body_diameter=13.2, body_length=65.0))
    if kind == "head":
        return replace(base, dialect="dmis", head=Head(), rack=RACK, margin=0.1)
    return replace(base, tilt=Tilt(), rack=RACK, margin=0.1)


def spec_of(model: Path, machine: MachineProfile, faces: list[int]) -> Spec:
    features = tuple(RevolvedSpec(f"R{f}", f"block: face {f}", "cylinder", f, None, None, 8,
                                  None) for f in faces)
    return Spec(source="block", model=model, machine=machine, dialect=machine.dialect,
                clearance_z=60.0, program_number=1001, program_name="BLOCK", features=features)


ALL = [FACES[k] for k in ("-Y", "+Z", "small", "45", "+X")]


@pytest.fixture(scope="module")
def loaded(model: Path) -> cad.Part:
    return cad.load_part(model)


@pytest.fixture(scope="module", params=["head", "tilt"])
def planned(request: pytest.FixtureRequest, model: Path, loaded: cad.Part
            ) -> tuple[str, PlannedProgram]:
    machine = profile(request.param)
    spec = spec_of(model, machine, ALL)
    return request.param, plan_program(spec, runtime_variables=False, part=loaded)


# ------------------------------------------------------------------ the turned part


def test_turned_part_is_the_model_in_the_frame(loaded: cad.Part,
                                               monkeypatch: pytest.MonkeyPatch) -> None:
    meshes = 0
    tessellate = part_module.tessellate

    def counted(*args: object, **kwargs: object) -> object:
        nonlocal meshes
        meshes += 1
        return tessellate(*args, **kwargs)  # type: ignore[arg-type]

    part = cad.Part(loaded.model)
    monkeypatch.setattr(part_module, "tessellate", counted)
    rotation = frames.frame_for((1.0, 0.0, 0.0))
    turned = part.turned(rotation)
    assert turned is part.turned(rotation) and turned.rotation == rotation
    assert turned.original is part and turned.turned(rotation) is turned
    # frame X = work Y, frame Y = work Z, frame Z = work X
    assert np.allclose(turned.bbox_min, (-30.0, 0.0, -30.0), atol=1e-6)
    assert np.allclose(turned.bbox_max, (30.0, 40.0, 30.0), atol=1e-6)
    assert [f.id for f in turned.faces] == [f.id for f in part.faces]
    bore = turned.faces[FACES["+X"] - 1]
    assert np.allclose(np.abs(bore.axis), (0.0, 0.0, 1.0), atol=1e-12)
    mesh, original = turned.mesh(), part.mesh()
    assert meshes == 1 and turned.mesh() is mesh
    assert np.allclose(mesh.vertices, original.vertices @ np.asarray(rotation))
    assert (mesh.metadata["face_ids"] == original.metadata["face_ids"]).all()
    point = np.array([25.0, 10.0 + 4.0, 20.0])  # on the +X bore's wall, work
    d_work, _ = part.exact.distance(FACES["+X"] - 1, point)
    d_frame, foot = turned.exact.distance(FACES["+X"] - 1, point @ np.asarray(rotation))
    assert d_work < 1e-9 and d_frame < 1e-9
    assert turned.exact.inside(np.array([0.0, 20.0, 0.0])) is True  # work (0, 0, 20)
    assert turned.exact.inside(np.array([0.0, 20.0, 40.0])) is False  # work (40, 0, 20)


def test_a_turned_part_finds_its_vertical_features(loaded: cad.Part) -> None:
    from probegen.cad.revolved import revolved_features

    turned = loaded.turned(frames.frame_for((1.0, 0.0, 0.0)))
    found = {f.faces: f for f in revolved_features(turned)}
    assert found[(FACES["+X"],)].accessible
    assert not found[(FACES["+Z"],)].accessible  # horizontal in this frame


# ---------------------------------------------------------------- the orientations


@pytest.mark.parametrize(("a", "b", "direction"), [
    (0.0, 0.0, (0.0, 0.0, 1.0)), (90.0, 0.0, (0.0, 1.0, 0.0)), (90.0, -90.0, (1.0, 0.0, 0.0)),
    (90.0, 90.0, (-1.0, 0.0, 0.0)), (90.0, 180.0, (0.0, -1.0, 0.0)),
    (45.0, -90.0, (math.sqrt(0.5), 0.0, math.sqrt(0.5)))])
def test_head_angles_convention(a: float, b: float, direction: ir.Vec3) -> None:
    """A from straight down, B counter-clockwise from above, B = 0 stylus towards -Y."""
    assert np.allclose(head_direction(a, b), direction, atol=1e-12)
    assert np.allclose(head_angles(direction), (a, b), atol=1e-9)


def test_head_orientation_names_grid_and_range() -> None:
    machine = profile("head")
    o = orientation_for(machine, (1.0, 0.0, 0.0))
    assert not isinstance(o, str) and o.head == (90.0, -90.0)
    assert orient_name(o, 3) == "A90BM90"
    assert o.rotation == frames.frame_for((1.0, 0.0, 0.0))
    near = orientation_for(machine, head_direction(37.3, 12.1))  # 1.8 deg off A37.5B15
    assert not isinstance(near, str) and near.head == (37.5, 15.0)
    assert near.exact == frames.frame_for(head_direction(37.3, 12.1))
    off = orientation_for(machine, head_direction(86.25, 3.75))
    assert off == ("axis at A 86.2 B 3.7: not on the head's 7.5 deg grid: the nearest index "
                   "A82.5 B0 stands 5.3 deg off the axis, more than 3.75 deg: needs a setup")
    down = orientation_for(machine, (0.0, 0.0, -1.0))
    assert isinstance(down, str) and "beyond the head's A range 0..105" in down
    narrow = replace(machine, head=Head(b=(-90.0, 90.0)))
    assert "add the B range or a setup" in str(orientation_for(narrow, (0.0, -1.0, 0.0)))
    identity = orientation_for(machine, (0.0, 0.0, 1.0))
    assert not isinstance(identity, str) and orient_name(identity, 0) == "A0B0"
    half = orientation_for(machine, head_direction(37.5, 7.5 + 1e-7))
    assert not isinstance(half, str) and orient_name(half, 1) == "A37_5B7_5"


def test_tilt_orientation() -> None:
    machine = profile("tilt")
    o = orientation_for(machine, head_direction(45.0, 30.0))
    assert not isinstance(o, str)
    assert dict(o.rotary)["A"] == pytest.approx(45.0)
    assert np.allclose(frames.from_euler_zxz(dict(o.rotary)["C"], 45.0, 0.0), o.rotation)
    assert orient_name(o, 2) == "TILT2"
    down = orientation_for(machine, (0.0, 0.0, -1.0))
    assert down == "tilt 180.0 deg: beyond the A axis's range -110..110: needs a setup"
    plain = load_profile(REPO / "samples/machines/vmc-fanuc.toml")
    assert "add a [head] or [tilt]" in str(orientation_for(plain, (1.0, 0.0, 0.0)))


# ------------------------------------------------------------------- the programs


def _touches_in_work(program: ir.Program) -> list[tuple[ir.Touch, ir.Orient | None]]:
    out = []
    for node, orient in frames.in_work(program.body):
        if isinstance(node, ir.FeatureBlock):
            out += [(t, orient) for t in node.body if isinstance(t, ir.Touch)]
    return out


def test_every_bore_planned_in_its_frame(planned: tuple[str, PlannedProgram],
                                         loaded: cad.Part) -> None:
    kind, p = planned
    ids = {o.plan.spec.id for o in p.oriented}
    assert ids == {f"R{f}" for f in ALL}
    heads = {o.plan.spec.id: o.orientation for o in p.oriented}
    assert heads[f"R{FACES['+Z']}"].identity
    expected = {"+X": (1.0, 0.0, 0.0), "-Y": (0.0, -1.0, 0.0),
                "45": (math.sqrt(0.5), 0.0, math.sqrt(0.5))}
    for key, a in expected.items():
        o = heads[f"R{FACES[key]}"]
        assert np.allclose(o.rotation, frames.frame_for(a), atol=1e-12)
    orients = [n for n in p.program.body if isinstance(n, ir.Orient)]
    names = [n.name for n in orients]
    if kind == "head":
        assert set(names) == {"A90BM90", "A90B180", "A45BM90", "A0B0"}
    else:
        assert set(names) == {"TILT1", "TILT2", "TILT3", "TILT0"}
    assert names[-1] in ("A0B0", "TILT0") and frames.is_identity(orients[-1].rotation)
    assert orients[-1].clearance_z == 60.0
    assert p.orientation_changes == len(orients) == 4
    assert p.stylus_changes == sum(isinstance(n, ir.SelectStylus) for n in p.program.body)
    # the +X bore's frame: its clearance is the turned top (30) plus the spec's gap (20)
    plus_x = next(n for n in orients if n.rotation == frames.frame_for((1.0, 0.0, 0.0)))
    assert plus_x.clearance_z == pytest.approx(50.0)


def test_touches_lie_on_the_model_with_the_outward_normal(
        planned: tuple[str, PlannedProgram], loaded: cad.Part) -> None:
    _, p = planned
    touches = _touches_in_work(p.program)
    assert len(touches) == 8 * 2 * len(ALL)
    tilted = 0
    for touch, orient in touches:
        tilted += orient is not None and not frames.is_identity(orient.rotation)
        face = int(touch.feature[1:])
        contact = np.array(touch.contact, dtype=np.float64)
        distance, _ = loaded.exact.distance(face - 1, contact)
        assert distance < 1e-6
        record = loaded.faces[face - 1]
        axis, origin = np.array(record.axis), np.array(record.origin)
        radial = contact - origin - np.dot(contact - origin, axis) * axis
        # a bore: the outward normal (out of material) points to the axis
        assert np.dot(touch.normal, -radial / np.linalg.norm(radial)) > 1.0 - 1e-9
    assert tilted == 8 * 2 * 3


def _work(node: ir.Node, frame: ir.Orient | None) -> np.ndarray:
    assert isinstance(node, ir.Move) and node.mode is ir.MoveMode.RAPID, node
    return np.array(frames.to_work(frame, node.target))  # type: ignore[arg-type]


def test_every_change_is_routed_at_the_index_height_in_the_program(
        planned: tuple[str, PlannedProgram], loaded: cad.Part) -> None:
    """Before each change taken at the index height (every Orient; a stylus change on the
    CMM) the program goes straight up in work Z to it; after it, level at that height
    over the next move's point, which then goes down: the moves are in the program (in
    the old frame's and the new frame's coordinates) and the check cleared them."""
    kind, p = planned
    machine = profile(kind)
    body = list(p.program.body)
    top = loaded.bbox_max[2]
    frame: ir.Orient | None = None
    seen: list[np.ndarray] = []
    routes = 0
    k = 0
    while k < len(body):
        node = body[k]
        if not needs_index(node, machine):
            for n in ir.walk((node,)):
                if isinstance(n, ir.Move) and n.mode is not ir.MoveMode.RETRACT:
                    seen.append(np.array(frames.to_work(frame, n.target)))  # type: ignore[arg-type]
            k += 1
            continue
        end = k
        while end < len(body) and isinstance(body[end], ir.Orient | ir.SelectStylus):
            end += 1
        up = _work(body[k - 1], frame)
        for n in body[k:end]:
            frame = n if isinstance(n, ir.Orient) else frame
        longest = max(s.length + s.ball_radius for s in RACK)
        assert np.allclose(seen[-1], up) and len(seen) >= 2  # the move up, then the one before
        assert up[:2] == pytest.approx(seen[-2][:2], abs=1e-9) and up[2] > seen[-2][2]
        assert top + 10.0 < up[2] <= top + longest + (60.0 if kind == "head" else 0.0) + 0.1 + 1e-6
        if end < len(body):
            over, down = _work(body[end], frame), _work(body[end + 1], frame)
            assert over[2] == pytest.approx(up[2], abs=1e-9)
            assert over[:2] == pytest.approx(down[:2], abs=1e-9) and down[2] < over[2]
        routes += 1
        k = end
    changes = sum(needs_index(n, machine) for n in body)
    assert routes == p.orientation_changes if kind == "tilt" else routes <= changes
    kinds = [s.kind for s in p.clearance.segments]
    assert "rapid" in kinds and any(k.startswith("stylus change to") for k in kinds)


def test_the_check_refuses_a_change_below_the_index_height_and_a_dive_after_it(
        planned: tuple[str, PlannedProgram], loaded: cad.Part) -> None:
    kind, p = planned
    machine = profile(kind)
    body = list(p.program.body)
    obstacle = obstacle_for(loaded, [])
    k = next(i for i, n in enumerate(body) if isinstance(n, ir.Orient))
    start = k - 1 if isinstance(body[k - 1], ir.SelectStylus) else k
    up = body[start - 1]
    assert isinstance(up, ir.Move)
    # the probe left at the old clearance level (60: above the part, below the index height)
    low = ir.Move((*up.target[:2], 60.0), ir.MoveMode.RAPID)
    name = body[start].name if isinstance(body[start], ir.Orient) else body[start].label
    with pytest.raises(CollisionError, match=rf"change to {name}: the probe stands at work "
                                             rf"z = 60\.000, expected the index height "):
        check_program(ir.Program(p.program.setup, (*body[:start - 1], low, *body[start:])),
                      obstacle, [], machine, part=loaded)
    # the Orient itself at 60 (the CMM's stylus change before it left out)
    orient = body[k]
    assert isinstance(orient, ir.Orient)
    with pytest.raises(CollisionError, match=rf"orientation change to {orient.name}: the "
                                             r"probe stands at work z = 60\.000"):
        check_program(ir.Program(p.program.setup, (*body[:start - 1], low, *body[k:])),
                      obstacle, [], machine, part=loaded)
    # down to 60 after a CMM's stylus change, before the Orient: the move leaves the height
    if kind == "head":
        with pytest.raises(PlanningError, match=rf"stylus change to {name}: the first move "
                                                r"after it goes to work z = 60\.000"):
            check_program(ir.Program(p.program.setup, (*body[:k], low, *body[k:])), obstacle,
                          [], machine, part=loaded)
    # no move before the change: the probe's position is unknown
    with pytest.raises(CollisionError, match="stands at an unknown position"):
        check_program(ir.Program(p.program.setup, tuple(body[start:])), obstacle, [],
                      machine, part=loaded)
    # the over point left out: the first move after the Orient dives from the index height
    with pytest.raises(PlanningError, match=rf"change to {body[k].name}: the first move "  # type: ignore[union-attr]
                                            r"after it goes to work z = .*expected the "
                                            r"index height .*\(the over point\)"):
        check_program(ir.Program(p.program.setup, (*body[:k + 1], *body[k + 2:])),
                      obstacle, [], machine, part=loaded)


def test_a_face_down_bore_is_left_out_for_a_reason(model: Path, loaded: cad.Part) -> None:
    for kind, reason in (("head", "beyond the head's A range 0..105: no orientation reaches "
                                  "this face: needs a setup"),
                         ("tilt", "tilt 180.0 deg: beyond the A axis's range -110..110")):
        spec = spec_of(model, profile(kind), [FACES["-Z"]])
        with pytest.raises(PlanningError, match=reason.replace(".", r"\.")):
            plan_program(spec, runtime_variables=False, part=loaded)


def test_the_stylus_that_fits(planned: tuple[str, PlannedProgram]) -> None:
    """A 3 mm bore takes the 2 mm ball; the 6 mm bores the 3 mm; the 8 mm ones the 6 mm."""
    _, p = planned
    styli = {o.plan.spec.id: o.stylus.label for o in p.oriented}
    assert styli == {f"R{FACES['small']}": "D2", f"R{FACES['-Y']}": "D3",
                     f"R{FACES['45']}": "D3", f"R{FACES['+X']}": "D6", f"R{FACES['+Z']}": "D6"}
    # the ball each feature's touches start from is the ball of its stylus
    ball = p.program.setup.ball_diameter / 2.0
    for node in p.program.body:
        if isinstance(node, ir.SelectStylus):
            ball = node.ball_diameter / 2.0
        if isinstance(node, ir.FeatureBlock):
            plan = next(o for o in p.oriented if o.plan.spec.id == node.feature.id)
            assert ball == plan.stylus.ball_radius


def test_a_forced_stylus(model: Path, loaded: cad.Part) -> None:
    from probegen.planning import orient, styli

    assert orient.pick_stylus is styli.pick_stylus  # one choice serves the planner
    machine = profile("head")
    chosen, value = orient.pick_stylus(machine, lambda m: m.probe.ball_diameter, "D3")
    assert (chosen.label, value) == ("D3", 3.0)
    with pytest.raises(SpecError, match=r"expected a stylus of the machine's rack "
                                        r"\(D6, D3, D2, D1; .*found 'D9'"):
        orient.pick_stylus(machine, lambda m: 0, "D9")


def test_group_order_has_the_fewest_changes() -> None:
    start, identity = ("D6", "V"), "V"
    groups = [("D3", "X"), ("D6", "X"), ("D3", "V"), ("D6", "Y"), ("D2", "V")]
    order = order_groups(groups, start, identity)
    import itertools

    best = min(sum(changes(o, start, identity)) for o in itertools.permutations(groups))
    assert sum(changes(order, start, identity)) == best == 6
    assert sum(changes(groups, start, identity)) > best
    assert sorted(order) == sorted(groups)


def test_a_vertical_program_has_no_orient(model: Path, loaded: cad.Part) -> None:
    """Vertical features with the [probe] stylus alone: no Orient, no SelectStylus."""
    machine = load_profile(REPO / "samples/machines/vmc-fanuc.toml")
    p = plan_program(spec_of(model, machine, [FACES["+Z"]]), runtime_variables=True,
                     part=loaded)
    assert not any(isinstance(n, (ir.Orient, ir.SelectStylus)) for n in p.program.body)
    assert (p.stylus_changes, p.orientation_changes) == (0, 0)
    with pytest.raises(PlanningError, match="not accessible"):
        plan_program(spec_of(model, machine, [FACES["+X"]]), runtime_variables=True,
                     part=loaded)


def test_ingest_turns_frame_touches_back_to_work(planned: tuple[str, PlannedProgram],
                                                 model: Path) -> None:
    """Ball centres printed in the frame (as #5061-#5063 under G68.2) of a bore 0.01 mm
    larger than nominal: evaluated in work coordinates with the ball of the feature's
    stylus, the centre and axis where the model has them."""
    from probegen.evaluate import ingest as ingest_module
    from probegen.evaluate.revolved import RevolvedResult
    from probegen.geometry.uncertainty import Budget

    kind, p = planned
    grow = 0.005  # radius
    touches: dict[tuple[str, int], ir.Vec3] = {}
    ball = p.program.setup.ball_diameter / 2.0
    for node in p.program.body:
        if isinstance(node, ir.SelectStylus):
            ball = node.ball_diameter / 2.0
        if isinstance(node, ir.FeatureBlock):
            for t in node.body:
                if isinstance(t, ir.Touch):
                    c, n = np.array(t.contact, dtype=float), np.array(t.normal)
                    touches[(t.feature, t.index)] = tuple((c - grow * n + ball * n).tolist())

    class NoGaps:
        def reason(self, feature: str, indices: object) -> str:
            return ""

    spec = spec_of(model, profile(kind), ALL)
    for o in p.oriented:
        notes: list[str] = []
        out = ingest_module._revolved(o.plan.spec, spec, o, touches, notes,
                                      NoGaps(), Budget(), None)  # type: ignore[arg-type]
        assert isinstance(out, RevolvedResult), notes
        face = int(o.plan.spec.id[1:])
        record = p.oriented[0].part.original.faces[face - 1]
        assert out.diameter == pytest.approx(2.0 * record.radius + 2.0 * grow, abs=1e-6)
        assert abs(float(np.dot(out.axis, record.axis))) == pytest.approx(1.0, abs=1e-9)
        off = np.subtract(out.centre, record.origin)
        assert np.linalg.norm(off - np.dot(off, record.axis) * np.array(record.axis)) < 1e-6


def test_all_revolved_reaches_every_side(loaded: cad.Part) -> None:
    """``--all-revolved`` with a head: every bore but the face-down one, which is left
    out for a reason; the plan table names each feature's orientation and stylus."""
    from probegen.planning.revolved_spec import all_revolved_spec, metrics_table

    machine = profile("head")
    spec, notes = all_revolved_spec(loaded, machine)
    assert sorted(f.face for f in spec.features) == sorted(ALL)  # type: ignore[union-attr]
    assert notes == (f"R5 bore D8.000 (cylinder, faces {FACES['-Z']}): axis at A 180.0 B 0.0: "
                     "beyond the head's A range 0..105: no orientation reaches this face: "
                     "needs a setup",)
    p = plan_program(spec, runtime_variables=False, part=loaded)
    table = metrics_table(p.revolved, machine, p.oriented).splitlines()
    assert table[0].endswith("orient     stylus  ")
    rows = {line.split()[0]: line.split()[-2:] for line in table[1:-1]}
    assert rows["R6"] == ["A90BM90", "D6"]  # recognised feature 6: the +X bore
    assert rows["R3"] == ["-", "D2"]  # the 3 mm bore, vertical
    plain = load_profile(REPO / "samples/machines/vmc-fanuc.toml")
    _, plain_notes = all_revolved_spec(loaded, plain)
    assert any("not along the probe: needs an orientation or a setup" in n
               for n in plain_notes)


def test_a_bore_too_small_for_every_stylus_names_the_smallest(loaded: cad.Part) -> None:
    from types import SimpleNamespace

    from probegen.planning.left_out import revolved_left_out, smallest_stylus
    from probegen.planning.revolved_spec import smallest_bore

    machine = profile("head")
    least = smallest_bore(machine.with_stylus(smallest_stylus(machine)))
    assert least == pytest.approx(2.0 * (0.5 + 0.15 + 0.25))  # ball + 1.5 margins + core
    bore = SimpleNamespace(id=9, type="cylinder", inner=True, radius=0.4, minor_radius=None,
                           faces=(40,), axis=(1.0, 0.0, 0.0))
    assert revolved_left_out(bore, loaded, machine, "", least) == (
        "R9 bore D0.800 (cylinder, faces 40): bore D0.800: the smallest stylus D1 (ball "
        "D1.000) needs D1.800 or more, the ball and 0.400 mm each side for the retract and "
        "safe circle: a smaller stylus")


@settings(max_examples=examples(200))
@given(st.floats(-1.0, 1.0), st.floats(-1.0, 1.0), st.floats(-1.0, 1.0))
def test_orientation_of_any_direction(x: float, y: float, z: float) -> None:
    """Any approach direction: the head's angles give it back, and the orientation is on
    the grid with its frame's Z along it, or at the head's nearest index within the tilt
    bound with the exact frame's Z along it, or a reason."""
    n = math.sqrt(x * x + y * y + z * z)
    if n < 1e-3:
        return
    a = (x / n, y / n, z / n)
    big_a, big_b = head_angles(a)
    assert 0.0 <= big_a <= 180.0 and -180.0 < big_b <= 180.0
    if math.hypot(a[0], a[1]) > 1e-6:  # B within GRID_SNAP (1.7e-8 rad) of -180 is 180
        assert np.allclose(head_direction(big_a, big_b), a, atol=2e-8)
    for kind in ("head", "tilt"):
        o = orientation_for(profile(kind), a)
        if isinstance(o, str):
            assert "needs a setup" in o or "add the B range" in o
            continue
        assert np.allclose(np.asarray(o.plan_rotation)[:, 2], a, atol=1e-9)
        z_axis = np.asarray(o.rotation)[:, 2]
        tilt = math.degrees(math.atan2(float(np.linalg.norm(np.cross(z_axis, a))),
                                       float(np.dot(z_axis, a))))
        assert tilt == pytest.approx(o.tilt, abs=1e-6) and o.tilt <= 3.75 + 1e-9
        assert (o.exact is None) == (o.tilt == 0.0)
        if o.head is not None:
            assert all(abs(v / 7.5 - round(v / 7.5)) < 1e-9 for v in o.head)
            assert np.allclose(z_axis, head_direction(*o.head), atol=1e-7)  # GRID_SNAP


@settings(max_examples=examples(60))
@given(st.lists(st.tuples(st.sampled_from("ABC"), st.sampled_from("VXYZ")), min_size=1,
                max_size=5, unique=True))
def test_group_order_is_optimal(groups: list[tuple[str, str]]) -> None:
    import itertools

    start = ("A", "V")
    order = order_groups(groups, start, "V")
    assert sorted(order) == sorted(groups)
    best = min(sum(changes(o, start, "V")) for o in itertools.permutations(groups))
    assert sum(changes(order, start, "V")) == best


def test_a_work_offset_update_from_a_turned_feature_is_refused(model: Path,
                                                               loaded: cad.Part) -> None:
    from probegen.spec.actions import Actions, WorkOffsetAction

    spec = spec_of(model, profile("head"), [FACES["+X"]])
    feature = replace(spec.features[0], actions=Actions(  # type: ignore[type-var]
        work_offset=WorkOffsetAction("G54", "XY")))
    with pytest.raises(PlanningError, match=r"found a feature measured in a turned frame "
                                            r"\(A90BM90\)"):
        plan_program(replace(spec, features=(feature,)), runtime_variables=True, part=loaded)


@pytest.mark.parametrize(("profile_path", "dialect", "suffix"), [
    ("samples/machines/cmm.toml", "dmis", "dmi"),
    ("samples/machines/vmc-5axis-fanuc.toml", "fanuc", "nc")])
def test_all_revolved_runs_on_the_virtual_machine_with_its_route(
        model: Path, loaded: cad.Part, tmp_path: Path, capsys: pytest.CaptureFixture[str],
        profile_path: str, dialect: str, suffix: str) -> None:
    """``--all-revolved`` on the block with the CMM sample (DMIS) and the five-axis sample
    (Fanuc): the program, routed at the index height around each change, runs on the
    virtual CMM / machine (``probegen sim``) without an alarm, every planned touch made."""
    from probegen.cli.app import main
    from probegen.dialects import get_dialect
    from probegen.planning.revolved_spec import all_revolved_spec

    machine = load_profile(REPO / profile_path)
    spec, _ = all_revolved_spec(loaded, machine)
    p = plan_program(spec, runtime_variables=dialect != "dmis", part=loaded)
    assert p.orientation_changes == 4
    d = get_dialect(dialect)
    d.compact = False
    text = d.generate(p.program)
    lines = text.split("\n")
    if dialect == "dmis":
        # each head index: GOTO up, SNSLCT (after the stylus's, if any), GOTO level over
        for k, line in enumerate(lines):
            if line.startswith("$$ ORIENT"):
                before = next(x for x in reversed(lines[:k]) if x.startswith("GOTO/"))
                after = lines[k + 2]
                assert after.startswith("GOTO/") and after.split(",")[-1] == \
                    before.split(",")[-1], (before, after)
    program, log = tmp_path / f"prog.{suffix}", tmp_path / "out.log"
    program.write_text(text, encoding="ascii")
    assert main(["sim", str(program), "--part", str(model), "--machine",
                 str(REPO / profile_path), "-o", str(log)]) == 0
    touches = Counter(n.feature for n in ir.walk(p.program.body) if isinstance(n, ir.Touch))
    side = {r.spec.id for r in p.revolved if r.spec.face in (FACES["-Y"], FACES["+X"])}
    if dialect == "dmis":
        assert set(touches.values()) == {16}
    else:
        # the five-axis sample's OMP40 body (40 mm across) along a side bore's axis, 20 mm
        # above the table the block stands on: the touches that take it lower are dropped
        # (10 of 16), the table named; the other bores whole
        assert {f: touches[f] for f in side} == dict.fromkeys(side, 6)
        assert all(touches[f.id] == 16 for f in spec.features if f.id not in side)
        for r in p.revolved:
            assert any("probe body cuts" in n and "into the table" in n
                       for n in r.notes) == (r.spec.id in side), r.notes
    assert len(touches) == len(spec.features)
    assert f"({sum(touches.values())} touches)" in capsys.readouterr().err


@pytest.mark.parametrize("axis", [(1.0, 0.0, 0.0), (0.6, 0.0, 0.8), (0.0, 0.94, -0.34),
                                  (0.0, 0.0, 1.0)])
def test_the_over_point_is_at_the_index_height_and_not_lower_in_the_frame(
        axis: tuple[float, float, float]) -> None:
    """Over a point at the index height; a tool axis below the horizontal (a tilt of
    110 deg) pushes it out along the axis so that it is as high in the frame."""
    from probegen.planning.orient import over_point

    a = np.array(axis) / np.linalg.norm(axis)
    rotation = frames.frame_for(tuple(a))  # type: ignore[arg-type]
    target = np.array([12.0, -7.0, 20.0])
    over = over_point(target, 150.0, rotation)
    assert over[2] == pytest.approx(150.0, abs=1e-9)
    rise = float(np.dot(over - target, a))
    assert rise >= -1e-9 if a[2] < 0.0 else rise == pytest.approx(130.0 * a[2], abs=1e-9)
    if a[2] >= 0.0:
        assert over[:2] == pytest.approx(target[:2], abs=1e-12)
    else:
        assert rise == pytest.approx(0.0, abs=1e-9)


def test_a_five_axis_change_needs_its_levels_above_the_turned_part(
        planned: tuple[str, PlannedProgram], loaded: cad.Part) -> None:
    """After G53.1 the control brings the probe down the tool axis to the frame's
    clearance level wherever the table's turn left it: the check refuses a frame whose
    clearance level leaves less than the ball and half the margin above the turned part."""
    kind, p = planned
    body = list(p.program.body)
    k = next(i for i, n in enumerate(body) if isinstance(n, ir.Orient))
    orient = body[k]
    assert isinstance(orient, ir.Orient)
    top = loaded.turned(orient.rotation).bbox_max[2]
    low = replace(orient, clearance_z=top + 1.0)
    if kind == "head":  # the head turns the stylus where it stands: the level is not used
        check_program(ir.Program(p.program.setup, (*body[:k], low, *body[k + 1:])),
                      obstacle_for(loaded, []), [], profile(kind), part=loaded)
        return
    with pytest.raises(CollisionError, match=rf"change to {orient.name}: its clearance level "
                                             rf"is at frame z = {top + 1.0:.3f}, expected "):
        check_program(ir.Program(p.program.setup, (*body[:k], low, *body[k + 1:])),
                      obstacle_for(loaded, []), [], profile(kind), part=loaded)
