"""Method M1: the probing test on a reference sphere.

Plans the points (``iso``, ``octahedral`` or an ``n``-point cap), their zigzag order, the
safe retract distance from the chord condition, and the stylus path as IR nodes.

Frames: the sphere's frame has its pole along +Z (the shank direction of a 3-axis machine
or of a CMM stylus pointing down), so contact point ``k`` is ``C + R·n_k`` with the layout's
unit vector ``n_k``, the ball centre at contact ``C + R'·n_k`` (``R' = R + r``) and the
approach/retract point ``C + (R' + d)·n_k``.

Locating (``locate = true``): on a machine tool the sphere's position is known only to
``u`` (``locate_uncertainty``), so the program first finds the real centre, in controller
variables at run time: a top touch gives an estimated centre height; two touches along X
at that height give the centre X exactly (the midpoint of a chord through a circle); two
along Y through that X give Y; a second top touch above (X, Y) gives Z.  Then the measuring
touches run around the found centre.  A dialect without run-time arithmetic (DMIS) instead
measures a 5-point sphere and translates the frame onto its centre (``LocalFrame``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from probegen import ir
from probegen.errors import ModelError, SpecError
from probegen.geometry import sphere_layout as sl
from probegen.machine.profile import MachineProfile
from probegen.spec.model import SphereTest, Vec3

if TYPE_CHECKING:
    from probegen.cad import Part


@dataclass(frozen=True, slots=True)
class SphereGeometry:
    """The nominal sphere: centre (mm) and the calibrated diameter (mm)."""

    centre: Vec3
    diameter: float


@dataclass(frozen=True, slots=True)
class SphereTestPlan:
    """What the planner decided for one sphere test, with its figures.

    Attributes:
        feature: the spec feature.
        sphere: nominal centre and diameter.
        directions: unit vectors of the points in measuring order.
        layout_index: for each measured point, its index in the layout's own order.
        uniformity: nearest-neighbour figures of the layout.
        alpha: largest central angle between consecutive points, rad.
        min_retract: the chord condition's minimum retract distance, mm.
        retract: the retract distance used, mm.
    """

    feature: SphereTest
    sphere: SphereGeometry
    directions: tuple[Vec3, ...]
    layout_index: tuple[int, ...]
    uniformity: sl.Uniformity
    alpha: float
    min_retract: float
    retract: float


def resolve_sphere(feature: SphereTest, part: Part | None) -> SphereGeometry:
    """Find the nominal sphere: explicit centre, or a sphere face of the model."""
    if feature.centre is not None and feature.diameter is not None:
        return SphereGeometry(feature.centre, feature.diameter)
    if part is None:
        raise SpecError(f"{feature.where}: face/at need [part] model, found none")
    from probegen import cad  # lazily: only planning from a model needs OCP

    model = part.model
    face = cad.face_by_id(model, feature.face) if feature.face else cad.face_at(
        model, feature.at or (0.0, 0.0, 0.0))
    if face.type != "sphere" or face.radius is None or face.inner:
        raise ModelError(f"{feature.where}: expected an outer sphere face, found face "
                         f"{face.id} of type {face.type}{' (inner)' if face.inner else ''}")
    diameter = feature.diameter if feature.diameter is not None else 2.0 * face.radius
    return SphereGeometry(face.origin, diameter)


def layout_points(feature: SphereTest) -> np.ndarray:
    """The feature's layout as (n, 3) unit vectors, in the layout's own order."""
    return sl.layout(feature.layout, feature.points, feature.max_polar_angle)


def sphere_test_profile(feature: SphereTest, machine: MachineProfile) -> MachineProfile:
    """The profile ``feature`` is planned and evaluated with: ``machine`` with the stylus
    the test names (``stylus = "D2"``) as its probe's, else ``machine``."""
    from probegen.planning.styli import profile_with, stylus_named

    if feature.stylus is None:
        return machine
    return profile_with(machine, stylus_named(machine, feature.stylus,
                                              f"{feature.where}: stylus"))


def plan_points(feature: SphereTest, sphere: SphereGeometry,
                machine: MachineProfile) -> SphereTestPlan:
    """Choose the points, their order and the retract distance (method M1)."""
    pts = layout_points(feature)
    uni = sl.uniformity(pts)
    band = None if feature.layout != "cap" else 2.0 * math.asin(uni.min_distance / 2.0)
    order = sl.zigzag_order(pts, band=band)
    alpha = sl.max_step_angle(pts, order)
    r_off = sphere.diameter / 2.0 + machine.probe.ball_radius
    d_min = sl.safe_retract(r_off, alpha)
    # d = d_min + m / cos(α/2) leaves exactly the margin m between every chord and the
    # offset sphere: (R' + d)·cos(α/2) = R' + m.
    safe = d_min + machine.margin / math.cos(alpha / 2.0)
    retract = _retract(feature, safe, d_min, alpha, machine)
    return SphereTestPlan(
        feature=feature, sphere=sphere,
        directions=tuple(_vec(pts[i]) for i in order), layout_index=tuple(order),
        uniformity=uni, alpha=alpha, min_retract=safe, retract=retract,
    )


def _retract(feature: SphereTest, safe: float, d_min: float, alpha: float,
             machine: MachineProfile) -> float:
    if feature.retract is None:
        return math.ceil(max(safe, machine.probe.approach) * 10.0 - 1e-9) / 10.0
    if feature.retract < safe:
        raise SpecError(
            f"{feature.where}.retract: expected at least {safe:.3f} mm (chord condition "
            f"{d_min:.3f} mm for the largest step {math.degrees(alpha):.2f} deg, plus the "
            f"margin {machine.margin:g} mm), found {feature.retract:g}")
    return feature.retract


def _vec(v: np.ndarray) -> Vec3:
    return (float(v[0]), float(v[1]), float(v[2]))


def _add(c: ir.Point, v: Vec3, k: float) -> ir.Point:
    """``c + k·v`` for a point whose coordinates may be run-time variables."""
    return (c[0] + k * v[0], c[1] + k * v[1], c[2] + k * v[2])


def measure_body(plan: SphereTestPlan, centre: ir.Point, z_high: ir.Coord,
                 machine: MachineProfile, clearance: ir.Coord) -> tuple[ir.Node, ...]:
    """The measuring touches around ``centre``, entered from above at ``z_high``.

    The body ends straight above the last point: first at ``z_high`` (protected), then
    at the clearance plane (rapid, a single-axis move).
    """
    f = plan.feature
    radius = plan.sphere.diameter / 2.0
    r_off = radius + machine.probe.ball_radius
    nodes: list[ir.Node] = [ir.Move((centre[0], centre[1], z_high), ir.MoveMode.PROTECTED)]
    for k, n in enumerate(plan.directions, start=1):
        approach = _add(centre, n, r_off + plan.retract)
        nodes.append(ir.Move(approach, ir.MoveMode.PROTECTED))
        nodes.append(ir.Touch(f.id, k, ir.TouchRole.MEASURE, _add(centre, n, radius), n,
                              plan.retract, machine.probe.overtravel))
        nodes.append(ir.Move(approach, ir.MoveMode.RETRACT))
    last = nodes[-1]
    assert isinstance(last, ir.Move)
    nodes.append(ir.Move((last.target[0], last.target[1], z_high), ir.MoveMode.PROTECTED))
    nodes.append(ir.Move((last.target[0], last.target[1], clearance), ir.MoveMode.RAPID))
    return tuple(nodes)
