"""The sphere test (method M1, ISO 10360-5): the probe measured on a reference sphere.

A least-squares (Gaussian) sphere through the compensated contact points; radial
residuals ``r_i = |P_i − C| − R``; probing form error ``P_FTU = max r_i − min r_i``
(least squares, as ISO 10360-5 defines it); size error ``P_STU = D_fit − D_cal``. When
the points were compensated with the nominal ball radius ``r``, the probe's effective
radius is ``r_eff = r + R_fit − R_cal`` (a smaller effective radius, from pre-travel,
makes the sphere look smaller), and the effective radius in each measured direction is
``r + |P_i − C| − R_cal``: that is the probe calibration the test produces. ``POS`` is
the ISO 1101 position zone diameter, ``2 |C − C_nominal|``, as for every kind
(docs/results.md).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from probegen.evaluate.characteristics import Characteristic, accepted
from probegen.evaluate.uncertainty import FittedShape, uncertainties
from probegen.geometry.fits import SphereFit, fit_sphere
from probegen.geometry.uncertainty import Budget
from probegen.machine.calibration import ProbeCalibration

Vec3 = tuple[float, float, float]


@dataclass(frozen=True, slots=True)
class SphereTestResult:
    """The evaluated sphere test.

    Attributes:
        feature: feature id.
        fit: the least-squares sphere.
        points: (n) contact points used, mm.
        directions: (n) nominal approach normals of the points.
        nominal_centre: nominal (or located) centre, mm.
        calibrated_diameter: the sphere's certified diameter, mm.
        ball_radius: the radius the points were compensated with (the nominal one, or a
            calibration's mean effective radius), mm.
        p_ftu: probing form error, mm.
        p_stu: probing size error, mm.
        effective_radius: mean effective stylus radius, mm.
        radii: effective radius in each direction, mm.
        characteristics: the checked quantities.
        nominal_radius: the stylus's nominal ball radius, mm (0: ``ball_radius``).
        stylus: the label of the rack's stylus the test was run with, or "" (a profile
            without a rack): the calibration it gives is that stylus's entry.
    """

    feature: str
    fit: SphereFit
    points: tuple[Vec3, ...]
    directions: tuple[Vec3, ...]
    nominal_centre: Vec3
    calibrated_diameter: float
    ball_radius: float
    p_ftu: float
    p_stu: float
    effective_radius: float
    radii: tuple[float, ...]
    characteristics: tuple[Characteristic, ...]
    nominal_radius: float = 0.0
    stylus: str = ""

    @property
    def ok(self) -> bool | None:
        """All toleranced characteristics within limits (None if none is toleranced)."""
        return accepted(self.characteristics)

    def calibration(self, source: str = "", date: str = "") -> ProbeCalibration:
        """The probe calibration this test measured (its ``ball_radius`` the nominal;
        ``u_radius``: the standard uncertainty of ``R_EFF``)."""
        u = next((c.u for c in self.characteristics if c.name == "R_EFF"), None)
        return ProbeCalibration(self.nominal_radius or self.ball_radius,
                                self.effective_radius, self.directions, self.radii, source,
                                u or 0.0, date, stylus=self.stylus)


def evaluate_sphere_test(feature: str, points: ArrayLike, directions: ArrayLike, *,
                         nominal_centre: Vec3, calibrated_diameter: float, ball_radius: float,
                         form: float | None = None, size: float | None = None,
                         position: float | None = None,
                         budget: Budget | None = None,
                         nominal_radius: float | None = None) -> SphereTestResult:
    """Evaluate the sphere test from compensated contact points.

    Args:
        feature: feature id.
        points: (n, 3) contact points, compensated with ``ball_radius``.
        directions: (n, 3) the nominal approach normals of the points.
        nominal_centre: the nominal centre, mm.
        calibrated_diameter: certified diameter of the sphere, mm.
        ball_radius: the radius used for compensation, mm.
        form: limit of P_FTU, or None.
        size: limit of |P_STU|, or None.
        position: the diameter of the position zone about the nominal centre (ISO
            1101: the centre may lie ``position / 2`` from it), or None.
        budget: the stated uncertainty contributions (``budget.radius``: of the radius
            the points were compensated with); default none stated.
        nominal_radius: the nominal ball radius (default ``ball_radius``), mm: the
            nominal of ``R_EFF`` and the ``ball_radius`` of the calibration written.

    Returns:
        The result with its characteristics.
    """
    p = np.asanyarray(points, dtype=np.float64)
    r_nom = ball_radius if nominal_radius is None else nominal_radius
    fit = fit_sphere(p)
    r_cal = calibrated_diameter / 2.0
    radial = np.linalg.norm(p - np.asarray(fit.centre), axis=1)
    p_ftu = float(radial.max() - radial.min())
    p_stu = 2.0 * fit.radius - calibrated_diameter
    dist = float(np.linalg.norm(np.asarray(fit.centre) - np.asarray(nominal_centre)))
    pos = 2.0 * dist  # ISO 1101: the diameter of the spherical zone holding the centre
    chars = [Characteristic(axis, c, n, c - n) for axis, c, n in
             zip("XYZ", fit.centre, nominal_centre, strict=True)]
    chars += [
        Characteristic("POS", pos, 0.0, pos, None, position),
        Characteristic("D", 2.0 * fit.radius, calibrated_diameter, p_stu,
                       None if size is None else -size, size),
        Characteristic("P_FTU", p_ftu, 0.0, p_ftu, None, form, method="least squares"),
        Characteristic("P_STU", p_stu, 0.0, p_stu, None if size is None else -size, size),
        Characteristic("R_EFF", ball_radius + fit.radius - r_cal, r_nom,
                       ball_radius + fit.radius - r_cal - r_nom),
    ]
    shape = FittedShape("sphere", np.asarray(fit.centre), np.array([0.0, 0.0, 1.0]),
                        fit.radius, 0.0)
    chars = list(uncertainties(shape, p, np.zeros(len(p), dtype=np.int64), tuple(chars),
                               nominal_centre=np.asarray(nominal_centre, dtype=np.float64),
                               nominal_axis=None, budget=budget or Budget(),
                               position_factor=2.0))
    return SphereTestResult(
        feature=feature, fit=fit, points=_tuples(p), directions=_tuples(directions),
        nominal_centre=nominal_centre, calibrated_diameter=calibrated_diameter,
        ball_radius=ball_radius, p_ftu=p_ftu, p_stu=p_stu,
        effective_radius=ball_radius + fit.radius - r_cal,
        radii=tuple(float(x) for x in ball_radius + radial - r_cal),
        characteristics=tuple(chars), nominal_radius=r_nom,
    )


def _tuples(a: ArrayLike) -> tuple[Vec3, ...]:
    arr = np.asanyarray(a, dtype=np.float64).reshape(-1, 3)
    return tuple((float(x), float(y), float(z)) for x, y, z in arr)
