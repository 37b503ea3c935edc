"""Revolved features of a spec (method M2 wired): resolve, plan, IR.

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
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from probegen import ir
from probegen.errors import CollisionError, ModelError, PlanningError, ProbegenError, SpecError
from probegen.machine.profile import MachineProfile
from probegen.planning.revolved import FeaturePlan, feature_nodes, plan_feature, section_of
from probegen.spec import RevolvedSpec, Spec

TYPE_OF_KIND = {"circle": "cylinder", "cylinder": "cylinder", "cone": "cone",
                "sphere": "sphere"}
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

    @property
    def normals(self) -> dict[int, tuple[float, float, float]]:
        """The planned outward normal of each touch index."""
        return {p.index: p.normal for p in self.plan.path if p.normal is not None}

    @property
    def section_of_touch(self) -> dict[int, int]:
        """The 0-based section of each touch index."""
        return {p.index: p.section for p in self.plan.path if p.normal is not None}


def _model(path: Path | None, feature: RevolvedSpec) -> Any:
    if path is None:
        raise SpecError(f"{feature.where}: kind {feature.kind} needs [part] model, found none")
    from probegen.planning.collision import load_model

    return load_model(str(path))


def resolve_revolved(feature: RevolvedSpec, model_path: Path | None) -> ResolvedRevolved:
    """Find the recognised feature and its sections.

    Raises:
        SpecError: no model; a depth outside the feature.
        ModelError: the face is not a face of a revolved feature of the right type.
        PlanningError: the feature or a chosen section is not accessible (with the
            recognition's reason).
    """
    from probegen import cad
    from probegen.cad.revolved import revolved_features, section_at

    model = _model(model_path, feature)
    face = cad.face_by_id(model, feature.face) if feature.face else cad.face_at(
        model, feature.at or (0.0, 0.0, 0.0))
    found = _features(model, revolved_features)
    owner = next((f for f in found if face.id in f.faces), None)
    want = TYPE_OF_KIND[feature.kind]
    if owner is None or owner.type != want:
        what = f"face {face.id} of type {face.type}" if owner is None else (
            f"face {face.id} of revolved feature {owner.id}, a {owner.type}")
        raise ModelError(f"{feature.where}: expected a face of a {want} for kind "
                         f"{feature.kind}, found {what}")
    if not owner.accessible:
        raise PlanningError(f"{feature.where}: revolved feature {owner.id} ({owner.type}, "
                            f"faces {','.join(map(str, owner.faces))}) is not accessible: "
                            f"{owner.reason}")
    sections: tuple[Any, ...]
    if feature.sections is None:
        if feature.kind == "circle":
            sections = (section_at(model, owner, sum(owner.extent) / 2.0),)
        else:
            sections = tuple(s for s in owner.sections if s.reachable)
    else:
        sections = tuple(section_at(model, owner, _axial(feature, owner, k, depth))
                         for k, depth in enumerate(feature.sections))
    for k, s in enumerate(sections):
        if not s.reachable:
            raise PlanningError(f"{feature.where}.sections[{k}]: the section at "
                                f"z = {s.centre[2]:.4f} is not accessible: {s.reason}")
    z_sorted = tuple(sorted(sections, key=lambda s: -s.centre[2]))
    return ResolvedRevolved(feature, owner, z_sorted)


_CACHE: dict[int, tuple[Any, tuple[Any, ...]]] = {}


def _features(model: Any, recognise: Any) -> tuple[Any, ...]:
    """Recognise once per loaded model (``load_model`` caches the model itself)."""
    hit = _CACHE.get(id(model))
    if hit is None or hit[0] is not model:
        hit = (model, recognise(model))
        _CACHE[id(model)] = hit
    return hit[1]


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
    return ir.SphereDef(fid, f.origin, 2.0 * f.radius, f.inner)


def plan_revolved(feature: RevolvedSpec, model_path: Path | None, machine: MachineProfile,
                  clearance_z: float) -> RevolvedPlan:
    """Resolve and plan one revolved feature (method M2) entered from ``clearance_z``."""
    resolved = resolve_revolved(feature, model_path)
    sections = [section_of(feature.id, resolved.feature, s) for s in resolved.sections]
    retract = feature.retract if feature.retract is not None else machine.probe.approach
    try:
        plan = plan_feature(sections, feature.points, ball=machine.probe.ball_radius,
                            retract=retract, margin=machine.margin, clear_z=clearance_z)
    except PlanningError as exc:
        raise PlanningError(f"{feature.where}: {exc}") from None
    return RevolvedPlan(feature, resolved, plan, definition(resolved))


def revolved_nodes(p: RevolvedPlan, machine: MachineProfile,
                   clearance_z: float) -> tuple[ir.Node, ...]:
    """The feature's nodes: a rapid above its entry, then its block."""
    nodes = feature_nodes(p.plan, overtravel=machine.probe.overtravel, clearance_z=clearance_z)
    return (nodes[0], ir.FeatureBlock(p.definition, nodes[1:]))


KIND_OF_TYPE = {"cylinder": "cylinder", "cone": "cone", "sphere": "sphere"}
"""The spec kind that measures each recognised type (tori are not planned yet)."""


def all_revolved(model_path: Path, machine: MachineProfile, clearance_z: float, *,
                 check: bool = True) -> tuple[tuple[RevolvedSpec, ...], tuple[str, ...]]:
    """A spec feature for every accessible revolved feature of a model that plans
    (default sections, 8 points) and, with ``check``, whose moves clear the collision
    check on their own (:func:`check_alone`); a note for each one left out."""
    from probegen.cad.revolved import revolved_features

    model = _model(model_path, RevolvedSpec("-", str(model_path), "cylinder", None, None,
                                            None, 8, None))
    out: list[RevolvedSpec] = []
    notes: list[str] = []
    for f in _features(model, revolved_features):
        fid = f"R{f.id}"
        if f.type not in KIND_OF_TYPE:
            notes.append(f"{fid} ({f.type}, faces {_faces(f)}): not planned: a {f.type}")
            continue
        if not f.accessible:
            notes.append(f"{fid} ({f.type}, faces {_faces(f)}): not accessible: {f.reason}")
            continue
        spec = RevolvedSpec(fid, f"{model_path}: revolved feature {f.id}", KIND_OF_TYPE[f.type],
                            f.faces[0], None, None, 8, None)
        try:
            planned = plan_revolved(spec, model_path, machine, clearance_z)
        except (PlanningError, ModelError, SpecError) as exc:
            notes.append(f"{fid} ({f.type}, faces {_faces(f)}): not planned: {exc}")
            continue
        if check:
            try:
                check_alone(planned, model_path, machine, clearance_z)
            except CollisionError as exc:
                notes.append(f"{fid} ({f.type}, faces {_faces(f)}): left out, it collides: "
                             f"{exc}")
                continue
        out.append(spec)
    return tuple(out), tuple(notes)


def check_alone(p: RevolvedPlan, model_path: Path, machine: MachineProfile,
                clearance_z: float) -> None:
    """Check one planned feature's moves (from the clearance plane and back) against the
    model with the machine's margin.

    Raises:
        CollisionError: a move of the feature brings the stylus into the part.
    """
    from probegen.planning import make_setup
    from probegen.planning.collision import check_program, obstacle_for
    from probegen.spec import Spec

    spec = Spec(source=str(model_path), model=model_path, machine=machine,
                dialect=machine.dialect, clearance_z=clearance_z, program_number=1001,
                program_name="ALL REVOLVED", features=(p.spec,))
    program = ir.Program(make_setup(spec), revolved_nodes(p, machine, clearance_z))
    check_program(program, obstacle_for(model_path, []), [], machine)


CLEARANCE_ABOVE_MODEL = 10.0
"""``all_revolved_spec``: the clearance plane is at least this far above the model, mm."""


def all_revolved_spec(model_path: Path, machine: MachineProfile) -> tuple[Spec, tuple[str, ...]]:
    """The spec of ``probegen plan MODEL --all-revolved``: every accessible cylinder, cone
    and sphere that plans and clears the collision check alone (default sections, 8
    points), the clearance plane at least ``CLEARANCE_ABOVE_MODEL`` above the model;
    and a note for each feature left out (with the reason or the collision).

    Raises:
        ProbegenError: no feature is left.
    """
    from probegen.planning.collision import load_model

    top = load_model(str(model_path)).bbox_max[2]
    clearance = max(machine.clearance_z, top + CLEARANCE_ABOVE_MODEL)
    features, notes = all_revolved(model_path, machine, clearance)
    if not features:
        raise ProbegenError(f"{model_path}: expected an accessible revolved feature that "
                            f"plans, found none; " + "; ".join(notes))
    spec = Spec(source=str(model_path), model=model_path, machine=machine,
                dialect=machine.dialect, clearance_z=clearance, program_number=1001,
                program_name="ALL REVOLVED", features=features)
    return spec, notes


def _faces(f: Any) -> str:
    return ",".join(str(k) for k in f.faces)


def metrics_table(plans: tuple[RevolvedPlan, ...], machine: MachineProfile) -> str:
    """Per feature: touches, path length (mm) and nominal cycle time (s) of the plan,
    the common baseline (up to the clearance level after every touch) and the lower
    bound (:func:`probegen.planning.revolved.compare`), with totals."""
    from probegen.planning.revolved import compare

    head = (f"{'feature':<8} {'kind':<8} {'side':<5} {'sect':>4} {'pts':>4}  "
            f"{'plan mm':>9} {'s':>7}  {'baseline mm':>11} {'s':>7}  {'bound mm':>9} {'s':>7}")
    rows = [head]
    total = [0.0] * 6
    for p in plans:
        c = compare(p.plan, machine)
        values = (c.plan.length, c.plan.time, c.baseline.length, c.baseline.time,
                  c.lower_bound.length, c.lower_bound.time)
        total = [a + b for a, b in zip(total, values, strict=True)]
        rows.append(_row(p.spec.id, p.spec.kind, "inner" if p.definition.inner else "outer",
                         len(p.plan.sections), len(p.normals), values))
    rows.append(_row("total", "", "", sum(len(p.plan.sections) for p in plans),
                     sum(len(p.normals) for p in plans), tuple(total)))
    return "\n".join(rows) + "\n"


def _row(fid: str, kind: str, side: str, sections: int, points: int,
         v: tuple[float, ...]) -> str:
    return (f"{fid:<8} {kind:<8} {side:<5} {sections:>4} {points:>4}  {v[0]:>9.1f} "
            f"{v[1]:>7.1f}  {v[2]:>11.1f} {v[3]:>7.1f}  {v[4]:>9.1f} {v[5]:>7.1f}")
