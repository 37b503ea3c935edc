"""A cylinder fit that starts from the nominal axis, as a CMM's does.

CMM point patterns are sparse: two rings of four points (the NIST IMTS program) lie
*exactly* on more than one cylinder (also on one whose axis is square to the bore), so
a fit that knows nothing of the nominal can return any of them.  A CMM knows the
nominal and starts there; :func:`cylinder_near` does the same: Gauss-Newton on the
orthogonal distances, started from the nominal axis through the points' centroid.
:func:`probegen.dmisrun.features.fit_feature` keeps it unless the unseeded
least-squares fit is clearly better.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from probegen.geometry.frames import FloatArray, orthonormal_basis, unit

ITERATIONS = 50
"""Most Gauss-Newton steps."""

STEP = 1e-13
"""Stop when the largest step (mm or rad) falls below this."""

CONVERGED = 1e-9
"""After :data:`ITERATIONS` steps the fit still counts if the last step was below this
(floating-point noise can keep steps above :data:`STEP`)."""


@dataclass(frozen=True, slots=True)
class SeededCylinder:
    """A cylinder fitted from a start axis.

    Attributes:
        point: ``(3,)`` the centroid projected onto the axis.
        axis: ``(3,)`` unit axis, signed like the start axis.
        radius: radius.
        residuals: ``(n,)`` distance from the axis minus ``radius``.
    """

    point: FloatArray
    axis: FloatArray
    radius: float
    residuals: FloatArray

    @property
    def rms(self) -> float:
        """Root mean square residual."""
        return float(np.sqrt(np.mean(self.residuals**2)))

    @property
    def form(self) -> float:
        """Cylindricity, ``max - min`` residual."""
        return float(self.residuals.max() - self.residuals.min())


def cylinder_near(points: FloatArray, axis: FloatArray) -> SeededCylinder | None:
    """Least-squares cylinder through ``points : (n, 3)`` started from ``axis : (3,)``.

    Returns:
        The converged fit, or None if the iteration did not converge (the caller then
        keeps an unseeded fit).
    """
    centroid = points.mean(axis=0)
    point, direction = centroid.copy(), unit(axis)
    radius = float(np.mean(_distances(points, point, direction)))
    largest = np.inf
    for _ in range(ITERATIONS):
        basis = orthonormal_basis(direction)
        local = (points - point) @ basis.T
        rho = np.hypot(local[:, 0], local[:, 1])
        if np.any(rho == 0.0):
            return None
        ux, uy, z = local[:, 0] / rho, local[:, 1] / rho, local[:, 2]
        jac = np.column_stack([-ux, -uy, -ux * z, -uy * z, -np.ones(len(z))])
        step = np.linalg.lstsq(jac, -(rho - radius), rcond=None)[0]
        point = point + step[0] * basis[0] + step[1] * basis[1]
        direction = unit(step[2] * basis[0] + step[3] * basis[1] + basis[2])
        radius += float(step[4])
        largest = float(np.max(np.abs(step)))
        if largest < STEP:
            break
    if not largest < CONVERGED:
        return None
    point = point + float((centroid - point) @ direction) * direction
    residuals = _distances(points, point, direction) - radius
    return SeededCylinder(point, direction, radius, residuals)


def _distances(points: FloatArray, point: FloatArray, direction: FloatArray) -> FloatArray:
    """Distance of each point from the line (point, unit direction)."""
    rel = points - point
    across = rel - np.outer(rel @ direction, direction)
    return np.asarray(np.sqrt(np.sum(across * across, axis=1)))
