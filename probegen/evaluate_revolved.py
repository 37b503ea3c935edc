"""Circles and cylinders (method M2 features) from their touches: position, size, form.

The fits run on the *ball centres* (the skip positions), which lie exactly on a circle
or cylinder of radius ``R ∓ r`` about the real axis whatever the real position of the
part (a vertical probe touching a vertical wall touches square to the axis); the
diameter is then ``2·(R_fit ± r)`` (+ for a bore, - for a boss).  Compensating each
touch along its *planned* normal instead would leave a cosine error of about
``r·θ²/2`` for a part ``θ`` rad off its nominal direction, which biases the diameter.
The contact points reported are the ball centres moved by ``r`` along the fitted
normals.

* Circle: least-squares circle in 3-D (``fit_circle_3d``) through one section.
* Cylinder: least-squares cylinder (``fit_cylinder``) through every section.

Characteristics: ``X``, ``Y``, ``Z`` of the centre (a cylinder: the point of the fitted
axis nearest the nominal centre), ``POS`` (the diameter of the position zone, twice the
distance of that point from the nominal axis, as in ISO 1101), ``D`` and ``FORM``
(roundness or cylindricity: the range of the radial residuals).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from probegen.evaluate import Characteristic
from probegen.geometry.fits import fit_circle_3d
from probegen.geometry.fits_axial import fit_cylinder

Vec3 = tuple[float, float, float]


@dataclass(frozen=True, slots=True)
class RevolvedResult:
    """An evaluated circle or cylinder.

    Attributes:
        feature: feature id.
        kind: ``circle`` or ``cylinder``.
        centre: fitted centre (see the module doc), mm.
        axis: fitted axis, unit, signed like the nominal one.
        diameter: fitted diameter of the surface, mm.
        form: roundness or cylindricity, mm.
        points: contact points, mm.
        directions: their fitted outward normals.
        residuals: radial residuals, mm (+ away from the axis).
        characteristics: the checked quantities.
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

    @property
    def ok(self) -> bool | None:
        """All toleranced characteristics within limits (None if none is toleranced)."""
        checks = [c.ok for c in self.characteristics if c.ok is not None]
        return all(checks) if checks else None


def evaluate_revolved(feature: str, kind: str, ball_centres: ArrayLike, *, inner: bool,
                      ball_radius: float, nominal_centre: Vec3, nominal_axis: Vec3,
                      nominal_diameter: float, diameter: tuple[float, float] | None = None,
                      position: float | None = None,
                      form: float | None = None) -> RevolvedResult:
    """Fit and evaluate a circle (one section) or a cylinder (all sections).

    Args:
        feature: feature id.
        kind: ``circle`` or ``cylinder``.
        ball_centres: (n, 3) skip positions (ball centres), mm.
        inner: a bore (True) or a boss.
        ball_radius: the stylus ball radius to offset by, mm.
        nominal_centre: a point of the nominal axis (the circle's centre), mm.
        nominal_axis: the nominal axis (unit).
        nominal_diameter: mm.
        diameter: lower and upper limit of the diameter's deviation, or None.
        position: diameter of the position zone, or None.
        form: limit of the form error, or None.
    """
    c = np.asanyarray(ball_centres, dtype=np.float64).reshape(-1, 3)
    v0 = np.asarray(nominal_axis, dtype=np.float64)
    grow = ball_radius if inner else -ball_radius
    if kind == "circle":
        fit = fit_circle_3d(c)
        centre, axis, radius = np.asarray(fit.centre), np.asarray(fit.normal), fit.radius
    else:
        cyl = fit_cylinder(c)
        point, axis, radius = np.asarray(cyl.point), np.asarray(cyl.axis), cyl.radius
        centre = point + float((np.asarray(nominal_centre) - point) @ axis) * axis
    if float(axis @ v0) < 0.0:
        axis = -axis
    rel = c - centre
    radial = rel - np.outer(rel @ axis, axis)
    dist = np.linalg.norm(radial, axis=1)
    outward = radial / dist[:, None]  # away from the axis
    residuals = dist - radius
    normals = -outward if inner else outward
    points = c - ball_radius * normals
    d = 2.0 * (radius + grow)
    off = np.asarray(centre) - np.asarray(nominal_centre)
    pos = 2.0 * float(np.linalg.norm(off - (off @ v0) * v0))
    f = float(residuals.max() - residuals.min())
    lo, hi = diameter if diameter is not None else (None, None)
    chars = [Characteristic(name, float(m), float(n), float(m - n)) for name, m, n in
             zip("XYZ", centre, nominal_centre, strict=True)]
    chars += [
        Characteristic("POS", pos, 0.0, pos, None, position),
        Characteristic("D", d, nominal_diameter, d - nominal_diameter, lo, hi),
        Characteristic("FORM", f, 0.0, f, None, form),
    ]
    return RevolvedResult(
        feature=feature, kind=kind, centre=_v(centre), axis=_v(axis), diameter=d, form=f,
        points=tuple(_v(p) for p in points), directions=tuple(_v(n) for n in normals),
        residuals=tuple(float(x) for x in residuals), characteristics=tuple(chars))


def _v(a: ArrayLike) -> Vec3:
    x = np.asarray(a, dtype=np.float64)
    return (float(x[0]), float(x[1]), float(x[2]))
