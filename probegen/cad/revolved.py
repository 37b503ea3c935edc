"""Revolved features of a model: cylinders, cones, spheres and tori, grouped by surface.

A *revolved feature* is one surface of revolution as a measuring task sees it: the
faces that lie on the same analytic surface (a bore that the STEP writer split into two
half-cylinders is one bore) and that touch along the axis.  For each feature this
module reports its axis, its extent along the axis, its radius and normal at any axial
position, and, for a few default *sections* (circles square to the axis), the azimuth
intervals of the circle that lie on the trimmed faces (a bore cut by a slot, a boss
beside a wall) and whether a vertical probe can reach the section.

Conventions (all lengths mm, angles rad):

* ``axis`` is a unit vector.  Cylinders and tori point up (``z > 0``; horizontal axes:
  ``y > 0``, then ``x > 0``); a cone's axis points where its radius grows (as in
  :class:`probegen.cad.FaceRecord`); a sphere's axis is +Z, the shank direction of a
  vertical probe (any line through the centre is an axis of a sphere).
* Axial positions ``h`` are measured from ``origin`` along ``axis``: cylinders and
  cones have ``origin`` at the low end of the extent (extent ``(0, length)``); spheres
  and tori have it at the centre.
* Azimuths are measured in the frame ``rotation_to_z(axis)`` (rows ``e1, e2, e3``,
  :func:`probegen.geometry.frames.rotation_to_z`): a section point is
  ``centre + radius·(cos φ·e1 + sin φ·e2)``.  For ``axis = +Z`` that is the usual
  polar angle from +X towards +Y.  The planner (method M2) uses the same frame.
* ``inner`` is the sense of method M2: True when the outward surface normal (away from
  the material) leans towards the axis (a bore, a countersink, a fillet at the foot of
  a bore), False when it leans away (a boss, a shaft, a ball).  ``tilt`` is the angle
  of that normal out of the section plane, positive towards ``+axis`` (0 for
  cylinders and at a sphere's equator).

Accessibility is decided simply: the vertical probe reaches only features whose axis is
parallel to Z (either sense).  An inner section is also refused when a ray up (+Z)
from its centre enters material (a bore that opens downwards) or starts in material.
The collision check of the planned path stays the final judge.

This module recognises the features (faces grouped by surface, split along the axis)
and lists them; the records are in :mod:`probegen.cad.revolved_records` and the
accessible-range analysis of sections in :mod:`probegen.cad.revolved_sections`
(:func:`section_at` and :func:`section_arcs` are re-exported here).

Part of the ``cad`` package, the only place that imports OCP.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np
from OCP.Bnd import Bnd_Box
from OCP.BRepBndLib import BRepBndLib
from OCP.gp import gp_Trsf
from OCP.TopLoc import TopLoc_Location

from probegen.cad.faces import FaceRecord, Model, Vec3
from probegen.cad.part import Part
from probegen.cad.revolved_records import (
    FULL_CIRCLE,
    SAME_LENGTH,
    Arc,
    RevolvedFeature,
    _ids,
    _radius_at,
    _vec3,
)
from probegen.cad.revolved_sections import (
    VERTICAL,
    _Queries,
    _queries,
    _reach,
    _section,
    default_axials,
    section_arcs,
    section_at,
)
from probegen.geometry.frames import rotation_to_z

__all__ = [
    "FULL_CIRCLE",
    "REVOLVED_TYPES",
    "SAME_ANGLE",
    "Arc",
    "RevolvedFeature",
    "revolved_features",
    "revolved_table",
    "section_arcs",
    "section_at",
]

REVOLVED_TYPES = ("cylinder", "cone", "sphere", "torus")

SAME_ANGLE = 1e-6
"""Axis directions and cone half angles that agree to this (rad) are the same."""


# ----------------------------------------------------------------------- surfaces


@dataclass(frozen=True, slots=True)
class _Surface:
    """The analytic surface of one face, in the feature's conventions (floats)."""

    face: int
    type: str
    origin: Vec3
    axis: Vec3
    radius: float
    minor: float | None
    half: float | None
    inner: bool
    side: int


def _canonical(axis: Vec3) -> Vec3:
    """``axis`` or its negative, whichever points up (then +Y, then +X)."""
    for c in (axis[2], axis[1], axis[0]):
        if abs(c) > SAME_ANGLE:
            return axis if c > 0.0 else (-axis[0], -axis[1], -axis[2])
    return axis


def _surface(record: FaceRecord) -> _Surface:
    """The :class:`_Surface` of a revolved face record."""
    kind, radius = record.type, record.radius or 0.0
    concave = bool(record.inner)
    if kind == "sphere":
        return _Surface(record.id, kind, record.origin, (0.0, 0.0, 1.0), radius, None, None,
                        concave, 0)
    if kind == "cone":
        return _Surface(record.id, kind, record.origin, record.axis, radius, None,
                        record.half_angle, concave, 0)
    axis = _canonical(record.axis)
    if kind == "cylinder":
        return _Surface(record.id, kind, record.origin, axis, radius, None, None, concave, 0)
    rel = np.subtract(record.centre, record.origin)
    spread = float(np.linalg.norm(rel - float(rel @ np.asarray(axis)) * np.asarray(axis)))
    side = 1 if spread >= radius else -1
    # the torus is concave or convex about its tube; M2's sense flips on the inner half
    inner = concave if side == 1 else not concave
    return _Surface(record.id, kind, record.origin, axis, radius, record.minor_radius,
                    None, inner, side)


def _off_axis(point: Vec3, origin: Vec3, axis: Vec3) -> tuple[float, float]:
    """(axial, radial) coordinates of ``point`` about the line ``origin + h·axis``."""
    rel = (point[0] - origin[0], point[1] - origin[1], point[2] - origin[2])
    along = rel[0] * axis[0] + rel[1] * axis[1] + rel[2] * axis[2]
    square = rel[0] ** 2 + rel[1] ** 2 + rel[2] ** 2 - along * along
    return along, math.sqrt(max(square, 0.0))


def _same(a: _Surface, b: _Surface) -> bool:
    """Whether two faces lie on the same surface (and on the same side of it)."""
    if (a.type, a.inner, a.side) != (b.type, b.inner, b.side):
        return False
    dot = sum(x * y for x, y in zip(a.axis, b.axis, strict=True))
    if math.sqrt(max(1.0 - dot * dot, 0.0)) > SAME_ANGLE:
        return False
    along, off = _off_axis(b.origin, a.origin, a.axis)
    if a.type == "cone":
        expected = a.radius + along * math.tan(a.half or 0.0)
        return (dot > 0.0 and off <= SAME_LENGTH and abs(expected - b.radius) <= SAME_LENGTH
                and abs((a.half or 0.0) - (b.half or 0.0)) <= SAME_ANGLE)
    if a.type in ("sphere", "torus") and math.hypot(along, off) > SAME_LENGTH:
        return False
    if off > SAME_LENGTH or abs(a.radius - b.radius) > SAME_LENGTH:
        return False
    return abs((a.minor or 0.0) - (b.minor or 0.0)) <= SAME_LENGTH


def _surface_groups(surfaces: Sequence[_Surface]) -> list[list[_Surface]]:
    """Faces grouped by surface, groups in the order of their first face."""
    groups: list[list[_Surface]] = []
    for s in surfaces:
        home = next((g for g in groups if _same(g[0], s)), None)
        if home is None:
            groups.append([s])
        else:
            home.append(s)
    return groups


# ------------------------------------------------------------------------ extents


def _axial_range(model: Model, face: int, origin: Vec3, axis: Vec3) -> tuple[float, float]:
    """Exact lowest and highest axial position of a face about ``origin``, ``axis``.

    The face is moved into the frame whose Z is the axis and its optimal (exact
    geometry) bounding box read along Z.
    """
    rot = rotation_to_z(axis)
    shift = -rot @ np.asarray(origin, dtype=np.float64)
    trsf = gp_Trsf()
    trsf.SetValues(*rot[0], shift[0], *rot[1], shift[1], *rot[2], shift[2])
    moved = model._topo_faces[face - 1].Moved(TopLoc_Location(trsf))
    box = Bnd_Box()
    BRepBndLib.AddOptimal_s(moved, box, False, False)
    return float(box.CornerMin().Z()), float(box.CornerMax().Z())


def _axial_clusters(model: Model, group: list[_Surface]
                    ) -> list[tuple[list[int], float, float]]:
    """Split one surface group into runs of faces that touch along the axis.

    Returns:
        ``(face ids, low, high)`` per run, axial positions about the group's first face.
    """
    ref = group[0]
    ranges = sorted((*_axial_range(model, s.face, ref.origin, ref.axis), s.face) for s in group)
    runs: list[tuple[list[int], float, float]] = []
    for low, high, face in ranges:
        if runs and low <= runs[-1][2] + SAME_LENGTH:
            faces, start, end = runs[-1]
            runs[-1] = (faces + [face], start, max(end, high))
        else:
            runs.append(([face], low, high))
    return runs


# ---------------------------------------------------------------------- features


def revolved_features(part: Part) -> tuple[RevolvedFeature, ...]:
    """Recognise the revolved features of a part, with their default sections (once per
    part: the part keeps them).

    Faces of type cylinder, cone, sphere and torus are grouped by surface (same axis
    line, radii / half angle and M2 sense); a group splits where its faces leave a gap
    along the axis (two lands of one shaft are two features).

    Args:
        part: a loaded part.

    Returns:
        The features, ordered by their lowest face id.
    """
    return part.memo(("revolved features",), lambda: _recognise(part))


def _recognise(part: Part) -> tuple[RevolvedFeature, ...]:
    queries = _queries(part)
    model = part.model
    surfaces = [_surface(f) for f in model.faces if f.type in REVOLVED_TYPES]
    runs = [(group[0], faces, low, high)
            for group in _surface_groups(surfaces)
            for faces, low, high in _axial_clusters(model, group)]
    runs.sort(key=lambda run: min(run[1]))
    turned = part.rotation is not None  # only its vertical features are measured there
    return tuple(_feature(queries, index, *run, sections=not turned or _vertical(run[0].axis))
                 for index, run in enumerate(runs, start=1))


def _vertical(axis: Vec3) -> bool:
    """Whether ``axis`` is along ±Z (:data:`probegen.cad.revolved_sections.VERTICAL`)."""
    return math.hypot(axis[0], axis[1]) <= VERTICAL


def _feature(queries: _Queries, index: int, ref: _Surface, faces: list[int], low: float,
             high: float, *, sections: bool = True) -> RevolvedFeature:
    """Assemble one feature from its reference surface and its run of faces; without
    ``sections`` (a feature not along Z of a turned part) no section is built and the
    feature is not accessible, with the reason of its axis."""
    origin, radius, extent = ref.origin, ref.radius, (low, high)
    if ref.type in ("cylinder", "cone"):
        origin = _vec3(np.add(ref.origin, low * np.asarray(ref.axis)))
        radius = _radius_at(ref.type, ref.radius, None, ref.half, 0, low)
        extent = (0.0, high - low)
    bare = RevolvedFeature(
        id=index, type=ref.type, faces=tuple(sorted(faces)), origin=origin, axis=ref.axis,
        inner=ref.inner, radius=radius, minor_radius=ref.minor, half_angle=ref.half,
        tube_side=ref.side, extent=extent, sections=(), accessible=False, reason="",
    )  # fmt: skip
    if not sections:
        reason = _reach(queries, ref.axis, ref.inner, np.asarray(origin))
        return replace(bare, reason=reason)
    built = tuple(_section(queries, bare, h) for h in default_axials(ref.type, extent))
    reachable = [s for s in built if s.reachable]
    reason = "" if reachable else (built[0].reason if built else "no section")
    return RevolvedFeature(
        id=bare.id, type=bare.type, faces=bare.faces, origin=bare.origin, axis=bare.axis,
        inner=bare.inner, radius=bare.radius, minor_radius=bare.minor_radius,
        half_angle=bare.half_angle, tube_side=bare.tube_side, extent=bare.extent,
        sections=built, accessible=bool(reachable), reason=reason,
    )  # fmt: skip


# ------------------------------------------------------------------------- output


def _fixed(value: float | None, decimals: int, width: int) -> str:
    """Fixed decimals right-aligned in ``width``; ``-`` for None; never ``-0.000``."""
    if value is None:
        return "-".rjust(width)
    text = f"{value:.{decimals}f}"
    return (f"{0.0:.{decimals}f}" if float(text) == 0.0 else text).rjust(width)


def _arc_text(arcs: tuple[Arc, ...]) -> str:
    """Arcs as start and span in degrees, e.g. ``15.466+329.068``; ``full`` or ``none``."""
    if arcs == FULL_CIRCLE:
        return "full"
    if not arcs:
        return "none"
    return " ".join(f"{math.degrees(a):.3f}+{math.degrees(b - a):.3f}" for a, b in arcs)


_HEADER = (f"{'id':>4}  {'type':<8}  {'side':<5}  {'faces':<12}  {'radius':>10}  "
           f"{'angle':>8}  {'origin x':>10} {'y':>10} {'z':>10}  {'axis x':>9} {'y':>9} "
           f"{'z':>9}  {'from':>9} {'to':>9}  access")


def revolved_table(features: Sequence[RevolvedFeature]) -> str:
    """A fixed-width text listing of revolved features, byte-for-byte repeatable.

    One row per feature (``radius``: see :class:`RevolvedFeature`; ``angle``: cone
    half angle, deg; ``from``/``to``: the axial extent) and one indented row per
    default section (axial position, centre, radius, tilt in degrees, and the arcs on
    the faces as ``start+span`` in degrees).
    Torus rows show the tube radius after the major radius as ``R/r``.
    """
    rows = [_HEADER]
    for f in features:
        size = _fixed(f.radius, 4, 10)
        if f.minor_radius is not None:
            size = f"{f.radius:.4f}/{f.minor_radius:.4f}".rjust(10)
        angle = None if f.half_angle is None else math.degrees(f.half_angle)
        access = "yes" if f.accessible else f"no: {f.reason}"
        rows.append(
            f"{f.id:>4}  {f.type:<8}  {'inner' if f.inner else 'outer':<5}  "
            f"{_ids(f.faces):<12}  {size}  {_fixed(angle, 4, 8)}  "
            f"{' '.join(_fixed(c, 4, 10) for c in f.origin)}  "
            f"{' '.join(_fixed(c, 6, 9) for c in f.axis)}  "
            f"{_fixed(f.extent[0], 4, 9)} {_fixed(f.extent[1], 4, 9)}  {access}")
        for s in f.sections:
            rows.append(
                f"      section h={_fixed(s.axial, 4, 0)} centre "
                f"({', '.join(_fixed(c, 4, 0) for c in s.centre)}) radius "
                f"{_fixed(s.radius, 4, 0)} tilt {_fixed(math.degrees(s.tilt), 3, 0)} "
                f"arcs {_arc_text(s.arcs)}{'' if s.reachable else ' (' + s.reason + ')'}")
    return "\n".join(rows) + "\n"
