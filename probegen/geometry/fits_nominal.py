"""Fits that start from the nominal feature and say when the points admit another one.

A CMM knows the nominal feature and starts its fit there.  Sparse patterns (two rings
of four points in a bore, the NIST DCX program's CYL1) lie on more than one cylinder
within the noise: the vertical Ø31 bore's eight points also fit a horizontal Ø24
cylinder.  A fit that takes the least sum of squares over every start returns either,
at the whim of the noise.  :func:`fit_near` instead

1. solves from the nominal axis only and keeps that solution (the optimum nearest the
   nominal: ``fits_axial.fit_cylinder(..., nearest=True)``);
2. searches for *another* solution: the unseeded multi-start fit, and starts from the
   nominal axis tilted by 45 and 90 degrees in four azimuths.  A solution distinct from
   the kept one (axis more than ``DISTINCT_ANGLE`` apart, or radius or axis position
   more than ``DISTINCT_SIZE`` of the radius apart) whose RMS residual is at most
   ``AMBIGUOUS_RATIO`` times the kept one's, or within ``AMBIGUOUS_RMS`` (1.5 um), is
   reported:
   "the points also fit a cylinder D24.012 with axis (-0.707, -0.707, 0.000) ...; the
   fit kept the one nearest the nominal";
3. compares the kept solution with the nominal: an axis tilted more than ``FAR_TILT``
   degrees (a cone: its half angle too), or a size off by more than ``FAR_SIZE`` of the
   nominal, is *far*: the caller must not report it as a measurement.

Circles and spheres have one least-squares optimum for any usable point set (their
residuals are convex in the centre near the data), so only step 3 applies; their
conditioning is the fit's ``condition`` as for every kind (``fits_conditioning``).
Lengths in the caller's units (mm), angles in radians unless named in degrees.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from probegen.constants import tol
from probegen.errors import ProbegenError
from probegen.geometry.fits import fit_circle_3d, fit_sphere
from probegen.geometry.fits_axial import fit_cone, fit_cylinder, fit_torus
from probegen.geometry.fits_results import Circle3dFit, ConeFit, CylinderFit, SphereFit, TorusFit
from probegen.geometry.fits_solver import FloatArray, subsample
from probegen.geometry.frames import orthonormal_basis, unit

#: Two solutions whose axes are further apart than this (degrees) are distinct.
DISTINCT_ANGLE = 1.0
#: ... or whose radii, or axis lines, differ by more than this fraction of the radius.
DISTINCT_SIZE = 0.01
#: A distinct solution is reported when its RMS residual is at most this many times
#: the kept solution's, or at most ``AMBIGUOUS_RMS``: "residuals as small".
AMBIGUOUS_RATIO = 2.0
#: RMS residual (mm) within which another solution explains the points as well as a
#: touch probe's repeatability (about 1 um) lets one tell: with 0.5 um of noise the
#: eight points of two rings of four fit the second cylinder within 0.1 to 1.1 um.
AMBIGUOUS_RMS = 0.0015
#: A kept solution whose axis (or cone half angle) is more than this many degrees off
#: the nominal is far from the nominal.
FAR_TILT = 10.0
#: ... or whose size differs from the nominal by more than this fraction.
FAR_SIZE = 0.2
#: Tilts (degrees) and azimuths (degrees) of the extra starts around the nominal axis.
PROBE_TILTS = (45.0, 90.0)
PROBE_AZIMUTHS = (0.0, 45.0, 90.0, 135.0)
#: The search for another solution runs on at most this many of the points.
SEARCH_SAMPLE = 1024

AxialFit = CylinderFit | ConeFit | TorusFit
AnyFit = AxialFit | Circle3dFit | SphereFit


@dataclass(frozen=True, slots=True)
class NominalShape:
    """The nominal of the surface being fitted (the surface the points lie on: for ball
    centres, the offset surface).

    Attributes:
        kind: ``circle``, ``cylinder``, ``cone``, ``sphere`` or ``torus``.
        axis: unit axis (circle: normal); None for a sphere.
        radius: circle, cylinder, sphere: the radius; torus: the tube radius; cone:
            unused (0).
        half_angle: cone: the half angle, rad.
        offset: what the measured surface's radius is more than the fitted one's (ball
            centres of a bore: the ball radius; of a boss: minus it), for the sizes
            named in messages.
    """

    kind: str
    axis: tuple[float, float, float] | None
    radius: float = 0.0
    half_angle: float = 0.0
    offset: float = 0.0


@dataclass(frozen=True, slots=True)
class FitCheck:
    """What :func:`fit_near` found about a fit besides the fit itself.

    Attributes:
        condition: the kept fit's condition number (``fits_conditioning``).
        alternatives: one sentence per distinct solution with residuals as small.
        far: why the kept solution is far from the nominal, or ``""``.
    """

    condition: float
    alternatives: tuple[str, ...] = ()
    far: str = ""

    @property
    def warnings(self) -> tuple[str, ...]:
        """Every finding, as sentences for a record's notes."""
        return self.alternatives + ((self.far,) if self.far else ())


def fit_near(points: ArrayLike, nominal: NominalShape) -> tuple[AnyFit, FitCheck]:
    """Fit ``points : (n, 3)`` starting from ``nominal`` and check the solution.

    Returns:
        ``(fit, check)``: the fit nearest the nominal (the record of ``fits``' fit of
        the kind) and what else the points admit.

    Raises:
        ProbegenError: the points cannot be fitted (see the kind's fit).
    """
    p = np.asanyarray(points, dtype=np.float64)
    if nominal.kind == "circle":
        circle = fit_circle_3d(p)
        return circle, FitCheck(circle.condition, far=_far(nominal, circle))
    if nominal.kind == "sphere":
        sphere = fit_sphere(p)
        return sphere, FitCheck(sphere.condition, far=_far(nominal, sphere))
    fit = _axial(nominal.kind, p, nominal.axis, nearest=nominal.axis is not None)
    others = _others(nominal.kind, p, fit, nominal.axis, nominal.offset)
    return fit, FitCheck(fit.condition, others, _far(nominal, fit))


def _axial(kind: str, points: FloatArray, axis: ArrayLike | None, *,
           nearest: bool) -> AxialFit:
    if kind == "cylinder":
        return fit_cylinder(points, axis, nearest=nearest)
    if kind == "cone":
        return fit_cone(points, axis, nearest=nearest)
    if kind == "torus":
        return fit_torus(points, axis, nearest=nearest)
    raise ValueError(f"fit_near: unknown kind {kind!r}")


def _starts(axis: FloatArray) -> list[FloatArray]:
    """The nominal axis tilted by each of ``PROBE_TILTS`` towards each azimuth."""
    e1, e2, _ = orthonormal_basis(axis)
    out = []
    for tilt in np.radians(PROBE_TILTS):
        for az in np.radians(PROBE_AZIMUTHS):
            side = math.cos(az) * e1 + math.sin(az) * e2
            out.append(math.cos(tilt) * axis + math.sin(tilt) * side)
    return out


def _others(kind: str, points: FloatArray, kept: AxialFit,
            axis: ArrayLike | None, offset: float) -> tuple[str, ...]:
    """Sentences for the distinct solutions with residuals as small as ``kept``'s."""
    sample = subsample(points, SEARCH_SAMPLE)
    base = kept if sample is points else _axial(kind, sample, kept.axis, nearest=True)
    found: list[AxialFit] = []
    starts: list[FloatArray | None] = [None]
    if axis is not None:
        starts += _starts(unit(axis, what="nominal axis"))
    for start in starts:
        try:
            other = _axial(kind, sample, start, nearest=start is not None)
        except ProbegenError:
            continue  # no usable solution from this start
        if not other.rms <= max(AMBIGUOUS_RATIO * base.rms, AMBIGUOUS_RMS):
            continue
        if _distinct(other, base) and all(_distinct(other, seen) for seen in found):
            found.append(other)
    return tuple(sorted(  # in the text's order, not the starts': the same report whichever
        # start a solver's last digits lead to which solution
        f"the points also fit {_describe(o, offset)} (RMS residual {_num(o.rms, 4)} "
        f"against {_num(base.rms, 4)}); the fit kept the one nearest the nominal"
        for o in found))


def _num(value: float, digits: int = 3) -> str:
    """``value`` with ``digits`` decimals, never ``-0.000``."""
    text = f"{value:.{digits}f}"
    return text[1:] if text.startswith("-") and float(text) == 0.0 else text


def _radius(fit: AnyFit) -> float:
    if isinstance(fit, TorusFit):
        return fit.minor_radius
    return fit.radius


def _distinct(a: AxialFit, b: AxialFit) -> bool:
    """True if the two solutions are different shapes (see the module docstring)."""
    va, vb = np.asarray(a.axis), np.asarray(b.axis)
    if _angle(va, vb) > DISTINCT_ANGLE:
        return True
    size = max(abs(_radius(b)), tol.fit)
    if abs(_radius(a) - _radius(b)) > DISTINCT_SIZE * size:
        return True
    if isinstance(a, ConeFit) and isinstance(b, ConeFit):
        if abs(math.degrees(a.half_angle - b.half_angle)) > DISTINCT_ANGLE:
            return True
    pa, pb = np.asarray(_axis_point(a)), np.asarray(_axis_point(b))
    rel = pa - pb
    across = rel - (rel @ vb) * vb
    return bool(np.linalg.norm(across) > DISTINCT_SIZE * size)


def _axis_point(fit: AnyFit) -> tuple[float, float, float]:
    if isinstance(fit, TorusFit | SphereFit | Circle3dFit):
        return fit.centre
    return fit.point


def _angle(a: FloatArray, b: FloatArray) -> float:
    """Angle between two lines (unsigned directions), degrees."""
    return math.degrees(math.atan2(float(np.linalg.norm(np.cross(a, b))), abs(float(a @ b))))


def _describe(fit: AxialFit, offset: float) -> str:
    """``a cylinder D24.012 with axis (-0.707, -0.707, 0.000) through (x, y, z)``."""
    axis = ", ".join(_num(v) for v in fit.axis)
    where = ", ".join(_num(v) for v in _axis_point(fit))
    if isinstance(fit, ConeFit):
        return (f"a cone of half angle {math.degrees(fit.half_angle):.3f} deg with axis "
                f"({axis}) through ({where})")
    name = "a torus of tube" if isinstance(fit, TorusFit) else "a cylinder"
    return f"{name} D{2.0 * (_radius(fit) + offset):.3f} with axis ({axis}) through ({where})"


def _far(nominal: NominalShape, fit: AnyFit) -> str:
    """Why ``fit`` is far from ``nominal`` (``""`` if it is not)."""
    reasons = []
    if nominal.axis is not None and not isinstance(fit, SphereFit):
        direction = fit.normal if isinstance(fit, Circle3dFit) else fit.axis
        tilt = _angle(np.asarray(direction), np.asarray(nominal.axis, dtype=np.float64))
        if tilt > FAR_TILT:
            reasons.append(f"its axis is {tilt:.1f} deg off the nominal (limit {FAR_TILT:g})")
    if isinstance(fit, ConeFit):
        off = abs(math.degrees(fit.half_angle - nominal.half_angle))
        if off > FAR_TILT:
            reasons.append(f"its half angle is {off:.1f} deg off the nominal "
                           f"(limit {FAR_TILT:g})")
    elif nominal.radius + nominal.offset > 0.0:
        # judged on the measured surface, not the ball centres' (a small bore's ball
        # centres lie on a tiny cylinder)
        size, ref = 2 * (_radius(fit) + nominal.offset), 2 * (nominal.radius + nominal.offset)
        ratio = abs(size - ref) / ref
        if ratio > FAR_SIZE:
            reasons.append(f"its diameter {size:.4g} is {100 * ratio:.0f} % off "
                           f"the nominal {ref:.4g} (limit "
                           f"{100 * FAR_SIZE:.0f} %)")
    if not reasons:
        return ""
    return f"the fit converged far from the nominal: {'; '.join(reasons)}"
