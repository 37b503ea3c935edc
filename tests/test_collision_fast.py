"""The fast collision check (planning.heightmap): never clears what the exact check rejects."""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
import pytest
import trimesh
from conftest import REPO
from fuzzing import examples
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from probegen import cad, ir
from probegen.errors import CollisionError, PlanningError
from probegen.planning import make_setup
from probegen.planning.collision import MeshObstacle, check_program, obstacle_for
from probegen.planning.freeform_spec import plan_freeform
from probegen.planning.heightmap import clear_paths, height_map
from probegen.spec.model import FreeformSpec, Spec, load_spec

SAMPLE = REPO / "samples/freeform/freeform.step"
NIST_CTC5 = REPO.parent / "shared/ref/nist-step/nist_ctc_05_asme1_rd.stp"
SPEC = load_spec(REPO / "samples/freeform/freeform.toml")
PART = cad.load_part(SAMPLE)
SETUP = make_setup(SPEC)
MACHINE = SPEC.machine
R = MACHINE.probe.ball_radius


def _exact_clears(path: tuple[ir.Node, ...], obstacle: Any) -> bool:
    """The exact check alone: on a copy of the obstacle whose sweep cache holds none of
    the fast check's entries."""
    obstacle = MeshObstacle(obstacle.mesh, obstacle.face_ids)
    try:
        check_program(ir.Program(SETUP, path), obstacle, [], MACHINE)
    except (CollisionError, PlanningError):
        return False
    return True


class Near:
    """Surface samples of one model (or one face of it): points and outward normals."""

    def __init__(self, part: cad.Part, face: int | None) -> None:
        obstacle = obstacle_for(part, [])
        assert isinstance(obstacle, MeshObstacle)
        self.obstacle = obstacle
        mesh = obstacle.mesh
        if face is not None:
            keep = np.asarray(obstacle.face_ids) == face
            mesh = mesh.submesh([np.flatnonzero(keep)], append=True)
        points, tri = trimesh.sample.sample_surface(mesh, 2000, seed=7)
        self.points, self.normals = points, mesh.face_normals[tri]

    def move(self, k: int, off: float, d: tuple[float, float, float], length: float,
             vertical: bool) -> tuple[ir.Node, ...]:
        """A move starting ``R + off`` off sample ``k`` along its normal, ``length`` mm
        along ``d`` (or straight down)."""
        a = self.points[k % len(self.points)] + (R + off) * self.normals[k % len(self.points)]
        u = np.array([0.0, 0.0, -1.0]) if vertical else np.asarray(d) / max(
            float(np.linalg.norm(d)), 1e-9)
        b = a + length * u
        return (ir.Move(_t(a), ir.MoveMode.PROTECTED), ir.Move(_t(b), ir.MoveMode.PROTECTED))

    def touch(self, k: int, approach: float, tilt: tuple[float, float, float],
              depth: float) -> tuple[ir.Node, ...]:
        """Down from above, a touch along a direction tilted from the normal by ``tilt``
        whose contact is ``depth`` mm off the sample (negative: into the part), back."""
        p, n = self.points[k % len(self.points)], self.normals[k % len(self.points)]
        d = n + np.asarray(tilt)
        d = d / np.linalg.norm(d) if np.linalg.norm(d) > 1e-6 else n
        contact = p + depth * n
        start = contact + (R + approach) * d
        touch = ir.Touch("F", 10, ir.TouchRole.MEASURE, _t(contact), _t(d), approach, 2.0,
                         surface=_t(n) if np.dot(n, d) < 1.0 - 1e-12 else None)
        return (ir.Move((float(start[0]), float(start[1]), float(start[2]) + 20.0),
                        ir.MoveMode.PROTECTED),
                ir.Move(_t(start), ir.MoveMode.PROTECTED), touch,
                ir.Move(_t(start), ir.MoveMode.RETRACT))


def _t(v: np.ndarray) -> tuple[float, float, float]:
    return (float(v[0]), float(v[1]), float(v[2]))


@pytest.fixture(scope="module")
def sample() -> Near:
    return Near(PART, None)


@pytest.fixture(scope="module")
def nist() -> Near:
    if not NIST_CTC5.exists():
        pytest.skip("NIST CTC 5 model not available")
    return Near(cad.load_part(NIST_CTC5), 17)


_unit = st.floats(-1.0, 1.0)
_FAST = settings(max_examples=examples(60),
                 suppress_health_check=[HealthCheck.too_slow,
                                        HealthCheck.function_scoped_fixture])


def _agree(near: Near, paths: list[tuple[ir.Node, ...]]) -> None:
    fast = clear_paths(paths, near.obstacle, SETUP, MACHINE)
    for path, ok in zip(paths, fast, strict=True):
        if ok:
            assert _exact_clears(path, near.obstacle), path


@_FAST
@given(k=st.integers(0, 1999), off=st.floats(-0.5, 6.0), d=st.tuples(_unit, _unit, _unit),
       length=st.floats(0.0, 12.0), vertical=st.booleans())
def test_fast_never_clears_a_move_the_exact_check_rejects_sample(
        sample: Near, k: int, off: float, d: tuple[float, float, float], length: float,
        vertical: bool) -> None:
    _agree(sample, [sample.move(k, off, d, length, vertical)])


@_FAST
@given(k=st.integers(0, 1999), approach=st.floats(0.3, 4.0),
       tilt=st.tuples(_unit, _unit, _unit).map(lambda t: tuple(0.6 * x for x in t)),
       depth=st.floats(-0.02, 0.3))
def test_fast_never_clears_a_touch_the_exact_check_rejects_sample(
        sample: Near, k: int, approach: float, tilt: tuple[float, float, float],
        depth: float) -> None:
    _agree(sample, [sample.touch(k, approach, tilt, depth)])  # type: ignore[arg-type]


@_FAST
@given(k=st.integers(0, 1999), off=st.floats(-0.5, 6.0), d=st.tuples(_unit, _unit, _unit),
       length=st.floats(0.0, 12.0), vertical=st.booleans(), approach=st.floats(0.3, 4.0),
       depth=st.floats(-0.02, 0.3))
def test_fast_never_clears_what_the_exact_check_rejects_nist_bspline_face(
        nist: Near, k: int, off: float, d: tuple[float, float, float], length: float,
        vertical: bool, approach: float, depth: float) -> None:
    _agree(nist, [nist.move(k, off, d, length, vertical),
                  nist.touch(k, approach, (0.0, 0.0, 0.0), depth)])


@pytest.mark.parametrize("kind", ["move", "touch"])
def test_the_random_paths_reach_both_answers(sample: Near, kind: str) -> None:
    """Not vacuous: among fixed random moves (touches) near the part the fast check
    clears many, the exact check rejects many, and every path the fast check clears
    the exact one clears too."""
    rng = np.random.default_rng(3)
    paths = [sample.move(int(rng.integers(2000)), float(rng.uniform(-0.5, 4.0)),
                         tuple(rng.normal(size=3)), float(rng.uniform(0.0, 8.0)),
                         bool(rng.integers(2))) if kind == "move"
             else sample.touch(int(rng.integers(2000)), float(rng.uniform(0.3, 4.0)),
                               tuple(0.3 * rng.uniform(-1.0, 1.0, 3)),
                               float(rng.uniform(-0.02, 0.3)))
             for _ in range(120)]
    fast = clear_paths(paths, sample.obstacle, SETUP, MACHINE)
    exact = np.array([_exact_clears(p, sample.obstacle) for p in paths])
    assert not np.any(fast & ~exact)
    assert fast.sum() > 20 and (~exact).sum() > 10


def test_height_map_bounds_the_mesh(sample: Near) -> None:
    hmap = height_map(sample.obstacle)
    pts, _ = trimesh.sample.sample_surface(sample.obstacle.mesh, 100_000, seed=2)
    at = hmap.highest_along(pts, pts, 0.0)
    assert np.all(at >= pts[:, 2])
    rng = np.random.default_rng(1)
    q = np.c_[rng.uniform(-5.0, 65.0, 200), rng.uniform(-5.0, 45.0, 200)]
    near = hmap.highest_along(q, q, 3.3)
    for x, h in zip(q, near, strict=True):
        inside = np.hypot(*(pts[:, :2] - x).T) <= 3.3
        assert not inside.any() or pts[inside, 2].max() <= h


@settings(max_examples=examples(40), deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(1, 40), size=st.floats(0.05, 30.0))
def test_large_triangles_are_rasterised_as_small_ones(seed: int, n: int, size: float) -> None:
    """A triangle whose XY box covers more than ``BIG`` cells is rasterised on its own,
    with its plane worked out once (``heightmap._planes``); every cell gets exactly the
    value the chunked path of small triangles (``HeightMap._bound``) gives it: random
    triangles, some vertical, rasterised with every triangle large and with none."""
    from probegen.planning import heightmap

    rng = np.random.default_rng(seed)
    vertices = rng.uniform(-size, size, (3 * n, 3))
    vertices[:3, :2] = vertices[0, :2] + rng.uniform(0.0, 1.0, (3, 1)) * rng.normal(size=2)
    faces = np.arange(3 * n, dtype=np.int64).reshape(n, 3)
    maps = []
    for big in (-1, heightmap.CHUNK):  # every triangle large, then none
        saved = heightmap.BIG
        heightmap.BIG = big
        try:
            maps.append(heightmap.HeightMap(vertices, faces).height)
        finally:
            heightmap.BIG = saved
    assert np.array_equal(maps[0], maps[1])
    assert np.isfinite(maps[0]).any()


@settings(max_examples=examples(30), deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(1, 30), size=st.floats(0.5, 300.0),
       radius=st.floats(0.0, 8.0))
def test_single_precision_dilations_stay_upper_bounds(seed: int, n: int, size: float,
                                                      radius: float) -> None:
    """The dilated grids in single precision (``heightmap.SINGLE``) lie at or above the
    double-precision ones everywhere (still upper bounds of the mesh), by no more than
    float32's rounding of the value, and empty (-inf) in the same cells."""
    from probegen.planning import heightmap

    rng = np.random.default_rng(seed)
    vertices = rng.uniform(-size, size, (3 * n, 3))
    faces = np.arange(3 * n, dtype=np.int64).reshape(n, 3)
    hmap = heightmap.HeightMap(vertices, faces)
    grids = []
    for single in (False, True):
        saved = heightmap.SINGLE
        heightmap.SINGLE = single
        try:
            hmap._dilated.clear()
            grids.append(hmap.dilated(radius)[0])
        finally:
            heightmap.SINGLE = saved
    double, single_grid = grids[0], grids[1].astype(np.float64)
    assert grids[1].dtype == np.float32
    assert np.array_equal(np.isneginf(double), np.isneginf(single_grid))
    finite = np.isfinite(double)
    assert np.all(single_grid[finite] >= double[finite])
    ulp = np.spacing(np.abs(double[finite]).astype(np.float32)).astype(np.float64)
    assert np.all(single_grid[finite] - double[finite] <= ulp)


def _feature(**changes: Any) -> tuple[FreeformSpec, Spec]:
    f = SPEC.features[0]
    assert isinstance(f, FreeformSpec)
    return dataclasses.replace(f, **changes), SPEC


@pytest.mark.parametrize("method", ["vector", "vertical", "vertical2d", "microplane"])
def test_fast_and_exact_plans_are_the_same(method: str) -> None:
    f, spec = _feature(counts=(9, 7), margin=1.0, method=method)
    sweeps = obstacle_for(PART, []).sweeps
    sweeps.clear()  # the exact check alone: no segment cleared by the fast check cached
    exact = plan_freeform(f, PART, MACHINE, SETUP, fast=False)
    sweeps.clear()
    quick = plan_freeform(f, PART, MACHINE, SETUP)
    assert quick.nodes == exact.nodes and quick.left_out == exact.left_out
    assert len(quick.guides) > 40


def test_unsure_paths_go_to_the_exact_check() -> None:
    """A path the fast check cannot read (a touch not starting at its approach point) is
    unsure, and the exact check refuses it with its own message."""
    near = Near(PART, None)
    path = near.touch(5, 2.0, (0.0, 0.0, 0.0), 0.0)
    bad = (path[0], ir.Move((0.0, 0.0, 40.0), ir.MoveMode.PROTECTED), *path[2:])
    assert not clear_paths([bad], near.obstacle, SETUP, MACHINE)[0]
    assert not _exact_clears(bad, near.obstacle)


@settings(max_examples=examples(60), suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(st.tuples(st.floats(-60.0, 60.0), st.floats(-60.0, 60.0),
                          st.floats(-5.0, 80.0)), min_size=2, max_size=12),
       st.floats(0.0, 2.0))
def test_the_body_query_skipped_only_where_it_cannot_be_the_least(
        centres: list[tuple[float, float, float]], step: float) -> None:
    """``MeshObstacle.clearance`` skips the body's distance query where the last one
    proves it larger than the shank's: along any sequence of centres (each also nudged by
    ``step``, as a sweep's next point), it gives exactly what an obstacle that forgot
    its last queries (and so queries everything) gives."""
    from probegen.planning.collision import Stylus

    stylus = Stylus(1.5, 1.0, 20.0, 6.6, 65.0)
    kept, fresh = _FAST_OBSTACLES
    for x, y, z in centres:
        for c in (np.array([x, y, z]), np.array([x + step, y, z - step])):
            fresh._last.clear()
            assert kept.clearance(c, stylus) == fresh.clearance(c, stylus)


def test_the_body_query_is_skipped_where_the_body_is_far(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """The ball just above the part's top: the body (20 mm up) is far, the shank near;
    a second point 0.1 mm on takes the body's distance from the first (not queried).
    (The grown collision test, which would settle both, is off.)"""
    from probegen.planning import collision
    from probegen.planning.collision import Stylus

    monkeypatch.setattr(collision, "GROWN_FIRST", False)
    stylus = Stylus(1.5, 1.0, 20.0, 6.6, 65.0)
    obstacle = MeshObstacle(PART.mesh(), None)
    top = PART.bbox_max[2]
    centre = np.array([(PART.bbox_min[0] + PART.bbox_max[0]) / 2.0,
                       (PART.bbox_min[1] + PART.bbox_max[1]) / 2.0, top + 2.0])
    obstacle.clearance(centre, stylus)
    first = obstacle._last[stylus][1]
    obstacle.clearance(centre + np.array([0.1, 0.0, 0.0]), stylus)
    assert obstacle._last[stylus][1] is first


_FAST_OBSTACLES = (MeshObstacle(PART.mesh(), None), MeshObstacle(PART.mesh(), None))


@settings(max_examples=examples(60), suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(st.tuples(st.floats(-60.0, 60.0), st.floats(-60.0, 60.0),
                          st.floats(-5.0, 80.0)), min_size=1, max_size=8),
       st.floats(0.0, 2.0))
def test_the_grown_body_test_changes_no_figure(
        centres: list[tuple[float, float, float]], step: float) -> None:
    """``MeshObstacle.clearance`` with the grown body's collision test first
    (``collision.GROWN_FIRST``) gives exactly what it gives with the body's distance
    queried, along any sequence of centres (each also nudged by ``step``)."""
    from probegen.planning import collision
    from probegen.planning.collision import Stylus

    stylus = Stylus(1.5, 1.0, 20.0, 6.6, 65.0)
    grown, queried = _GROWN_OBSTACLES
    for x, y, z in centres:
        for c in (np.array([x, y, z]), np.array([x + step, y, z - step])):
            with_test = grown.clearance(c, stylus)
            collision.GROWN_FIRST = False
            try:
                without = queried.clearance(c, stylus)
            finally:
                collision.GROWN_FIRST = True
            assert with_test == without, (c, with_test, without)


_GROWN_OBSTACLES = (MeshObstacle(PART.mesh(), None), MeshObstacle(PART.mesh(), None))


def test_the_grown_body_test_saves_the_body_query_and_nearest_agrees() -> None:
    """The ball 2 mm over the part's top: the body (20 mm up) is settled by the grown
    collision test, its distance never queried; ``nearest`` names the element with the
    least ``clearance_of`` (the first of equals) at centres near and far, querying the
    body's distance only where it could be the least."""
    from probegen.planning.collision import Stylus
    from probegen.planning.intrusion import elements

    stylus = Stylus(1.5, 1.0, 20.0, 6.6, 65.0)
    obstacle = MeshObstacle(PART.mesh(), None)
    queried: list[float] = []
    to = obstacle._to

    def counted(obj: Any) -> float:
        d = to(obj)
        queried.append(d)
        return d

    obstacle._to = counted  # type: ignore[method-assign]
    top = PART.bbox_max[2]
    mid = (np.asarray(PART.bbox_min) + np.asarray(PART.bbox_max)) / 2.0
    centre = np.array([mid[0], mid[1], top + 2.0])
    got = obstacle.clearance(centre, stylus)
    assert len(queried) == 2  # the ball and the shank: not the body
    parts = elements(stylus.ball, stylus.cylinders())[1:]
    assert got[1] == obstacle.clearance_of(centre, parts[0])  # the shank's
    skipped = 0
    for dz in (-25.0, -10.0, 0.5, 2.0, 30.0, 70.0):
        for dx in (-80.0, 0.0, 40.0):
            c = np.array([mid[0] + dx, mid[1], top + dz])
            queried.clear()
            near = obstacle.nearest(c, parts)
            skipped += len(queried) < len(parts)
            assert near == min(parts, key=lambda e: obstacle.clearance_of(c, e)), c
    assert skipped >= 3
