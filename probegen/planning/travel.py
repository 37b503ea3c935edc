"""Travel between revolved features, and the figures of the whole tour.

Between two features the stylus goes from the last safe point of one to the first safe
point of the next.  :class:`Linker` offers the straight move or a lift over what lies
between (:meth:`probegen.planning.reroute.Sweeper.lift`: up to the lowest local height
the collision check clears, across, down) when it is quicker than the clearance plane
(:func:`travel_time`: every move below the clearance plane at the positioning feed, the
move across the clearance plane at the rapid rate); otherwise the order
(:func:`probegen.planning.order.order_stops`, on these times) travels by the clearance
plane: up, across, down.  A link is looked for only where even the straight move would
be quicker than the clearance plane.  :func:`linked_nodes` writes the chosen travel into
the program: a feature reached by a link starts with the link's moves instead of the
rapid above its entry and the descent.

:func:`over_obstacles` does the same inside line and plane features: a move from one
contact's start point to the next that the collision check refuses (a boss between them)
becomes a lift over it.

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
from probegen.machine.profile import Feeds, MachineProfile
from probegen.planning.order import Stop
from probegen.planning.reroute import Sweeper
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


def travel_time(points: Sequence[Vec3], clearance_z: float, feeds: Feeds) -> float:
    """Nominal time (s) of a travel through ``points``: a level move at or above
    ``clearance_z`` at the rapid rate, every other move at the positioning feed (as
    :func:`linked_nodes` writes them; accelerations ignored)."""
    minutes = 0.0
    for p, q in pairwise(points):
        level = p[2] == q[2] and p[2] >= clearance_z
        minutes += math.dist(p, q) / (feeds.rapid if level else feeds.position)
    return 60.0 * minutes


def clearance_travel(a: Vec3, b: Vec3, clearance_z: float) -> tuple[Vec3, ...]:
    """Up from ``a`` to the clearance plane, across, down to ``b``."""
    z = max(clearance_z, a[2], b[2])
    return (a, (a[0], a[1], z), (b[0], b[1], z), b)


def stop_of(plan: Any) -> Stop:
    """The stop of a planned feature (``RevolvedPlan``): its first and last safe points
    (the points after its entry and before its exit at the clearance level)."""
    path = plan.plan.path
    return Stop(path[1].position, path[-2].position)


class Linker:
    """Clear links between the stops of one program, quicker than the clearance plane
    (memoised).  ``stops`` is kept for the callers' sake: every pair may be linked."""

    def __init__(self, sweeper: Sweeper, stops: Sequence[Stop], clearance_z: float,
                 feeds: Feeds | None = None) -> None:
        self.sweeper, self.clearance_z = sweeper, clearance_z
        self.feeds = feeds if feeds is not None else sweeper.feeds
        self._memo: dict[tuple[Vec3, Vec3], tuple[Vec3, ...] | None] = {}

    def time(self, points: Sequence[Vec3]) -> float:
        """:func:`travel_time` of a travel of this program, s."""
        return travel_time(points, self.clearance_z, self.feeds)

    def route(self, a: Vec3, b: Vec3) -> tuple[Vec3, ...] | None:
        """The points (``a`` and ``b`` included) of a clear link below the clearance
        plane from exit ``a`` to entry ``b`` that is quicker than the clearance plane,
        or None."""
        key = (a, b)
        if key not in self._memo:
            self._memo[key] = self._find(a, b)
        return self._memo[key]

    def _find(self, a: Vec3, b: Vec3) -> tuple[Vec3, ...] | None:
        above = self.time(clearance_travel(a, b, self.clearance_z))
        if self.time((a, b)) >= above:
            return None  # no link below the clearance plane can be quicker
        if not self.sweeper.refused(a, b) and self.sweeper.move(a, b) is None:
            return (a, b)
        # a lift at z is quicker than the clearance plane below this height
        across = math.hypot(b[0] - a[0], b[1] - a[1])
        ceiling = self.clearance_z - across * (1.0 - self.feeds.position / self.feeds.rapid) / 2
        points = self.sweeper.lift(a, b, min(ceiling, self.clearance_z))
        return points if points is not None and self.time(points) < above else None


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


def over_obstacles(nodes: Sequence[ir.Node], sweeper: Sweeper,
                   clearance_z: float) -> list[ir.Node]:
    """``nodes`` with every move of a line or plane feature from one contact's start
    point to the next that the collision check refuses (a boss or a wall between them)
    replaced by the lowest clear lift over it (:meth:`Sweeper.lift`), else by the
    clearance plane.  Other nodes and moves that clear come back unchanged."""
    out: list[ir.Node] = []
    for node in nodes:
        if isinstance(node, ir.FeatureBlock) and isinstance(node.feature,
                                                             ir.PlaneDef | ir.LineDef):
            node = replace(node, body=_over(node.body, sweeper, clearance_z))
        out.append(node)
    return out


def _over(body: Sequence[ir.Node], sweeper: Sweeper, clearance_z: float) -> tuple[ir.Node, ...]:
    """A planar block's body with its moves between contacts lifted where blocked."""
    out: list[ir.Node] = []
    pos: Vec3 | None = None
    for k, node in enumerate(body):
        if not isinstance(node, ir.Move) or any(isinstance(c, ir.Var) for c in node.target):
            out.append(node)
            continue
        target: Vec3 = tuple(float(c) for c in node.target)  # type: ignore[assignment,arg-type]
        after_touch = k > 0 and isinstance(body[k - 1], ir.Move) and (
            body[k - 1].mode is ir.MoveMode.RETRACT)  # type: ignore[union-attr]
        if (pos is not None and after_touch and node.mode is ir.MoveMode.PROTECTED
                and target[2] < clearance_z
                and sweeper.move(pos, target) is not None):
            points = (sweeper.lift(pos, target, clearance_z)
                      or clearance_travel(pos, target, clearance_z))
            out += [ir.Move(q, ir.MoveMode.PROTECTED) for q in points[1:]]
        else:
            out.append(node)
        pos = target
    return tuple(out)


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
