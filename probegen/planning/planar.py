"""Line and plane features: touches at given nominal points of one planar face.

The face is chosen like a revolved feature's (``face = N`` or ``at``) and must be a
plane; every contact point must lie on it (within ``ON_FACE`` mm of the plane and inside
its bounding box).  The path: a rapid above the first start point, a protected move down
to it, then for each contact a touch along ``-normal`` from ``approach`` off the surface,
a retract to the start point and a protected move to the next start point; a protected
move straight up to the clearance plane at the end.  The collision check clears it all
with the rest of the program.

A line's face must be vertical (its normal square to Z, within ``VERTICAL`` of it): the
line is fitted in XY.  The part is assumed placed by its work offset within the touch's
approach and overtravel.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

from probegen import ir
from probegen.errors import ModelError, SpecError
from probegen.machine.profile import MachineProfile
from probegen.spec.actions import PlanarSpec

if TYPE_CHECKING:
    from probegen.cad import Part

ON_FACE = 1e-3
"""How far (mm) a contact point may be from the face's plane."""
VERTICAL = 1e-6
"""Largest |normal_z| of a line's face."""


@dataclass(frozen=True, slots=True)
class PlanarPlan:
    """A planned line or plane: its spec, face normal (outward, unit), start points (ball
    centres ``approach`` off each contact) and IR definition."""

    spec: PlanarSpec
    normal: ir.Vec3
    starts: tuple[ir.Vec3, ...]
    definition: ir.PlaneDef | ir.LineDef


def plan_planar(feature: PlanarSpec, part: Part | None,
                machine: MachineProfile) -> PlanarPlan:
    """Resolve the face and plan the touches.

    Raises:
        SpecError: no model; a contact point off the face.
        ModelError: the face is not a plane, or a line's face is not vertical.
    """
    from probegen import cad

    if part is None:
        raise SpecError(f"{feature.where}: kind {feature.kind} needs [part] model, found none")
    model = part.model
    face = cad.face_by_id(model, feature.face) if feature.face else cad.face_at(
        model, feature.at or (0.0, 0.0, 0.0))
    if face.type != "plane":
        raise ModelError(f"{feature.where}: expected a planar face for kind {feature.kind}, "
                         f"found face {face.id} of type {face.type}")
    n = face.axis
    if feature.kind == "line" and abs(n[2]) > VERTICAL:
        raise ModelError(f"{feature.where}: a line is measured on a vertical face; face "
                         f"{face.id} has normal {_vec(n)}")
    for k, p in enumerate(feature.contacts):
        _check_on_face(feature, k, p, face)
    d = feature.retract if feature.retract is not None else machine.probe.approach
    r = machine.probe.ball_radius
    starts = tuple(_along(p, n, r + d) for p in feature.contacts)
    return PlanarPlan(feature, n, starts, _definition(feature, n))


def _check_on_face(feature: PlanarSpec, k: int, p: ir.Vec3, face: object) -> None:
    origin, n = face.origin, face.axis  # type: ignore[attr-defined]
    off = sum((p[i] - origin[i]) * n[i] for i in range(3))
    lo, hi = face.bbox_min, face.bbox_max  # type: ignore[attr-defined]
    inside = all(lo[i] - ON_FACE <= p[i] <= hi[i] + ON_FACE for i in range(3))
    if abs(off) > ON_FACE or not inside:
        raise SpecError(f"{feature.where}.contacts[{k}]: expected a point on face "
                        f"{face.id} (a plane through {_vec(origin)} with normal "  # type: ignore[attr-defined]
                        f"{_vec(n)}), found {_vec(p)} ({off:.4f} mm off the plane"
                        f"{'' if inside else ', outside the face'})")


def _vec(v: ir.Vec3) -> str:
    return "(" + ", ".join(f"{x:.4f}".replace("-0.0000", "0.0000") for x in v) + ")"


def _along(p: ir.Vec3, n: ir.Vec3, s: float) -> ir.Vec3:
    return (p[0] + s * n[0], p[1] + s * n[1], p[2] + s * n[2])


def _definition(feature: PlanarSpec, n: ir.Vec3) -> ir.PlaneDef | ir.LineDef:
    c = feature.contacts
    if feature.kind == "line":
        return ir.LineDef(feature.id, c[0], c[-1], n)
    mean = tuple(sum(p[i] for p in c) / len(c) for i in range(3))
    return ir.PlaneDef(feature.id, mean, n)  # type: ignore[arg-type]


def direction_degrees(definition: ir.LineDef) -> float:
    """The nominal direction of a line in XY, from its start to its end, degrees in
    (-180, 180]."""
    return math.degrees(math.atan2(definition.end[1] - definition.start[1],
                                   definition.end[0] - definition.start[0]))


def planar_nodes(p: PlanarPlan, machine: MachineProfile, clearance_z: float,
                 stores: str) -> tuple[ir.Node, ...]:
    """The feature's nodes: a rapid above the first start, then its block; each touch
    keeps the ball centre's axes ``stores`` (e.g. ``"XY"``) in run-time values for a
    ``Check``."""
    from probegen.ir.actions import point_names

    first, last = p.starts[0], p.starts[-1]
    d = p.spec.retract if p.spec.retract is not None else machine.probe.approach
    body: list[ir.Node] = [ir.Move(first, ir.MoveMode.PROTECTED)]
    for k, (contact, start) in enumerate(zip(p.spec.contacts, p.starts, strict=True), 1):
        if k > 1:
            body.append(ir.Move(start, ir.MoveMode.PROTECTED))
        store = point_names(p.spec.id, k, stores)
        body.append(ir.Touch(p.spec.id, k, ir.TouchRole.MEASURE, contact, p.normal, d,
                             machine.probe.overtravel, store))
        body.append(ir.Move(start, ir.MoveMode.RETRACT))
    body.append(ir.Move((last[0], last[1], clearance_z), ir.MoveMode.PROTECTED))
    high = ir.Move((first[0], first[1], clearance_z), ir.MoveMode.RAPID)
    return (high, ir.FeatureBlock(p.definition, tuple(body)))
