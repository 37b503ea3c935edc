"""The order in which features are measured: nearest neighbour, then 2-opt and Or-opt.

Each feature is a *stop* with an entry point (where its path starts) and an exit point
(where it ends); the time inside a feature does not depend on the order, so only the
travel between stops counts.  Travel from an exit to the next entry goes straight where
the caller's predicate says the straight move is clear, else by the clearance plane:
up from the exit, across, down to the entry.  A travel costs its length, or what the
caller's ``cost`` says (e.g. its time: a move across the clearance plane is a rapid, a
link below it is not).  Costs are therefore asymmetric, and the moves below are
evaluated on the directed costs.

The tour is an open path: it starts at ``start`` (a point, e.g. the tool-change
position) or, without one, at whichever stop is best, and it does not return.

1. Nearest neighbour from the start; equal costs go to the lower stop index.
2. Improve until no move shortens the tour by more than :data:`IMPROVEMENT`:
   *2-opt* (reverse a run of stops; the best move of each pass is taken, the first in
   index order among equals) and *Or-opt* (move a run of 1-3 stops elsewhere, order
   kept).  Only improving moves are made, so the result is never longer than the
   nearest-neighbour tour.  Everything is deterministic.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from functools import partial

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]
Vec3 = tuple[float, float, float]
Direct = Callable[[Vec3, Vec3], bool]
"""``direct(a, b)``: whether the straight move from ``a`` to ``b`` is clear."""
Route = Callable[[Vec3, Vec3], "tuple[Vec3, ...] | None"]
"""``route(a, b)``: the points of a clear travel from ``a`` to ``b`` below the clearance
plane (both ends included), or None."""
Cost = Callable[[Sequence[Vec3]], float]
"""``cost(points)``: what the travel through ``points`` costs (default: its length)."""

IMPROVEMENT = 1e-9
"""A move must shorten the tour by more than this (mm) to be made: float noise must not
make the search cycle."""
OR_OPT_RUNS = (1, 2, 3)
"""Run lengths Or-opt moves."""


@dataclass(frozen=True, slots=True)
class Stop:
    """One feature to visit: its path starts at ``entry`` and ends at ``exit`` (mm)."""

    entry: Vec3
    exit: Vec3


@dataclass(frozen=True, slots=True)
class Tour:
    """An order of the stops and its travel length.

    Attributes:
        order: stop indices in visiting order (the least total cost).
        length: travel from the start through every stop, mm.
        nearest: the nearest-neighbour order the improvement started from.
        nearest_length: its travel length, mm.
    """

    order: tuple[int, ...]
    length: float
    nearest: tuple[int, ...]
    nearest_length: float


def travel_path(a: Vec3, b: Vec3, *, clearance_z: float, direct: Direct | None = None,
                route: Route | None = None) -> tuple[Vec3, ...]:
    """The points of the travel from ``a`` to ``b`` (``a`` and ``b`` included).

    The caller's ``route`` when it gives one; straight when ``direct(a, b)`` holds;
    else up to ``clearance_z`` (or the higher end), across, and down.
    """
    found = route(a, b) if route is not None else None
    if found is not None:
        return found
    if direct is not None and direct(a, b):
        return (a, b)
    z = max(clearance_z, a[2], b[2])
    return (a, (a[0], a[1], z), (b[0], b[1], z), b)


def polyline_length(points: Sequence[Vec3]) -> float:
    """Length of the polyline through ``points``, mm."""
    return sum(math.dist(p, q) for p, q in zip(points, points[1:], strict=False))


def travel_length(a: Vec3, b: Vec3, *, clearance_z: float, direct: Direct | None = None,
                  route: Route | None = None) -> float:
    """Length of :func:`travel_path`, mm."""
    return polyline_length(travel_path(a, b, clearance_z=clearance_z, direct=direct,
                                       route=route))


def cost_matrix(stops: Sequence[Stop], *, clearance_z: float, direct: Direct | None = None,
                start: Vec3 | None = None, route: Route | None = None,
                cost: Cost = polyline_length) -> FloatArray:
    """Travel costs with a start node.

    Returns:
        (n + 1, n + 1) float: row/column 0 is the start (costs from it to each entry;
        all 0 without a start; nothing travels back to it), ``[i + 1, j + 1]`` the
        travel from stop ``i``'s exit to stop ``j``'s entry (``cost`` of
        :func:`travel_path`).
    """
    n = len(stops)
    costs = np.zeros((n + 1, n + 1))

    def one(a: Vec3, b: Vec3) -> float:
        return cost(travel_path(a, b, clearance_z=clearance_z, direct=direct, route=route))

    for j, b in enumerate(stops, start=1):
        if start is not None:
            costs[0, j] = one(start, b.entry)
        for i, a in enumerate(stops, start=1):
            if i != j:
                costs[i, j] = one(a.exit, b.entry)
    return costs


def tour_length(path: Sequence[int], costs: FloatArray) -> float:
    """Travel length of a node path (node 0 = the start) under ``costs``."""
    return float(sum(costs[a, b] for a, b in zip(path, path[1:], strict=False)))


def nearest_neighbour(costs: FloatArray) -> list[int]:
    """The nearest-neighbour node path from node 0; ties go to the lower index."""
    n = costs.shape[0]
    path = [0]
    free = np.ones(n, dtype=bool)
    free[0] = False
    for _ in range(n - 1):
        row = np.where(free, costs[path[-1]], np.inf)
        nxt = int(np.argmin(row))  # the first minimum: the lowest index
        path.append(nxt)
        free[nxt] = False
    return path


def two_opt_pass(path: list[int], costs: FloatArray) -> list[int] | None:
    """The best 2-opt move (reverse ``path[i..k]``, ``1 <= i < k``), or None.

    Directed costs: reversing a run also reverses every travel inside it, so the gain
    uses prefix sums of the forward and backward costs along the path.
    """
    p = np.asarray(path)
    m = len(p)
    if m < 3:
        return None
    fwd = np.concatenate(([0.0], np.cumsum(costs[p[:-1], p[1:]])))
    bwd = np.concatenate(([0.0], np.cumsum(costs[p[1:], p[:-1]])))
    i, k = np.triu_indices(m, 1)
    keep = i >= 1
    i, k = i[keep], k[keep]
    after = np.minimum(k + 1, m - 1)
    has_after = k + 1 < m
    delta = (costs[p[i - 1], p[k]] - costs[p[i - 1], p[i]]
             + np.where(has_after, costs[p[i], p[after]] - costs[p[k], p[after]], 0.0)
             + (bwd[k] - bwd[i]) - (fwd[k] - fwd[i]))
    best = int(np.argmin(delta))
    if delta[best] >= -IMPROVEMENT:
        return None
    a, b = int(i[best]), int(k[best])
    return path[:a] + path[a:b + 1][::-1] + path[b + 1:]


def or_opt_pass(path: list[int], costs: FloatArray) -> list[int] | None:
    """The first improving Or-opt move (runs of :data:`OR_OPT_RUNS`), or None."""
    m = len(path)
    for run in OR_OPT_RUNS:
        for i in range(1, m - run + 1):
            block = path[i:i + run]
            rest = path[:i] + path[i + run:]
            removed = (costs[path[i - 1], block[0]]
                       + (costs[block[-1], path[i + run]] if i + run < m else 0.0)
                       - (costs[path[i - 1], path[i + run]] if i + run < m else 0.0))
            for j in range(len(rest)):
                if j == i - 1:
                    continue  # the same place
                nxt = rest[j + 1] if j + 1 < len(rest) else None
                added = costs[rest[j], block[0]] + (
                    0.0 if nxt is None else costs[block[-1], nxt] - costs[rest[j], nxt])
                if added - removed < -IMPROVEMENT:
                    return rest[:j + 1] + block + rest[j + 1:]
    return None


def improve(path: list[int], costs: FloatArray) -> list[int]:
    """Apply 2-opt and Or-opt moves until neither shortens the node path."""
    while True:
        better = two_opt_pass(path, costs) or or_opt_pass(path, costs)
        if better is None:
            return path
        path = better


def order_stops(stops: Sequence[Stop], *, clearance_z: float, direct: Direct | None = None,
                start: Vec3 | None = None, route: Route | None = None,
                cost: Cost | None = None) -> Tour:
    """Order the stops: nearest neighbour, improved by 2-opt and Or-opt.

    Args:
        stops: the features, each with its entry and exit point.
        clearance_z: the clearance plane for travel that is not direct, mm.
        direct: whether a straight move between two points is clear (default: never).
        route: a clear travel below the clearance plane, when there is one (see
            :data:`Route`; tried before ``direct``).
        start: where the stylus is before the first stop (default: anywhere).
        cost: what a travel costs (see :data:`Cost`; default its length): the order
            minimises the sum.

    Returns:
        The order and its travel length, with the nearest-neighbour figures.
    """
    if not stops:
        return Tour((), 0.0, (), 0.0)
    matrix = partial(cost_matrix, stops, clearance_z=clearance_z, direct=direct, start=start,
                     route=route)
    lengths = matrix()
    costs = lengths if cost is None else matrix(cost=cost)
    nearest = nearest_neighbour(costs)
    best = improve(list(nearest), costs)
    return Tour(tuple(k - 1 for k in best[1:]), tour_length(best, lengths),
                tuple(k - 1 for k in nearest[1:]), tour_length(nearest, lengths))
