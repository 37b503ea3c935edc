"""How well the points determine a fit: condition number and parameter uncertainties.

Every fit record carries ``condition``: the condition number (largest over smallest
singular value) of the Jacobian of the residuals with respect to the fit's parameters
at the solution.  It is computed on the fit's *normalised* data (centroid at the origin,
RMS distance 1: ``fits_solver.normalise``), so lengths are in units of the points' own
spread and angles in radians; it does not depend on units, position or point count.
About 1 for points all round a circle or sphere, it grows as the points cover less of
the shape: ~50 for a 60-degree arc, ~2000 for 10 degrees, ~8000 for 5 degrees, ~2e5 for
1 degree.  Parameters computed in double precision lose about ``log10(condition)`` of
their 16 digits.

A fit raises ``ProbegenError`` (``"... expected points that determine the shape ..."``)
when either figure says the points cannot determine the shape:

* ``condition > CONDITION_LIMIT`` (1e8): the problem is numerically singular, whatever
  the noise (points on a tiny arc or cap, very nearly collinear or coplanar);
* a parameter's standard uncertainty, ``s * sqrt(diag((J^T J)^-1))`` with ``s`` the RMS
  residual corrected for the parameters fitted (``sqrt(sum(r^2) / (n - p))``), exceeds
  ``UNCERTAINTY_LIMIT`` (1) times the RMS spread of the points for a length (centre,
  radius; for a cylinder and a cone the spread *across the axis*, as their length does
  not pin the radius down), or one radian for an angle (axis direction, half angle).
  This is the noisy short arc: 40 points on a 5-degree arc of a 33 mm radius with 2 um
  scatter give a radius uncertain by +-1.1 mm over a 0.85 mm spread.
  With as many points as parameters there are no residuals to judge, so only the
  condition number is checked.

Lines (always determined once the points are not coincident) report ``1 / e`` with
``e`` the relative extent of the points along the line, and are never refused.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from probegen.geometry.fits_solver import FloatArray, Model, Normalised, fit_error

#: Condition number above which a fit is refused (see the module docstring).  The
#: hardest accepted case in the test suites (a 10-degree arc) is near 2e3; a
#: noise-free 0.1-degree arc, 2e7, still gives its centre to about 1e-9 of its spread.
CONDITION_LIMIT = 1e8
#: Largest standard uncertainty of a parameter, in normalised units (lengths in RMS
#: spreads of the points, angles in radians), before a fit is refused.
UNCERTAINTY_LIMIT = 1.0
#: Above this condition number estimated from ``J^T J`` (whose rounding squares it), the
#: figure is recomputed from ``J`` itself.
GRAM_TRUSTED = 1e6

_HINT = "too short an arc, too small a cap, too few points or too much scatter"


@dataclass(frozen=True, slots=True)
class Conditioning:
    """Condition number and standard uncertainties of a solution (normalised units).

    Attributes:
        condition: largest over smallest singular value of the Jacobian (inf if singular).
        std: ``(p,)`` standard uncertainty of each parameter; zeros when there are no
            more points than parameters.
        sigma: RMS residual corrected for the ``p`` fitted parameters (0 if ``n <= p``).
    """

    condition: float
    std: FloatArray
    sigma: float


def _spectrum(jac: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Return the singular values (descending) and right singular vectors (columns) of
    ``jac : (n, p)``; many rows go through ``J^T J`` unless that is too ill-conditioned."""
    if len(jac) > 8 * jac.shape[1]:
        eigenvalues, vectors = np.linalg.eigh(jac.T @ jac)
        values = np.sqrt(np.clip(eigenvalues[::-1], 0.0, None))
        if values[-1] > 0.0 and values[0] / values[-1] <= GRAM_TRUSTED:
            return values, vectors[:, ::-1]
    _, values, vt = np.linalg.svd(jac, full_matrices=False)
    return values, vt.T


def conditioning(jac: FloatArray, residuals: FloatArray) -> Conditioning:
    """Return the conditioning of a least-squares solution.

    Args:
        jac: ``(n, p)`` Jacobian of the residuals at the solution.
        residuals: ``(n,)`` residuals at the solution.
    """
    n, p = jac.shape
    values, vectors = _spectrum(jac)
    if not (values[-1] > 0.0 and math.isfinite(float(values[0]))):
        return Conditioning(math.inf, np.full(p, math.inf), 0.0)
    condition = float(values[0] / values[-1])
    if n <= p:
        return Conditioning(condition, np.zeros(p), 0.0)
    sigma = math.sqrt(float(residuals @ residuals) / (n - p))
    std = sigma * np.sqrt(np.sum((vectors / values) ** 2, axis=1))
    return Conditioning(condition, np.asarray(std, dtype=np.float64), sigma)


def assess(fit: str, jac: FloatArray, residuals: FloatArray, *, names: Sequence[str],
           angular: Sequence[bool], data: Normalised, spread: float = 1.0,
           where: str = "") -> float:
    """Return the condition number of a solution, or raise if the points cannot
    determine the shape (see the module docstring).

    Args:
        fit: the fit's name, for messages.
        jac: ``(n, p)`` Jacobian at the solution, normalised units.
        residuals: ``(n,)`` residuals at the solution, normalised units.
        names: the ``p`` parameter names, for messages.
        angular: which parameters are angles (radians).
        data: the normalised data (its ``scale`` turns lengths back to input units).
        spread: the RMS spread of the points that the lengths are judged against,
            normalised units: 1 (all of it), or less (across an axis).
        where: how to name that spread in a message (``" across the axis"``).

    Raises:
        ProbegenError: condition above CONDITION_LIMIT, or a standard uncertainty
            above UNCERTAINTY_LIMIT.
    """
    result = conditioning(jac, residuals)
    if not result.condition <= CONDITION_LIMIT:
        raise fit_error(fit, "points that determine the shape",
                        f"an ill-conditioned problem (condition number {result.condition:.1e},"
                        f" limit {CONDITION_LIMIT:.0e}): {_HINT}")
    relative = result.std / np.where(angular, 1.0, spread)
    worst = int(np.argmax(relative))
    if relative[worst] > UNCERTAINTY_LIMIT:
        scatter = f"RMS residual {result.sigma * data.scale:.2g}"
        value = float(result.std[worst])
        if angular[worst]:
            limit = f"more than {math.degrees(UNCERTAINTY_LIMIT):.0f} degrees; {scatter}"
            found = f"{math.degrees(value):.2g} degrees ({limit})"
        else:
            limit = f"{UNCERTAINTY_LIMIT * spread * data.scale:.2g} RMS spread of the points"
            found = f"{value * data.scale:.2g} (more than the {limit}{where}; {scatter})"
        raise fit_error(fit, "points that determine the shape",
                        f"the {names[worst]} uncertain by +-{found}: {_HINT}")
    return result.condition


def assess_model(fit: str, model: Model, jac: FloatArray, residuals: FloatArray,
                 data: Normalised, axis: FloatArray | None = None) -> float:
    """``assess`` for an iterative fit, with the model's parameter names; lengths are
    judged against the spread of the points across ``axis`` when one is given."""
    names = model.names
    angular = [model.is_angle(k) for k in range(len(names))]
    if axis is None:
        return assess(fit, jac, residuals, names=names, angular=angular, data=data)
    spread = spread_across(data, axis)
    return assess(fit, jac, residuals, names=names, angular=angular, data=data,
                  spread=spread, where=" across the axis")


def spread_across(data: Normalised, axis: FloatArray) -> float:
    """RMS spread of normalised points across a unit ``axis``: ``sqrt(1 - a^T C a)``
    with ``C`` their covariance, from the principal extents (no pass over the points)."""
    along = float(np.sum((data.extents * (data.directions @ axis)) ** 2))
    return math.sqrt(max(1.0 - along, 0.0))


def assess_plane(fit: str, data: Normalised, normal: FloatArray,
                 residuals: FloatArray) -> float:
    """``assess`` for a least-squares plane through normalised ``data`` (tilts of the
    normal about the two in-plane principal directions, and the offset)."""
    u, v = data.directions[0], data.directions[1]
    q = data.points
    jac = np.column_stack([-(q @ u), -(q @ v), -np.ones(len(q))])
    names = ("normal direction", "normal direction", "offset")
    return assess(fit, jac, residuals, names=names, angular=(True, True, False), data=data)


def line_condition(data: Normalised) -> float:
    """The condition number of a least-squares line: ``1 / extent`` along the line."""
    return float(1.0 / data.extents[0])
