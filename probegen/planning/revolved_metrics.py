"""Method M2, the metrics: path length and cycle time of a plan against the baseline.

Owns the segments of a path, the common baseline (up to the clearance level after each
touch), the lower bound (the shortest collision-free path through the same touches),
the cycle-time estimate from the machine's feeds and :func:`compare`, which puts the
three side by side (``docs/m2.md``).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from itertools import pairwise

import numpy as np
from numpy.typing import ArrayLike

from probegen.machine.profile import MachineProfile
from probegen.planning.revolved_geometry import TWO_PI, SectionPlan
from probegen.planning.revolved_path import FeaturePlan, PathKind, PathPoint


@dataclass(frozen=True, slots=True)
class Segment:
    """One straight move of a path: ``rapid``, ``protected``, ``touch`` or ``retract``."""

    kind: str
    length: float


@dataclass(frozen=True, slots=True)
class Figures:
    """Path length (mm) and estimated time (s)."""

    length: float
    time: float


@dataclass(frozen=True, slots=True)
class Comparison:
    """The plan against the common baseline and the lower bound (see :func:`compare`)."""

    plan: Figures
    baseline: Figures
    lower_bound: Figures


def path_length(points: ArrayLike) -> float:
    """Length of the polyline through ``points : (k, 3) float``, mm."""
    p = np.asanyarray(points, dtype=np.float64).reshape(-1, 3)
    return float(np.linalg.norm(np.diff(p, axis=0), axis=1).sum())


def _dist(a: Sequence[float], b: Sequence[float]) -> float:
    return math.dist(a, b)


def plan_segments(plan: FeaturePlan) -> tuple[Segment, ...]:
    """The plan's moves: ``touch`` into a target, ``retract`` out, ``protected`` else."""
    return tuple(Segment(_kind(a, b), _dist(a.position, b.position))
                 for a, b in pairwise(plan.path))


def baseline_segments(plan: FeaturePlan) -> tuple[Segment, ...]:
    """The common baseline: the same touches, but after each one up to the clearance
    level (protected), across there (rapid) and down to the next safe point
    (protected)."""
    touches = [(a.position, b.position) for a, b in pairwise(plan.path)
               if b.kind is PathKind.TARGET]
    z = plan.clear_z
    out: list[Segment] = []
    previous = plan.path[0].position
    for k, (safe, target) in enumerate(touches):
        if k:
            out.append(Segment("rapid", math.hypot(safe[0] - previous[0],
                                                   safe[1] - previous[1])))
        out.append(Segment("protected", z - safe[2]))
        d = _dist(safe, target)
        out += [Segment("touch", d), Segment("retract", d), Segment("protected", z - safe[2])]
        previous = safe
    return tuple(out)


def _geodesic(plan: SectionPlan, delta: float, chord: float) -> float:
    """Shortest path between two safe-circle points ``delta`` apart that stays out of
    the offset surface (outer: wraps the offset circle where the chord cuts it)."""
    if plan.alpha_max is None:
        return chord
    c = math.cos(plan.section.tilt)
    rs = plan.safe_radius
    rho = rs - plan.retract / c
    free = 2.0 * math.acos(rho / rs)
    if abs(delta) <= free:
        return chord
    return 2.0 * math.sqrt(rs * rs - rho * rho) + rho * (abs(delta) - free)


def lower_bound_segments(plan: FeaturePlan) -> tuple[Segment, ...]:
    """The lower bound: the plan with every run of transitions between two points of a
    safe circle replaced by the shortest collision-free path between them (the chord,
    or for an outer section where the chord cuts the offset circle, the tangents and
    the arc of that circle).  No path through the same touches in the same order that
    avoids the part is shorter."""
    path = plan.path
    out: list[Segment] = []
    i = 0
    while i < len(path) - 1:
        j = i + 1
        while path[j].kind is PathKind.TRANSITION:
            j += 1
        a, b = path[i], path[j]
        if j > i + 1 and a.section == b.section:
            turn = sum(_wrap(path[k + 1].azimuth, path[k].azimuth) for k in range(i, j))
            chord = _dist(a.position, b.position)
            out.append(Segment("protected", _geodesic(plan.sections[a.section], turn, chord)))
        else:
            out += [Segment(_kind(path[k], path[k + 1]),
                            _dist(path[k].position, path[k + 1].position))
                    for k in range(i, j)]
        i = j
    return tuple(out)


def _kind(a: PathPoint, b: PathPoint) -> str:
    """The segment kind of the move ``a → b`` (see :class:`Segment`)."""
    if b.kind is PathKind.TARGET:
        return "touch"
    return "retract" if a.kind is PathKind.TARGET else "protected"


def _wrap(b: float | None, a: float | None) -> float:
    """Signed azimuth step from ``a`` to ``b`` in (-π, π]."""
    if a is None or b is None:
        return 0.0
    return (b - a + math.pi) % TWO_PI - math.pi


def cycle_time(segments: Sequence[Segment], *, rapid: float, position_feed: float,
               probe_feed: float, approach: float, overtravel: float = 0.0) -> float:
    """Estimated time of a path, s (feeds in mm/min).

    ``rapid`` moves at the rapid rate; ``protected`` and ``retract`` moves at the
    positioning feed; a ``touch`` covers its last ``approach`` mm (and ``overtravel``,
    0 for the nominal estimate, the probe's overtravel for the worst case) at the
    probing feed and the rest at the positioning feed.  Accelerations are ignored.
    """
    minutes = 0.0
    for s in segments:
        if s.kind == "rapid":
            minutes += s.length / rapid
        elif s.kind == "touch":
            slow = min(approach, s.length)
            minutes += (s.length - slow) / position_feed + (slow + overtravel) / probe_feed
        else:
            minutes += s.length / position_feed
    return 60.0 * minutes


def compare(plan: FeaturePlan, machine: MachineProfile) -> Comparison:
    """Length and nominal time of the plan, the baseline and the lower bound."""
    feeds = machine.feeds

    def figures(segments: Sequence[Segment]) -> Figures:
        time = cycle_time(segments, rapid=feeds.rapid, position_feed=feeds.position,
                          probe_feed=feeds.probe, approach=machine.probe.approach)
        return Figures(sum(s.length for s in segments), time)

    return Comparison(figures(plan_segments(plan)), figures(baseline_segments(plan)),
                      figures(lower_bound_segments(plan)))
