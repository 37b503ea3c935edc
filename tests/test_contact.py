"""The skip signal's geometry: first contact of the stylus ball against exact truth."""

from __future__ import annotations

import math
import time

import numpy as np
import pytest
from conftest import REPO, SHARED
from fuzzing import examples
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from probegen import cad
from probegen.errors import ProbegenError
from probegen.sim.contact import PlacedPart

SPHERE25 = REPO / "samples/sphere25/sphere25.step"
IPP = SHARED / "ref/nist-ippdme/IPlusSimplePart/STEP_Part21_AP203/ipp_simple.stp"
CTC05 = SHARED / "ref/nist-step/nist_ctc_05_asme1_rd.stp"
R, STEM, BALL = 12.5, 4.0, 3.0  # sphere25: sphere and stem radii; stylus ball radius


@pytest.fixture(scope="module")
def sphere25() -> cad.Model:
    return cad.load_step(SPHERE25)


@pytest.fixture(scope="module")
def part(sphere25: cad.Model) -> PlacedPart:
    return PlacedPart.from_model(sphere25)


def _line_sphere(a: np.ndarray, b: np.ndarray, centre: np.ndarray, radius: float) -> float:
    """Fraction along a → b where the line first meets the sphere (textbook quadratic)."""
    d = b - a
    w = a - centre
    qa, qb, qc = d @ d, 2.0 * (w @ d), w @ w - radius**2
    return float((-qb - math.sqrt(qb * qb - 4.0 * qa * qc)) / (2.0 * qa))


def _exact_gap(model: cad.Model, centre: np.ndarray, r: float) -> float:
    """Unsigned distance from a point to the whole shape, less r (OCCT BRepExtrema)."""
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeVertex
    from OCP.BRepExtrema import BRepExtrema_DistShapeShape
    from OCP.gp import gp_Pnt

    vertex = BRepBuilderAPI_MakeVertex(gp_Pnt(*map(float, centre))).Vertex()
    return float(BRepExtrema_DistShapeShape(vertex, model._shape.wrapped).Value()) - r


# ------------------------------------------------------------------ the sphere part


def test_down_onto_the_top(part: PlacedPart) -> None:
    hit = part.first_contact([0.0, 0.0, 20.0], [0.0, 0.0, 0.0], BALL)
    assert hit is not None and hit.kind == "face" and hit.face_id == 5
    assert hit.centre[2] == pytest.approx(R + BALL, abs=1e-9)
    assert hit.t == pytest.approx((20.0 - R - BALL) / 20.0, abs=1e-12)
    np.testing.assert_allclose(hit.point, [0.0, 0.0, R], atol=1e-9)
    np.testing.assert_allclose(hit.normal, [0.0, 0.0, 1.0], atol=1e-12)


def test_sideways_onto_the_equator(part: PlacedPart) -> None:
    hit = part.first_contact([0.0, -25.0, 0.0], [0.0, 0.0, 0.0], BALL)
    assert hit is not None
    np.testing.assert_allclose(hit.centre, [0.0, -(R + BALL), 0.0], atol=1e-9)
    np.testing.assert_allclose(hit.point, [0.0, -R, 0.0], atol=1e-9)


def test_inclined_approach_matches_line_sphere(part: PlacedPart) -> None:
    a, b = np.array([18.0, 7.0, 14.0]), np.array([-3.0, -1.5, 2.0])
    hit = part.first_contact(a, b, BALL)
    assert hit is not None
    assert hit.t == pytest.approx(_line_sphere(a, b, np.zeros(3), R + BALL), abs=1e-9 / 25)
    np.testing.assert_allclose(hit.point, R * hit.centre / np.linalg.norm(hit.centre),
                               atol=1e-9)
    np.testing.assert_allclose(hit.normal, hit.centre / (R + BALL), atol=1e-12)


def test_a_miss_returns_none(part: PlacedPart) -> None:
    assert part.first_contact([30.0, 30.0, 20.0], [30.0, -30.0, 20.0], BALL) is None
    # passes 0.001 mm clear of the offset sphere
    assert part.first_contact([-20.0, 0.0, R + BALL + 1e-3], [20.0, 0.0, R + BALL + 1e-3],
                              BALL) is None
    assert part.first_contact([0.0, 0.0, 20.0], [0.0, 0.0, R + BALL + 1e-6], BALL) is None


def test_stem_cylinder_and_base_plane(part: PlacedPart) -> None:
    stem = part.first_contact([12.0, 5.0, -30.0], [-2.0, -1.0, -30.0], BALL)
    assert stem is not None and stem.face_id == 4 and stem.kind == "face"
    assert math.hypot(*stem.centre[:2]) == pytest.approx(STEM + BALL, abs=1e-9)
    assert math.hypot(*stem.point[:2]) == pytest.approx(STEM, abs=1e-9)
    base = part.first_contact([15.0, 2.0, -50.0], [13.0, 2.5, -66.0], BALL)
    assert base is not None and base.face_id == 2
    assert base.centre[2] == pytest.approx(-60.0 + BALL, abs=1e-9)
    np.testing.assert_allclose(base.normal, [0.0, 0.0, 1.0], atol=1e-12)


def test_convex_edge_of_the_base(part: PlacedPart) -> None:
    # 1 mm outside the rim of the base disc (radius 20, top at z = -60), moving down
    hit = part.first_contact([21.0, 0.0, -40.0], [21.0, 0.0, -65.0], BALL)
    assert hit is not None and hit.kind == "edge"
    assert hit.centre[2] == pytest.approx(-60.0 + math.sqrt(BALL**2 - 1.0), abs=1e-9)
    np.testing.assert_allclose(hit.point, [20.0, 0.0, -60.0], atol=1e-9)


def test_placed_part_matches_the_analytic_truth(sphere25: cad.Model) -> None:
    turn = math.radians(0.5)
    rot = np.array([[math.cos(turn), -math.sin(turn), 0.0],
                    [math.sin(turn), math.cos(turn), 0.0], [0.0, 0.0, 1.0]])
    shift = np.array([1.234, -0.5, 0.3])
    placed = PlacedPart.from_model(sphere25, rotation=rot, translation=shift)
    for a, b in (([0.0, 0.0, 25.0], [0.0, 0.0, 0.0]), ([20.0, 3.0, 4.0], [-5.0, -1.0, 1.0]),
                 ([-9.0, 14.0, -6.0], [3.0, 0.0, 0.0])):
        a_, b_ = np.array(a), np.array(b)
        hit = placed.first_contact(a_, b_, BALL)
        assert hit is not None
        assert hit.t == pytest.approx(_line_sphere(a_, b_, shift, R + BALL), abs=1e-10)
        assert np.linalg.norm(hit.point - shift) == pytest.approx(R, abs=1e-9)
    # a tilted placement: the stem's axis turns with the part
    tilt = math.radians(2.0)
    rot_x = np.array([[1.0, 0.0, 0.0], [0.0, math.cos(tilt), -math.sin(tilt)],
                      [0.0, math.sin(tilt), math.cos(tilt)]])
    tilted = PlacedPart.from_model(sphere25, rotation=rot_x, translation=shift)
    hit = tilted.first_contact(shift + [15.0, 0.0, -30.0], shift + [0.0, 0.0, -30.0], BALL)
    assert hit is not None
    axis = rot_x[:, 2]
    rel = hit.centre - shift
    assert np.linalg.norm(rel - (rel @ axis) * axis) == pytest.approx(STEM + BALL, abs=1e-9)


def test_start_in_contact_and_clearance(part: PlacedPart) -> None:
    hit = part.first_contact([0.0, 0.0, 15.0], [0.0, 0.0, 30.0], BALL)  # 0.5 mm in
    assert hit is not None and hit.t == 0.0
    np.testing.assert_allclose(hit.normal, [0.0, 0.0, 1.0], atol=1e-12)
    np.testing.assert_allclose(hit.point, [0.0, 0.0, R], atol=1e-12)
    # touching and moving away: no contact
    assert part.first_contact([0.0, 0.0, R + BALL], [0.0, 0.0, 30.0], BALL) is None
    assert part.clearance([0.0, 0.0, 20.0], BALL) == pytest.approx(20.0 - R - BALL, abs=1e-12)
    assert part.clearance([0.0, 0.0, 10.0], BALL) == pytest.approx(-2.5 - BALL, abs=1e-12)
    assert part.clearance([0.0, 0.0, -30.0], BALL) == pytest.approx(-STEM - BALL, abs=1e-12)


def test_analytic_spheres_agree_with_the_model(part: PlacedPart) -> None:
    spheres = PlacedPart.from_spheres([[0.0, 0.0, 0.0]], [R])
    a, b = [17.0, -4.0, 9.0], [-2.0, 1.0, 0.5]
    exact, model = spheres.first_contact(a, b, BALL), part.first_contact(a, b, BALL)
    assert exact is not None and model is not None
    assert exact.t == pytest.approx(model.t, abs=1e-12)
    assert spheres.clearance([0.0, 0.0, 20.0], BALL) == pytest.approx(4.5)
    with pytest.raises(ProbegenError, match="positive radii"):
        PlacedPart.from_spheres([[0.0, 0.0, 0.0]], [0.0])


def test_one_contact_takes_well_under_5_ms(part: PlacedPart) -> None:
    moves = [([0.0, 0.0, 20.0], [0.0, 0.0, 0.0]), ([20.0, 3.0, 5.0], [-5.0, -1.0, 2.0]),
             ([12.0, 5.0, -30.0], [-2.0, -1.0, -30.0])]
    spent = []
    for a, b in moves * 20:
        start = time.perf_counter()
        part.first_contact(a, b, BALL)
        spent.append(time.perf_counter() - start)
    assert float(np.median(spent)) < 0.005


@settings(max_examples=examples(30))
@given(st.tuples(*[st.floats(-1.0, 1.0)] * 3), st.tuples(*[st.floats(-1.0, 1.0)] * 3),
       st.floats(0.2, 4.0), st.floats(2.0, 12.0))
def test_property_contact_touches_and_the_way_there_is_clear(
        sphere25: cad.Model, part: PlacedPart, direction: tuple[float, float, float],
        aim: tuple[float, float, float], gap: float, length: float) -> None:
    d = np.array(direction)
    if np.linalg.norm(d) < 0.1:
        d = np.array([0.0, 0.0, 1.0])
    d /= np.linalg.norm(d)
    start = (R + BALL + gap) * d  # off the sphere, in a random direction
    assume(part.clearance(start, BALL) > 0.0)  # not in (or touching) the stem below
    end = start + length * (-d + 0.6 * np.array(aim))
    hit = part.first_contact(start, end, BALL)
    if hit is None:
        assert _exact_gap(sphere25, end, BALL) > 0.0
        return
    assert abs(_exact_gap(sphere25, hit.centre, BALL)) <= 1e-7
    for t in np.linspace(0.0, hit.t, 40, endpoint=False):
        assert _exact_gap(sphere25, start + t * (end - start), BALL) > -1e-9


# ------------------------------------------------------------------- NIST models


def test_nist_bore_touches_from_inside_are_at_radius_25() -> None:
    # simple_in.dms: FEAT/CIRCLE,INNER at (50, 50, 40), diameter 50; PTMEAS at the four
    # quadrant points; SNSDEF ball diameter 4.
    placed = PlacedPart.from_model(cad.load_step(IPP))
    centre = np.array([50.0, 50.0, 40.0])
    for target in ([75.0, 50.0, 40.0], [25.0, 50.0, 40.0], [50.0, 75.0, 40.0],
                   [50.0, 25.0, 40.0], [50.0 + 15.0, 50.0 + 20.0, 40.0]):
        hit = placed.first_contact(centre, centre + 1.2 * (np.array(target) - centre), 2.0)
        assert hit is not None and hit.kind == "face"
        assert math.hypot(*(hit.point - centre)[:2]) == pytest.approx(25.0, abs=1e-9)
        np.testing.assert_allclose(hit.point, target, atol=1e-9)
        np.testing.assert_allclose(hit.normal, -(np.array(target) - centre) / 25.0, atol=1e-12)


def test_nist_block_corner_is_a_vertex_touch() -> None:
    placed = PlacedPart.from_model(cad.load_step(IPP))
    hit = placed.first_contact([110.0, 110.0, 60.0], [100.0, 100.0, 50.0], 2.0)
    assert hit is not None and hit.kind == "vertex"
    np.testing.assert_allclose(hit.point, [100.0, 100.0, 50.0], atol=1e-9)
    corner = np.array([100.0, 100.0, 50.0])
    np.testing.assert_allclose(hit.centre, corner + 2.0 / math.sqrt(3.0), atol=1e-9)


def test_bspline_face_converges_to_a_tenth_of_a_micrometre() -> None:
    from OCP.BRep import BRep_Tool
    from OCP.GeomAPI import GeomAPI_ProjectPointOnSurf
    from OCP.gp import gp_Pnt

    model = cad.load_step(CTC05)
    face = model.faces[17]
    assert face.type == "bspline"
    placed = PlacedPart.from_model(model)
    surface = BRep_Tool.Surface_s(model._topo_faces[17])

    def distance(p: np.ndarray) -> tuple[float, np.ndarray]:
        proj = GeomAPI_ProjectPointOnSurf(gp_Pnt(*map(float, p)), surface)
        q = proj.NearestPoint()
        return float(proj.LowerDistance()), np.array([q.X(), q.Y(), q.Z()])

    outside = np.array(face.centre) + 5.0 * np.array(face.axis)
    gap, foot = distance(outside)
    normal = (outside - foot) / gap
    side = np.cross(normal, [0.0, 0.0, 1.0])
    for shift in (0.0, 0.4, -0.7):
        start = foot + (BALL + 4.0) * normal + shift * side
        hit = placed.first_contact(start, start - 10.0 * normal, BALL)
        assert hit is not None and hit.face_id == 18
        gap, nearest = distance(hit.centre)
        assert abs(gap - BALL) <= 1e-7  # the requirement is 1e-4 mm (0.1 µm)
        np.testing.assert_allclose(hit.point, nearest, atol=1e-6)
