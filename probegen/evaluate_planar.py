"""Lines and planes (``kind = "line"``/``"plane"``, ``spec_actions``) from their touches.

Every touch is compensated by the ball radius along the face's nominal outward normal
``n`` (the touches go straight down ``-n``).  The values are the ones the in-process
check computes (:func:`probegen.ingest_actions.evaluate_check`, the same code), so a
feature with actions shows in the results what the control decided on:

* ``DIST``: the face's position, the mean distance of the contact points from the
  nominal face along ``n`` (+ = material added), mm; toleranced by ``position``
  (``[lower, upper]``).
* ``ANGLE`` (lines): the fitted direction in XY, degrees, against the nominal one (start
  to end); the deviation is taken modulo 180 degrees, toleranced by ``angle`` (±).
* ``FORM``: flatness of a plane (least-squares plane, range of the residuals; from 4
  touches) or straightness of a line (least-squares line in XY; from 3 touches), mm,
  not toleranced.

``residuals`` are each contact point's distance from the nominal face along ``n`` minus
``DIST``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from probegen.compensate import ProbeCalibration, compensate
from probegen.evaluate import Characteristic
from probegen.geometry.fits import fit_line_2d, fit_plane
from probegen.ingest_actions import evaluate_check
from probegen.ir_actions import Check, point_index

Vec3 = tuple[float, float, float]

FORM_MIN_POINTS = {"plane": 4, "line": 3}
"""Fewest touches the form is reported from: one more than the fit's parameters."""


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
        checks = [c.ok for c in self.characteristics if c.ok is not None]
        return all(checks) if checks else None


def evaluate_planar(check: Check, balls: dict[int, Vec3], *,
                    radius: float | ProbeCalibration | None = None) -> PlanarResult:
    """Evaluate a line or plane from its ball centres by touch index.

    Args:
        check: the feature's fit and limits (:func:`probegen.planning.actions.planar_fit`).
        balls: the ball centre of every touch of the check, mm.
        radius: what the contact points are compensated with (default the check's
            ball radius).

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
        form = (fit_line_2d(contacts[:, :2]) if check.fit == "line"
                else fit_plane(contacts)).form
        chars.append(Characteristic("FORM", form, 0.0, form))
    return PlanarResult(check.feature, check.fit, _rows(contacts), _rows(normals),
                        tuple(float(v - dist) for v in along), tuple(chars))


def _rows(a: np.ndarray) -> tuple[Vec3, ...]:
    return tuple((float(x), float(y), float(z)) for x, y, z in a)
