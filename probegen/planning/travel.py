"""Travel between revolved features, and the figures of the whole tour.

Between two features the stylus goes from the last safe point of one to the first safe
point of the next.  :class:`Linker` offers, for the nearest few features only
(:data:`NEIGHBOURS`), the straight move or a lift to a local height
(:data:`probegen.planning.reroute.LIFT_HEIGHTS` above the higher end) when the collision
check clears it; otherwise the order (:func:`probegen.planning.order.order_stops`)
travels by the clearance plane: up, across, down.  :func:`linked_nodes` writes the
chosen travel into the program: a feature reached by a link starts with the link's
moves instead of the rapid above its entry and the descent.

:func:`tour_figures` compares the whole tour (features and travel, from above the first
feature's entry to above the last one's exit) with the common baseline (every touch
from and back to the clearance plane, travel at the clearance plane) and with the lower
bound (each feature's lower bound; between features the quicker of the straight move at
the positioning feed, as every move below the clearance plane, and the clearance-plane
travel, whether or not either clears).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace
from itertools import pairwise
from typing import Any

from probegen import ir
from probegen.machine.profile import MachineProfile
from probegen.planning.order import Stop
from probegen.planning.reroute import LIFT_HEIGHTS, Sweeper
from probegen.planning.revolved import (
    Comparison,
    Figures,
    Segment,
    baseline_segments,
    cycle_time,
    lower_bound_segments,
)
from probegen.planning.revolved_spec import revolved_nodes

Vec3 = tuple[float, float, float]
NEIGHBOURS = 6
"""Each feature is linked directly only to this many nearest features (by the straight
distance from its exit to their entries): the others are far enough that the
clearance plane costs little more, and checking every pair would cost n² sweeps."""


def stop_of(plan: Any) -> Stop:
    """The stop of a planned feature (``RevolvedPlan``): its first and last safe points
    (the points after its entry and before its exit at the clearance level)."""
    path = plan.plan.path
    return Stop(path[1].position, path[-2].position)


class Linker:
    """Clear links between the stops of one program (memoised)."""

    def __init__(self, sweeper: Sweeper, stops: Sequence[Stop], clearance_z: float) -> None:
        self.sweeper, self.clearance_z = sweeper, clearance_z
        self.near: dict[Vec3, set[Vec3]] = {}
        for a in stops:
            others = sorted((math.dist(a.exit, b.entry), b.entry) for b in stops if b != a)
            self.near[a.exit] = {e for _, e in others[:NEIGHBOURS]}
        self._memo: dict[tuple[Vec3, Vec3], tuple[Vec3, ...] | None] = {}

    def route(self, a: Vec3, b: Vec3) -> tuple[Vec3, ...] | None:
        """The points (``a`` and ``b`` included) of a clear link below the clearance
        plane from exit ``a`` to entry ``b``, or None."""
        if b not in self.near.get(a, ()):
            return None
        key = (a, b)
        if key not in self._memo:
            self._memo[key] = self._find(a, b)
        return self._memo[key]

    def _find(self, a: Vec3, b: Vec3) -> tuple[Vec3, ...] | None:
        if self.sweeper.move(a, b) is None:
            return (a, b)
        top = max(a[2], b[2])
        for h in LIFT_HEIGHTS:
            z = top + h
            if z >= self.clearance_z:
                break
            points = (a, (a[0], a[1], z), (b[0], b[1], z), b)
            if self.sweeper.path(points) is None:
                return points
        return None


def linked_nodes(plans: Sequence[Any], machine: MachineProfile, clearance_z: float,
                 linker: Linker | None) -> list[ir.Node]:
    """The nodes of the revolved features (``RevolvedPlan``s in measuring order), each
    reached from the previous one by its link where :class:`Linker` has one."""
    out: list[ir.Node] = []
    last: ir.FeatureBlock | None = None
    for k, p in enumerate(plans):
        rapid, block = revolved_nodes(p, machine, clearance_z)
        assert isinstance(block, ir.FeatureBlock)
        link = None
        if k and linker is not None:
            link = linker.route(stop_of(plans[k - 1]).exit, stop_of(p).entry)
        if link is None:
            if last is not None:
                out.append(last)
            out.append(rapid)
            last = block
            continue
        assert last is not None
        out.append(replace(last, body=last.body[:-1]))  # no climb to the exit
        moves = tuple(ir.Move(q, ir.MoveMode.PROTECTED) for q in link[1:])
        last = replace(block, body=moves + block.body[1:])  # no descent from the entry
    if last is not None:
        out.append(last)
    return out


def program_segments(nodes: Sequence[ir.Node], ball: float) -> tuple[Segment, ...]:
    """The moves of revolved-feature nodes (no run-time variables) as segments, from the
    first move's target on: rapid, protected, touch (its approach, to the ball centre
    ``ball`` mm off the contact) and retract."""
    out: list[Segment] = []
    pos: Sequence[float] | None = None
    for node in ir.walk(tuple(nodes)):
        if isinstance(node, ir.Move):
            target = [float(c) for c in node.target]  # type: ignore[arg-type]
            if pos is not None:
                kind = {ir.MoveMode.RAPID: "rapid", ir.MoveMode.RETRACT: "retract"}.get(
                    node.mode, "protected")
                out.append(Segment(kind, math.dist(pos, target)))
            pos = target
        elif isinstance(node, ir.Touch):
            out.append(Segment("touch", node.approach))
            pos = [float(c) + ball * n  # type: ignore[arg-type]
                   for c, n in zip(node.contact, node.normal, strict=True)]
    return tuple(out)


def tour_figures(plans: Sequence[Any], nodes: Sequence[ir.Node],
                 machine: MachineProfile, clearance_z: float) -> Comparison:
    """Length and nominal time of the whole tour of revolved features: ours (the
    program's moves), the baseline and the lower bound (see the module docstring)."""
    ours = list(program_segments(nodes, machine.probe.ball_radius))
    base: list[Segment] = []
    bound: list[Segment] = []
    for k, p in enumerate(plans):
        base += baseline_segments(p.plan)
        own = list(lower_bound_segments(p.plan))
        bound += own[(1 if k else 0):(len(own) - 1 if k < len(plans) - 1 else len(own))]
    feeds = machine.feeds

    def figures(segments: Sequence[Segment]) -> Figures:
        time = cycle_time(segments, rapid=feeds.rapid, position_feed=feeds.position,
                          probe_feed=feeds.probe, approach=machine.probe.approach)
        return Figures(sum(s.length for s in segments), time)

    for a, b in pairwise(plans):
        out, into = stop_of(a).exit, stop_of(b).entry
        across = Segment("rapid", math.hypot(into[0] - out[0], into[1] - out[1]))
        base.append(across)
        above = [Segment("protected", clearance_z - out[2]), across,
                 Segment("protected", clearance_z - into[2])]
        straight = [Segment("protected", math.dist(out, into))]
        bound += min(straight, above, key=lambda run: figures(list(run)).time)

    return Comparison(figures(ours), figures(base), figures(bound))
