"""Revolved features (method M2) from their touches: position, size, form, sections.

Every fit runs on the *ball centres* (the skip positions).  The ball centres of a
vertical probe touching a surface of revolution lie on its offset surface, which is a
surface of the same kind about the same axis whatever the real position of the part:

* circle, cylinder: radius ``R ∓ r``; sphere: radius ``R ∓ r``;
* cone: the same axis and half angle ``α``, section radius ``R(h) ∓ r / cos α`` at every
  height ``h`` (the apex moves along the axis by ``∓ r / sin α``);
* torus: the same centre circle, tube radius ``ρ ∓ r``;

(``−`` where the ball is on the axis side of the surface: a bore, a conical hole, a
spherical cavity; a torus whose air is inside the tube, a fillet).  So the surface's
size is the fitted size offset back by the ball, exactly; compensating each touch along
its *planned* normal instead would leave a cosine error of about ``r·θ²/2`` for a part
``θ`` rad off its nominal direction.  The reported contact points are the ball centres
moved by ``r`` along the fitted surface normals; residuals are the orthogonal distances
to the fitted offset surface, ``+`` where material is outside it (along the outward
material normal: away from the axis on a boss, towards it in a bore; docs/results.md).
Every fit starts from the nominal (``geometry.fits_nominal``): other solutions the
touches admit are named in the result's ``notes``; a fit far from the nominal raises.

Kinds and characteristics (names as in ``results.json``; lengths in mm, angles in
degrees):

* circle (``fit_circle_3d``, one section): ``X Y Z`` centre, ``POS``, ``D``, ``FORM``
  (roundness).
* cylinder (``fit_cylinder``, at least two sections): ``X Y Z`` (the point of the fitted
  axis nearest the nominal centre), ``POS``, ``D``, ``FORM`` (cylindricity), then per
  section ``k`` (1 = top) ``D_Sk`` and ``RON_Sk``, then ``TAPER`` (``D`` of the top
  section − ``D`` of the bottom one, from the least-squares line of the section
  diameters over their axial positions) and ``TILT`` (angle between the fitted and the
  nominal axis).
* cone (``fit_cone``, at least two sections): ``X Y Z`` (the fitted axis in the top
  gauge plane), ``POS``, ``ANGLE`` (half angle), per section ``D_Sk`` (the fitted
  cone's diameter in the gauge plane: square to the fitted axis, the top one through
  the foot of the nominal top section centre on it, the others at their nominal spacing
  from it) and ``RON_Sk``, ``FORM`` (conicity, least squares); the record holds the
  apex.
* sphere (``fit_sphere``, touches in at least two sections): ``X Y Z``, ``POS`` (the
  diameter of a spherical zone about the nominal centre), ``D``, ``FORM``.
* torus (``fit_torus``, at least three sections: two circles of a torus lie on a
  one-parameter family of tori): ``X Y Z``, ``POS``, ``D`` (tube diameter), ``DMAJ``
  (major diameter, not toleranced), ``FORM``.

``POS`` is the diameter of the position zone: twice the distance of the centre from the
nominal axis, square to it (ISO 1101); a sphere: twice the distance from the nominal
centre.  Roundness ``RON_Sk``, a circle's, cylinder's and sphere's ``FORM`` are by the
ISO 1101 minimum zone (``geometry.minimum_zone``) or, with ``form_method =
"least_squares"``, the range of the least-squares residuals (ISO 12181 LSCI); the
characteristic's ``method`` names it.  ``RON_Sk`` uses the ball centres of section
``k`` projected on the plane square to the fitted axis (their zone equals the
surface's: the ball centres lie ``r`` off it along the normal).  Each ``D_Sk`` is
checked against the ``diameter`` tolerance (every local size within the limits),
``RON_Sk`` against ``roundness``, ``TAPER`` against ``±taper``, ``ANGLE`` against
``angle``.

With a probe calibration (``compensate.ProbeCalibration``: effective radius by direction,
from the sphere test) the offset surface is fitted with the calibration's mean effective
radius ``r_ref`` after each ball centre was moved by ``r(n) − r_ref`` along its normal
``n`` (``compensate.calibrated_centres``, the one function every caller uses).  The
normals are those of a first fit on the raw centres: they differ from the true surface
normals by the part's form and misplacement (milliradians), and ``r(n)`` changes by at
most its lobing amplitude (a few µm) per radian, so the error of the correction is
nanometres; the second fit is the result (no further iteration changes it measurably).
The planned normals would do as well for a part near nominal, but the fitted ones stay
right for a part placed or tilted far off, and need nothing but the touches.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray

from probegen.errors import ProbegenError
from probegen.evaluate.characteristics import Characteristic, accepted
from probegen.evaluate.uncertainty import FittedShape, uncertainties
from probegen.geometry import minimum_zone
from probegen.geometry.determined import EVALUATED_SECTIONS
from probegen.geometry.fits import (
    Circle3dFit,
    ConeFit,
    CylinderFit,
    SphereFit,
    TorusFit,
    fit_circle_2d,
)
from probegen.geometry.fits_nominal import AnyFit, FitCheck, NominalShape, fit_near
from probegen.geometry.frames import rotation_to_z
from probegen.geometry.uncertainty import Budget
from probegen.machine.calibration import ProbeCalibration, calibrated_centres

Vec3 = tuple[float, float, float]
Array = NDArray[np.float64]
IntArray = NDArray[np.int64]


class Limits(Protocol):
    """The tolerances ``evaluate_revolved`` reads (``spec.RevolvedTolerance``); an
    optional ``form_method`` attribute (``"minimum_zone"``, the default, or
    ``"least_squares"``) chooses how form is evaluated."""

    @property
    def diameter(self) -> tuple[float, float] | None: ...
    @property
    def position(self) -> float | None: ...
    @property
    def form(self) -> float | None: ...
    @property
    def roundness(self) -> float | None: ...
    @property
    def taper(self) -> float | None: ...
    @property
    def angle(self) -> tuple[float, float] | None: ...


@dataclass(frozen=True, slots=True)
class Nominal:
    """The nominal feature, as planned.

    Attributes:
        kind: ``circle``, ``cylinder``, ``cone``, ``sphere`` or ``torus``.
        centre: circle, cylinder: a point of the axis (the circle's centre, the
            cylinder's middle); sphere, torus: the centre; cone: the apex.
        axis: unit axis (a cone: towards the growing radius).
        diameter: circle, cylinder, sphere: the diameter; torus: the tube diameter;
            cone: 0 (its sizes are the section diameters).
        ball_inside: the ball touches from the axis side of the surface (a bore, a
            conical hole, a cavity; a torus: from inside the tube).
        sections: the planned sections (top first): centre on the axis and diameter.
        half_angle: cone half angle, rad.
        major_diameter: torus: the diameter of the tube's centre circle.
    """

    kind: str
    centre: Vec3
    axis: Vec3
    diameter: float
    ball_inside: bool
    sections: tuple[tuple[Vec3, float], ...]
    half_angle: float = 0.0
    major_diameter: float = 0.0


@dataclass(frozen=True, slots=True)
class RevolvedResult:
    """An evaluated revolved feature.

    Attributes:
        feature: feature id.
        kind: ``circle``, ``cylinder``, ``cone``, ``sphere`` or ``torus``.
        centre: fitted centre (see the module doc), mm.
        axis: fitted axis, unit, signed like the nominal one.
        diameter: fitted diameter (a cone: in the top gauge plane; a torus: the tube), mm.
        form: roundness, cylindricity, conicity or sphericity, mm.
        points: contact points, mm.
        directions: their fitted outward normals.
        residuals: residuals, mm (+ where material is outside the fitted surface).
        characteristics: the checked quantities.
        half_angle: a cone's fitted half angle, rad, else None.
        apex: a cone's fitted apex, mm, else None.
        major_diameter: a torus's fitted major diameter, mm, else None.
        notes: what the fit found besides the feature: other solutions the touches
            admit (``geometry.fits_nominal``; the fit kept the one nearest the nominal).
        condition: the fit's condition number (``geometry.fits_conditioning``).
    """

    feature: str
    kind: str
    centre: Vec3
    axis: Vec3
    diameter: float
    form: float
    points: tuple[Vec3, ...]
    directions: tuple[Vec3, ...]
    residuals: tuple[float, ...]
    characteristics: tuple[Characteristic, ...]
    half_angle: float | None = None
    apex: Vec3 | None = None
    major_diameter: float | None = None
    notes: tuple[str, ...] = ()
    condition: float | None = None

    @property
    def ok(self) -> bool | None:
        """All toleranced characteristics within limits (None if none is toleranced)."""
        return accepted(self.characteristics)


@dataclass(frozen=True, slots=True)
class _Fit:
    """A fitted offset surface: its centre (see the module doc), axis, the surface's
    size, form, residuals and the outward normal at each ball centre."""

    centre: Array
    axis: Array
    diameter: float
    form: float
    residuals: Array
    normals: Array
    extra: tuple[Characteristic, ...] = ()
    half_angle: float | None = None
    apex: Vec3 | None = None
    major_diameter: float | None = None
    check: FitCheck | None = None
    form_method: str = minimum_zone.LABELS["least_squares"]


def evaluate_revolved(feature: str, nominal: Nominal, ball_centres: ArrayLike,
                      sections: ArrayLike, *, ball_radius: float | ProbeCalibration,
                      limits: Limits, budget: Budget | None = None) -> RevolvedResult:
    """Fit and evaluate one revolved feature from its ball centres.

    Args:
        feature: feature id.
        nominal: the nominal feature.
        ball_centres: (n, 3) skip positions (ball centres), mm.
        sections: (n,) 0-based section of each touch (into ``nominal.sections``).
        ball_radius: the stylus ball radius to offset by, mm, or the probe calibration
            (see the module doc).
        limits: the feature's tolerances.
        budget: the stated uncertainty contributions (default: none stated); every
            characteristic gets its ``u`` (``probegen.evaluate.uncertainty``).

    Raises:
        ProbegenError: the touches lie in too few sections for the kind, the fit
            failed (too few or degenerate points), or it converged far from the
            nominal (``geometry.fits_nominal``: not a measurement of this feature).
    """
    c = np.asanyarray(ball_centres, dtype=np.float64).reshape(-1, 3)
    k = np.asanyarray(sections, dtype=np.int64).reshape(-1)
    found = len(set(k.tolist()))
    if found < EVALUATED_SECTIONS[nominal.kind]:
        raise ProbegenError(f"feature {feature}: a {nominal.kind} needs touches in at least "
                            f"{EVALUATED_SECTIONS[nominal.kind]} sections, found {found}")
    v0 = np.asarray(nominal.axis, dtype=np.float64)
    sign = 1.0 if nominal.ball_inside else -1.0  # surface size = ball size + sign·r
    if isinstance(ball_radius, ProbeCalibration):
        cal, ball_radius = ball_radius, ball_radius.effective_radius
        first = _FITS[nominal.kind](nominal, c, k, sign * ball_radius, limits)
        c = calibrated_centres(c, -sign * first.normals, cal, ball_radius)
    fit = _FITS[nominal.kind](nominal, c, k, sign * ball_radius, limits)
    check = fit.check or FitCheck(math.nan)
    if check.far:
        raise ProbegenError(f"feature {feature}: {check.far}; not reported as a measurement")
    off = fit.centre - np.asarray(nominal.centre if nominal.kind != "cone" else
                                  nominal.sections[0][0])
    across = off if nominal.kind == "sphere" else off - (off @ v0) * v0
    pos = 2.0 * float(np.linalg.norm(across))
    out_normals = -sign * fit.normals  # from the surface towards the ball
    points = c - ball_radius * out_normals
    nominal_xyz = nominal.sections[0][0] if nominal.kind == "cone" else nominal.centre
    chars = [Characteristic(name, float(m), float(n), float(m - n)) for name, m, n in
             zip("XYZ", fit.centre, nominal_xyz, strict=True)]
    chars.append(Characteristic("POS", pos, 0.0, pos, None, limits.position))
    if nominal.kind != "cone":
        chars.append(_size("D", fit.diameter, nominal.diameter, limits.diameter))
    chars.extend(fit.extra)
    chars.append(Characteristic("FORM", fit.form, 0.0, fit.form, None, limits.form,
                                method=fit.form_method))
    bad = [ch.name for ch in chars if not math.isfinite(ch.measured)]
    if bad or not np.all(np.isfinite(points)):
        raise ProbegenError(f"feature {feature}: expected touches that determine the "
                            f"{nominal.kind}, found a fit with non-finite "
                            f"{', '.join(bad) or 'contact points'} (a touch on its axis?)")
    shape = FittedShape(
        nominal.kind, fit.centre, fit.axis,
        fit.diameter / 2.0 - sign * ball_radius / math.cos(fit.half_angle or 0.0),
        sign * ball_radius, half_angle=fit.half_angle or 0.0,
        major_radius=(fit.major_diameter or 0.0) / 2.0,
        gauges=tuple((np.asarray(s, dtype=np.float64), v0) for s, _ in nominal.sections))
    chars = list(uncertainties(
        shape, c, k, tuple(chars), nominal_centre=np.asarray(nominal_xyz, dtype=np.float64),
        nominal_axis=None if nominal.kind == "sphere" else v0,
        budget=budget or Budget()))
    return RevolvedResult(
        feature=feature, kind=nominal.kind, centre=_v(fit.centre), axis=_v(fit.axis),
        diameter=fit.diameter, form=fit.form, points=tuple(_v(p) for p in points),
        directions=tuple(_v(n) for n in out_normals),
        residuals=tuple(float(x) for x in -sign * fit.residuals),
        characteristics=tuple(chars),
        half_angle=fit.half_angle, apex=fit.apex, major_diameter=fit.major_diameter,
        notes=tuple(f"feature {feature}: {note}" for note in check.alternatives),
        condition=check.condition)


def _size(name: str, measured: float, nominal: float,
          limits: tuple[float, float] | None) -> Characteristic:
    """A characteristic with ``[lower, upper]`` limits on its deviation (or none)."""
    lo, hi = limits if limits is not None else (None, None)
    return Characteristic(name, measured, nominal, measured - nominal, lo, hi)


def _signed(axis: Array, v0: Array) -> Array:
    return -axis if float(axis @ v0) < 0.0 else axis


def _radial(c: Array, centre: Array, axis: Array) -> tuple[Array, Array]:
    """Distance of each point from the axis line and the unit vector away from it."""
    rel = c - centre
    across = rel - np.outer(rel @ axis, axis)
    dist = np.linalg.norm(across, axis=1)
    return dist, across / dist[:, None]


def _near(nominal: Nominal, c: Array, grow: float) -> tuple[AnyFit, FitCheck]:
    """The fit of the ball centres started from the nominal (``fits_nominal``)."""
    radius = max(nominal.diameter / 2.0 - grow, 0.0)
    axis = None if nominal.kind == "sphere" else nominal.axis
    return fit_near(c, NominalShape(nominal.kind, axis, radius, nominal.half_angle, grow))


def _circle(nominal: Nominal, c: Array, k: IntArray, grow: float, limits: Limits) -> _Fit:
    fit, check = _near(nominal, c, grow)
    assert isinstance(fit, Circle3dFit)
    centre = np.asarray(fit.centre)
    axis = _signed(np.asarray(fit.normal), np.asarray(nominal.axis))
    dist, outward = _radial(c, centre, axis)
    res = dist - fit.radius
    in_plane = ((c - centre) @ rotation_to_z(axis).T)[:, :2]
    form, method = _form(limits, res, lambda: minimum_zone.roundness(in_plane, (0.0, 0.0)))
    return _Fit(centre, axis, 2.0 * (fit.radius + grow), form, res, outward, check=check,
                form_method=method)


def _cylinder(nominal: Nominal, c: Array, k: IntArray, grow: float, limits: Limits) -> _Fit:
    fit, check = _near(nominal, c, grow)
    assert isinstance(fit, CylinderFit)
    v0 = np.asarray(nominal.axis)
    axis = _signed(np.asarray(fit.axis), v0)
    point = np.asarray(fit.point)
    centre = point + float((np.asarray(nominal.centre) - point) @ axis) * axis
    dist, outward = _radial(c, centre, axis)
    res = dist - fit.radius
    extra, diameters, heights = _sections(nominal, c, k, axis, grow, limits, point=centre)
    slope = np.polyfit(heights, diameters, 1)[0] if len(heights) > 1 else 0.0
    taper = float(slope * (heights.max() - heights.min()))
    t = limits.taper
    extra += (Characteristic("TAPER", taper, 0.0, taper, None if t is None else -t, t),
              _size("TILT", _degrees(axis, v0), 0.0, None))
    form, method = _form(limits, res, lambda: minimum_zone.cylindricity(c, centre, axis))
    return _Fit(centre, axis, 2.0 * (fit.radius + grow), form, res, outward, extra,
                check=check, form_method=method)


def _sections(nominal: Nominal, c: Array, k: IntArray, axis: Array, grow: float,
              limits: Limits, *, point: Array, slope: float = 0.0,
              gauge: list[float] | None = None
              ) -> tuple[tuple[Characteristic, ...], Array, Array]:
    """Per section ``D_Sk`` and ``RON_Sk`` (LS circle square to ``axis``); also the
    section diameters and their axial positions.

    A cone (``slope = tan α``, ``point`` on its fitted axis): the touches of a section
    lie at slightly different heights when the part is off nominal, so each ball centre
    is first moved along the fitted cone to the section's mean height (its distance
    from the axis changes by ``slope·Δh``); ``gauge`` replaces the diameters with the
    fitted surface's in each gauge plane."""
    frame = rotation_to_z(axis)
    out: list[Characteristic] = []
    diameters, heights = [], []
    for j in sorted(set(k.tolist())):
        local = (c[k == j] - point) @ frame.T
        rho = np.hypot(local[:, 0], local[:, 1])
        scale = (rho - slope * (local[:, 2] - local[:, 2].mean())) / rho
        flat = local[:, :2] * scale[:, None]
        circle = fit_circle_2d(flat)
        ron, method = _form(limits, np.asarray(circle.residuals),
                            functools.partial(minimum_zone.roundness, flat, circle.centre))
        d = 2.0 * (circle.radius + grow) if gauge is None else gauge[j]
        diameters.append(d)
        heights.append(float(np.mean(local[:, 2])))
        out.append(_size(f"D_S{j + 1}", d, nominal.sections[j][1], limits.diameter))
        out.append(Characteristic(f"RON_S{j + 1}", ron, 0.0, ron, None, limits.roundness,
                                  method=method))
    return tuple(out), np.asarray(diameters), np.asarray(heights)


def _form(limits: Limits, residuals: Array, zone: Callable[[], float]) -> tuple[float, str]:
    """The form value by the feature's ``form_method`` and the method's name: the
    minimum zone (``zone()``) or the range of the least-squares ``residuals``."""
    if getattr(limits, "form_method", "minimum_zone") == "least_squares":
        return float(residuals.max() - residuals.min()), minimum_zone.LABELS["least_squares"]
    return zone(), minimum_zone.LABELS["minimum_zone"]


def _cone(nominal: Nominal, c: Array, k: IntArray, grow: float, limits: Limits) -> _Fit:
    fit, check = _near(nominal, c, grow)
    assert isinstance(fit, ConeFit)
    alpha = fit.half_angle
    axis, point = np.asarray(fit.axis), np.asarray(fit.point)
    v0 = np.asarray(nominal.axis)
    shift = grow / math.cos(alpha)  # surface section radius = ball cone's + shift

    top_centre = np.asarray(nominal.sections[0][0])
    top_t = float((top_centre - point) @ axis)  # the top centre's foot on the fitted axis

    def at_gauge(centre: Vec3) -> tuple[Array, float]:
        """Gauge point and diameter: square to the fitted axis, the nominal spacing of
        the sections kept along it from the top one (the part frame follows the
        feature: a part moved or tilted about its top gauge point reads the same)."""
        t = top_t + float((np.asarray(centre) - top_centre) @ v0)
        return point + t * axis, 2.0 * (fit.radius + t * math.tan(alpha) + shift)

    gauges = [at_gauge(centre) for centre, _ in nominal.sections]
    top = gauges[0][0]
    apex = point - (fit.radius + shift) / math.tan(alpha) * axis
    extra, _, _ = _sections(nominal, c, k, axis, grow, limits, point=point,
                            slope=math.tan(alpha), gauge=[g[1] for g in gauges])
    ang = _size("ANGLE", math.degrees(alpha), math.degrees(nominal.half_angle), limits.angle)
    rel = c - apex
    along = rel @ axis
    across = rel - np.outer(along, axis)
    e = across / np.linalg.norm(across, axis=1)[:, None]
    normals = math.cos(alpha) * e - math.sin(alpha) * axis[None, :]
    res = np.asarray(fit.residuals)
    return _Fit(top, axis, gauges[0][1], float(res.max() - res.min()), res, normals,
                (ang, *extra), alpha, _v(apex), check=check)


def _sphere(nominal: Nominal, c: Array, k: IntArray, grow: float, limits: Limits) -> _Fit:
    fit, check = _near(nominal, c, grow)
    assert isinstance(fit, SphereFit)
    centre = np.asarray(fit.centre)
    rel = c - centre
    res = np.asarray(fit.residuals)
    form, method = _form(limits, res, lambda: minimum_zone.sphericity(c, centre))
    return _Fit(centre, np.asarray(nominal.axis), 2.0 * (fit.radius + grow), form, res,
                rel / np.linalg.norm(rel, axis=1)[:, None], check=check, form_method=method)


def _torus(nominal: Nominal, c: Array, k: IntArray, grow: float, limits: Limits) -> _Fit:
    fit, check = _near(nominal, c, grow)
    assert isinstance(fit, TorusFit)
    centre = np.asarray(fit.centre)
    axis = _signed(np.asarray(fit.axis), np.asarray(nominal.axis))
    _, e = _radial(c, centre, axis)
    tube = c - (centre + fit.major_radius * e)
    res = np.asarray(fit.residuals)
    dmaj = 2.0 * fit.major_radius
    return _Fit(centre, axis, 2.0 * (fit.minor_radius + grow), float(res.max() - res.min()),
                res, tube / np.linalg.norm(tube, axis=1)[:, None],
                (_size("DMAJ", dmaj, nominal.major_diameter, None),),
                major_diameter=dmaj, check=check)


_FITS = {"circle": _circle, "cylinder": _cylinder, "cone": _cone, "sphere": _sphere,
         "torus": _torus}


def _degrees(a: Array, b: Array) -> float:
    """Angle between two unit vectors, degrees (accurate for small angles)."""
    return math.degrees(math.atan2(float(np.linalg.norm(np.cross(a, b))), float(a @ b)))


def _v(a: ArrayLike) -> Vec3:
    x = np.asarray(a, dtype=np.float64)
    return (float(x[0]), float(x[1]), float(x[2]))
