"""Legendre polynomials on an axis range, fits with the degree chosen by cross-validation.

An error function of an axis is written ``f(q) = Σ_k c_k·P_k(s)`` with
``s = (2q − lo − hi)/(hi − lo)`` the position normalised to [−1, 1] over the axis range
``[lo, hi]`` (mm) and ``P_k`` the Legendre polynomials.  The basis is orthogonal over the
range, so the coefficients of degree 0 and 1 are the mean and the least-squares slope of
the function (``slope = 2·c_1/(hi − lo)`` per mm): removing them leaves the function about
its least-squares reference line, the ISO 230-1 convention for a straightness.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.polynomial import legendre
from numpy.typing import ArrayLike, NDArray

from probegen.errors import CalibrationError

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class AxisRange:
    """The range ``[lo, hi]`` (mm) an error function is defined on."""

    lo: float
    hi: float

    def normalise(self, q: ArrayLike) -> FloatArray:
        """Positions (mm) mapped to [−1, 1]."""
        return np.asarray((2.0 * np.asarray(q, dtype=np.float64) - self.lo - self.hi)
                          / (self.hi - self.lo))

    def positions(self, count: int) -> FloatArray:
        """``count`` evenly spaced positions over the range, ends included, mm."""
        return np.linspace(self.lo, self.hi, count)


def basis(rng: AxisRange, q: ArrayLike, degrees: Sequence[int]) -> FloatArray:
    """``P_k(s(q))`` for each position (rows) and degree (columns): (n, len(degrees))."""
    s = rng.normalise(np.atleast_1d(q))
    cols = [legendre.legval(s, np.eye(k + 1)[k]) for k in degrees]
    return np.asarray(np.column_stack(cols) if cols else np.zeros((len(s), 0)))


def evaluate(rng: AxisRange, q: ArrayLike, coefficients: ArrayLike, lowest: int = 0) -> FloatArray:
    """``Σ c_k·P_k`` at positions ``q`` (mm); ``coefficients[0]`` is of degree ``lowest``."""
    c = np.asarray(coefficients, dtype=np.float64)
    return basis(rng, q, range(lowest, lowest + len(c))) @ c


def project(rng: AxisRange, func: Callable[[FloatArray], FloatArray],
            degree: int) -> FloatArray:
    """Legendre coefficients 0..``degree`` of ``func`` over the range (Gauss quadrature).

    Exact for a polynomial of degree ≤ ``degree``; ``func`` maps positions (mm) to values.
    """
    s, w = legendre.leggauss(degree + 1)
    values = func(np.asarray(rng.lo + (s + 1.0) * (rng.hi - rng.lo) / 2.0))
    k = np.arange(degree + 1)
    p = np.stack([legendre.legval(s, np.eye(degree + 1)[j]) for j in k])
    return np.asarray((p * w) @ values * (2 * k + 1) / 2.0)


def rms(rng: AxisRange, coefficients: ArrayLike, lowest: int = 0) -> float:
    """RMS over the range of ``Σ c_k·P_k`` (exact: ``Σ c_k²/(2k + 1)``)."""
    c = np.asarray(coefficients, dtype=np.float64)
    k = np.arange(lowest, lowest + len(c))
    return float(np.sqrt(np.sum(c**2 / (2 * k + 1))))


def rms_difference(rng: AxisRange, a: ArrayLike, b: ArrayLike, lowest: int = 0) -> float:
    """RMS over the range of ``a − b``, two coefficient arrays of any lengths."""
    ca, cb = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    n = max(len(ca), len(cb))
    return rms(rng, np.pad(ca, (0, n - len(ca))) - np.pad(cb, (0, n - len(cb))), lowest)


@dataclass(frozen=True)
class PolyFit:
    """A least-squares fit of degrees 0..degree, reported from ``lowest``: ``Σ c_k·P_k``.

    Attributes:
        range: the axis range.
        lowest: degree of the first coefficient (0, 1 or 2).
        coefficients: (degree − lowest + 1,) float, in the unit of the samples.
        offset: the fitted degree-0 coefficient (not part of the function when
            ``lowest`` > 0: an unknown zero of the measurement).
        cv_rms: the cross-validated RMS prediction error at the chosen degree.
        residual_rms: RMS residual of the fit on all samples.
    """

    range: AxisRange
    lowest: int
    coefficients: FloatArray
    offset: float
    cv_rms: float
    residual_rms: float

    @property
    def degree(self) -> int:
        """The highest degree fitted."""
        return self.lowest + len(self.coefficients) - 1

    def __call__(self, q: ArrayLike) -> FloatArray:
        """The function (without ``offset``) at positions ``q``, mm."""
        return evaluate(self.range, q, self.coefficients, self.lowest)


def fit(rng: AxisRange, q: ArrayLike, f: ArrayLike, lowest: int, degree: int) -> PolyFit:
    """Least-squares fit of degrees 0..``degree``; those below ``lowest`` are fitted but
    not part of the function (an unknown zero, and for ``lowest`` = 2 a reference line).

    Raises:
        CalibrationError: fewer samples than unknowns.
    """
    qa, fa = np.asarray(q, dtype=np.float64), np.asarray(f, dtype=np.float64)
    a = basis(rng, qa, range(degree + 1))
    if len(qa) < a.shape[1]:
        raise CalibrationError(f"polynomial fit of degree {degree}: expected at least "
                               f"{a.shape[1]} samples, found {len(qa)}")
    sol, *_ = np.linalg.lstsq(a, fa, rcond=None)
    res = fa - a @ sol
    return PolyFit(rng, lowest, np.asarray(sol[lowest:]), float(sol[0]), float("nan"),
                   float(np.sqrt(np.mean(res**2))))


def fit_cv(rng: AxisRange, q: ArrayLike, f: ArrayLike, lowest: int, max_degree: int,
           folds: int = 5) -> PolyFit:
    """Fit with the degree (``lowest``..``max_degree``) of least ``folds``-fold CV error.

    Samples are dealt to folds in turn (sample ``i`` to fold ``i mod folds``), so every
    fold spans the range.  Ties (within 1e-9 relative) go to the lower degree.  Degrees
    stop where a training fold has fewer than two samples per unknown (a CV estimate
    from fewer is noise itself).
    """
    qa, fa = np.asarray(q, dtype=np.float64), np.asarray(f, dtype=np.float64)
    best: tuple[float, int] | None = None
    for degree in range(lowest, max_degree + 1):
        err = cv_error(rng, qa, fa, lowest, degree, folds)
        if err is None:
            break
        if best is None or err < best[0] * (1.0 - 1e-9) - 1e-300:
            best = (err, degree)
    if best is None:
        need = int(np.ceil(2 * (lowest + 1) * folds / (folds - 1)))
        raise CalibrationError(f"polynomial fit: expected at least {need} samples for "
                               f"cross-validation, found {len(qa)}")
    chosen = fit(rng, qa, fa, lowest, best[1])
    return PolyFit(rng, lowest, chosen.coefficients, chosen.offset, best[0],
                   chosen.residual_rms)


def cv_error(rng: AxisRange, q: FloatArray, f: FloatArray, lowest: int, degree: int,
             folds: int) -> float | None:
    """RMS of the held-out prediction errors over ``folds`` folds (None: too few samples)."""
    width = degree + 1
    errors = []
    for k in range(folds):
        test = np.arange(len(q)) % folds == k
        if np.count_nonzero(~test) < 2 * width or not np.any(test):
            return None  # at least two training samples per unknown, or no estimate
        sol, *_ = np.linalg.lstsq(basis(rng, q[~test], range(width)), f[~test], rcond=None)
        errors.append(f[test] - basis(rng, q[test], range(width)) @ sol)
    return float(np.sqrt(np.mean(np.concatenate(errors) ** 2)))
