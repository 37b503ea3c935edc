"""Fitted features against their nominals: deviations, form, pass/fail.

The sphere test (method M1, ISO 10360-5): a least-squares (Gaussian) sphere through the
compensated contact points; radial residuals ``r_i = |P_i − C| − R``; probing form error
``P_FTU = max r_i − min r_i`` (least squares, as ISO 10360-5 defines it); size error
``P_STU = D_fit − D_cal``.  When the points were compensated with the nominal ball
radius ``r``, the probe's effective radius is ``r_eff = r + R_fit − R_cal`` (a smaller
effective radius, from pre-travel, makes the sphere look smaller), and the effective
radius in each measured direction is ``r + |P_i − C| − R_cal``: that is the probe
calibration the test produces.  ``POS`` is the ISO 1101 position zone diameter,
``2 |C − C_nominal|``, as for every kind (docs/results.md).
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike

from probegen.geometry.fits import SphereFit, fit_sphere
from probegen.geometry.uncertainty import COVERAGE_FACTOR, Budget, decide, verdict
from probegen.machine.calibration import ProbeCalibration

Vec3 = tuple[float, float, float]

OK, NOT_OK, NOT_EVALUATED, UNTOLERANCED = "OK", "NOT OK", "NOT EVALUATED", "-"
"""The status strings of a characteristic, a feature and a run (``results.json``
``status``, ``results.csv``, the table, the report): within its limits; out of them;
toleranced but not evaluated (missing or no-contact touches, a failed fit, a run cut
short); not toleranced (a run: nothing toleranced at all)."""
STATUSES = (OK, NOT_OK, NOT_EVALUATED, UNTOLERANCED)


@dataclass(frozen=True, slots=True)
class Characteristic:
    """One checked quantity of a feature.

    Attributes:
        name: e.g. ``X``, ``D``, ``P_FTU``.
        measured: the measured value, mm.
        nominal: the nominal value, mm.
        deviation: measured − nominal, mm.
        lower: lowest allowed deviation, or None when not toleranced.
        upper: highest allowed deviation, or None.
        u: standard uncertainty of the value, same unit, or None when not estimated
            (``probegen.geometry.uncertainty`` says how it is found).
        method: how a form value was evaluated (``"minimum zone"``, ``"least
            squares"``), ``""`` for other characteristics.
    """

    name: str
    measured: float
    nominal: float
    deviation: float
    lower: float | None = None
    upper: float | None = None
    u: float | None = None

    @property
    def U(self) -> float | None:
        """Expanded uncertainty ``k·u`` (``k = 2``), or None."""
        return None if self.u is None else COVERAGE_FACTOR * self.u

    @property
    def decision(self) -> str | None:
        """ISO 14253-1: ``conforming``, ``non-conforming`` or ``undecided`` (the value lies
        within ``U`` of a limit); None when not toleranced."""
        return decide(self.deviation, self.lower, self.upper, self.u)

    def accepted(self, rule: str = "simple") -> bool | None:
        """The verdict under ``rule`` (``simple``: ``ok``; ``guard_band``: conforming)."""
        return verdict(self.ok, self.decision, rule)
    method: str = ""

    @property
    def ok(self) -> bool | None:
        """Within tolerance (None when not toleranced)."""
        if self.lower is None and self.upper is None:
            return None
        lo = -math.inf if self.lower is None else self.lower
        hi = math.inf if self.upper is None else self.upper
        return lo <= self.deviation <= hi


def status_of(ok: bool | None) -> str:
    """The status string of a verdict of an evaluated characteristic or feature."""
    return UNTOLERANCED if ok is None else (OK if ok else NOT_OK)


def run_status(verdicts: Iterable[bool | None], *, not_evaluated: bool,
               complete: bool) -> str:
    """The status of a whole run from its evaluated features' verdicts.

    ``NOT OK`` as soon as one evaluated feature is out of tolerance, even when others
    could not be evaluated: a nonconformity measured completely is a definite finding
    that no further measurement can reverse (the part is rejected either way).  Else
    ``NOT EVALUATED`` when a spec feature could not be evaluated or the run did not
    finish (the run cannot be signed); else ``OK`` when something is toleranced, ``-``
    when nothing is.
    """
    checks = [v for v in verdicts if v is not None]
    if not all(checks):
        return NOT_OK
    if not_evaluated or not complete:
        return NOT_EVALUATED
    return OK if checks else UNTOLERANCED


def accepted(characteristics: Iterable[Characteristic], rule: str = "simple"
             ) -> bool | None:
    """A feature's verdict under the decision ``rule`` (``simple``: every toleranced
    characteristic within its limits): None when nothing is toleranced."""
    found = [v for v in (c.accepted(rule) for c in characteristics) if v is not None]
    return all(found) if found else None


class Evaluated(Protocol):
    """What every evaluated feature result has (sphere test, revolved, free-form,
    planar)."""

    @property
    def feature(self) -> str:
        """Feature id."""
        ...

    @property
    def characteristics(self) -> tuple[Characteristic, ...]:
        """The checked quantities."""
        ...

    @property
    def points(self) -> tuple[tuple[float, float, float], ...]:
        """The contact points, mm."""
        ...

    @property
    def ok(self) -> bool | None:
        """All toleranced characteristics within limits (None if none is toleranced)."""
        ...


@dataclass(frozen=True, slots=True)
class NotEvaluated:
    """A spec feature that could not be evaluated completely: its status, and that of
    each of its toleranced characteristics, is ``NOT EVALUATED``, never OK.

    Attributes:
        feature: feature id.
        kind: feature kind (``sphere_test``, ``cylinder``, ``plane`` ...).
        reason: why, for people (``no touch for points 17-18``, ``no contact at point
            5 (ERR NOTOUCH, line 12)``, the fit's error ...).
        characteristics: names of the toleranced characteristics the spec asks for
            (as an evaluation would name them).
        limits: the ``(lower, upper)`` limits of each of ``characteristics``.
        partial: the fit of the touches there were, when they sufficed for one: shown
            for information only, its verdicts do not count.
    """

    feature: str
    kind: str
    reason: str
    characteristics: tuple[str, ...] = ()
    limits: tuple[tuple[float | None, float | None], ...] = ()
    partial: Evaluated | None = None


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
                                u or 0.0, date)


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
    from probegen.evaluate.uncertainty import FittedShape, uncertainties

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
