"""Revolved features in any orientation the machine reaches, with the stylus that fits
(issue 17): plan one spec feature (:func:`plan_oriented`); the planned features of a
program are laid out in (stylus, orientation) groups by
:func:`probegen.planning.groups.grouped_nodes`.

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

from collections.abc import Callable, Hashable
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
    frame_clearance,
    head_direction,
    identity_of,
    orient_name,
    orientation_for,
    pick_stylus,
    tilt_bound,
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
