"""Measurement uncertainty of evaluated characteristics and ISO 14253-1 decisions.

Every characteristic carries its standard uncertainty ``u`` (same unit as its value) and
the expanded uncertainty ``U = k·u`` with ``k = 2`` (``COVERAGE_FACTOR``).  ``u`` combines
in quadrature (GUM, uncorrelated inputs):

* the fit: the covariance of the least-squares parameters ``σ²·(JᵀJ)⁻¹`` with
  ``σ² = SSR / (n − p)`` (the residuals' variance about the fit; ``J`` the Jacobian of
  the orthogonal residuals with respect to the ``p`` fit parameters, in mm), propagated
  to the characteristic through its gradient (``u² = gᵀ C g``); when ``n − p < 5`` the
  residual-based ``σ`` is unreliable and ``max(σ, u_probe)`` is used instead;
* the calibration: the probe's effective-radius uncertainty ``u_radius`` times the
  characteristic's sensitivity to the radius (2 for a diameter, 0 for a centre);
* the machine profile's stated machine contribution ``u_machine`` (a length
  measurement's standard uncertainty, mm) times the characteristic's sensitivity to a
  length: 1 for coordinates and sizes, 2 for a position zone diameter, ``1/L`` rad for
  an angle over an axial extent ``L``.

Form values (roundness, cylindricity, P_FTU...) are ranges of residuals: two single
readings, so ``u = √2·u_noise`` with ``u_noise`` the stated probe contribution, or when
none is stated the fit's residual ``σ`` (an overestimate: it contains the form itself).

Decisions (ISO 14253-1): with ``U`` the expanded uncertainty, a toleranced value is
*conforming* inside the limits shrunk by ``U``, *non-conforming* outside the limits
widened by ``U``, *undecided* in between.  The verdict (``OK`` / ``NOT OK``) follows the
decision rule: ``simple`` (the default, simple acceptance): the measured value alone;
``guard_band``: ``OK`` only when conforming.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]

COVERAGE_FACTOR = 2.0
"""``k`` of the expanded uncertainty ``U = k·u`` (about 95 % for a normal distribution)."""
DECISION_RULES = ("simple", "guard_band")
"""The decision rules: simple acceptance, or guard-banding by ``U`` (ISO 14253-1)."""
FEW_DOF = 5
"""Below this many degrees of freedom ``n − p`` the residual-based sigma is replaced by
``max(sigma, u_probe)``."""
STEP = 1e-6
"""Parameter step (mm, rad) of the numerical derivatives: far above the fits' convergence
(1e-10 mm), far below any curvature of the models."""
CONFORMING, NON_CONFORMING, UNDECIDED = "conforming", "non-conforming", "undecided"
FIT_PARAMETERS = {"sphere_test": 4, "circle": 3, "cylinder": 5, "cone": 6, "sphere": 4,
                  "torus": 7}
"""Parameters ``p`` of each kind's fit (a circle: in its plane)."""


@dataclass(frozen=True, slots=True)
class Budget:
    """The stated contributions to every characteristic's uncertainty.

    Attributes:
        radius: standard uncertainty of the probe's effective radius, mm (the
            calibration's ``u_radius``; 0 without a calibration or for an old file).
        machine: the machine profile's stated machine contribution, mm, or None when
            the profile states none (then counted as 0 and said so).
        probe: the stated probing (repeatability) contribution per touch, mm, or None.
    """

    radius: float = 0.0
    machine: float | None = None
    probe: float | None = None

    @property
    def u_machine(self) -> float:
        """The machine contribution, 0 when not stated."""
        return self.machine or 0.0

    @property
    def u_probe(self) -> float:
        """The probe contribution, 0 when not stated."""
        return self.probe or 0.0

    def notes(self) -> tuple[str, ...]:
        """What the uncertainties leave out, for the outputs."""
        out = []
        if self.machine is None:
            out.append("uncertainty: the machine contribution was not stated (the profile's "
                       "[uncertainty] machine), counted as 0")
        if self.probe is None:
            out.append("uncertainty: the probe contribution was not stated (the profile's "
                       "[uncertainty] probe); form uncertainties use the fit's residuals")
        return tuple(out)


@dataclass(frozen=True, slots=True)
class FitCovariance:
    """The least-squares covariance of a fit's parameters.

    Attributes:
        cov: ``(p, p)`` covariance, in the parameters' units (mm, rad).
        sigma: the per-point standard deviation used, mm.
        dof: ``n − p``.
        few: True when ``dof < FEW_DOF`` (sigma is ``max(residual sigma, u_probe)``).
    """

    cov: Array
    sigma: float
    dof: int
    few: bool


def few_dof_note(feature: str, kind: str, n: int, budget: Budget) -> str | None:
    """The note for a fit with ``n − p < FEW_DOF`` degrees of freedom, else None."""
    dof = n - FIT_PARAMETERS.get(kind, n)
    if kind not in FIT_PARAMETERS or dof >= FEW_DOF:
        return None
    floor = ("the stated probe contribution when larger" if budget.probe is not None
             else "nothing: state the profile's [uncertainty] probe")
    return (f"uncertainty: feature {feature}: {n} touches for {FIT_PARAMETERS[kind]} fit "
            f"parameters leave {dof} degrees of freedom (< {FEW_DOF}): the residual sigma "
            f"is unreliable; u uses it or {floor}")


def jacobian(func: Callable[[Array], Array], size: int) -> Array:
    """Central-difference Jacobian ``(m, size)`` of ``func : (size,) -> (m,)`` at 0."""
    cols = []
    for j in range(size):
        step = np.zeros(size)
        step[j] = STEP
        cols.append((func(step) - func(-step)) / (2.0 * STEP))
    return np.column_stack(cols)


def fit_covariance(residuals: Callable[[Array], Array], size: int, budget: Budget,
                   sigma: float | None = None) -> FitCovariance:
    """Covariance ``σ²(JᵀJ)⁻¹`` of a least-squares fit.

    Args:
        residuals: the fit's orthogonal residuals (mm) as a function of a parameter
            perturbation ``(size,)`` about the solution (0 = the fitted solution).
        size: number of fit parameters ``p``.
        budget: gives ``u_probe`` for few degrees of freedom.
        sigma: use this per-point sigma instead of the residuals' (a sub-fit that shares
            a pooled sigma).
    """
    r0 = residuals(np.zeros(size))
    jac = jacobian(residuals, size)
    dof = len(r0) - size
    if sigma is None:
        sigma = math.sqrt(float(r0 @ r0) / dof) if dof > 0 else 0.0
    few = dof < FEW_DOF
    if few:
        sigma = max(sigma, budget.u_probe)
    cov = np.asarray(sigma**2 * np.linalg.pinv(jac.T @ jac), dtype=np.float64)
    return FitCovariance(cov, sigma, dof, few)


def propagate(func: Callable[[Array], Array], fit: FitCovariance) -> Array:
    """Covariance ``G C Gᵀ`` of the derived values ``func : (p,) -> (m,)``."""
    g = jacobian(func, fit.cov.shape[0])
    return np.asarray(g @ fit.cov @ g.T)


def magnitude_u(vector: Array, cov: Array) -> float:
    """Standard uncertainty of ``|v|`` for a vector ``v`` with covariance ``cov``: the
    variance along ``v``; near ``v = 0``, where the direction is noise, the mean variance
    of the components."""
    norm = float(np.linalg.norm(vector))
    var = float(np.trace(cov)) / len(vector)
    if norm > math.sqrt(max(var, 0.0)):
        e = vector / norm
        var = float(e @ cov @ e)
    return math.sqrt(max(var, 0.0))


def combine(*parts: float) -> float:
    """Root sum of squares."""
    return math.sqrt(sum(p * p for p in parts))


def form_u(fit_sigma: float, budget: Budget) -> float:
    """Standard uncertainty of a form value (a range of residuals, see the module doc)."""
    noise = budget.probe if budget.probe else fit_sigma
    return math.sqrt(2.0) * noise


def t_factor(dof: int, level: float = 0.95) -> float:
    """Student's t coverage factor for a two-sided ``level`` interval with ``dof`` degrees
    of freedom (``nan`` without any): the factor a standard uncertainty estimated from a
    few samples needs, in place of the normal distribution's 1.96."""
    if dof < 1:
        return math.nan
    from scipy.stats import t

    return float(t.ppf(0.5 + level / 2.0, dof))


def decide(deviation: float, lower: float | None, upper: float | None,
           u: float | None) -> str | None:
    """ISO 14253-1 decision for a deviation and its limits (None when not toleranced)."""
    if lower is None and upper is None:
        return None
    big = 0.0 if u is None else COVERAGE_FACTOR * u
    lo = -math.inf if lower is None else lower
    hi = math.inf if upper is None else upper
    if lo + big <= deviation <= hi - big and (big == 0.0 or lo + big < hi - big):
        return CONFORMING
    if deviation < lo - big or deviation > hi + big:
        return NON_CONFORMING
    return UNDECIDED


def verdict(ok: bool | None, decision: str | None, rule: str) -> bool | None:
    """The verdict under a decision rule: simple acceptance follows the value (``ok``);
    guard banding accepts only a conforming decision."""
    if rule == "guard_band" and decision is not None:
        return decision == CONFORMING
    return ok
