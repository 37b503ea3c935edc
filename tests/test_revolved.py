"""Revolved features: recognition (probegen.cad.revolved) and method M2
(probegen.planning.revolved), proved against the model mesh, not the formulas."""

from __future__ import annotations

import math
import time
from collections import Counter
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from build123d import Align, Box, Cylinder, Pos, export_step
from fuzzing import examples
from hypothesis import given, settings
from hypothesis import strategies as st

from probegen import cad, ir
from probegen.cad.revolved import (
    FULL_CIRCLE,
    REVOLVED_TYPES,
    RevolvedFeature,
    revolved_features,
    revolved_table,
    section_arcs,
    section_at,
)
from probegen.errors import CollisionError, ModelError, PlanningError
from probegen.machine.profile import MachineProfile, load_profile
from probegen.planning.collision import check_program, obstacle_for
from probegen.planning.revolved import (
    FeaturePlan,
    PathKind,
    Section,
    Segment,
    alpha_max,
    baseline_segments,
    compare,
    cycle_time,
    feature_nodes,
    lower_bound_segments,
    m1_rotation,
    m2_rotation,
    path_length,
    plan_feature,
    plan_section,
    plan_segments,
    section_of,
    transition_count,
)

ROOT = Path(__file__).resolve().parents[1]
REF = ROOT.parent / "shared" / "ref"
SIMPLE = REF / "nist-ippdme/IPlusSimplePart/STEP_Part21_AP203/ipp_simple.stp"
DCX = REF / "nist-ippdme/DCXpart/STEP_AP214/DaimlerChryslerTestPartAP214.stp"
NIST = sorted(REF.glob("nist-step/*.stp"))
UP = (0.0, 0.0, 1.0)
C, MIN = Align.CENTER, Align.MIN


@pytest.fixture(scope="module")
def simple() -> cad.Part:
    return cad.load_part(SIMPLE)


@pytest.fixture(scope="module")
def dcx() -> tuple[RevolvedFeature, ...]:
    return revolved_features(cad.load_part(DCX))


@pytest.fixture(scope="module")
def machine() -> MachineProfile:
    return load_profile(ROOT / "samples/machines/vmc-fanuc.toml")


def _by_faces(features: tuple[RevolvedFeature, ...], faces: tuple[int, ...]) -> RevolvedFeature:
    return next(f for f in features if f.faces == faces)


def _check_arcs(arcs: tuple[tuple[float, float], ...]) -> None:
    for a, b in arcs:
        assert 0.0 <= a < 2.0 * math.pi and a < b <= a + 2.0 * math.pi
    for (_, b), (a, _) in zip(arcs, arcs[1:], strict=False):
        assert b < a  # sorted, apart


# -------------------------------------------------------------------- recognition


def test_simple_part_bore(simple: cad.Part) -> None:
    (bore,) = revolved_features(simple)
    assert (bore.type, bore.inner, bore.faces, bore.accessible) == ("cylinder", True, (8,), True)
    assert bore.radius == pytest.approx(25.0, abs=1e-9)
    assert bore.origin == pytest.approx((50.0, 50.0, 25.0), abs=1e-6)
    assert bore.axis == pytest.approx(UP, abs=1e-12)
    assert bore.extent == pytest.approx((0.0, 25.0), abs=1e-6)
    assert [s.axial for s in bore.sections] == pytest.approx([6.25, 18.75], abs=1e-6)
    assert all(s.arcs == FULL_CIRCLE and s.reachable and s.tilt == 0.0 for s in bore.sections)
    at40 = section_at(simple, bore, 15.0)
    assert at40.centre == pytest.approx((50.0, 50.0, 40.0), abs=1e-6) and at40.full
    with pytest.raises(ModelError, match=r"revolved feature 1 \(faces 8\): expected a section "
                                         r"from 0.0000 to 25.0000 mm.*found 30.0000"):
        section_at(simple, bore, 30.0)


def test_simple_part_table(simple: cad.Part) -> None:
    text = revolved_table(revolved_features(simple))
    rows = text.splitlines()
    assert rows[1].split() == ["1", "cylinder", "inner", "8", "25.0000", "-", "50.0000",
                               "50.0000", "25.0000", "0.000000", "0.000000", "1.000000",
                               "0.0000", "25.0000", "yes"]
    assert rows[2].strip() == ("section h=6.2500 centre (50.0000, 50.0000, 31.2500) "
                               "radius 25.0000 tilt 0.000 arcs full")
    assert text == revolved_table(revolved_features(simple)) and text.endswith("\n")


def test_dcx_bores_and_counts(dcx: tuple[RevolvedFeature, ...]) -> None:
    assert Counter(f.type for f in dcx) == {"cylinder": 43, "torus": 17, "sphere": 11,
                                            "cone": 1}
    bore = _by_faces(dcx, (78, 79))  # the 31 mm bore: two half-cylinders, one feature
    assert bore.radius == pytest.approx(15.5) and bore.inner and bore.accessible
    assert bore.origin == pytest.approx((0.0, 0.0, 14.0), abs=1e-6)
    assert bore.extent == pytest.approx((0.0, 12.0), abs=1e-6)
    assert all(s.full for s in bore.sections)
    small = [f for f in dcx if f.type == "cylinder" and f.inner
             and f.radius == pytest.approx(6.25)]
    assert sorted(f.faces for f in small) == [(40, 41), (42, 43), (44, 45), (46, 47),
                                              (48, 49), (83, 84)]
    assert all(f.accessible and f.axis == pytest.approx(UP) for f in small)
    # the 12.5 mm bore at (0, -34) is cut by the inclined bore above z = 16.8
    cut = _by_faces(dcx, (42, 43))
    assert cut.sections[0].full and not cut.sections[1].full
    cone = next(f for f in dcx if f.type == "cone")
    assert cone.faces == (50, 51) and cone.inner
    assert cone.sections[0].tilt == pytest.approx(math.pi / 4)


def test_dcx_horizontal_axes_are_not_accessible(dcx: tuple[RevolvedFeature, ...]) -> None:
    inclined = _by_faces(dcx, (19, 20))
    assert not inclined.accessible and "not parallel to Z" in inclined.reason
    assert all(not s.reachable for s in inclined.sections)
    ball = _by_faces(dcx, (1, 2))  # a half ball on the +X side wall
    assert ball.type == "sphere" and ball.axis == UP and ball.accessible
    (equator,) = ball.sections
    assert equator.axial == 0.0 and len(equator.arcs) == 1
    start, end = equator.arcs[0]
    assert (start, end - start) == pytest.approx((1.5 * math.pi, math.pi), abs=1e-6)


@pytest.mark.parametrize("path", NIST, ids=lambda p: p.stem)
def test_every_nist_model(path: Path) -> None:
    model = cad.load_part(path)
    began = time.perf_counter()
    features = revolved_features(model)
    elapsed = time.perf_counter() - began
    revolved = sorted(f.id for f in model.faces if f.type in REVOLVED_TYPES)
    assert sorted(i for f in features for i in f.faces) == revolved
    for f in features:
        assert f.extent[0] <= f.extent[1] and f.radius >= 0.0  # 0: a cone from its apex
        assert f.accessible == any(s.reachable for s in f.sections)
        for s in f.sections:
            _check_arcs(s.arcs)
    assert elapsed < 20.0


def test_section_arcs_on_a_synthetic_circle() -> None:
    def gaps(*cut: tuple[float, float]) -> Callable[[float], bool]:
        def on(phi: float) -> bool:
            p = phi % (2.0 * math.pi)
            return not any(a < q < b for a, b in cut for q in (p, p + 2.0 * math.pi))

        return on

    arcs = section_arcs(gaps((1.0, 2.0), (5.5, 7.0)), 360)  # the second gap passes 0
    assert [a for arc in arcs for a in arc] == pytest.approx(
        [7.0 - 2.0 * math.pi, 1.0, 2.0, 5.5], abs=1e-7)
    ((start, end),) = section_arcs(gaps((1.0, 2.0)), 360)  # the arc passes 0
    assert (start, end) == pytest.approx((2.0, 1.0 + 2.0 * math.pi), abs=1e-7)
    assert section_arcs(gaps(), 360) == FULL_CIRCLE
    assert section_arcs(lambda phi: False, 360) == ()


# ------------------------------------------------------------- a bore cut by a slot

BORE, SLOT, SLOT_FLOOR = 15.0, 8.0, 10.0


@pytest.fixture(scope="module")
def slotted(tmp_path_factory: pytest.TempPathFactory) -> cad.Part:
    """A 60 x 60 x 20 block, a through bore r15 at the origin, and a slot 8 wide from
    the bore to the +X side, from z = 10 to the top."""
    part = Box(60, 60, 20, align=(C, C, MIN))
    part -= Cylinder(BORE, 20, align=(C, C, MIN))
    part -= Pos(0, 0, SLOT_FLOOR) * Box(40, SLOT, 20, align=(MIN, C, MIN))
    path = tmp_path_factory.mktemp("slot") / "slotted.step"
    export_step(part, path)
    return cad.load_part(path)


def test_slot_is_left_out_of_the_accessible_range(slotted: cad.Part) -> None:
    bore = next(f for f in revolved_features(slotted) if f.inner and f.type == "cylinder")
    assert bore.radius == pytest.approx(BORE) and bore.extent == pytest.approx((0.0, 20.0))
    low, high = bore.sections  # z = 5 below the slot, z = 15 in it
    assert low.full
    half = math.asin(SLOT / 2.0 / BORE)  # the slot's walls y = ±4 meet the circle here
    ((start, end),) = high.arcs
    assert (start, end) == pytest.approx((half, 2.0 * math.pi - half), abs=1e-6)
    assert section_at(slotted, bore, SLOT_FLOOR - 0.5).full


# ------------------------------------------------------------------------ M2 figures


def test_rotations() -> None:
    assert np.array_equal(m1_rotation(UP), np.eye(3))
    assert np.array_equal(m1_rotation((0.0, 0.0, -1.0)), np.diag([1.0, -1.0, -1.0]))
    v = np.array([1.0, -2.0, 0.5]) / math.sqrt(5.25)
    m1, m2 = m1_rotation(v), m2_rotation(v)
    assert m1 @ v == pytest.approx([0.0, 0.0, 1.0], abs=1e-15)
    assert m2 == pytest.approx(m1.T) and m2 @ m1 == pytest.approx(np.eye(3), abs=1e-15)
    assert np.linalg.det(m1) == pytest.approx(1.0)


def test_alpha_max_and_transition_counts_by_hand() -> None:
    # R = 10, r = 3, d = 2: cos(α_max/2) = 13/15, α_max = 59.8530 deg
    alpha = alpha_max(10.0, 3.0, 2.0)
    assert alpha == pytest.approx(2.0 * math.acos(13.0 / 15.0))
    assert math.degrees(alpha) == pytest.approx(59.853, abs=1e-3)
    for n, m in ((3, 2), (4, 1), (6, 1), (7, 0)):  # 120, 90, 60 (> 59.85), 51.4 deg
        assert transition_count(2.0 * math.pi / n, alpha) == m
        section = Section("S", (0.0, 0.0, 0.0), UP, 10.0, False)
        plan = plan_section(section, n, ball=3.0, retract=2.0, margin=0.0)
        assert plan.transitions == (m,) * (n - 1)
    # with the margin m = 0.5: cos(α/2) = 13.5/15
    assert alpha_max(10.0, 3.0, 2.0, margin=0.5) == pytest.approx(2.0 * math.acos(0.9))
    assert transition_count(2.0 * alpha, alpha) == 1  # an exact multiple: no extra point


def _safe_chords(plan: FeaturePlan) -> list[tuple[np.ndarray, np.ndarray, int]]:
    """Consecutive points on one section's safe circle (safe, transition, link)."""
    on = (PathKind.SAFE, PathKind.TRANSITION, PathKind.LINK)
    return [(np.array(a.position), np.array(b.position), a.section)
            for a, b in zip(plan.path, plan.path[1:], strict=False)
            if a.kind in on and b.kind in on and a.section == b.section
            and a.position != b.position]


def _closest_to_axis(a: np.ndarray, b: np.ndarray, section: Section) -> float:
    """Smallest distance from the axis of the points of the segment a-b."""
    v, o = np.array(section.axis), np.array(section.centre)
    t = np.linspace(0.0, 1.0, 2001)[:, None]
    p = a + t * (b - a) - o
    radial = p - (p @ v)[:, None] * v
    return float(np.linalg.norm(radial, axis=1).min())


@settings(max_examples=examples(40))
@given(radius=st.floats(2.0, 80.0), ball=st.floats(0.5, 4.0), retract=st.floats(0.6, 6.0),
       n=st.integers(1, 24))
def test_outer_chords_clear_the_offset_circle(radius: float, ball: float, retract: float,
                                              n: int) -> None:
    margin = 0.5
    section = Section("S", (1.0, 2.0, 3.0), UP, radius, False)
    plan = plan_feature([section], n, ball=ball, retract=retract, margin=margin, clear_z=20.0)
    for a, b, _ in _safe_chords(plan):
        assert _closest_to_axis(a, b, section) >= radius + ball + margin - 1e-6
    count = sum(p.kind is PathKind.TRANSITION for p in plan.path)
    assert count == sum(plan.sections[0].transitions)


def test_inner_chords_stay_inside_and_small_bores_are_refused() -> None:
    section = Section("B", (0.0, 0.0, 0.0), UP, 12.0, True)
    plan = plan_feature([section], 5, ball=3.0, retract=2.0, margin=0.5, clear_z=10.0)
    assert plan.sections[0].alpha_max is None and plan.sections[0].transitions == (0,) * 4
    safe = plan.sections[0].safe_radius
    assert safe == pytest.approx(7.0)
    for a, b, _ in _safe_chords(plan):
        assert np.linalg.norm(a[:2]) == pytest.approx(safe)
        assert max(np.linalg.norm(a[:2]), np.linalg.norm(b[:2])) <= 12.0 - 3.0 - 0.5
    with pytest.raises(PlanningError, match=r"feature B7: .*R - r - d = 0.000 mm: expected "
                                            r"R > r \+ d = 5.000 mm"):
        plan_feature([Section("B7", (0.0, 0.0, 0.0), UP, 5.0, True)], 4, ball=3.0,
                     retract=2.0, margin=0.5, clear_z=10.0)


def _azimuth(p: np.ndarray, section: Section) -> float:
    q = m1_rotation(section.axis) @ (p - np.array(section.centre))
    return math.atan2(q[1], q[0]) % (2.0 * math.pi)


def _in_arcs(phi: float, section: Section) -> bool:
    return any((phi - a) % (2.0 * math.pi) <= b - a + 1e-9 for a, b in section.arcs)


@pytest.mark.parametrize("inner", [False, True])
def test_partial_arcs_are_never_crossed(inner: bool) -> None:
    arcs = ((0.3, 2.2), (3.0, 5.9))  # two arcs: a wall or key at 2.2-3.0 and 5.9-0.3
    axis = (0.3, -0.2, 1.0)
    sections = [Section("P", (5.0, 5.0, z), axis, 20.0, inner, arcs) for z in (10.0, 4.0)]
    plan = plan_feature(sections, 7, ball=2.0, retract=2.0, margin=0.5, clear_z=60.0)
    touches = [p for p in plan.path if p.kind is PathKind.TARGET]
    assert len(touches) == 14
    for a, b in zip(plan.path, plan.path[1:], strict=False):
        if PathKind.CLEAR in (a.kind, b.kind) or PathKind.EXIT in (a.kind, b.kind):
            continue  # up to the clearance level and across there
        if PathKind.ENTRY in (a.kind, b.kind):
            continue
        section = sections[b.section]
        for t in np.linspace(0.0, 1.0, 201):
            p = np.array(a.position) + t * (np.array(b.position) - np.array(a.position))
            assert _in_arcs(_azimuth(p, section), section), (a, b)
    inset = (2.0 + 0.5) / 20.0  # the end margin r + margin, as an angle
    for p in touches:
        assert any(a + inset - 1e-12 <= (p.azimuth or 0.0) <= b - inset + 1e-12 for a, b in arcs)


def test_oblique_section_points_lie_on_the_circle() -> None:
    axis = np.array([1.0, 1.0, 1.0]) / math.sqrt(3.0)
    section = Section("O", (10.0, 0.0, 5.0), tuple(axis), 8.0, False)
    plan = plan_feature([section], 6, ball=1.0, retract=1.5, margin=0.2, clear_z=100.0)
    for p in plan.path:
        if p.kind is PathKind.TARGET:
            rel = np.array(p.contact) - section.centre
            assert abs(rel @ axis) < 1e-12 and np.linalg.norm(rel) == pytest.approx(8.0)
            assert np.array(p.normal) == pytest.approx(rel / 8.0)
            assert np.array(p.position) == pytest.approx(np.array(p.contact) + np.array(p.normal))


def test_cone_section_touches_along_the_surface_normal(dcx: tuple[RevolvedFeature, ...]) -> None:
    cone = next(f for f in dcx if f.type == "cone")  # the 45 deg countersink of the bore
    section = section_of("K", cone, cone.sections[1])
    plan = plan_feature([section], 4, ball=3.0, retract=2.0, margin=0.5, clear_z=40.0)
    alpha = cone.half_angle or 0.0
    apex = np.array(cone.origin) - cone.radius / math.tan(alpha) * np.array(cone.axis)
    for p in plan.path:
        if p.kind is PathKind.TARGET:  # the ball centre lies r off the cone's surface
            rel = np.array(p.position) - apex
            along, off = rel[2], math.hypot(rel[0], rel[1])
            distance = along * math.sin(alpha) - off * math.cos(alpha)
            assert distance == pytest.approx(3.0, abs=1e-9)


# ------------------------------------------------------- the simple part, end to end


def _simple_plan(simple: cad.Part, n: int, machine: MachineProfile) -> FeaturePlan:
    (bore,) = revolved_features(simple)
    section = section_of("BORE", bore, section_at(simple, bore, 15.0))  # z = 40
    return plan_feature([section], n, ball=machine.probe.ball_radius,
                        retract=machine.probe.approach, margin=machine.margin, clear_z=55.0)


def _setup(machine: MachineProfile) -> ir.Setup:
    m, p = machine, machine.probe
    return ir.Setup(
        program_number=1, program_name="M2", units=m.units, work_offset=m.work_offset,
        clearance_z=m.clearance_z, ball_diameter=p.ball_diameter,
        shank_diameter=p.shank_diameter, tool_number=p.tool_number,
        tool_change=m.controller.tool_change, position_feed=m.feeds.position,
        probe_feed=m.feeds.probe, probe_on=m.controller.probe_on,
        probe_off=m.controller.probe_off, variable_base=m.controller.variable_base,
        reset_codes=m.controller.reset_codes, probe_length=p.length,
    )  # fmt: skip


@pytest.mark.parametrize("n", [4, 8])
def test_simple_part_plan_clears_the_mesh(simple: cad.Part, machine: MachineProfile,
                                          n: int) -> None:
    plan = _simple_plan(simple, n, machine)
    nodes = feature_nodes(plan, overtravel=machine.probe.overtravel,
                          clearance_z=machine.clearance_z)
    touches = [t for t in nodes if isinstance(t, ir.Touch)]
    assert [t.index for t in touches] == list(range(1, n + 1))
    assert all(t.approach == machine.probe.approach for t in touches)
    program = ir.Program(_setup(machine), nodes)
    report = check_program(program, obstacle_for(simple, []), [], machine)
    assert report.minimum >= 0.0
    assert sum(s.kind.startswith("touch") for s in report.segments) == n


def test_the_check_is_not_vacuous(simple: cad.Part, machine: MachineProfile) -> None:
    # the same section planned as a boss sends the stylus into the bore's wall
    plan = _simple_plan(simple, 4, machine)
    wrong = replace(plan.sections[0].section, inner=False)
    bad = plan_feature([wrong], 4, ball=3.0, retract=2.0, margin=0.5, clear_z=55.0)
    program = ir.Program(_setup(machine), feature_nodes(bad, overtravel=2.0))
    with pytest.raises(CollisionError, match=r"segment 1 \(protected\) .* cuts .* into face"):
        check_program(program, obstacle_for(simple, []), [], machine)


def test_simple_part_metrics(simple: cad.Part, machine: MachineProfile) -> None:
    plan = _simple_plan(simple, 8, machine)
    figures = compare(plan, machine)
    assert figures.lower_bound.length <= figures.plan.length < figures.baseline.length
    points = np.array([p.position for p in plan.path])
    assert figures.plan.length == pytest.approx(path_length(points))
    # the baseline adds the climb to z = 55 and back down after each of 7 touches
    extra = 7 * 2 * 15.0
    chord = 2.0 * 20.0 * math.sin(math.pi / 8.0)
    assert figures.baseline.length == pytest.approx(figures.plan.length + extra, abs=1e-5)
    assert sum(s.length for s in baseline_segments(plan) if s.kind == "rapid") == (
        pytest.approx(7 * chord))


def test_outer_lower_bound_wraps_the_offset_circle(machine: MachineProfile) -> None:
    section = Section("S", (0.0, 0.0, 0.0), UP, 10.0, False)
    plan = plan_feature([section], 3, ball=3.0, retract=2.0, margin=0.5, clear_z=20.0)
    bound = sum(s.length for s in lower_bound_segments(plan))
    own = sum(s.length for s in plan_segments(plan))
    # per step: two tangents from radius 15 to the offset circle 13, then its arc
    free = 2.0 * math.acos(13.0 / 15.0)
    step = 2.0 * math.sqrt(15.0**2 - 13.0**2) + 13.0 * (2.0 * math.pi / 3.0 - free)
    chords = 2.0 * 2.0 * 15.0 * math.sin(math.pi / 3.0)  # the two direct chords
    assert bound == pytest.approx(own - _transition_length(plan) + 2.0 * step)
    assert bound < own and own - _transition_length(plan) + chords < bound


def _transition_length(plan: FeaturePlan) -> float:
    """Length of the runs safe → transitions → safe of the plan."""
    total, inside = 0.0, False
    for a, b in zip(plan.path, plan.path[1:], strict=False):
        inside = b.kind is PathKind.TRANSITION or (inside and a.kind is PathKind.TRANSITION)
        if inside or a.kind is PathKind.TRANSITION:
            total += math.dist(a.position, b.position)
    return total


def test_cycle_time_by_hand() -> None:
    segments = [Segment("rapid", 240.0), Segment("protected", 20.0), Segment("touch", 5.0),
                Segment("retract", 5.0)]
    seconds = cycle_time(segments, rapid=24000.0, position_feed=2000.0, probe_feed=300.0,
                         approach=2.0)
    # 0.6 s + 0.6 s + (3 mm at 2000 + 2 mm at 300) + 0.15 s
    assert seconds == pytest.approx(0.6 + 0.6 + 0.09 + 0.4 + 0.15)
    worst = cycle_time(segments, rapid=24000.0, position_feed=2000.0, probe_feed=300.0,
                       approach=2.0, overtravel=2.0)
    assert worst - seconds == pytest.approx(0.4)
