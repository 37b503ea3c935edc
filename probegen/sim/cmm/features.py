"""Features of the virtual CMM: nominal definitions, measured actuals, constructions.

Every :class:`DmisFeature` is held in machine coordinates (MCS) and millimetres, so it
stays valid whatever frame is active later; the output converts it to the active PCS
and the program's units.

Measured features (:func:`fit_feature`) are fitted by least squares from the ball
centres the CMM recorded.  Stylus compensation, two modes:

* ``"feature"`` (default, what CMMs do for a measured feature): fit the shape to the
  ball centres, then offset it by the ball radius away from the side the probe came
  from (the PTMEAS vectors): a plane moves by ``r`` against its outward normal, an
  INNER circle/cylinder/sphere grows by ``r``, an OUTER one shrinks, a cone's apex
  moves ``r / sin(half angle)`` along its axis, a torus's tube grows by ``r`` (INNER:
  the air is inside the tube) or shrinks (OUTER), its centre and major diameter stay.
  Exact for any tilt of the real part.
* ``"vector"``: compensate each ball centre by ``r`` along its PTMEAS vector (the
  nominal surface normal) and fit those points; exact only where the real surface
  normal equals the nominal one (an error of ``r (1 - cos t)`` for a tilt ``t``).

Points and lines are always vector compensated.  Circles, cylinders, spheres, cones and
tori are fitted from the nominal (:func:`probegen.geometry.fits_nominal.fit_near`:
sparse CMM patterns fit several cylinders within the noise; the fit keeps the one
nearest the nominal, names the others in the actual's ``notes`` and refuses a
solution far from the nominal).

The actual's reported location: the fitted centre for circles, spheres and tori, the apex
for cones, and for unbounded features (plane, cylinder axis, line) the nominal
location projected onto the actual feature, so actual and nominal values compare
directly.  A cylinder keeps its nominal length (the points of a bore do not determine
it); a point keeps its nominal vector.  Directions are signed like the nominal's.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Literal

import numpy as np

from probegen.errors import ProbegenError
from probegen.geometry import determined, minimum_zone
from probegen.geometry.fits import (
    Circle3dFit,
    CylinderFit,
    SphereFit,
    TorusFit,
    fit_line_3d,
    fit_plane,
)
from probegen.geometry.fits_nominal import NominalShape, fit_near
from probegen.geometry.frames import FloatArray, orthonormal_basis, unit

Vec3 = tuple[float, float, float]
Compensation = Literal["feature", "vector"]

KINDS = ("POINT", "PLANE", "CIRCLE", "CYLNDR", "SPHERE", "CONE", "TORUS", "LINE")
"""Feature types the virtual CMM defines, measures and reports."""

SIDED = frozenset({"CIRCLE", "CYLNDR", "SPHERE", "CONE", "TORUS"})
"""Types written with INNER|OUTER."""


@dataclass(frozen=True, slots=True)
class DmisFeature:
    """A nominal (``F``) or actual (``FA``) feature, in MCS millimetres.

    Attributes:
        name: the label name (``C1`` for ``F(C1)``/``FA(C1)``).
        kind: one of :data:`KINDS`.
        qualifier: ``INNER``/``OUTER`` (circle, cylinder, sphere, cone, torus),
            ``BND``/``UNBND`` (line), None otherwise.  A torus is INNER when the air is
            inside its tube (a concave fillet), OUTER when the material is.
        location: point, centre (circle, sphere, torus), apex (cone), axis point or line
            start.
        vector: unit normal, axis or direction; None for a sphere written without one.
        size: diameter (circle, cylinder, sphere), major diameter (torus: twice the
            radius of the tube's centre circle) or included angle in degrees (cone).
        minor: torus only: the tube (minor) diameter.
        length: cylinder length, None if not given.
        end: end point of a bounded line.
        normal: the line's plane normal (``LINE`` with a third vector).
        form: actual only: flatness, roundness, cylindricity, sphericity or
            straightness by the ISO 1101 minimum zone (``geometry.minimum_zone``); a
            cone's conicity and a torus's form: the least-squares ``max - min`` residual.
        points: actual only: the compensated contact points, ``(n, 3)`` as tuples.
        notes: actual only: what the fit found besides the feature (another solution
            the points admit: :mod:`probegen.geometry.fits_nominal`).
        condition: actual only: the fit's condition number, None where not fitted
            iteratively.
    """

    name: str
    kind: str
    qualifier: str | None
    location: Vec3
    vector: Vec3 | None
    size: float | None = None
    minor: float | None = None
    length: float | None = None
    end: Vec3 | None = None
    normal: Vec3 | None = None
    form: float | None = None
    points: tuple[Vec3, ...] = ()
    notes: tuple[str, ...] = ()
    condition: float | None = None


def vec3(array: FloatArray) -> Vec3:
    """Return a ``(3,)`` array as a tuple of Python floats."""
    return (float(array[0]), float(array[1]), float(array[2]))


def arr(values: Vec3) -> FloatArray:
    """Return a tuple as a ``(3,)`` float array."""
    return np.array(values, dtype=np.float64)


def signed_like(direction: FloatArray, reference: Vec3 | None) -> FloatArray:
    """Return the unit ``direction`` flipped, if needed, to agree with ``reference``."""
    d = unit(direction, what="direction")
    if reference is not None and float(d @ arr(reference)) < 0.0:
        return -d
    return d


# ---------------------------------------------------------------- nominal definitions

_COUNTS = {
    "POINT": (6,), "PLANE": (6,), "CIRCLE": (7,), "CYLNDR": (7, 8), "SPHERE": (4, 7),
    "CONE": (7,), "TORUS": (8,), "LINE": (6, 9),
}
"""Numbers after ``CART`` each type takes (alternatives)."""


def parse_nominal(name: str, kind: str, qualifier: str | None,
                  numbers: list[float], scale: float) -> DmisFeature:
    """Build a nominal feature in PCS millimetres from the numbers of ``FEAT/...,CART,...``.

    Args:
        name: label name.
        kind: one of :data:`KINDS`.
        qualifier: INNER/OUTER/BND/UNBND or None.
        numbers: the values after ``CART`` as written.
        scale: millimetres per program unit.

    Raises:
        ValueError: wrong count of numbers or a zero vector.
    """
    if len(numbers) not in _COUNTS[kind]:
        raise ValueError(f"FEAT/{kind} takes {_counts_text(kind)} numbers after CART, "
                         f"found {len(numbers)}")
    v = np.array(numbers, dtype=np.float64)
    loc = vec3(v[:3] * scale)
    if kind == "LINE" and qualifier == "BND":
        end = v[3:6] * scale
        normal = vec3(unit(v[6:9], what="line normal")) if len(v) == 9 else None
        direction = vec3(unit(end - arr(loc), what="line end points"))
        return DmisFeature(name, kind, qualifier, loc, direction, end=vec3(end), normal=normal)
    if kind == "SPHERE":
        vector = vec3(unit(v[3:6], what="vector")) if len(v) == 7 else None
        return DmisFeature(name, kind, qualifier, loc, vector, size=float(v[-1]) * scale)
    vector = vec3(unit(v[3:6], what="vector"))
    if kind == "LINE":
        normal = vec3(unit(v[6:9], what="line normal")) if len(v) == 9 else None
        return DmisFeature(name, kind, qualifier, loc, vector, normal=normal)
    size = _nominal_size(kind, v, scale)
    if kind == "TORUS":
        return DmisFeature(name, kind, qualifier, loc, vector, size=size,
                           minor=float(v[7]) * scale)
    length = float(v[7]) * scale if kind == "CYLNDR" and len(v) == 8 else None
    return DmisFeature(name, kind, qualifier, loc, vector, size=size, length=length)


def _nominal_size(kind: str, v: FloatArray, scale: float) -> float | None:
    if kind == "CONE":
        return float(v[6])  # included angle, degrees: no unit scale
    if kind in ("CIRCLE", "CYLNDR", "TORUS"):
        return float(v[6]) * scale
    return None


def _counts_text(kind: str) -> str:
    return " or ".join(str(n) for n in _COUNTS[kind])


# ------------------------------------------------------------------------ measuring

SHAPES = {"CIRCLE": "circle", "CYLNDR": "cylinder", "SPHERE": "sphere", "CONE": "cone",
          "TORUS": "torus"}
"""The shape name (``geometry.fits_nominal``, ``geometry.determined``) of each sided type."""
MINIMUM_POINTS = {"POINT": 1, "PLANE": 3, "LINE": 2} | {
    kind: determined.MINIMUM_POINTS[shape] for kind, shape in SHAPES.items()}
"""Fewest points each measured type needs (those of the least-squares fits)."""


def undetermined(nominal: DmisFeature, centres: FloatArray) -> str:
    """Why the measured ball centres do not determine a circle, cylinder, sphere, cone or
    torus in a free fit, as a CMM fits (:func:`probegen.geometry.determined.undetermined`:
    a cone in one section, a sphere on one circle, a torus in two tube positions), or
    ``""`` (also for the other types)."""
    shape = SHAPES.get(nominal.kind)
    if shape is None:
        return ""
    return determined.undetermined(shape, centres, nominal.vector)


def fit_feature(nominal: DmisFeature, centres: FloatArray, vectors: FloatArray,
                radius: float, compensation: Compensation) -> DmisFeature:
    """Fit the actual feature to measured ball centres and compensate the stylus.

    Args:
        nominal: the nominal feature (MCS).
        centres: ``(n, 3)`` float, ball centres where the probe touched (MCS).
        vectors: ``(n, 3)`` float, the unit PTMEAS vectors (out of the material, MCS).
        radius: the stylus ball radius used for compensation (mm).
        compensation: ``"feature"`` or ``"vector"`` (see the module docstring).

    Returns:
        The actual feature (MCS), with ``form`` and the compensated ``points``.

    Raises:
        ProbegenError: the fit cannot use the points (too few, degenerate).
    """
    contacts = centres - radius * vectors
    kind = nominal.kind
    if kind in ("POINT", "LINE") or compensation == "vector":
        fitted = fit_points(nominal, contacts)
    elif kind == "PLANE":
        fitted = _fit_plane(nominal, centres, vectors, radius)
    else:
        fitted = _fit_offset_shape(nominal, centres, radius)
    return replace(fitted, points=tuple(vec3(p) for p in contacts))


def fit_points(nominal: DmisFeature, points: FloatArray) -> DmisFeature:
    """Fit contact points (already compensated) directly."""
    kind = nominal.kind
    if kind == "POINT":
        return replace(nominal, location=vec3(points.mean(axis=0)), form=0.0)
    if kind == "LINE":
        return _fit_line(nominal, points)
    if kind == "PLANE":
        return _fit_plane(nominal, points, np.zeros_like(points), 0.0)
    return _fit_offset_shape(nominal, points, 0.0)


def _fit_plane(nominal: DmisFeature, centres: FloatArray, vectors: FloatArray,
               radius: float) -> DmisFeature:
    fit = fit_plane(centres)
    n = signed_like(arr(fit.normal), nominal.vector)
    side = 1.0 if float(vectors.sum(axis=0) @ n) >= 0.0 else -1.0
    point = arr(fit.point) - side * radius * n
    return replace(nominal, location=_onto_plane(arr(nominal.location), point, n),
                   vector=vec3(n), form=minimum_zone.flatness(centres, fit.point, fit.normal))


def _fit_offset_shape(nominal: DmisFeature, centres: FloatArray, radius: float) -> DmisFeature:
    """Circle, cylinder, sphere, cone or torus through ball centres, offset by ``radius``.

    The fit starts from the nominal (:func:`~probegen.geometry.fits_nominal.fit_near`):
    another solution the points admit goes into ``notes``; a solution far from the
    nominal is refused (a ProbegenError), never reported as the feature."""
    grow = radius if nominal.qualifier == "INNER" else -radius
    fit, check = fit_near(centres, _nominal_shape(nominal, grow))
    if check.far:
        raise ProbegenError(f"{check.far}; not reported as a measurement")
    notes, condition = check.alternatives, check.condition
    if isinstance(fit, Circle3dFit):
        in_plane = (centres - arr(fit.centre)) @ orthonormal_basis(arr(fit.normal))[:2].T
        return replace(nominal, location=fit.centre, size=2.0 * (fit.radius + grow),
                       vector=vec3(signed_like(arr(fit.normal), nominal.vector)),
                       form=minimum_zone.roundness(in_plane, (0.0, 0.0)), notes=notes,
                       condition=condition)
    if isinstance(fit, SphereFit):
        return replace(nominal, location=fit.centre, size=2.0 * (fit.radius + grow),
                       form=minimum_zone.sphericity(centres, fit.centre), notes=notes,
                       condition=condition)
    if isinstance(fit, CylinderFit):
        axis = signed_like(arr(fit.axis), nominal.vector)
        location = _onto_line(arr(nominal.location), arr(fit.point), axis)
        return replace(nominal, location=vec3(location), vector=vec3(axis),
                       size=2.0 * (fit.radius + grow),
                       form=minimum_zone.cylindricity(centres, fit.point, fit.axis),
                       notes=notes, condition=condition)
    if isinstance(fit, TorusFit):
        # the ball centres lie on a torus with the same centre circle, tube -grow larger
        return replace(nominal, location=fit.centre,
                       vector=vec3(signed_like(arr(fit.axis), nominal.vector)),
                       size=2.0 * fit.major_radius, minor=2.0 * (fit.minor_radius + grow),
                       form=fit.form, notes=notes, condition=condition)
    # a cone: the apex moves grow / sin(half angle) towards the narrow end (INNER,
    # grow > 0) or the wide end (OUTER)
    opening = arr(fit.axis)  # points to increasing radius
    apex = arr(fit.apex) - (grow / math.sin(fit.half_angle)) * opening
    return replace(nominal, location=vec3(apex),
                   vector=vec3(signed_like(opening, nominal.vector)),
                   size=math.degrees(2.0 * fit.half_angle), form=fit.form, notes=notes,
                   condition=condition)


def _nominal_shape(nominal: DmisFeature, grow: float) -> NominalShape:
    """The nominal of the surface the ball centres lie on (``grow`` inside it)."""
    kind = SHAPES[nominal.kind]
    if kind == "cone":
        return NominalShape(kind, nominal.vector, 0.0, math.radians((nominal.size or 0.0) / 2),
                            grow)
    size = nominal.minor if kind == "torus" else nominal.size
    return NominalShape(kind, nominal.vector, max((size or 0.0) / 2.0 - grow, 0.0), 0.0, grow)


def _fit_line(nominal: DmisFeature, points: FloatArray) -> DmisFeature:
    fit = fit_line_3d(points)
    d = signed_like(arr(fit.direction), nominal.vector)
    return _line_actual(nominal, arr(fit.point), d,
                        minimum_zone.straightness_3d(points, fit.point, fit.direction))


def _line_actual(nominal: DmisFeature, point: FloatArray, direction: FloatArray,
                 form: float) -> DmisFeature:
    """A line's actual record: nominal points projected onto the actual line."""
    start = _onto_line(arr(nominal.location), point, direction)
    end = _onto_line(arr(nominal.end), point, direction) if nominal.end else None
    normal = None
    if nominal.normal is not None:
        raw = arr(nominal.normal)
        square = raw - (raw @ direction) * direction
        normal = vec3(unit(square, what="line normal"))
    return replace(nominal, location=vec3(start), vector=vec3(direction), normal=normal,
                   end=vec3(end) if end is not None else None, form=form)


def _onto_plane(point: FloatArray, plane_point: FloatArray, normal: FloatArray) -> Vec3:
    """Orthogonal projection of ``point`` onto a plane."""
    return vec3(point - float((point - plane_point) @ normal) * normal)


def _onto_line(point: FloatArray, line_point: FloatArray, direction: FloatArray) -> FloatArray:
    """Orthogonal projection of ``point`` onto a line."""
    return np.asarray(line_point + float((point - line_point) @ direction) * direction)


# --------------------------------------------------------------------- constructions


def intersect_planes(nominal: DmisFeature, first: DmisFeature,
                     second: DmisFeature) -> DmisFeature:
    """``CONST/LINE,F(x),INTOF,FA(plane),FA(plane)``: the line where two planes meet.

    The direction is signed like the nominal's; the location is the nominal location
    projected onto the line.

    Raises:
        ValueError: the planes are parallel.
    """
    n1, n2 = arr(_vector(first)), arr(_vector(second))
    cross = np.cross(n1, n2)
    if float(np.linalg.norm(cross)) < 1e-9:
        raise ValueError(f"planes {first.name} and {second.name} are parallel")
    d = signed_like(cross, nominal.vector)
    rhs = [n1 @ arr(first.location), n2 @ arr(second.location), d @ arr(nominal.location)]
    point = np.linalg.solve(np.vstack([n1, n2, d]), np.array(rhs))
    return _line_actual(replace(nominal, qualifier=nominal.qualifier or "UNBND"),
                        point, d, 0.0)


def intersect_line_plane(nominal: DmisFeature, line: DmisFeature,
                         plane: DmisFeature) -> DmisFeature:
    """``CONST/POINT,F(x),INTOF,FA(line),FA(plane)``: where a line meets a plane.

    Raises:
        ValueError: the line is parallel to the plane.
    """
    d, n = arr(_vector(line)), arr(_vector(plane))
    along = float(d @ n)
    if abs(along) < 1e-9:
        raise ValueError(f"line {line.name} is parallel to plane {plane.name}")
    start = arr(line.location)
    t = float((arr(plane.location) - start) @ n) / along
    return replace(nominal, location=vec3(start + t * d), form=0.0)


def _vector(feature: DmisFeature) -> Vec3:
    if feature.vector is None:
        raise ValueError(f"feature {feature.name} has no direction")
    return feature.vector
