"""The planned revolved features of a program laid out in (stylus, orientation) groups
(:func:`grouped_nodes`: each group's tour with the ``ir.SelectStylus`` and ``ir.Orient``
nodes between them, ordered for the fewest changes), and the route of every change
taken at the index height written out as moves the collision check clears
(:func:`with_index_moves`: up to the index height, the change, over to the next target).
"""

from __future__ import annotations

from collections.abc import Callable, Hashable, Sequence
from dataclasses import dataclass

import numpy as np

from probegen import ir
from probegen.errors import PlanningError
from probegen.ir import frames
from probegen.machine.profile import MachineProfile, Stylus
from probegen.planning.orient import (
    changes,
    identity_of,
    index_height,
    needs_index,
    order_groups,
    orient_name,
    orient_node,
    over_point,
    select_node,
    to_frame,
    to_work,
)
from probegen.planning.oriented import OrientedPlan


@dataclass(frozen=True, slots=True)
class GroupedNodes:
    """The revolved features' nodes in groups, with what the grouping cost.

    Attributes:
        nodes: the top-level nodes (``SelectStylus``, ``Orient`` and each group's tour).
        plans: the plans in measuring order.
        stylus_changes: ``SelectStylus`` nodes (the return to the first stylus included).
        orientation_changes: ``Orient`` nodes (the return to the vertical included).
    """

    nodes: tuple[ir.Node, ...]
    plans: tuple[OrientedPlan, ...]
    stylus_changes: int
    orientation_changes: int


Tour = Callable[[Sequence[OrientedPlan]], tuple[list[ir.Node], list[OrientedPlan]]]
"""Lays out one group's plans (one stylus, one orientation) as today's tour: its nodes
and the plans in tour order."""


def grouped_nodes(plans: Sequence[OrientedPlan], machine: MachineProfile,
                  clearance_z: float, tour: Tour) -> GroupedNodes:
    """Group ``plans`` by (stylus, orientation), order the groups for the fewest changes
    (:func:`probegen.planning.orient.order_groups`) from the program's start (the
    ``[probe]`` stylus, vertical) and lay out each with ``tour``; a ``SelectStylus`` and
    an ``Orient`` where they change (the stylus first, at the old frame's clearance
    level), and at the end back to the start stylus and the vertical (at the spec's
    ``clearance_z``)."""
    first = machine.stylus
    identity = identity_of(machine)
    groups: dict[tuple[str, Hashable], list[OrientedPlan]] = {}
    for p in plans:
        groups.setdefault(p.group, []).append(p)
    start = (first.label, identity.key)
    order = order_groups(list(groups), start, identity.key)
    nodes: list[ir.Node] = []
    done: list[OrientedPlan] = []
    here = start
    names: dict[Hashable, str] = {identity.key: orient_name(identity, 0)}
    for key in order:
        members = groups[key]
        head = members[0]
        if key[0] != here[0]:
            nodes.append(select_node(head.stylus))
        if key[1] != here[1]:
            name = names.setdefault(key[1], orient_name(head.orientation, len(names)))
            nodes.append(orient_node(head.orientation, name, head.clearance_z))
        laid, ordered = tour(members)
        nodes += laid
        done += ordered
        here = key
    if here[0] != start[0]:
        nodes.append(select_node(first))
    if here[1] != start[1]:
        nodes.append(orient_node(identity, names[identity.key], clearance_z))
    stylus, orient = changes(order, start, identity.key)
    return GroupedNodes(tuple(nodes), tuple(done), stylus, orient)


# ------------------------------------------------------- the route of a change


def _target(move: ir.Move, frame: ir.Orient | None, local: int) -> np.ndarray | None:
    """A move's target in work coordinates, None when it is not a plain point of the
    frame in force (run-time coordinates, inside a local frame)."""
    if local:
        return None
    point = [c for c in move.target if isinstance(c, float | int)]
    return to_work(frame, np.array(point, dtype=np.float64)) if len(point) == 3 else None


def _first_target(nodes: Sequence[ir.Node], frame: ir.Orient | None) -> np.ndarray | None:
    """The work point of the first move of ``nodes`` (None: unknown or no move)."""
    for node in ir.walk(tuple(nodes)):
        if isinstance(node, ir.LocalFrame | ir.Orient):
            return None
        if isinstance(node, ir.Move):
            return _target(node, frame, 0)
    return None


def with_index_moves(body: Sequence[ir.Node], top: float, machine: MachineProfile,
                     start: Stylus) -> tuple[ir.Node, ...]:
    """``body`` with the route of every change taken at the index height written out
    (:func:`probegen.planning.orient.needs_index`: every ``Orient``, a CMM's stylus
    change), so that the program holds every move the collision check clears.

    A run of top-level changes (a ``SelectStylus`` and an ``Orient``) becomes: a rapid
    straight up in work Z from the last position to the index height
    (:func:`probegen.planning.orient.index_height` of the longest stylus of the run and
    the one before it), in the old frame's coordinates; the changes; a rapid to the over
    point (:func:`probegen.planning.orient.over_point` of the next move's target), in the
    new frame's coordinates; then the body's own next move down.  On a machine tool a
    stylus change is no change taken at the index height: it stays at the old frame's
    clearance level, before the move up (the dialect's tool change comes back to where
    it left).  The probe already at or above the index height does not move up; the
    next move at or above it needs no over point.  When the last position is not known
    exactly (a run-time coordinate, a local frame, the program's start), the move up
    goes to the index height over the next target instead; with no next move (the end
    of the program) there is no over point.  ``top``: the work Z of the part's top
    (:func:`probegen.planning.orient.top_of`); ``start``: the stylus at the program's
    start.

    Raises:
        PlanningError: neither the position before a change nor the move after it is
            known.
    """
    nodes = list(body)
    out: list[ir.Node] = []
    frame: ir.Orient | None = None
    local = 0
    stylus = (start.length, start.ball_radius)
    here: np.ndarray | None = None
    k = 0
    while k < len(nodes):
        node = nodes[k]
        if not needs_index(node, machine):
            for n in ir.walk((node,)):
                if isinstance(n, ir.LocalFrame):
                    local += 1
                elif isinstance(n, ir.RestoreFrame):
                    local -= 1
                elif isinstance(n, ir.Move):
                    here = _target(n, frame, local)
                elif isinstance(n, ir.SelectStylus):
                    stylus = (n.length, n.ball_diameter / 2.0)
            out.append(node)
            k += 1
            continue
        end = k
        while end < len(nodes) and isinstance(nodes[end], ir.Orient | ir.SelectStylus):
            end += 1
        run = nodes[k:end]
        new = _frame_after(run, frame)
        out += _route(run, here, frame, new, nodes[end:], top, machine, stylus)
        for n in run:
            if isinstance(n, ir.SelectStylus):
                stylus = (n.length, n.ball_diameter / 2.0)
        frame, here = new, None
        k = end
    return tuple(out)


def _frame_after(run: Sequence[ir.Node], frame: ir.Orient | None) -> ir.Orient | None:
    """The frame in force after a run of changes (None: the work frame)."""
    for n in run:
        if isinstance(n, ir.Orient):
            frame = None if frames.is_identity(n.rotation) and not any(n.origin) else n
    return frame


def _route(run: Sequence[ir.Node], here: np.ndarray | None, frame: ir.Orient | None,
           new: ir.Orient | None, after: Sequence[ir.Node], top: float,
           machine: MachineProfile, stylus: tuple[float, float]) -> list[ir.Node]:
    """One run of changes from ``frame`` to ``new`` with its move up before and its move
    over after; ``stylus``: the (length, ball radius) in force before it, mm."""
    lengths = [stylus] + [(n.length, n.ball_diameter / 2.0) for n in run
                          if isinstance(n, ir.SelectStylus)]
    height = max(index_height(top, length, ball, machine) for length, ball in lengths)
    target = _first_target(after, new)
    if here is None and target is None:
        names = ", ".join(n.name if isinstance(n, ir.Orient) else n.label for n in run
                          if isinstance(n, ir.Orient | ir.SelectStylus))
        raise PlanningError(f"change {names}: the probe's position before it and the move "
                            "after it are both unknown (run-time coordinates): expected a "
                            "plain move on either side to route it at the index height")
    rotation = new.rotation if new is not None else frames.IDENTITY
    over = over_point(target, height, rotation) if target is not None else None
    if here is not None:
        up = np.array([here[0], here[1], max(float(here[2]), height)])
    else:
        assert over is not None
        up = over
    moved = here is None or not np.allclose(up, here, atol=1e-9)
    out: list[ir.Node] = [*([_rapid(to_frame(frame, up))] if moved else []), *run]
    if over is not None and target is not None and not np.allclose(over, target, atol=1e-9):
        out.append(_rapid(to_frame(new, over)))
    return out


def _rapid(p: np.ndarray) -> ir.Move:
    """A rapid to frame point ``p``, rounded to 1e-9 mm (no ``-0.0``, no float noise)."""
    return ir.Move(tuple(round(float(c), 9) + 0.0 for c in p), ir.MoveMode.RAPID)  # type: ignore[arg-type]
