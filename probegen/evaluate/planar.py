"""Lines and planes (``kind = "line"``/``"plane"``, ``spec_actions``) from their touches.

Every touch is compensated by the ball radius along the face's nominal outward normal
``n`` (the touches go straight down ``-n``).  The values are the ones the in-process
check computes (:func:`probegen.evaluate.actions.evaluate_check`, the same code), so a
feature with actions shows in the results what the control decided on:

* ``DIST``: the face's position, the mean distance of the contact points from the
  nominal face along ``n`` (+ = material added), mm; toleranced by ``position``
  (``[lower, upper]``).
* ``ANGLE`` (lines): the fitted direction in XY, degrees, against the nominal one (start
  to end); the deviation is taken modulo 180 degrees, toleranced by ``angle`` (±).
* ``FORM``: flatness of a plane (from 4 touches) or straightness of a line in XY (from
  3 touches), mm: the width of the ISO 1101 minimum zone (two parallel planes, two
  parallel lines; ``geometry.minimum_zone``), or with ``form_method =
  "least_squares"`` the range of the residuals about the least-squares plane or line
  (never narrower); the characteristic's ``method`` names which.  Toleranced by
  ``form`` (an upper limit).  The in-process check of a line or plane computes no
  form: this value is the offline evaluation's alone.

``residuals`` are each contact point's distance from the nominal face along ``n`` minus
``DIST``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from probegen.evaluate.actions import evaluate_check
from probegen.evaluate.characteristics import Characteristic, accepted
from probegen.geometry import minimum_zone
from probegen.geometry.fits import fit_line_2d, fit_plane
from probegen.ir.actions import Check, point_index
from probegen.machine.calibration import ProbeCalibration, compensate
from probegen.spec.actions import FORM_MIN_POINTS, PlanarTolerance

Vec3 = tuple[float, float, float]

NO_TOLERANCE = PlanarTolerance()
"""No form limit, the minimum zone."""


@dataclass(frozen=True, slots=True)
class PlanarResult:
    """An evaluated line or plane.

    Attributes:
        feature: feature id.
        kind: ``line`` or ``plane``.
        points: (n) compensated contact points, mm.
        directions: (n) the nominal outward normal, once per point.
        residuals: (n) see the module doc, mm.
        characteristics: ``DIST``, ``ANGLE`` (lines), ``FORM`` (enough touches).
    """

    feature: str
    kind: str
    points: tuple[Vec3, ...]
    directions: tuple[Vec3, ...]
    residuals: tuple[float, ...]
    characteristics: tuple[Characteristic, ...]

    @property
    def ok(self) -> bool | None:
        """All toleranced characteristics within limits (None if none is toleranced)."""
        return accepted(self.characteristics)


def evaluate_planar(check: Check, balls: dict[int, Vec3], *,
                    radius: float | ProbeCalibration | None = None,
                    tolerance: PlanarTolerance = NO_TOLERANCE) -> PlanarResult:
    """Evaluate a line or plane from its ball centres by touch index.

    Args:
        check: the feature's fit and limits (:func:`probegen.planning.actions.planar_fit`).
        balls: the ball centre of every touch of the check, mm.
        radius: what the contact points are compensated with (default the check's
            ball radius).
        tolerance: the feature's form limit and form method (its position and angle
            limits are the check's).

    Raises:
        ProbegenError: a touch missing, or touches that fit no line.
    """
    values = evaluate_check(check, balls)
    order = [point_index(next(n for n in p if n is not None)) for p in check.points]
    centres = np.array([balls[k] for k in order], dtype=np.float64)
    n = np.asarray(check.normal, dtype=np.float64)
    normals = np.tile(n, (len(order), 1))
    contacts = compensate(centres, normals, check.ball_radius if radius is None else radius)
    along = (contacts - np.asarray(check.nominal)) @ n
    dist = float(along.mean())  # = values["E"] with the nominal radius
    limits = {lim.key: (lim.lower, lim.upper) for lim in check.limits}
    pos = limits.get("position", (None, None))
    chars = [Characteristic("DIST", dist, 0.0, dist, *pos)]
    if check.fit == "line":
        a = values["A"]
        top = limits["angle"][1] if "angle" in limits else None
        chars.append(Characteristic("ANGLE", check.direction + a, check.direction, a,
                                    None if top is None else -top, top))
    if len(order) >= FORM_MIN_POINTS[check.fit]:
        form, method = planar_form(check.fit, contacts, tolerance.form_method)
        chars.append(Characteristic("FORM", form, 0.0, form, None, tolerance.form,
                                    method=method))
    return PlanarResult(check.feature, check.fit, _rows(contacts), _rows(normals),
                        tuple(float(v - dist) for v in along), tuple(chars))


def planar_form(kind: str, contacts: np.ndarray, form_method: str) -> tuple[float, str]:
    """The flatness (``kind`` ``plane``, ``contacts (n, 3)``) or straightness in XY
    (``line``) of the contact points, mm, and the method's name: the minimum zone
    started from the least-squares fit, or (``form_method = "least_squares"``) the
    range of the least-squares residuals."""
    least_squares = form_method == "least_squares"
    if kind == "line":
        line = fit_line_2d(contacts[:, :2])
        form = line.form if least_squares else minimum_zone.straightness_2d(
            contacts[:, :2], line.point, line.direction)
    else:
        plane = fit_plane(contacts)
        form = plane.form if least_squares else minimum_zone.flatness(
            contacts, plane.point, plane.normal)
    return form, minimum_zone.LABELS[form_method]


def _rows(a: np.ndarray) -> tuple[Vec3, ...]:
    return tuple((float(x), float(y), float(z)) for x, y, z in a)
