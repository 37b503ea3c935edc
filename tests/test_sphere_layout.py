"""Method M1: the layouts, their figures, the zigzag order and the safe retract distance."""

from __future__ import annotations

import math

import numpy as np
import pytest

from probegen.geometry import sphere_layout as sl

# The angle tables of docs (shared/methods.md M1), written out again independently:
# (theta, phi) in degrees.
ISO = [(0, 0)] + [(22.5, 90 * k) for k in range(4)] + [(45, 22.5 + 45 * k) for k in range(8)] \
    + [(67.5, 45 + 90 * k) for k in range(4)] + [(90, 22.5 + 45 * k) for k in range(8)]
OCTA = [(0, 0)] + [(90, 90 * k) for k in range(4)] \
    + [(t, 90 * k) for k in range(4) for t in (30, 60)] \
    + [(90, 90 * k + d) for k in range(4) for d in (30, 60)] \
    + [(math.degrees(math.acos(1 / math.sqrt(3))), 45 + 90 * k) for k in range(4)]


def to_xyz(table: list[tuple[float, float]]) -> np.ndarray:
    out = []
    for t, p in table:
        t, p = math.radians(t), math.radians(p)
        out.append((math.sin(t) * math.cos(p), math.sin(t) * math.sin(p), math.cos(t)))
    return np.array(out)


def same_set(a: np.ndarray, b: np.ndarray) -> bool:
    d = np.linalg.norm(a[:, None] - b[None], axis=2)
    return bool(len(a) == len(b) and (d.min(axis=1) < 1e-12).all() and
                (d.min(axis=0) < 1e-12).all())


@pytest.mark.parametrize(("name", "table"), [("iso", ISO), ("octahedral", OCTA)])
def test_points_recomputed_independently(name: str, table: list[tuple[float, float]]) -> None:
    assert len(table) == 25
    assert same_set(sl.layout(name), to_xyz(table))


@pytest.mark.parametrize(("name", "min_d", "ratio"),
                         [("iso", 0.390, 0.721), ("octahedral", 0.518, 0.796)])
def test_uniformity_figures(name: str, min_d: float, ratio: float) -> None:
    u = sl.uniformity(sl.layout(name))
    assert round(u.min_distance, 3) == min_d
    assert round(u.ratio, 3) == ratio


def test_cap_layout_beats_octahedral_at_25() -> None:
    cap = sl.uniformity(sl.cap_layout(25, 90.0))
    octa = sl.uniformity(sl.octahedral_layout())
    assert cap.min_distance > octa.min_distance
    assert cap.ratio > octa.ratio


def test_cap_layout_stays_on_cap_and_is_repeatable() -> None:
    a = sl.cap_layout(30, 100.0)
    assert np.allclose(np.linalg.norm(a, axis=1), 1.0)
    assert np.degrees(np.arccos(a[:, 2])).max() <= 100.0 + 1e-9
    assert np.array_equal(a, sl.cap_layout(30, 100.0))


@pytest.mark.parametrize("name", ["iso", "octahedral"])
def test_zigzag_starts_at_pole_and_visits_every_point_once(name: str) -> None:
    pts = sl.layout(name)
    order = sl.zigzag_order(pts)
    assert sorted(order) == list(range(25))
    assert pts[order[0]][2] == pytest.approx(1.0)
    theta = np.degrees(np.arccos(np.clip(pts[order, 2], -1, 1)))
    assert (np.diff(theta) > -10.0).all(), "rings go outward from the pole"


def test_octahedral_order_merges_the_near_rings() -> None:
    # 54.7 and 60 deg points form one ring of 8, so no step is the 75.5 deg of a
    # 4-point ring.
    pts = sl.octahedral_layout()
    alpha = sl.max_step_angle(pts, sl.zigzag_order(pts))
    assert math.degrees(alpha) == pytest.approx(41.4096, abs=1e-3)


@pytest.mark.parametrize("alpha_deg", [10.0, 41.4, 81.6, 150.0])
def test_safe_retract_is_the_grazing_limit(alpha_deg: float) -> None:
    r_off = 15.5
    alpha = math.radians(alpha_deg)
    d = sl.safe_retract(r_off, alpha)
    t = np.linspace(0, 1, 2001)[:, None]
    a = (r_off + d) * np.array([1.0, 0.0, 0.0])
    b = (r_off + d) * np.array([math.cos(alpha), math.sin(alpha), 0.0])
    closest = np.linalg.norm(a + t * (b - a), axis=1).min()
    assert closest == pytest.approx(r_off, abs=1e-9)
    smaller = 0.99 * d
    a2, b2 = a * (r_off + smaller) / (r_off + d), b * (r_off + smaller) / (r_off + d)
    assert np.linalg.norm(a2 + t * (b2 - a2), axis=1).min() < r_off


def test_safe_retract_impossible_at_half_turn() -> None:
    assert sl.safe_retract(10.0, math.pi) == math.inf
