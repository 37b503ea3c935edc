"""Revolved features in any orientation the machine reaches, with the stylus that fits
(issue 17): plan one spec feature (:func:`plan_oriented`) and lay out the planned features
of a program in (stylus, orientation) groups with their ``ir.SelectStylus`` and
``ir.Orient`` nodes between them (:func:`grouped_nodes`).

A feature whose axis is along +Z and reachable from above is planned as it always was, on
the part as loaded; another is resolved on the part as loaded (its axis, which end is
open: out of material), then planned in the frame of the approach from that end
(:func:`probegen.planning.orient.orientation_for`) on ``part.turned(R)`` at the frame's
clearance level, exactly as a vertical feature.  Its plan, nodes and definition are in
frame coordinates; :func:`probegen.ir.frames.in_work` maps them back.

A feature a CMM head reaches only at the nearest index off its axis
(:attr:`probegen.planning.orient.Orientation.exact`) is planned so in its exact frame
``E``, then expressed in the index's frame ``I`` (:func:`at_index`: ``p_I = Iᵀ·E·p_E``,
its moves up to the clearance level lengthened along its axis to the index frame's
level) and checked there against ``part.turned(I)`` with the stylus along the index's
axis: the touches stay square to the feature, the stylus stands tilted.  Features of one
index share its frame and clearance level whatever their own axes.
"""

from __future__ import annotations

from collections.abc import Callable, Hashable, Sequence
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any

import numpy as np

from probegen import ir
from probegen.errors import CollisionError, PlanningError, ProbegenError
from probegen.ir import frames
from probegen.machine.profile import Head, MachineProfile, Stylus
from probegen.planning.collision import obstacle_for, probe_stylus
from probegen.planning.orient import (
    Orientation,
    can_orient,
    changes,
    frame_clearance,
    head_direction,
    identity_of,
    index_height,
    needs_index,
    order_groups,
    orient_name,
    orient_node,
    orientation_for,
    over_point,
    pick_stylus,
    select_node,
    tilt_bound,
    to_frame,
    to_work,
)
from probegen.planning.revolved import PathKind, PathPoint
from probegen.planning.revolved_plan import (
    RevolvedPlan,
    check_alone,
    find_owner,
    plan_revolved,
    resolved_in,
    unrouted,
)
from probegen.planning.styli import profile_with, rack_order, stylus_named
from probegen.planning.tilted import MOST_PLANS, TRIED, screen, touches_in_work, view_of
from probegen.planning.well_posed import free_fit
from probegen.spec.model import RevolvedSpec

if TYPE_CHECKING:
    from probegen.cad import Part

OPEN_PROBE = 0.05
"""How far beyond an end of a feature (mm, along its axis) the open-end test looks."""


@dataclass(frozen=True, slots=True)
class OrientedPlan:
    """A revolved feature planned in its orientation with its stylus.

    Attributes:
        plan: the plan, in the frame's coordinates (``plan.spec`` is the spec's feature).
        orientation: the orientation (the identity for a vertical feature).
        stylus: the stylus of the rack it is measured with.
        part: the part in the frame (``part.turned(R)``; the part itself for the
            identity).
        clearance_z: the frame's clearance level (frame Z), mm.
    """

    plan: RevolvedPlan
    orientation: Orientation
    stylus: Stylus
    part: Part
    clearance_z: float

    @property
    def group(self) -> tuple[str, Hashable]:
        """The (stylus label, orientation key) group of the feature."""
        return (self.stylus.label, self.orientation.key)


def forced_stylus(feature: RevolvedSpec) -> str | None:
    """The stylus label a spec feature forces (the ``stylus =`` key, when the spec has
    it), or None."""
    value = getattr(feature, "stylus", None)
    return value if isinstance(value, str) else None


def approaches(owner: Any, part: Part) -> list[ir.Vec3]:
    """The approach directions of a recognised feature, best first: along its axis out
    of each end.  A bore's end must be open (a point :data:`OPEN_PROBE` beyond it on the
    axis out of material; both ends when the model has no solid); a boss, a shaft or a
    fillet is approached beside its surface, so both ends are tried (the planner and the
    collision check decide), the open ones first.  Then the more upward first."""
    axis = np.asarray(owner.axis, dtype=np.float64)
    low, high = owner.extent
    out: list[tuple[bool, float, ir.Vec3]] = []
    for sign, end in ((1.0, high), (-1.0, low)):
        beyond = np.asarray(owner.centre_at(end)) + sign * OPEN_PROBE * axis
        closed = part.exact.inside(beyond) is True
        if closed and owner.inner:
            continue
        a = tuple(float(sign * v) for v in axis)
        out.append((closed, -a[2], a))  # type: ignore[arg-type]
    return [a for *_, a in sorted(out, key=lambda t: t[:2])]


def cap_opening(owner: Any, part: Part) -> ir.Vec3:
    """The direction a sphere's face opens to (unit, work coordinates): out of the
    material from the face's pole (its record's axis points from the centre to the
    face's centre of mass: a ball's cap opens along it, a cavity's against it)."""
    from probegen import cad

    axis = cad.face_by_id(part.model, owner.faces[0]).axis
    sign = -1.0 if owner.inner else 1.0
    return (sign * axis[0] + 0.0, sign * axis[1] + 0.0, sign * axis[2] + 0.0)


def reorientable(owner: Any, machine: MachineProfile) -> bool:
    """Whether a recognised feature not reachable from above may be in another
    orientation: the machine turns its probe and the feature has an axis (not a sphere)."""
    return can_orient(machine) and owner.type != "sphere"


def in_frame(feature: RevolvedSpec, rotation: frames.Rotation) -> RevolvedSpec:
    """The spec feature as the turned part sees it (``at`` turned into the frame)."""
    if feature.at is None:
        return feature
    return replace(feature, at=frames.apply_t(rotation, feature.at))


def _planner(feature: RevolvedSpec, part: Part, clearance_z: float
             ) -> Callable[[MachineProfile], RevolvedPlan]:
    """Plan ``feature`` on ``part`` at ``clearance_z`` with a given profile."""
    return lambda machine: plan_revolved(feature, part, machine, clearance_z)


def plan_oriented(feature: RevolvedSpec, part: Part | None, machine: MachineProfile,
                  clearance_z: float) -> OrientedPlan:
    """Plan one revolved feature in the orientation that reaches it, with the largest
    stylus of the rack that plans it (or the one the spec forces).

    Raises:
        PlanningError: no orientation reaches it (the reason of each tried), or it does
            not plan (the first reason).
        ModelError: the face is not a face of the right feature.
    """
    force = forced_stylus(feature)
    if part is None:
        plan_revolved(feature, part, machine, clearance_z)  # the SpecError of no model
        raise AssertionError("unreachable")  # pragma: no cover
    owner = find_owner(feature, part)
    try:
        return _plan_along(feature, owner, part, machine, clearance_z, force)
    except PlanningError:
        tilted = part.memo(("tilted plan", feature, machine, clearance_z),
                           lambda: _plan_tilted(feature, owner, part, machine, clearance_z,
                                                force))
        if tilted is None:
            raise
        return tilted


def _plan_along(feature: RevolvedSpec, owner: Any, part: Part, machine: MachineProfile,
                clearance_z: float, force: str | None) -> OrientedPlan:
    """:func:`plan_oriented` with the probe along the feature's axis (or at the head's
    index nearest it)."""
    if owner.accessible or not reorientable(owner, machine):
        s, plan = pick_stylus(machine, _planner(feature, part, clearance_z), force)
        return OrientedPlan(plan, identity_of(machine), s, part, clearance_z)
    reasons: list[str] = []
    errors: list[ProbegenError] = []
    for a in approaches(owner, part):
        o = orientation_for(machine, a)
        if isinstance(o, str):
            reasons.append(o)
            continue
        exact = Orientation(o.plan_rotation)
        planner = _planner(in_frame(feature, exact.rotation), part.turned(exact.rotation),
                           frame_clearance(part, exact, clearance_z))
        turned = part.turned(o.rotation)
        clear = frame_clearance(part, o, clearance_z)
        collisions: list[CollisionError] = []
        if o.exact is not None:
            planner = _at_index(planner, feature, o, turned, clear, collisions)
        try:
            s, plan = pick_stylus(machine, planner, force)
        except ProbegenError as exc:
            errors.append(collisions[0] if collisions else exc)
            continue
        if feature.actions.work_offset is not None or feature.actions.align is not None:
            raise PlanningError(f"{feature.where}: update_work_offset and align are computed "
                                "in work X and Y, found a feature measured in a turned frame "
                                f"({orient_name(o, 1)}): measure it from above or drop the "
                                "action")
        return OrientedPlan(replace(plan, spec=feature), o, s, turned, clear)
    if errors:
        raise errors[0]
    why = "; ".join(dict.fromkeys(reasons)) or "no open end to approach it from"
    raise PlanningError(f"{feature.where}: {why}")


def _plan_tilted(feature: RevolvedSpec, owner: Any, part: Part, machine: MachineProfile,
                 clearance_z: float, force: str | None) -> OrientedPlan | None:
    """A feature the probe along its axis does not measure, probed with the stylus
    leaning off the axis (:mod:`probegen.planning.tilted`): a CMM's head at one of its
    indices, a five-axis machine's tilted work plane (G68.2) along a direction of the
    same grid (:func:`lean_grid`: every :data:`LEAN_STEP` deg within the tilt axis's
    range, :func:`~probegen.planning.orient.orientation_for` turning each into the
    machine's angles).  Out of each end :func:`approaches` gives, with each stylus of the
    rack (largest first, or the one the spec forces), the best
    :data:`~probegen.planning.tilted.TRIED` directions
    :func:`~probegen.planning.tilted.screen` finds, until one plans (its path checked
    against the part and the table under it, :mod:`probegen.planning.table`: a
    countersink facing down is not reached from below the part); None when none does, on
    a machine that cannot lean the probe, or for a feature with a work-offset or align
    action."""
    head = machine.head if machine.head is not None else lean_grid(machine)
    if head is None or feature.actions.work_offset is not None or (
            feature.actions.align is not None):
        return None
    sphere = owner.type == "sphere"  # never planned along an axis: the least tilt is 0
    ends = [cap_opening(owner, part)] if sphere else approaches(owner, part)
    styli = rack_order(machine) if force is None else (stylus_named(machine, force,
                                                                    "stylus"),)
    obstacle = obstacle_for(part, [])
    tries = 0
    for a in ends:
        exact = frames.frame_for(a)
        own = part if frames.is_identity(exact) else part.turned(exact)
        own_clear = frame_clearance(part, Orientation(exact), clearance_z)
        own_feature = in_frame(feature, exact)
        for s in styli:
            m = profile_with(machine, s)
            touches = unrouted(own_feature, own, m, own_clear)
            if touches is None:
                continue
            ranked = screen(touches_in_work(touches, exact), feature.kind, a, obstacle,
                            probe_stylus(m, m.probe.ball_radius), m.margin / 2.0, head,
                            -1.0 if sphere else tilt_bound(head), free_fit(m), TRIED)
            for angles in ranked[:TRIED]:
                o = _leaning(machine, angles, exact)
                if o is None:
                    continue
                tries += 1
                if tries > MOST_PLANS:
                    return None
                turned = part if o.identity else part.turned(o.rotation)
                clear = frame_clearance(part, o, clearance_z)
                try:
                    plan = plan_revolved(own_feature, own, m, own_clear,
                                         view_of(o.rotation, exact, turned, clear))
                except PlanningError:
                    continue
                return OrientedPlan(replace(plan, spec=feature), o, s, turned, clear)
    return None


LEAN_STEP = 7.5
"""The step (deg) of the directions a five-axis machine leans the probe in to reach a
feature off its axis (:func:`lean_grid`): a CMM head's usual index step."""


def lean_grid(machine: MachineProfile) -> Head | None:
    """The directions a five-axis machine's tilted work plane may lean the probe in,
    as a head's grid (:func:`~probegen.planning.tilted.head_indices`): A from vertical
    to the tilt axis's reach, B a whole turn, every :data:`LEAN_STEP` deg; None without
    a ``[tilt]``."""
    if machine.tilt is None:
        return None
    low, high = machine.tilt.tilt_range
    return Head(a=(0.0, max(high, -low)), b=(-180.0, 180.0), step=LEAN_STEP)


def _leaning(machine: MachineProfile, angles: tuple[float, float],
             exact: frames.Rotation) -> Orientation | None:
    """The orientation that probes along the grid direction ``angles`` (``(A, B)``,
    deg) a feature planned in frame ``exact``: a CMM head's index, or a five-axis
    machine's tilted plane (None where its axes do not reach it)."""
    direction = head_direction(*angles)
    if machine.head is not None:
        return Orientation(frames.frame_for(direction), angles, (), exact)
    o = orientation_for(machine, direction)
    return None if isinstance(o, str) else replace(o, exact=exact)


def _at_index(planner: Callable[[MachineProfile], RevolvedPlan], feature: RevolvedSpec,
              o: Orientation, part: Part, clearance_z: float,
              collisions: list[CollisionError]) -> Callable[[MachineProfile], RevolvedPlan]:
    """``planner`` (in the exact frame of ``o``) with its plan expressed at the head's
    index (:func:`at_index`) and checked there with the profile's stylus against
    ``part`` (turned to the index frame) at its ``clearance_z``.  A collision there names
    the index and the tilt, and is kept in ``collisions``: when no stylus plans, the
    first one (the largest ball that plans in the exact frame) is the reason, not a ball
    too large for the feature."""
    def plan_with(machine: MachineProfile) -> RevolvedPlan:
        plan = at_index(planner(machine), o, clearance_z)
        try:
            check_alone(plan, part, machine, clearance_z)
        except CollisionError as exc:
            error = CollisionError(f"{feature.where}: at the nearest head index "
                                   f"{orient_name(o, 0)} the stylus stands {o.tilt:.2f} deg "
                                   f"off the feature's axis: it collides: {exc}")
            collisions.append(error)
            raise error from None
        return plan

    return plan_with


LEVEL_KINDS = (PathKind.ENTRY, PathKind.EXIT, PathKind.CLEAR)
"""The path points at the clearance level, moved along the feature's axis to the index
frame's level by :func:`at_index`."""


def at_index(plan: RevolvedPlan, o: Orientation, clearance_z: float) -> RevolvedPlan:
    """A plan made in ``o``'s exact frame ``E`` (``o.exact``) in its index frame ``I``
    (``o.rotation``): every point ``p_I = Iᵀ·E·p_E``, every normal and axis turned alike;
    the points at the clearance level (entry, exit, the moves over it between arcs)
    moved along the feature's axis to the index frame's ``clearance_z`` (frame Z, mm), so
    the stylus still leaves the feature along its axis and crosses level in the index
    frame.  The M2 section figures (``plan.plan.sections``: radii, retracts, azimuths
    about the axis) are those of the exact frame: they do not depend on the frame.

    Raises:
        PlanningError: a point of the plan lies above the index frame's clearance level.
    """
    assert o.exact is not None
    turn = ir.Orient("EXACT", frames.product_t(o.rotation, o.exact))
    axis = frames.direction_to_work(turn, (0.0, 0.0, 1.0))

    def moved(p: PathPoint) -> PathPoint:
        q = frames.to_work(turn, p.position)
        if p.kind in LEVEL_KINDS:
            t = (clearance_z - q[2]) / axis[2]
            q = (q[0] + t * axis[0], q[1] + t * axis[1], clearance_z)
        return replace(p, position=q,
                       contact=None if p.contact is None else frames.to_work(turn, p.contact),
                       normal=None if p.normal is None else frames.direction_to_work(
                           turn, p.normal))

    path = tuple(moved(p) for p in plan.plan.path)
    top = max(p.position[2] for p in path)
    if top > clearance_z + 1e-9:
        raise PlanningError(f"{plan.spec.where}: at the head index {orient_name(o, 0)}: a "
                            f"point of the plan at frame z = {top:.3f}, expected none above "
                            f"the clearance level {clearance_z:.3f}")
    return replace(plan, resolved=resolved_in(turn, plan.resolved),
                   plan=replace(plan.plan, path=path, clear_z=clearance_z),
                   definition=frames.definition_in_work(turn, plan.definition))


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


@dataclass(frozen=True, slots=True)
class _Where:
    """The probe's last known position while walking a body: work coordinates (None when
    not known exactly: a run-time coordinate or a move relative to a local frame)."""

    work: np.ndarray | None
    frame: ir.Orient | None


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
