"""The in-process decisions of a spec (``docs/actions.md``) as IR nodes.

A feature with actions keeps the ball centres of its touches in run-time values and is
followed by a ``Check`` (fit, print, tolerances, what to do when out of tolerance).  The
work offset, tool and rotation updates come at the end of the program, once every
feature has been measured and checked: a program stopped by a bad feature writes
nothing.  The rotation comes last, about the nominal centre of the feature that sets
the X and Y offsets (so ``offset + G68`` maps the part's nominal geometry onto the
measured one), or about the work origin when none does.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

import numpy as np

from probegen import ir
from probegen.errors import SpecError
from probegen.ir.actions import Align, Check, Limit, SetWorkOffset, UpdateTool, point_names, result
from probegen.machine.calibration import calibrated_centres, for_stylus
from probegen.machine.profile import WORK_OFFSETS, MachineProfile
from probegen.planning.planar import PlanarPlan, direction_degrees
from probegen.spec.actions import PlanarSpec
from probegen.spec.model import RevolvedSpec, Spec, SphereTest

AXIS_ALIGNED = 1.0 - 1e-9
"""A line's or plane's normal counts as along an axis when that component exceeds this."""
ACTION_KINDS = ("circle", "cylinder", "line", "plane")
"""The kinds whose actions are computed on the machine."""


def normal_axis(feature: PlanarSpec, normal: ir.Vec3) -> int:
    """The axis (0-2) of a line's or plane's axis-aligned normal.

    Raises:
        SpecError: the normal is not along X, Y or Z.
    """
    for i in range(3):
        if abs(normal[i]) > AXIS_ALIGNED:
            return i
    raise SpecError(f"{feature.where}: run-time actions need a face square to X, Y or Z, "
                    f"found normal ({', '.join(f'{v:.6f}' for v in normal)})")


def revolved_check(nodes: tuple[ir.Node, ...], feature: RevolvedSpec,
                   definition: ir.FeatureDef, machine: MachineProfile) -> tuple[ir.Node, ...]:
    """A revolved feature's nodes, with stores and its ``Check`` when it has actions."""
    if not feature.actions.any:
        return nodes
    if feature.kind not in ("circle", "cylinder") or not isinstance(
            definition, ir.CircleDef | ir.CylinderDef):
        raise SpecError(f"{feature.where}: run-time actions are computed for kinds "
                        f"{', '.join(ACTION_KINDS)}, found kind {feature.kind}")
    if feature.actions.tool is not None and feature.actions.tool.offset != "radius":
        raise SpecError(f"{feature.where}.update_tool.offset: expected \"radius\" for a "
                        f"{feature.kind} (its size corrects the radius), found "
                        f"{feature.actions.tool.offset!r}")
    nodes, points, normals = _with_stores(nodes, feature.id, "XY")
    t = feature.tolerance
    limits = []
    if t.diameter is not None:
        limits.append(Limit("diameter", *t.diameter))
    if t.position is not None:
        limits.append(Limit("position", 0.0, t.position))
    if t.form is not None:
        limits.append(Limit("form", 0.0, t.form))
    radius, corrections = calibrated_radius(machine, normals)
    check = Check(feature.id, "circle", points, definition.centre, definition.axis,
                  definition.diameter, definition.inner, radius, 0.0,
                  tuple(limits), feature.actions.on_fail, feature.actions.flag, corrections)
    return (*nodes, check)


def planar_check(p: PlanarPlan, machine: MachineProfile) -> tuple[str, Check | None]:
    """The axes a line or plane must store and its ``Check`` (None without actions)."""
    feature = p.spec
    if not feature.actions.any:
        return "", None
    axis = normal_axis(feature, p.normal)
    letter = "XYZ"[axis]
    w = feature.actions.work_offset
    if w is not None and w.axes != letter:
        raise SpecError(f"{feature.where}.set_work_offset.axes: expected {letter!r} (the "
                        f"axis of the face's normal), found {w.axes!r}")
    axes = "XY" if feature.kind == "line" else letter
    return axes, planar_fit(p, machine, axes)


def planar_fit(p: PlanarPlan, machine: MachineProfile, axes: str = "XYZ") -> Check:
    """The ``Check`` of a line or plane: its fit, nominal and limits, with the touches
    stored in ``axes``.  The program runs it for a feature with actions; ``ingest``
    evaluates every line and plane with it offline, actions or not."""
    feature = p.spec
    points = tuple(point_names(feature.id, k, axes) for k in range(1, len(p.starts) + 1))
    t = feature.tolerance
    limits = []
    if t.position is not None:
        limits.append(Limit("position", *t.position))
    if t.angle is not None:
        limits.append(Limit("angle", 0.0, t.angle))
    d = p.definition
    direction = direction_degrees(d) if isinstance(d, ir.LineDef) else 0.0
    nominal = d.start if isinstance(d, ir.LineDef) else d.point
    radius, corrections = calibrated_radius(machine, [p.normal] * len(points))
    return Check(feature.id, feature.kind, points, nominal, p.normal, 0.0, False,
                 radius, direction, tuple(limits),
                 feature.actions.on_fail, feature.actions.flag, corrections)


def calibrated_radius(machine: MachineProfile, normals: Sequence[ir.Vec3]
                      ) -> tuple[float, tuple[ir.Vec3, ...]]:
    """The radius a ``Check`` offsets by and its per-point corrections.

    Without a calibration: the nominal ball radius, no corrections.  With one (the
    machine's ``calibration``): its mean effective radius ``r_ref`` and, for each touch,
    ``(r(n) − r_ref)·n`` subtracted from its ball centre (``calibrated_centres``, the
    same function the offline evaluation uses), ``n`` the touch's nominal outward
    normal: the effective radius along each direction the action's touches use,
    computed from the calibration's map at plan time.
    """
    cal = for_stylus(machine.calibration, machine.probe.ball_radius, machine.source)
    if cal is None:
        return machine.probe.ball_radius, ()
    n = np.asarray(normals, dtype=np.float64).reshape(-1, 3)
    moved = calibrated_centres(np.zeros_like(n), n, cal, cal.effective_radius)
    return cal.effective_radius, tuple((float(x) + 0.0, float(y) + 0.0, float(z) + 0.0)
                                       for x, y, z in moved)


Store = tuple[str | None, str | None, str | None]


def _with_stores(nodes: tuple[ir.Node, ...], fid: str, axes: str
                 ) -> tuple[tuple[ir.Node, ...], tuple[Store, ...], tuple[ir.Vec3, ...]]:
    """Give every measuring touch of ``fid`` stores; return the nodes, the names and
    the touches' nominal outward normals."""
    names: list[Store] = []
    normals: list[ir.Vec3] = []

    def visit(node: ir.Node) -> ir.Node:
        if isinstance(node, ir.FeatureBlock):
            return dataclasses.replace(node, body=tuple(visit(n) for n in node.body))
        if isinstance(node, ir.Touch) and node.feature == fid:
            store = point_names(fid, node.index, axes)
            names.append(store)
            normals.append(node.normal)
            return dataclasses.replace(node, store=store)
        return node

    out = tuple(visit(n) for n in nodes)
    return out, tuple(names), tuple(normals)


def sphere_offset(feature: SphereTest, centre: ir.Vec3, running: str) -> SetWorkOffset | None:
    """A sphere test's ``set_work_offset`` from the centre the control located
    (``planning.locate``: run-time values ``<id>_CX``, ``_CY``, ``_CZ``)."""
    w = feature.actions.work_offset
    if w is None:
        return None
    shifts = tuple((i, f"{feature.id}_C{'XYZ'[i]}", centre[i])
                   for i in range(3) if "XYZ"[i] in w.axes)
    return SetWorkOffset(feature.id, w.offset, running, shifts)


def check_options(spec: Spec) -> None:
    """Refuse an action that needs a controller option the machine profile does not
    declare (``[controller] options``): ``align = { mode = "g68" }`` needs G68,
    ``set_work_offset`` to ``G54.1 Pn`` needs the extended work offsets (``G54.1``, on a
    Haas profile ``G154``).

    Raises:
        SpecError: names the feature's key, the option and the profile key.
    """
    machine = spec.machine
    extended = "G154" if machine.dialect == "haas" else "G54.1"
    for feature in spec.features:
        actions = getattr(feature, "actions", None)
        if actions is None:
            continue
        if actions.align is not None and actions.align.mode == "g68":
            machine.require("G68", f"{feature.where}.align.mode",
                            "align = { mode = \"g68\" } (G68 rotation)")
        w = actions.work_offset
        if w is not None and w.offset not in WORK_OFFSETS:
            machine.require(extended, f"{feature.where}.set_work_offset.offset",
                            f"work offset {w.offset}")


def final_actions(checked: Sequence[tuple[RevolvedSpec | PlanarSpec, Check]],
                  running: str, spheres: Sequence[SetWorkOffset] = ()) -> tuple[ir.Node, ...]:
    """The work offset, tool and rotation updates after every feature was checked
    (``spheres``: the sphere tests' offsets, first)."""
    offsets: list[ir.Node] = list(spheres)
    tools: list[ir.Node] = []
    aligns: list[tuple[RevolvedSpec | PlanarSpec, Check]] = []
    centre = (0.0, 0.0)
    for s in spheres:
        if {i for i, _, _ in s.shifts} >= {0, 1}:
            centre = (s.shifts[0][2], s.shifts[1][2])
    for feature, check in checked:
        a = feature.actions
        if a.work_offset is not None:
            shifts = tuple((i, _value_of(check, i), check.nominal[i])
                           for i in range(3) if "XYZ"[i] in a.work_offset.axes)
            offsets.append(SetWorkOffset(feature.id, a.work_offset.offset, running, shifts))
            if "X" in a.work_offset.axes and "Y" in a.work_offset.axes:
                centre = (check.nominal[0], check.nominal[1])
        if a.tool is not None:
            u = a.tool
            tools.append(UpdateTool(feature.id, u.tool, u.offset, result(feature.id, "E"),
                                    u.dead_band, u.max_correction, u.feedback))
        if a.align is not None:
            aligns.append((feature, check))
    rotations = [Align(f.id, result(f.id, "A"), centre, f.actions.align.mode,
                       f.actions.align.variable)
                 for f, _ in aligns if f.actions.align is not None]
    return (*offsets, *tools, *rotations)


def _value_of(check: Check, axis: int) -> str:
    """The result that gives ``axis`` of the feature's position."""
    if check.fit == "circle":
        return result(check.feature, "XY"[axis])
    return result(check.feature, "P")
