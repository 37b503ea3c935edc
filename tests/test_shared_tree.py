"""A turned part's collision obstacle queries the loaded part's FCL and ray trees placed
by its rotation (``collision.SHARED_TREE``), and answers as trees built on its own turned
mesh do (before stop 33): the same clearances to fcl's precision, the same faces, the
same inside tests.  Part: ``samples/parts/five_face_block.step`` (bores on five faces)."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import REPO

from probegen import cad
from probegen.planning import collision
from probegen.planning.collision import MeshObstacle, Stylus, mesh_obstacle, obstacle_for
from probegen.planning.intrusion import Element

BLOCK = REPO / "samples/parts/five_face_block.step"
# a head index A 60 B 30 (p_work = R·p_frame, rows), and the part turned over
ROTATIONS = [
    ((0.866025403784, -0.25, 0.433012701892), (0.0, 0.866025403784, 0.5),
     (-0.5, -0.433012701892, 0.75)),
    ((1.0, 0.0, 0.0), (0.0, -1.0, 0.0), (0.0, 0.0, -1.0)),
]


def _orthonormal(r: tuple[tuple[float, ...], ...]) -> tuple[tuple[float, ...], ...]:
    u, _, vt = np.linalg.svd(np.asarray(r))
    m = u @ vt
    return tuple(tuple(float(x) for x in row) for row in m)


@pytest.mark.parametrize("rotation", [_orthonormal(r) for r in ROTATIONS])
def test_a_turned_obstacle_answers_as_its_own_trees(rotation: tuple[tuple[float, ...], ...],
                                                    monkeypatch: pytest.MonkeyPatch) -> None:
    part = cad.load_part(BLOCK)
    turned = part.turned(rotation)  # type: ignore[arg-type]
    shared = obstacle_for(turned, [])
    assert isinstance(shared, MeshObstacle) and shared._turned is not None
    monkeypatch.setattr(collision, "SHARED_TREE", False)
    own = mesh_obstacle(turned)
    assert own._turned is None
    rng = np.random.default_rng(7)
    low, high = turned.mesh(collision.MESH_TOLERANCE).bounds
    points = low - 5.0 + rng.random((60, 3)) * (high - low + 10.0)
    stylus = Stylus(1.5, 1.0, 40.0, 6.6, 65.0)
    inside = 0
    for p in points:
        b1, s1 = shared.clearance(p, stylus)
        b2, s2 = own.clearance(p, stylus)
        assert abs(b1 - b2) < 1e-6 and abs(s1 - s2) < 1e-6
        assert shared.inside(p) == own.inside(p)
        inside += shared.inside(p)
        ball = Element("ball", 1.5, None, None)
        named = shared.face_of(p, ball), own.face_of(p, ball)
        if named[0] != named[1]:  # a tie: the ball as deep in (or as near) both faces
            assert abs(_depth(own, p, named[0]) - _depth(own, p, named[1])) < 1e-6
    assert 0 < inside < len(points)  # both answers occur
    # the turned obstacle built no tree of its own: it placed the loaded part's
    assert shared._trees()[2] is obstacle_for(part, [])._trees()[2]


def _depth(obstacle: MeshObstacle, p: np.ndarray, face: str) -> float:
    """The distance from ``p`` to the triangles of ``face`` ("face n") of the mesh."""
    import trimesh

    mesh = obstacle.mesh
    assert obstacle.face_ids is not None
    keep = obstacle.face_ids == int(face.split()[1])
    sub = trimesh.Trimesh(mesh.vertices, mesh.faces[keep], process=False)
    _, distance, _ = trimesh.proximity.closest_point(sub, p[None])
    return float(distance[0])
