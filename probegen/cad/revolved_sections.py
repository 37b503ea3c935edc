"""Accessible-range analysis of revolved features: which arcs of a section lie on the
faces, and whether a vertical probe can reach it.

Owns the default section positions, the sampling and bisection of a section circle
against the trimmed faces (:func:`section_arcs`), the reachability test (a ray up from
an inner section's centre) and :func:`section_at`.  The exact face tests come from
:mod:`probegen.cad.exact`; the features from :mod:`probegen.cad.revolved`.  Part of the
``cad`` package, the only place that imports OCP.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np
import OCP.Standard
from OCP.gp import gp_Dir, gp_Lin, gp_Pnt
from OCP.IntCurvesFace import IntCurvesFace_Intersector, IntCurvesFace_ShapeIntersector

from probegen.cad.exact import CLASSIFY_TOLERANCE
from probegen.cad.faces import Vec3
from probegen.cad.part import Part
from probegen.cad.revolved_records import (
    FULL_CIRCLE,
    SAME_LENGTH,
    TWO_PI,
    Arc,
    FeatureSection,
    FloatArray,
    RevolvedFeature,
    _ids,
    _vec3,
)
from probegen.errors import ModelError

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


OCCT_FAILURES: tuple[type[Exception], ...] = tuple(
    e for name in dir(OCP.Standard) if name.startswith("Standard_")
    and isinstance(e := getattr(OCP.Standard, name), type) and issubclass(e, Exception))
"""OCCT's exceptions as OCP raises them (each its own class: ``Standard_NullObject`` is
not a ``Standard_Failure`` in Python)."""


class _Queries:
    """The exact face tests and the ray caster of one part, built on first use."""

    def __init__(self, part: Part) -> None:
        self.model = part.model
        self.exact = part.exact
        self._rays: IntCurvesFace_ShapeIntersector | None = None

    def hits_up(self, point: FloatArray) -> list[float]:
        """Parameters (mm, ascending) where the ray ``point + t·Z``, ``t > 0``, meets a face."""
        if self._rays is None:
            self._rays = IntCurvesFace_ShapeIntersector()
            self._rays.Load(self.model._shape.wrapped, CLASSIFY_TOLERANCE)
        top = self.model.bbox_max[2] - float(point[2]) + 1.0
        line = gp_Lin(gp_Pnt(*map(float, point)), gp_Dir(0.0, 0.0, 1.0))
        try:
            self._rays.Perform(line, SAME_LENGTH, max(top, 2.0 * SAME_LENGTH))
        except OCCT_FAILURES:
            return self._hits_face_by_face(line, max(top, 2.0 * SAME_LENGTH))
        if not self._rays.IsDone():
            return []
        return sorted(self._rays.WParameter(i) for i in range(1, self._rays.NbPnt() + 1))

    def _hits_face_by_face(self, line: gp_Lin, far: float) -> list[float]:
        """:meth:`hits_up` one face at a time, where OCCT's whole-shape intersector fails
        on a face (seen on NIST CTC 4 along a horizontal ray: ``Standard_NullObject``); a
        face whose own intersection fails is passed over (the collision check of every
        planned move, on the mesh, stays the judge of what is in the way)."""
        hits: list[float] = []
        for face in self.model._topo_faces:
            try:
                one = IntCurvesFace_Intersector(face, CLASSIFY_TOLERANCE)
                one.Perform(line, SAME_LENGTH, far)
            except OCCT_FAILURES:
                continue
            if one.IsDone():
                hits += [one.WParameter(i) for i in range(1, one.NbPnt() + 1)]
        return sorted(hits)


def _queries(part: Part) -> _Queries:
    """The part's :class:`_Queries`, built once per part (the ray caster's load alone
    takes tens of milliseconds on a large model)."""
    return part.memo(("revolved section queries",), lambda: _Queries(part))


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


def _reach(queries: _Queries, axis: Vec3, inner: bool, centre: FloatArray,
           beside: Sequence[FloatArray] = ()) -> str:
    """Why a vertical probe cannot reach a section (empty when it can).

    A ray from a point in air that meets no face leaves the part, so the solid is
    classified only where the ray meets a face: at the centre, and just past the hit.
    An inner section whose centre lies in material (the concave wall of a groove around
    an island, a letter engraved in a face) is reached where its arcs are: the section
    is reachable when the ray up from one of the points ``beside`` its arcs (in air just
    inside the wall, :func:`_beside`) is open; the collision check of every planned move
    stays the judge of the path.
    """
    if math.hypot(axis[0], axis[1]) > VERTICAL:
        return (f"axis ({axis[0]:.4f}, {axis[1]:.4f}, {axis[2]:.4f}) is not parallel to Z: "
                "a vertical probe reaches only sections square to Z")
    if not inner:
        return ""
    why = _closed_above(queries, centre, "the centre")
    if why != IN_MATERIAL or not beside:
        return why
    open_beside = any(not queries.exact.inside(p) and not _closed_above(queries, p, "")
                      for p in beside)
    return "" if open_beside else (
        "the section's centre lies in material and no arc has open air above it")


IN_MATERIAL = "the section's centre lies in material"


def _closed_above(queries: _Queries, point: FloatArray, what: str) -> str:
    """Why the ray up from ``point`` does not lead out of the part into the open (empty
    when it does): ``point`` in material, or material over it (``what`` names it)."""
    hits = queries.hits_up(point)
    if not hits:
        return ""
    if queries.exact.inside(point):
        return IN_MATERIAL
    after = hits[1] if len(hits) > 1 else hits[0] + 2.0 * SAME_LENGTH
    if queries.exact.inside(point + np.array([0.0, 0.0, 0.5 * (hits[0] + after)])):
        return f"closed above: material at z = {point[2] + hits[0]:.4f} over {what}"
    return ""


BESIDE_DEPTH = 0.5
"""The point beside an arc lies this far inside the wall (at most a quarter of the
radius), mm."""


def _beside(feature: RevolvedFeature, centre: FloatArray, radius: float,
            arcs: tuple[Arc, ...]) -> list[FloatArray]:
    """A point in the air side of each partial arc of an inner section: at the arc's
    middle azimuth, :data:`BESIDE_DEPTH` inside the wall (none for a full circle)."""
    if arcs == FULL_CIRCLE or not feature.inner:
        return []
    frame = feature.frame()
    inset = radius - min(BESIDE_DEPTH, 0.25 * radius)
    middles = [0.5 * (a + b) for a, b in arcs]
    return [centre + inset * (math.cos(phi) * frame[0] + math.sin(phi) * frame[1])
            for phi in middles]


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
    reason = _reach(queries, feature.axis, feature.inner, centre,
                    _beside(feature, centre, radius, arcs))
    if not arcs and not reason:
        reason = "no arc of the section lies on the feature's faces"
    return FeatureSection(axial, _vec3(centre), radius, feature.tilt_at(axial), arcs,
                          not reason, reason)


def section_at(part: Part, feature: RevolvedFeature, axial: float) -> FeatureSection:
    """A section of ``feature`` at any axial position inside its extent.

    Args:
        part: the part the feature came from.
        feature: a feature of :func:`revolved_features`.
        axial: position along the axis from ``feature.origin``, mm.

    Raises:
        ModelError: ``axial`` lies outside the feature's extent.
    """
    low, high = feature.extent
    if not low - SAME_LENGTH <= axial <= high + SAME_LENGTH:
        raise ModelError(f"{part.path}: revolved feature {feature.id} (faces "
                         f"{_ids(feature.faces)}): expected a section from {low:.4f} to "
                         f"{high:.4f} mm along the axis, found {axial:.4f}")
    return _section(_queries(part), feature, axial)

