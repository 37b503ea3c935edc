"""Free-form features of a spec (method M3 wired): face, guide points, touches, IR.

A spec feature of kind ``freeform`` names a model face (``face = N`` or ``at``); any
face type works (B-spline faces are what the method is for).  Planning:

1. guide points on the face (:func:`probegen.cad.freeform.guide_points`: grid, margin
   from every edge, holes avoided; grid points left out are kept with the reason);
2. touches per guide point (:mod:`probegen.planning.freeform`), the theoretical ball
   centres solved on the surface offset by the ball radius; a theoretical contact
   point outside the trimmed face refuses its guide point;
3. each guide point's moves (down from the *safe height* above the patch, the touches,
   up again) pass the collision check on their own: the fast conservative check of all
   guide points at once (:func:`probegen.planning.heightmap.clear_paths`), then the exact
   one (:func:`check_program`) for those it is unsure of, which refuses the guide point
   with its message (which part of the stylus, which face); refused guide points are
   reported, never dropped silently;
4. travel between guide points at the safe height (the face's highest point + ball
   radius + approach + the machine margin, at most the clearance plane), each such move
   checked, else by the clearance plane.

The part is set up by its work offset (no locating, no run-time variables).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from probegen import ir
from probegen.errors import CollisionError, PlanningError, SpecError
from probegen.machine.profile import MachineProfile
from probegen.planning.collision import Obstacle, check_program, obstacle_for
from probegen.planning.freeform import PlannedTouch, group_nodes, plan_touches
from probegen.planning.heightmap import clear_paths
from probegen.spec.model import FreeformSpec

if TYPE_CHECKING:
    from probegen.cad import Part

Vec3 = tuple[float, float, float]


@dataclass(frozen=True, slots=True)
class LeftOut:
    """A grid point or guide point that is not measured: ``guide`` (1-based; 0 for a
    grid point that never became a guide point), where (mm) and why."""

    guide: int
    point: Vec3
    reason: str


@dataclass(frozen=True, slots=True)
class FreeformPlan:
    """A planned free-form feature.

    Attributes:
        spec: the spec feature.
        face: the model face id.
        guides: the guide points measured: (index, point, outward normal).
        touches: every touch in program order.
        left_out: grid points and guide points not measured, with the reasons.
        safe_z: the travel height above the patch (ball centre), mm.
        definition: the IR feature.
        nodes: a rapid above the entry, then the feature block.
    """

    spec: FreeformSpec
    face: int
    guides: tuple[tuple[int, Vec3, Vec3], ...]
    touches: tuple[PlannedTouch, ...]
    left_out: tuple[LeftOut, ...]
    safe_z: float
    definition: ir.FreeformDef
    nodes: tuple[ir.Node, ...]

    @property
    def entry(self) -> Vec3:
        """Where the feature's path starts (above the first touch, at the clearance plane)."""
        target = self.nodes[0]
        assert isinstance(target, ir.Move)
        return _plain(target.target)

    @property
    def exit(self) -> Vec3:
        """Where the feature's path ends."""
        block = self.nodes[-1]
        assert isinstance(block, ir.FeatureBlock) and isinstance(block.body[-1], ir.Move)
        return _plain(block.body[-1].target)


def resolve_face(feature: FreeformSpec, model: Any) -> int:
    """The face id the feature names (``face`` or the face nearest ``at``)."""
    from probegen import cad

    if feature.face is not None:
        return cad.face_by_id(model, feature.face).id
    return cad.face_at(model, feature.at or (0.0, 0.0, 0.0)).id


def plan_freeform(feature: FreeformSpec, part: Part | None, machine: MachineProfile,
                  setup: ir.Setup, *, check: bool = True, fast: bool = True) -> FreeformPlan:
    """Plan one free-form feature (see the module docstring).

    Args:
        feature: the spec feature.
        part: the part model, loaded.
        machine: the machine profile (probe, margin).
        setup: the program's setup (ball, clearance plane) for the collision checks.
        check: check each guide point and each link (False: plan only, for speed).
        fast: try the fast conservative check first (False: the exact check alone, the
            baseline of the benchmark; the plan is the same either way).

    Raises:
        SpecError: no model.
        ModelError: no such face.
        PlanningError: no guide point left to measure (the message gives the reasons).
    """
    from probegen.cad.freeform import FaceSurface, guide_points

    if part is None:
        raise SpecError(f"{feature.where}: kind freeform needs [part] model, found none")
    model = part.model
    face = resolve_face(feature, model)
    grid = guide_points(model, face, grid=feature.grid, counts=feature.counts,
                        spacing=feature.spacing, margin=feature.margin,
                        direction=feature.direction)
    left = [LeftOut(0, s.where, s.reason) for s in grid.skipped]
    surface = FaceSurface(model, face)
    r = machine.probe.ball_radius
    approach = machine.probe.approach if feature.retract is None else feature.retract
    points = np.array([g.point for g in grid.points]).reshape(-1, 3)
    groups, failed = plan_touches(
        surface, surface.normal_sign, points,
        np.array([g.normal for g in grid.points]).reshape(-1, 3),
        np.array([g.uv for g in grid.points]).reshape(-1, 2), d=feature.direction,
        method=feature.method, spacing=feature.extra_spacing, r=r,
        first_index=tuple(g.index for g in grid.points))
    left += [LeftOut(f.guide, f.point, f"no theoretical ball centre: {f.reason}")
             for f in failed]
    by_guide = {g.index: g for g in grid.points}
    groups = _on_face(surface, groups, by_guide, left)
    record = model.faces[face - 1]
    safe_z = min(record.bbox_max[2] + r + approach + machine.margin, setup.clearance_z)
    obstacle = obstacle_for(part, [])
    paths: list[tuple[ir.Node, ...]] = []
    kept: list[list[PlannedTouch]] = []
    every = [group_nodes(feature.id, grp, r=r, approach=approach,
                         overtravel=machine.probe.overtravel, safe_z=safe_z)
             for grp in groups]
    cleared = _fast(every, obstacle, setup, machine, check, fast)
    for grp, nodes, ok in zip(groups, every, cleared, strict=True):
        why = None if ok else _collides(nodes, obstacle, setup, machine)
        if why is None:
            paths.append(nodes)
            kept.append(grp)
        else:
            g = grp[0].guide
            left.append(LeftOut(g, by_guide[g].point, f"unreachable from above: {why}"))
    if not paths:
        reasons = "; ".join(f"{_where(x)}: {x.reason}" for x in left[:3])
        raise PlanningError(f"{feature.where}: no guide point of face {face} can be "
                            f"measured ({len(left)} left out; {reasons})")
    definition = ir.FreeformDef(feature.id, face, feature.method, len(kept))
    body = _link(paths, obstacle, setup, machine, check, fast)
    guides = tuple((grp[0].guide, by_guide[grp[0].guide].point,
                    by_guide[grp[0].guide].normal) for grp in kept)
    return FreeformPlan(feature, face, guides, tuple(t for grp in kept for t in grp),
                        tuple(sorted(left, key=lambda x: x.guide)), safe_z, definition,
                        (body[0], ir.FeatureBlock(definition, tuple(body[1:]))))


def summary_lines(plan: FreeformPlan) -> list[str]:
    """What ``probegen compile`` and ``plan`` print about a free-form feature: counts,
    then one line per grid or guide point left out, with the reason."""
    f = plan.spec
    lines = [f"{f.id}: free-form face {plan.face}, method {f.method}, {len(plan.guides)} "
             f"guide points, {len(plan.touches)} touches, travel at z = {plan.safe_z:.3f}, "
             f"{len(plan.left_out)} left out"]
    lines += [f"  left out: {_where(x)}: {x.reason}" for x in plan.left_out]
    return lines


def _where(x: LeftOut) -> str:
    return f"guide point {x.guide}" if x.guide else "grid point (" + ", ".join(
        f"{v:.3f}" for v in x.point) + ")"


def _on_face(surface: Any, groups: list[list[PlannedTouch]], points: dict[int, Any],
             left: list[LeftOut]) -> list[list[PlannedTouch]]:
    """Keep the groups whose every theoretical contact lies on the trimmed face."""
    if not groups:
        return groups
    flat = [t for grp in groups for t in grp]
    inside = surface.inside(np.array([t.uv for t in flat]))
    bad = {t.guide for t, ok in zip(flat, inside, strict=True) if not ok}
    for g in sorted(bad):
        left.append(LeftOut(g, points[g].point,
                            "a theoretical contact point lies outside the trimmed face "
                            "(too near its edge or a hole for this ball)"))
    return [grp for grp in groups if grp[0].guide not in bad]


def _collides(nodes: tuple[ir.Node, ...], obstacle: Obstacle, setup: ir.Setup,
              machine: MachineProfile) -> str | None:
    """The collision check's message for these nodes on their own, or None when clear."""
    try:
        check_program(ir.Program(setup, nodes), obstacle, [], machine)
    except (CollisionError, PlanningError) as exc:
        return str(exc).split(": ", 1)[-1]
    return None


def _fast(paths: Sequence[Sequence[ir.Node]], obstacle: Obstacle, setup: ir.Setup,
          machine: MachineProfile, check: bool, fast: bool) -> list[bool]:
    """Per path: cleared without the exact check (unchecked, or by the fast check)."""
    if not check:
        return [True] * len(paths)
    if not fast:
        return [False] * len(paths)
    return [bool(x) for x in clear_paths(paths, obstacle, setup, machine)]


def _link(paths: list[tuple[ir.Node, ...]], obstacle: Obstacle, setup: ir.Setup,
          machine: MachineProfile, check: bool, fast: bool) -> list[ir.Node]:
    """The feature's nodes: a rapid above the first group, the groups joined at the safe
    height (or by the clearance plane where that move is not clear), a rapid up."""
    clear = setup.clearance_z

    def target(node: ir.Node) -> Vec3:
        assert isinstance(node, ir.Move)
        return _plain(node.target)

    first = target(paths[0][0])
    body: list[ir.Node] = [ir.Move((first[0], first[1], clear), ir.MoveMode.RAPID)]
    hops = [(ir.Move(target(before[-1]), ir.MoveMode.PROTECTED),
             ir.Move(target(after[0]), ir.MoveMode.PROTECTED))
            for before, after in zip(paths[:-1], paths[1:], strict=True)]
    cleared = _fast(hops, obstacle, setup, machine, check, fast)
    for k, path in enumerate(paths):
        if k:
            a, b = target(paths[k - 1][-1]), target(path[0])
            if not cleared[k - 1] and _collides(hops[k - 1], obstacle, setup,
                                                 machine) is not None:
                body += [ir.Move((a[0], a[1], clear), ir.MoveMode.RAPID),
                         ir.Move((b[0], b[1], clear), ir.MoveMode.RAPID)]
        body += path
    last = target(paths[-1][-1])
    body.append(ir.Move((last[0], last[1], clear), ir.MoveMode.RAPID))
    return body


def _plain(p: ir.Point) -> Vec3:
    x, y, z = p
    assert not isinstance(x, ir.Var) and not isinstance(y, ir.Var) and not isinstance(z, ir.Var)
    return (x, y, z)
