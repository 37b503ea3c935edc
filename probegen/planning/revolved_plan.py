"""Revolved features of a spec (method M2 wired): resolve, plan, IR (one feature in the
probe's frame; :mod:`probegen.planning.revolved_spec` holds what serves the whole spec).

A spec feature of kind ``circle``, ``cylinder``, ``cone`` or ``sphere`` names a model
face (``face = N`` or ``at = [x, y, z]``); it is resolved to the recognised revolved
feature (:func:`probegen.cad.revolved.revolved_features`) whose faces hold that face.
Sections are given as depths below the feature's top end, along -Z (accessible
features have vertical axes), and sorted top first; without ``sections`` the
recognised default sections are used (a circle: one, at the middle of the extent).

The part is assumed set up by its work offset: no locating, no run-time variables, and
the collision check adds no position uncertainty.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from probegen import ir
from probegen.errors import ModelError, PlanningError, ProbegenError, SpecError
from probegen.ir import frames
from probegen.machine.profile import MachineProfile
from probegen.planning.collision import check_program, obstacle_for
from probegen.planning.reach import reach_fractions
from probegen.planning.reroute import Rerouted, RerouteError, Sweeper, Text, reroute
from probegen.planning.revolved import FeaturePlan, Section, feature_nodes, plan_feature, section_of
from probegen.planning.revolved_geometry import ArcTooShortError
from probegen.planning.setup import make_setup
from probegen.planning.tilted import View, express, feature_in, sections_in
from probegen.planning.well_posed import IllPosedError, free_fit, refused_reason, unevaluable
from probegen.spec.model import RevolvedSpec, Spec

if TYPE_CHECKING:
    from probegen.cad import Part

TYPE_OF_KIND = {"circle": "cylinder", "cylinder": "cylinder", "cone": "cone",
                "sphere": "sphere", "torus": "torus"}
"""The recognised surface type each revolved kind measures."""


@dataclass(frozen=True, slots=True)
class ResolvedRevolved:
    """A spec feature with its recognised feature and chosen sections (``cad.revolved``
    objects: ``RevolvedFeature`` and ``FeatureSection``s, top first)."""

    spec: RevolvedSpec
    feature: Any
    sections: tuple[Any, ...]


@dataclass(frozen=True, slots=True)
class RevolvedPlan:
    """A planned revolved feature: what it is, its M2 plan and its IR definition."""

    spec: RevolvedSpec
    resolved: ResolvedRevolved
    plan: FeaturePlan
    definition: ir.FeatureDef
    notes: tuple[str, ...] = ()
    """What the reroute changed (:mod:`probegen.planning.reroute`), one line each."""

    @property
    def normals(self) -> dict[int, tuple[float, float, float]]:
        """The planned outward normal of each touch index."""
        return {p.index: p.normal for p in self.plan.path if p.normal is not None}

    @property
    def section_of_touch(self) -> dict[int, int]:
        """The 0-based section of each touch index."""
        return {p.index: p.section for p in self.plan.path if p.normal is not None}


def _need_part(part: Part | None, feature: RevolvedSpec) -> Part:
    """``part``, or a SpecError for a spec without a model."""
    if part is None:
        raise SpecError(f"{feature.where}: kind {feature.kind} needs [part] model, found none")
    return part


def find_owner(feature: RevolvedSpec, part: Part) -> Any:
    """The recognised revolved feature (``cad.revolved.RevolvedFeature``) holding the
    spec feature's face (``face`` or ``at``), accessible or not.

    Raises:
        ModelError: the face is not a face of a revolved feature of the right type.
    """
    from probegen import cad
    from probegen.cad.revolved import revolved_features

    face = cad.face_by_id(part.model, feature.face) if feature.face else cad.face_at(
        part.model, feature.at or (0.0, 0.0, 0.0))
    owner = next((f for f in revolved_features(part) if face.id in f.faces), None)
    want = TYPE_OF_KIND[feature.kind]
    if owner is None or owner.type != want:
        what = f"face {face.id} of type {face.type}" if owner is None else (
            f"face {face.id} of revolved feature {owner.id}, a {owner.type}")
        raise ModelError(f"{feature.where}: expected a face of a {want} for kind "
                         f"{feature.kind}, found {what}")
    return owner


def resolve_revolved(feature: RevolvedSpec, part: Part | None, *,
                     tilted: bool = False) -> ResolvedRevolved:
    """Find the recognised feature and its sections (``tilted``: for a probe standing
    off the feature's axis, :mod:`probegen.planning.tilted`: a section is taken where
    it has arcs, whether a probe along the axis reaches it or not; the collision check
    of the tilted probe judges).

    Raises:
        SpecError: no model; a depth outside the feature.
        ModelError: the face is not a face of a revolved feature of the right type.
        PlanningError: the feature or a chosen section is not accessible (with the
            recognition's reason).
    """
    from probegen.cad.revolved import section_at

    part = _need_part(part, feature)
    owner = find_owner(feature, part)
    if not owner.accessible and not tilted:
        raise PlanningError(f"{feature.where}: revolved feature {owner.id} ({owner.type}, "
                            f"faces {','.join(map(str, owner.faces))}) is not accessible: "
                            f"{owner.reason}")
    sections: tuple[Any, ...]
    if feature.sections is None:
        sections = _default_sections(part, owner, feature.kind, section_at, tilted)
    else:
        sections = tuple(section_at(part, owner, _axial(feature, owner, k, depth))
                         for k, depth in enumerate(feature.sections))
    for k, s in enumerate(sections):
        if not usable(s, tilted):
            raise PlanningError(f"{feature.where}.sections[{k}]: the section at "
                                f"z = {s.centre[2]:.4f} is not accessible: {s.reason}")
    z_sorted = tuple(sorted(sections, key=lambda s: -s.centre[2]))
    return ResolvedRevolved(feature, owner, z_sorted)


DEFAULT_SECTIONS = {"circle": (0.5,), "cone": (0.25, 0.75), "torus": (0.2, 0.5, 0.8)}
"""Default sections (fractions of the axial extent) of a spec feature without
``sections``, where the recognised ones do not serve: a circle has one, at the middle;
a cone two (its angle needs two), a torus three at distinct tube angles (two circles
of a torus lie on a family of tori).  Cylinders take the recognised sections; a sphere
the recognised one and a second at 3/4 of its extent (one circle lies on many
spheres)."""
SPHERE_SECOND = 0.75


def usable(section: Any, tilted: bool) -> bool:
    """Whether a recognised section can be planned: reachable by a probe along the axis;
    with ``tilted`` (a probe standing off it), any section with arcs."""
    return bool(section.arcs) if tilted else bool(section.reachable)


def _default_sections(part: Part, owner: Any, kind: str, section_at: Any,
                      tilted: bool = False) -> tuple[Any, ...]:
    """The reachable (:func:`usable`) default sections of ``owner`` for ``kind`` (see
    :data:`DEFAULT_SECTIONS`); the recognised ones when none of these is reachable."""
    low, high = owner.extent
    recognised = tuple(s for s in owner.sections if usable(s, tilted))
    if kind == "cylinder":
        return recognised
    if kind == "sphere":
        extra = section_at(part, owner, low + SPHERE_SECOND * (high - low))
        return recognised + ((extra,) if usable(extra, tilted) else ())
    chosen = tuple(s for s in (section_at(part, owner, low + q * (high - low))
                               for q in DEFAULT_SECTIONS[kind]) if usable(s, tilted))
    return chosen or recognised


def top_z(feature: Any) -> float:
    """The highest Z of a vertical feature's extent, mm."""
    az = feature.axis[2]
    return max(feature.origin[2] + h * az for h in feature.extent)


def _axial(spec: RevolvedSpec, feature: Any, k: int, depth: float) -> float:
    """The axial position of the section ``depth`` mm below the top end."""
    if depth > feature.length + 1e-9:
        raise SpecError(f"{spec.where}.sections[{k}]: expected a depth from 0 to "
                        f"{feature.length:.4f} mm (the feature's length), found {depth:g}")
    az = feature.axis[2]
    return (top_z(feature) - depth - feature.origin[2]) / az


def definition(resolved: ResolvedRevolved) -> ir.FeatureDef:
    """The nominal feature for the IR (and DMIS ``FEAT/...``)."""
    f, fid = resolved.feature, resolved.spec.id
    axis = tuple(float(v) for v in f.axis)
    if resolved.spec.kind == "circle":
        s = resolved.sections[0]
        return ir.CircleDef(fid, s.centre, axis, 2.0 * s.radius, f.inner)  # type: ignore[arg-type]
    if f.type == "cylinder":
        centre = f.centre_at(sum(f.extent) / 2.0)
        return ir.CylinderDef(fid, centre, axis, 2.0 * f.radius, f.length,  # type: ignore[arg-type]
                              f.inner)
    if f.type == "cone":
        half = f.half_angle or 0.0
        apex = f.centre_at(-f.radius / math.tan(half))
        return ir.ConeDef(fid, apex, axis, half, f.inner)  # type: ignore[arg-type]
    if f.type == "torus":
        return ir.TorusDef(fid, f.origin, axis, 2.0 * f.radius,  # type: ignore[arg-type]
                           2.0 * (f.minor_radius or 0.0), f.inner, f.tube_side)
    return ir.SphereDef(fid, f.origin, 2.0 * f.radius, f.inner)


FALLBACK_RETRACT = 1.0
"""A retract tried when the profile's approach leaves touches that cannot be made safe
(a boss beside a wall), mm."""
LEAST_RETRACT = 1.5
"""No retract below this many margins is tried (a touch must start clear of the
surface by more than the margin), a ratio."""
SMALL_BORE_CORE = 0.25
"""The safe circle of a bore too small for the usual retract keeps this radius, mm."""


def _core_retract(section: Section, machine: MachineProfile) -> float:
    """The largest retract that keeps a bore section's safe circle
    :data:`SMALL_BORE_CORE` in radius, mm (a tilted section: along its surface)."""
    return (section.radius / math.cos(section.tilt) - machine.probe.ball_radius
            - SMALL_BORE_CORE)


def _retracts(feature: RevolvedSpec, machine: MachineProfile,
              sections: list[Section]) -> tuple[float, ...]:
    """The retracts to try, largest first: the spec's alone when it gives one, else the
    probe's approach, :data:`FALLBACK_RETRACT`, and the largest that fits the smallest
    bore section (its safe circle :data:`SMALL_BORE_CORE` in radius); none above the
    approach or below :data:`LEAST_RETRACT` margins."""
    if feature.retract is not None:
        return (feature.retract,)
    low, usual = LEAST_RETRACT * machine.margin, machine.probe.approach
    out = [usual, max(FALLBACK_RETRACT, low)]
    cores = [_core_retract(s, machine) for s in sections if s.inner]
    if cores:
        out.append(min(cores))
    return tuple(sorted({d for d in out if low <= d <= usual}, reverse=True))


def _fitting(retract: float, machine: MachineProfile, sections: list[Section]) -> float:
    """The retract an alternative choice of sections tries after ``retract`` (the one
    that served the default sections best): less where a bore section's safe circle
    would keep under :data:`SMALL_BORE_CORE` in radius with it, the largest that keeps
    it.  Below :data:`LEAST_RETRACT` margins a bore (a cylinder's section) keeps
    ``retract`` (:func:`smallest_bore` is the narrowest bore a stylus measures), and a
    tilted section (a cone's, a sphere's or a torus's, whose radius is the planner's
    choice of section: a drill point's near its tip) takes the least retract, which
    its own check refuses only where the safe circle vanishes."""
    low = LEAST_RETRACT * machine.margin
    out = retract
    for s in sections:
        if not s.inner:
            continue
        fits = _core_retract(s, machine)
        if fits >= low:
            out = min(out, fits)
        elif s.tilt != 0.0:
            out = min(out, low)
    return out


def smallest_bore(machine: MachineProfile) -> float:
    """The smallest bore diameter the profile's stylus measures, mm: the ball and the
    smallest retract :func:`_retracts` tries (at least 1.5 margins, and in a small bore
    one that keeps a safe circle of :data:`SMALL_BORE_CORE`)."""
    low = LEAST_RETRACT * machine.margin
    retract = min(low + SMALL_BORE_CORE, max(FALLBACK_RETRACT, low), machine.probe.approach)
    return 2.0 * (machine.probe.ball_radius + retract)


ALTERNATIVE_SECTIONS = {
    "circle": ((0.25,), (0.75,)),
    "cylinder": ((0.55, 0.9), (0.1, 0.9), (0.4, 0.6)),
    "cone": ((0.55, 0.9), (0.1, 0.9), (0.4, 0.6)),
    "sphere": ((0.5, 0.9), (0.3, 0.7), (0.1, 0.3)),
    "torus": ((0.4, 0.65, 0.9), (0.1, 0.35, 0.6)),
}
"""Sections tried (fractions of the axial extent) when the default ones of a spec
without ``sections`` lose touches to the collision check, in order (a sphere's last
pair near its pole: the blend in a pocket's corner, an octant, has full circles only
there)."""


def _candidates(resolved: ResolvedRevolved, part: Part | None, machine: MachineProfile,
                tilted: bool = False
                ) -> Iterator[ResolvedRevolved]:
    """The resolved feature, then (without spec sections) its alternative sections, and
    those within the stylus's reach with the probe body clear
    (:func:`probegen.planning.reach.reach_fractions`), each built only when asked for."""
    yield resolved
    if resolved.spec.sections is not None:
        return
    from probegen.cad.revolved import section_at

    part = _need_part(part, resolved.spec)
    f = resolved.feature
    low, high = f.extent
    reached = reach_fractions(f, machine, resolved.spec.kind, part.bbox_max[2])
    for fractions in (*ALTERNATIVE_SECTIONS[resolved.spec.kind], *reached):
        sections = [section_at(part, f, low + q * (high - low)) for q in fractions]
        if all(usable(s, tilted) for s in sections):
            ordered = tuple(sorted(sections, key=lambda s: -s.centre[2]))
            yield ResolvedRevolved(resolved.spec, f, ordered)


def _plan_safe(resolved: ResolvedRevolved, machine: MachineProfile, clearance_z: float,
               sweeper: Sweeper, errors: list[ProbegenError],
               retract_only: float | None = None, view: View | None = None
               ) -> Rerouted | None:
    """The rerouted plan of one choice of sections with the first retract of
    :func:`_retracts` (or ``retract_only``, then, unless the spec gives the retract,
    the one :func:`_fitting` gives these sections where it is less) that keeps every
    touch, else the one that keeps the most (None when none plans; the reasons go to
    ``errors``); with ``view`` the plan is expressed in its frame
    (:func:`probegen.planning.tilted.express`) and rerouted there (``sweeper`` is the
    view's)."""
    feature = resolved.spec
    sections = [section_of(feature.id, resolved.feature, s) for s in resolved.sections]
    best: Rerouted | None = None
    if retract_only is None:
        retracts = _retracts(feature, machine, sections)
    elif feature.retract is not None:  # the spec's retract is the only one
        retracts = (retract_only,)
    else:
        retracts = tuple(sorted({retract_only, _fitting(retract_only, machine, sections)},
                                reverse=True))
    for retract in retracts:
        try:
            plan = _plan_touches(sections, feature, machine, retract, clearance_z)
            safe = reroute(plan if view is None else express(plan, view), sweeper)
        except RerouteError as exc:  # a CollisionError, itself a PlanningError
            errors.append(RerouteError(Text.format("{}: {}", feature.where, exc)))
            continue
        except PlanningError as exc:
            errors.append(PlanningError(f"{feature.where}: {exc}"))
            continue
        if best is None or len(safe.dropped) < len(best.dropped):
            best = safe
        if not safe.dropped or view is not None:  # a leaning stylus drops touches
            break
    return best


def _plan_touches(sections: list[Section], feature: RevolvedSpec, machine: MachineProfile,
                  retract: float, clearance_z: float) -> FeaturePlan:
    """The touches and path of one choice of sections and retract: the end margin of a
    partial arc the ball's radius and the margin (arc length), else, on an arc too short
    for it, the margin alone.  The ball's radius keeps it off a face that meets the arc's
    end at an angle; a face that continues the arc (the straight sides of a rounded
    corner, the rest of a bore split into faces) needs none, and the collision check of
    each touch (:func:`probegen.planning.reroute.reroute`) drops a touch that would meet
    a face there.

    Raises:
        PlanningError: no plan; an arc too short for the margin alone: the reason with
            the full end margin (the ball's, what the user can act on).
    """
    def plan(end_margin: float | None) -> FeaturePlan:
        return plan_feature(sections, feature.points, ball=machine.probe.ball_radius,
                            retract=retract, margin=machine.margin, clear_z=clearance_z,
                            end_margin=end_margin)
    try:
        return plan(None)
    except ArcTooShortError as exc:
        try:
            return plan(machine.margin)
        except ArcTooShortError:
            raise exc from None


def _touches(plan: FeaturePlan) -> int:
    return sum(1 for p in plan.path if p.normal is not None)


def plan_revolved(feature: RevolvedSpec, part: Part | None, machine: MachineProfile,
                  clearance_z: float, view: View | None = None) -> RevolvedPlan:
    """Resolve and plan one revolved feature (method M2) entered from ``clearance_z``,
    made safe against the part (:func:`probegen.planning.reroute.reroute`).

    Tried in order until every touch is kept: the sections (the spec's or the default
    ones) with the retracts of :func:`_retracts`, then (when the spec gives no sections)
    :data:`ALTERNATIVE_SECTIONS` with the retract that kept the most touches there; else
    the plan that keeps the most touches.

    Raises:
        PlanningError: nothing plans: the reason of the smallest retract on the
            feature's own sections (the most permissive attempt).
        CollisionError: no touch can be made safe (names the move and the face).

    The plan is kept on the part by (spec feature, machine, clearance level):
    ``--all-revolved`` plans each feature to choose the spec, then the program plans the
    spec; ``ingest`` plans the program, then each feature again.

    With ``view`` (a probe standing off the feature's axis,
    :mod:`probegen.planning.tilted`) the feature is planned on ``part`` (turned into its
    own frame) at ``clearance_z`` and probed in the view's frame: the plan, its
    feature and definition come back in the view's coordinates.
    """
    loaded = _need_part(part, feature)
    return loaded.memo(("revolved plan", feature, machine, clearance_z, view),
                       lambda: _plan_revolved(feature, loaded, machine, clearance_z, view))


def _plan_revolved(feature: RevolvedSpec, part: Part, machine: MachineProfile,
                   clearance_z: float, view: View | None) -> RevolvedPlan:
    tilted = view is not None
    resolved = resolve_revolved(feature, part, tilted=tilted)
    probed = part if view is None else view.part
    sweeper = Sweeper(obstacle_for(probed, []), machine, machine.probe.ball_radius)
    errors: list[ProbegenError] = []
    free = free_fit(machine)
    best: tuple[ResolvedRevolved, Rerouted, str] | None = None
    own = 0  # the errors of the feature's own sections (the first candidate)
    for k, candidate in enumerate(_candidates(resolved, part, machine, tilted)):
        # other sections only with the retract that served the default ones best (or
        # less where their bore sections are smaller: _fitting)
        only = best[1].plan.sections[0].retract if k and best is not None else None
        safe = _plan_safe(candidate, machine, clearance_z, sweeper, errors, only, view)
        own = own if k else len(errors)
        if safe is None:
            continue
        seen = candidate.feature if view is None else feature_in(view.turn, candidate.feature)
        why = unevaluable(feature.kind, seen, safe.plan, free)
        if best is None or (not why, _touches(safe.plan)) > (not best[2],
                                                              _touches(best[1].plan)):
            notes = safe.notes if not k else (
                "default sections lose touches; measured at z = " + ", ".join(
                    f"{s.centre[2]:.3f}" for s in candidate.sections), *safe.notes)
            best = (candidate, replace(safe, notes=tuple(notes)), why)
        if not why and (not safe.dropped or tilted):  # a leaning stylus drops touches
            break
    if best is None:
        # the most permissive attempt's reason: the smallest retract on the feature's
        # own sections (a larger retract's "R > r + d" is not why a bore is left out)
        raise errors[own - 1 if own else 0]
    chosen, safe, why = best
    if why:
        lost = str(safe.first_drop)
        raise IllPosedError(f"{feature.where}: {refused_reason(feature.kind, why, free, lost)}")
    if view is not None:
        return RevolvedPlan(feature, resolved_in(view.turn, chosen), safe.plan,
                            frames.definition_in_work(view.turn, definition(chosen)),
                            tuple(map(str, safe.notes)))
    return RevolvedPlan(feature, chosen, safe.plan, definition(chosen),
                        tuple(map(str, safe.notes)))


def unrouted(feature: RevolvedSpec, part: Part, machine: MachineProfile,
             clearance_z: float) -> FeaturePlan | None:
    """The touches of ``feature`` on ``part`` as M2 plans them before the collision
    check (its default sections whether a probe along the axis reaches them or not, else
    the first :data:`ALTERNATIVE_SECTIONS` that plan; the smallest retract): what
    :func:`probegen.planning.tilted.screen` screens the head's indices with; None when
    it does not plan."""
    try:
        resolved = resolve_revolved(feature, part, tilted=True)
    except ProbegenError:
        return None
    for candidate in _candidates(resolved, part, machine, tilted=True):
        sections = [section_of(feature.id, candidate.feature, s) for s in candidate.sections]
        try:
            retract = _retracts(feature, machine, sections)[-1]
            return _plan_touches(sections, feature, machine, retract, clearance_z)
        except (ProbegenError, IndexError):
            continue
    return None


def resolved_in(turn: ir.Orient, resolved: ResolvedRevolved) -> ResolvedRevolved:
    """A resolved feature with its recognised feature and sections turned by ``turn``."""
    return replace(resolved, feature=feature_in(turn, resolved.feature),
                   sections=sections_in(turn, resolved.sections))


def revolved_nodes(p: RevolvedPlan, machine: MachineProfile,
                   clearance_z: float) -> tuple[ir.Node, ...]:
    """The feature's nodes: a rapid above its entry, then its block."""
    nodes = feature_nodes(p.plan, overtravel=machine.probe.overtravel, clearance_z=clearance_z)
    return (nodes[0], ir.FeatureBlock(p.definition, nodes[1:]))


def check_alone(p: RevolvedPlan, part: Part, machine: MachineProfile,
                clearance_z: float) -> None:
    """Check one planned feature's moves (from the clearance plane and back) against the
    model with the machine's margin (a feature planned in a frame: against the turned
    part, at the frame's clearance level, with the profile of its stylus).

    Raises:
        CollisionError: a move of the feature brings the stylus into the part.
    """
    spec = Spec(source=part.path, model=Path(part.path), machine=machine,
                dialect=machine.dialect, clearance_z=clearance_z, program_number=1001,
                program_name="ALL REVOLVED", features=(p.spec,), raised=part.raised)
    program = ir.Program(make_setup(spec), revolved_nodes(p, machine, clearance_z))
    check_program(program, obstacle_for(part, []), [], machine)
