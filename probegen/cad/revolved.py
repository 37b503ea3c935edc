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

Part of the ``cad`` package, the only place that imports OCP.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from OCP.Bnd import Bnd_Box
from OCP.BRepBndLib import BRepBndLib
from OCP.gp import gp_Dir, gp_Lin, gp_Pnt, gp_Trsf
from OCP.IntCurvesFace import IntCurvesFace_ShapeIntersector
from OCP.TopLoc import TopLoc_Location

from probegen.cad import FaceRecord, Model, Vec3
from probegen.cad.exact import CLASSIFY_TOLERANCE, ExactFaces
from probegen.errors import ModelError
from probegen.geometry.frames import rotation_to_z

FloatArray = NDArray[np.float64]
Arc = tuple[float, float]
"""An azimuth interval ``(start, end)``, rad: ``0 <= start < 2π``, ``start < end <= start + 2π``."""

TWO_PI = 2.0 * math.pi
FULL_CIRCLE: tuple[Arc, ...] = ((0.0, TWO_PI),)
REVOLVED_TYPES = ("cylinder", "cone", "sphere", "torus")

SAME_LENGTH = 1e-4
"""Axes, centres and radii that agree to this (mm) belong to one surface: STEP writers
round at 1e-7 to 1e-6 mm, and no two machined surfaces are meant to be this close."""
SAME_ANGLE = 1e-6
"""Axis directions and cone half angles that agree to this (rad) are the same."""
VERTICAL = 1e-6
"""An axis within this angle (rad) of ±Z is vertical."""
ARC_STEP_ANGLE = math.radians(1.0)
"""Largest azimuth step when sampling a section circle, rad."""
ARC_STEP_LENGTH = 0.5
"""Largest arc length between samples of a section circle, mm (governs large radii):
an interruption of the face shorter than the step can slip between two samples."""
ARC_REFINE = 1e-7
"""The ends of each interval are bisected between samples to this, rad."""
SHORT_FEATURE = 4.0
"""A cylinder or cone shorter than this (mm) gets one section, at its middle."""
SECTION_INSET = 0.1
"""A sphere or torus section stays this fraction of the extent away from its ends."""


@dataclass(frozen=True, slots=True)
class FeatureSection:
    """One section of a revolved feature: a circle square to its axis.

    Attributes:
        axial: position along the axis from the feature's origin, mm.
        centre: the circle's centre on the axis, mm.
        radius: the circle's radius on the surface, mm.
        tilt: angle of the outward normal out of the section plane, rad, positive
            towards ``+axis``.
        arcs: azimuth intervals of the circle that lie on the feature's faces, sorted
            by start; :data:`FULL_CIRCLE` when the whole circle does.
        reachable: whether a vertical probe can reach the section.
        reason: why not (empty when reachable).
    """

    axial: float
    centre: Vec3
    radius: float
    tilt: float
    arcs: tuple[Arc, ...]
    reachable: bool
    reason: str

    @property
    def full(self) -> bool:
        """Whether the whole circle lies on the feature."""
        return self.arcs == FULL_CIRCLE


@dataclass(frozen=True, slots=True)
class RevolvedFeature:
    """One surface of revolution of a model, possibly made of several faces.

    Attributes:
        id: 1-based index in the order of :func:`revolved_features`.
        type: ``cylinder``, ``cone``, ``sphere`` or ``torus``.
        faces: the model face ids, ascending.
        origin: the point of the axis where axial positions start (see module doc).
        axis: unit vector (see module doc for its sense).
        inner: M2 sense: True when the outward normal leans towards the axis.
        radius: cylinder, sphere: the radius; cone: the radius at ``origin``; torus:
            the major radius.
        minor_radius: torus tube radius, else None.
        half_angle: cone half angle (positive), else None.
        tube_side: torus: +1 when the faces lie on the outer half of the tube (farther
            from the axis than the centre circle), -1 on the inner half; else 0.
        extent: lowest and highest axial position of the faces, mm.
        sections: the default sections (see :func:`default_axials`).
        accessible: whether a vertical probe can measure at least one section.
        reason: why not (empty when accessible).
    """

    id: int
    type: str
    faces: tuple[int, ...]
    origin: Vec3
    axis: Vec3
    inner: bool
    radius: float
    minor_radius: float | None
    half_angle: float | None
    tube_side: int
    extent: tuple[float, float]
    sections: tuple[FeatureSection, ...]
    accessible: bool
    reason: str

    @property
    def length(self) -> float:
        """Length of the extent along the axis, mm."""
        return self.extent[1] - self.extent[0]

    def radius_at(self, axial: float) -> float:
        """Radius of the section circle at ``axial`` (0 where the surface has none)."""
        return _radius_at(self.type, self.radius, self.minor_radius, self.half_angle,
                          self.tube_side, axial)

    def tilt_at(self, axial: float) -> float:
        """Angle of the outward normal out of the section plane at ``axial``, rad."""
        sigma = -1.0 if self.inner else 1.0
        if self.type == "cone":
            return -sigma * (self.half_angle or 0.0)
        if self.type == "cylinder":
            return 0.0
        size = self.minor_radius if self.type == "torus" else self.radius
        sense = sigma * (self.tube_side if self.type == "torus" else 1)
        return math.asin(min(max(sense * axial / (size or 1.0), -1.0), 1.0))

    def centre_at(self, axial: float) -> Vec3:
        """The point of the axis at ``axial``, mm."""
        return _vec3(np.add(self.origin, axial * np.asarray(self.axis)))

    def frame(self) -> FloatArray:
        """The azimuth frame: (3, 3) float, rows ``e1, e2, axis``."""
        return rotation_to_z(self.axis)


def _radius_at(kind: str, radius: float, minor: float | None, half: float | None,
               side: int, axial: float) -> float:
    """The section radius of a surface of revolution at ``axial`` (see the feature)."""
    if kind == "cylinder":
        return radius
    if kind == "cone":
        return max(radius + axial * math.tan(half or 0.0), 0.0)
    if kind == "sphere":
        return math.sqrt(max(radius * radius - axial * axial, 0.0))
    tube = minor or 0.0
    return max(radius + side * math.sqrt(max(tube * tube - axial * axial, 0.0)), 0.0)


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


# ----------------------------------------------------------------------- sections


def default_axials(kind: str, extent: tuple[float, float]) -> tuple[float, ...]:
    """Default section positions along the axis.

    Cylinders and cones: at 25 % and 75 % of the extent, or one at the middle when the
    feature is shorter than :data:`SHORT_FEATURE`.  Spheres and tori: the equator
    (``h = 0``, the widest circle of a sphere or of a torus's outer half), moved
    inside the extent by :data:`SECTION_INSET` of its length when the faces do not
    reach it.

    Args:
        kind: the feature type.
        extent: lowest and highest axial position, mm.
    """
    low, high = extent
    length = high - low
    if kind in ("cylinder", "cone"):
        if length < SHORT_FEATURE:
            return (low + 0.5 * length,)
        return (low + 0.25 * length, low + 0.75 * length)
    inset = SECTION_INSET * length
    return (min(max(0.0, low + inset), high - inset),)


class _Queries:
    """The exact face tests and the ray caster of one model, built on first use."""

    def __init__(self, model: Model) -> None:
        self.model = model
        self.exact = ExactFaces(model)
        self._rays: IntCurvesFace_ShapeIntersector | None = None

    def hits_up(self, point: FloatArray) -> list[float]:
        """Parameters (mm, ascending) where the ray ``point + t·Z``, ``t > 0``, meets a face."""
        if self._rays is None:
            self._rays = IntCurvesFace_ShapeIntersector()
            self._rays.Load(self.model._shape.wrapped, CLASSIFY_TOLERANCE)
        top = self.model.bbox_max[2] - float(point[2]) + 1.0
        line = gp_Lin(gp_Pnt(*map(float, point)), gp_Dir(0.0, 0.0, 1.0))
        self._rays.Perform(line, SAME_LENGTH, max(top, 2.0 * SAME_LENGTH))
        if not self._rays.IsDone():
            return []
        return sorted(self._rays.WParameter(i) for i in range(1, self._rays.NbPnt() + 1))


_QUERIES: dict[int, tuple[Model, _Queries]] = {}


def _queries(model: Model) -> _Queries:
    """The model's :class:`_Queries`, built once per loaded model (the ray caster's
    load alone takes tens of milliseconds on a large model)."""
    hit = _QUERIES.get(id(model))
    if hit is None or hit[0] is not model:
        hit = _QUERIES[id(model)] = (model, _Queries(model))
    return hit[1]


def _sample_count(radius: float) -> int:
    """How many equally spaced samples a section circle of ``radius`` gets."""
    by_angle = math.ceil(TWO_PI / ARC_STEP_ANGLE)
    return max(by_angle, math.ceil(TWO_PI * radius / ARC_STEP_LENGTH))


def _bisect(on: Callable[[float], bool], inside: float, outside: float) -> float:
    """The switch between ``inside`` (on the face) and ``outside``, to :data:`ARC_REFINE`."""
    while abs(outside - inside) > ARC_REFINE:
        middle = 0.5 * (inside + outside)
        if on(middle):
            inside = middle
        else:
            outside = middle
    return inside


def section_arcs(on: Callable[[float], bool], count: int,
                 inside: Sequence[bool] | None = None) -> tuple[Arc, ...]:
    """Azimuth intervals where ``on(φ)`` holds, from ``count`` samples plus bisection.

    Args:
        on: whether the circle's point at azimuth φ (rad) lies on the faces.
        count: number of equally spaced samples over the circle.
        inside: ``on`` at the samples ``2πk/count`` when the caller has them already.

    Returns:
        The intervals (see :data:`Arc`), sorted by start; :data:`FULL_CIRCLE` when every
        sample is on the faces; empty when none is.
    """
    step = TWO_PI / count
    if inside is None:
        inside = [on(k * step) for k in range(count)]
    if all(inside):
        return FULL_CIRCLE
    first_out = inside.index(False)  # walk from an outside sample: no run wraps
    arcs: list[Arc] = []
    j = first_out
    while j < first_out + count:
        if not inside[j % count]:
            j += 1
            continue
        run_start = j
        while inside[j % count]:
            j += 1
        start = _bisect(on, run_start * step, (run_start - 1) * step)
        end = _bisect(on, (j - 1) * step, j * step)
        offset = math.floor(start / TWO_PI) * TWO_PI
        arcs.append((start - offset, end - offset))
    return tuple(sorted(arcs))


def _reach(queries: _Queries, axis: Vec3, inner: bool, centre: FloatArray) -> str:
    """Why a vertical probe cannot reach a section (empty when it can).

    A ray from a point in air that meets no face leaves the part, so the solid is
    classified only where the ray meets a face: at the centre, and just past the hit.
    """
    if math.hypot(axis[0], axis[1]) > VERTICAL:
        return (f"axis ({axis[0]:.4f}, {axis[1]:.4f}, {axis[2]:.4f}) is not parallel to Z: "
                "a vertical probe reaches only sections square to Z")
    if not inner:
        return ""
    hits = queries.hits_up(centre)
    if not hits:
        return ""
    if queries.exact.inside(centre):
        return "the section's centre lies in material"
    after = hits[1] if len(hits) > 1 else hits[0] + 2.0 * SAME_LENGTH
    if queries.exact.inside(centre + np.array([0.0, 0.0, 0.5 * (hits[0] + after)])):
        return f"closed above: material at z = {centre[2] + hits[0]:.4f} over the centre"
    return ""


class _Circle:
    """Tells which azimuths of one section circle lie on a feature's faces."""

    def __init__(self, queries: _Queries, feature: RevolvedFeature, centre: FloatArray,
                 radius: float) -> None:
        frame = feature.frame()
        self.queries, self.faces = queries, list(feature.faces)
        self.centre, self.e1, self.e2 = centre, radius * frame[0], radius * frame[1]

    def __call__(self, phi: float) -> bool:
        """Whether the point at azimuth ``phi`` lies on one of the faces."""
        return self.holds(self.centre + math.cos(phi) * self.e1 + math.sin(phi) * self.e2)

    def holds(self, point: FloatArray) -> bool:
        """Whether ``point`` lies on a face; the face that held last is asked first."""
        for k, face in enumerate(self.faces):
            if self.queries.exact.contains(face - 1, point):
                if k:
                    self.faces.insert(0, self.faces.pop(k))
                return True
        return False

    def samples(self, count: int) -> list[bool]:
        """``holds`` at ``count`` equally spaced azimuths from 0."""
        phi = np.arange(count)[:, None] * (TWO_PI / count)
        points = self.centre + np.cos(phi) * self.e1 + np.sin(phi) * self.e2
        return [self.holds(p) for p in points]


def _section(queries: _Queries, feature: RevolvedFeature, axial: float) -> FeatureSection:
    """Build one :class:`FeatureSection` of ``feature`` at ``axial``."""
    centre = np.asarray(feature.centre_at(axial))
    radius = feature.radius_at(axial)
    arcs: tuple[Arc, ...] = ()
    if radius > SAME_LENGTH:
        circle = _Circle(queries, feature, centre, radius)
        count = _sample_count(radius)
        arcs = section_arcs(circle, count, circle.samples(count))
    reason = _reach(queries, feature.axis, feature.inner, centre)
    if not arcs and not reason:
        reason = "no arc of the section lies on the feature's faces"
    return FeatureSection(axial, _vec3(centre), radius, feature.tilt_at(axial), arcs,
                          not reason, reason)


def section_at(model: Model, feature: RevolvedFeature, axial: float) -> FeatureSection:
    """A section of ``feature`` at any axial position inside its extent.

    Args:
        model: the model the feature came from.
        feature: a feature of :func:`revolved_features`.
        axial: position along the axis from ``feature.origin``, mm.

    Raises:
        ModelError: ``axial`` lies outside the feature's extent.
    """
    low, high = feature.extent
    if not low - SAME_LENGTH <= axial <= high + SAME_LENGTH:
        raise ModelError(f"{model.path}: revolved feature {feature.id} (faces "
                         f"{_ids(feature.faces)}): expected a section from {low:.4f} to "
                         f"{high:.4f} mm along the axis, found {axial:.4f}")
    return _section(_queries(model), feature, axial)


# ---------------------------------------------------------------------- features


def revolved_features(model: Model) -> tuple[RevolvedFeature, ...]:
    """Recognise the revolved features of a model, with their default sections.

    Faces of type cylinder, cone, sphere and torus are grouped by surface (same axis
    line, radii / half angle and M2 sense); a group splits where its faces leave a gap
    along the axis (two lands of one shaft are two features).

    Args:
        model: a loaded model.

    Returns:
        The features, ordered by their lowest face id.
    """
    queries = _queries(model)
    surfaces = [_surface(f) for f in model.faces if f.type in REVOLVED_TYPES]
    runs = [(group[0], faces, low, high)
            for group in _surface_groups(surfaces)
            for faces, low, high in _axial_clusters(model, group)]
    runs.sort(key=lambda run: min(run[1]))
    return tuple(_feature(queries, index, *run) for index, run in enumerate(runs, start=1))


def _feature(queries: _Queries, index: int, ref: _Surface, faces: list[int], low: float,
             high: float) -> RevolvedFeature:
    """Assemble one feature from its reference surface and its run of faces."""
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
    sections = tuple(_section(queries, bare, h) for h in default_axials(ref.type, extent))
    reachable = [s for s in sections if s.reachable]
    reason = "" if reachable else (sections[0].reason if sections else "no section")
    return RevolvedFeature(
        id=bare.id, type=bare.type, faces=bare.faces, origin=bare.origin, axis=bare.axis,
        inner=bare.inner, radius=bare.radius, minor_radius=bare.minor_radius,
        half_angle=bare.half_angle, tube_side=bare.tube_side, extent=bare.extent,
        sections=sections, accessible=bool(reachable), reason=reason,
    )  # fmt: skip


# ------------------------------------------------------------------------- output


def _vec3(values: Sequence[float] | FloatArray) -> Vec3:
    """A 3-tuple of plain floats."""
    return (float(values[0]), float(values[1]), float(values[2]))


def _ids(faces: Sequence[int]) -> str:
    """Face ids as ``78,79``."""
    return ",".join(str(f) for f in faces)


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
