"""The head-index screen (planning/tilted.py ``screen``): with ``best`` it stops testing
where the first ``best`` indices cannot change, and gives the same first ``best`` as the
full ranking (``PRUNED`` False: every index and touch tested)."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import REPO
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from probegen import cad
from probegen.machine.profile import load_profile
from probegen.planning import tilted
from probegen.planning.collision import MeshObstacle, obstacle_for, probe_stylus
from probegen.planning.styli import profile_with, stylus_named
from probegen.planning.tilted import Touch, screen

PART = cad.load_part(REPO / "samples/parts/five_face_block.step")
OBSTACLE = obstacle_for(PART, [])
MACHINE = load_profile(REPO / "samples/machines/cmm.toml")
HEAD = MACHINE.head
LOW, HIGH = (np.asarray(b) for b in OBSTACLE.mesh.bounds)  # type: ignore[attr-defined]
AXES = [(1.0, 0.0, 0.0), (-1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, -1.0, 0.0),
        (0.0, 0.0, 1.0), (0.707107, 0.0, 0.707107)]


def _ranking(touches: list[Touch], kind: str, axis: tuple[float, float, float],
             stylus_label: str, free: bool, best: int | None) -> list[tuple[float, float]]:
    assert isinstance(OBSTACLE, MeshObstacle) and HEAD is not None
    m = profile_with(MACHINE, stylus_named(MACHINE, stylus_label, "stylus"))
    return screen(touches, kind, axis, OBSTACLE, probe_stylus(m, m.probe.ball_radius),
                  m.margin / 2.0, HEAD, -1.0, free, best)


touch = st.tuples(st.floats(0.0, 1.0), st.floats(0.0, 1.0), st.floats(0.0, 1.0),
                  st.integers(0, 1))


@settings(max_examples=20, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(touch, min_size=1, max_size=10), st.sampled_from(AXES),
       st.sampled_from(["cylinder", "cone", "circle"]), st.sampled_from(["D1", "D3L"]),
       st.booleans(), st.integers(1, 3))
def test_the_pruned_screen_keeps_the_first_indices_of_the_full_one(
        raw: list[tuple[float, float, float, int]], axis: tuple[float, float, float],
        kind: str, stylus: str, free: bool, best: int) -> None:
    # ball centres over the block's box grown by 10 mm: some touches clear at many
    # indices, some at few, some at none
    span = HIGH - LOW + 20.0
    touches = [Touch(LOW - 10.0 + np.array(p[:3]) * span, LOW - 10.0 + np.array(p[:3]) * span,
                     p[3]) for p in raw]
    full = _ranking(touches, kind, axis, stylus, free, None)
    assert _ranking(touches, kind, axis, stylus, free, best) == full[:best]


def test_the_screen_of_a_side_bore_stops_early_and_agrees(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """Sixteen touches of a bore in the block's +X face (two rings, ball centres 1 mm in
    from the wall): the pruned screen makes under a third of the collision tests for the same two
    indices."""
    import fcl

    from probegen.cad.revolved import revolved_features

    side = [f for f in revolved_features(PART) if abs(f.axis[0]) > 0.9 and f.inner
            and f.type == "cylinder"]
    assert side
    f = max(side, key=lambda f: f.radius)
    axis = np.asarray(f.axis)
    e1 = np.cross(axis, (0.0, 0.0, 1.0))
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(axis, e1)
    touches = []
    for section, q in enumerate((0.3, 0.7)):
        centre = np.asarray(f.origin) + (f.extent[0] + q * f.length) * axis
        for k in range(8):
            phi = 2.0 * np.pi * k / 8
            radial = np.cos(phi) * e1 + np.sin(phi) * e2
            touches.append(Touch(centre + (f.radius - 1.0) * radial,
                                 centre + f.radius * radial, section))
    out = axis if (np.asarray(f.origin) + f.extent[1] * axis)[0] > 0 else -axis
    calls = {"n": 0}
    real = fcl.collide

    def counted(*args: object) -> int:
        calls["n"] += 1
        return int(real(*args))

    monkeypatch.setattr(fcl, "collide", counted)
    full = _ranking(touches, "cylinder", tuple(out), "D1", False, None)
    full_calls = calls["n"]
    calls["n"] = 0
    pruned = _ranking(touches, "cylinder", tuple(out), "D1", False, 2)
    assert pruned == full[:2] and len(pruned) == 2
    assert calls["n"] * 3 < full_calls, (calls["n"], full_calls)
    monkeypatch.setattr(tilted, "PRUNED", False)
    calls["n"] = 0
    assert _ranking(touches, "cylinder", tuple(out), "D1", False, 2) == full
    assert calls["n"] == full_calls
