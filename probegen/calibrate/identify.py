"""Method M5: global least-squares identification of the geometric errors (and the truth
of a planted error model in the same terms, for closed-loop tests).

All readings of all setups go into one linear least-squares problem through the
linearised volumetric model (:mod:`probegen.calibrate.identify_model`): every Legendre
coefficient of the 18 error motions, the squareness errors and each setup's zero and
plate turn.  The problem is rank deficient by construction (gauge freedoms) and by the
plan (confounded functions); the minimum-norm solution is taken and only the quantities
the plan determines (orthogonal to the null space) are reported; the others are listed
as NOT identifiable with what they are confounded with, and carry no value.

The common Legendre degree of the functions is chosen by ``folds``-fold
cross-validation over the stops (stop ``i`` of the readings in fold ``i mod folds``).
The dispersion reported is ``sqrt(RSS / (m − rank))`` of the grating rows: the
standard deviation of a reading if the model holds.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from probegen.calibrate.grating_io import GratingReading, LevelReading
from probegen.calibrate.identify_model import (
    AXIS,
    FUNCTIONS,
    RANK_TOL,
    Design,
    ErrorFunction,
    FloatArray,
    Identifiability,
    SetupKey,
    VolumetricModel,
    analyse,
    axis_positions,
    combinations,
    design,
)
from probegen.errors import CalibrationError
from probegen.geometry.orthopoly import AxisRange, basis, project
from probegen.geometry.uncertainty import t_factor
from probegen.machine.errors_model import ErrorModel
from probegen.machine.kinematics import PLANES

SQUARENESS = {"XY": "S_XY", "XZ": "S_XZ", "YZ": "S_YZ"}


@dataclass(frozen=True)
class FunctionResult:
    """One error motion as identified.

    Attributes:
        function: which motion.
        range: its axis range, mm.
        coefficients: Legendre coefficients of degrees ``function.lowest``.. (µm or µrad),
            or None when the plan does not determine it.
        partners: the functions it is confounded with (empty when determined).
        curvature: when the function is not determined but its part about its
            least-squares line is (only its slope is confounded): the coefficients of
            degrees ``function.lowest + 1``..; else None.
        covariance: the coefficients' covariance (µm² or µrad²) from the least-squares
            fit, ``s²·g (AᵀA)⁺ gᵀ`` (``s`` the dispersion; a determined function is an
            estimable combination, so the pseudo-inverse gives its true variance), or
            None (not determined, or an identification without it).
    """

    function: ErrorFunction
    range: AxisRange
    coefficients: FloatArray | None
    partners: tuple[str, ...] = ()
    curvature: FloatArray | None = None
    covariance: FloatArray | None = None

    @property
    def determined(self) -> bool:
        """Whether the plan determines it."""
        return self.coefficients is not None

    def band(self, q: FloatArray, k: float) -> FloatArray | None:
        """Half width ``k·u`` of the confidence band of the function at positions ``q``
        (mm), or None without a covariance."""
        if self.covariance is None or self.coefficients is None:
            return None
        b = basis(self.range, q, range(self.function.lowest,
                                       self.function.lowest + len(self.coefficients)))
        var = np.einsum("ij,jk,ik->i", b, self.covariance, b)
        return np.asarray(k * np.sqrt(np.maximum(var, 0.0)))


@dataclass(frozen=True)
class SquarenessResult:
    """The squareness of one plane at its first setup, µrad (None: not determined)."""

    name: str
    setup: SetupKey
    value: float | None


@dataclass(frozen=True)
class SlopeCombination:
    """A combination ``Σ weight·slope`` of the least-squares slopes (unit per metre) of
    functions whose slopes are confounded; ``value`` None when it is not determined."""

    terms: tuple[tuple[str, float], ...]
    value: float | None


@dataclass(frozen=True)
class Identification:
    """The result of an identification.

    Attributes:
        method: ``global`` or ``stepwise``.
        degree: the highest Legendre degree (global: common; stepwise: the largest chosen).
        functions: the 18 error motions in ``FUNCTIONS`` order.
        squareness: one per plane measured.
        rank, columns: of the global design (stepwise: both the number of coefficients fitted).
        dispersion: estimated standard deviation of a grating reading, µm.
        cv: (degree, cross-validated RMS µm) for each degree tried.
        slopes: for the functions known but for their slope (``curvature``), the
            combinations of their slopes the plan determines (with values) and those
            it does not (value None).
        dof: degrees of freedom of ``dispersion`` (grating readings − rank).
    """

    method: str
    degree: int
    functions: tuple[FunctionResult, ...]
    squareness: tuple[SquarenessResult, ...]
    rank: int
    columns: int
    dispersion: float
    cv: tuple[tuple[int, float], ...] = ()
    slopes: tuple[SlopeCombination, ...] = ()
    dof: int = 0

    @property
    def k95(self) -> float:
        """Student's t factor of the 95 % confidence bands (on ``dof``)."""
        return t_factor(self.dof)

    def function(self, name: str) -> FunctionResult:
        """The result of the function with ISO name ``name`` (e.g. ``EXX``)."""
        return next(f for f in self.functions if f.function.name == name)


def axis_ranges(readings: Sequence[GratingReading]) -> tuple[AxisRange, ...]:
    """Each axis' range: the extent of its positions over the planes that move it.

    Raises:
        CalibrationError: an axis no plane moves, or one that never moves.
    """
    out = []
    for axis in range(3):
        rows = [r for r in readings if axis in PLANES[r.plane][:2]]
        if not rows:
            raise CalibrationError(f"grating readings: expected a plane moving {AXIS[axis]}, "
                                   f"found planes {sorted({r.plane for r in readings})}")
        q = axis_positions(np.array([r.point for r in rows]),
                           np.array([r.head for r in rows]))[:, axis]
        if q.max() - q.min() < 1e-6:
            raise CalibrationError(f"grating readings: the {AXIS[axis]} axis never moves")
        out.append(AxisRange(float(q.min()), float(q.max())))
    return tuple(out)


def solve(d: Design) -> tuple[FloatArray, int]:
    """Minimum-norm least-squares solution (columns scaled) and the numerical rank."""
    scale = np.linalg.norm(d.matrix, axis=0)
    scale[scale == 0.0] = 1.0
    sol, _, rank, _ = np.linalg.lstsq(d.matrix / scale, d.values, rcond=RANK_TOL)
    return sol / scale, int(rank)


def cv_error(d: Design, folds: int) -> float:
    """RMS held-out prediction error (µm) over ``folds`` folds of the stops (a stop's
    two rows stay together; level rows always train)."""
    stop = np.arange(len(d.values)) // 2
    grating = np.array([k == "grating" for k in d.kinds])
    errors = []
    for k in range(folds):
        test = grating & (stop % folds == k)
        sol, _ = solve(Design(d.model, d.setups, d.level_axes, d.matrix[~test],
                              d.values[~test], tuple(np.asarray(d.kinds)[~test])))
        errors.append(d.values[test] - d.matrix[test] @ sol)
    return float(np.sqrt(np.mean(np.concatenate(errors) ** 2)))


def identify_global(readings: Sequence[GratingReading], level: Sequence[LevelReading] = (),
                    *, degree: int | None = None, max_degree: int = 6, folds: int = 5,
                    level_weight: float = 1.0) -> Identification:
    """Identify every determined error function at once (see the module docstring).

    Args:
        readings: grating readings of all setups.
        level: roll readings (electronic level), optional.
        degree: the Legendre degree; None chooses it by cross-validation (1..max_degree).
        max_degree: the highest degree tried.
        folds: cross-validation folds.
        level_weight: weight of a level row (µm per µrad) against a grating row.
    """
    ranges = axis_ranges(readings)
    cv: list[tuple[int, float]] = []
    if degree is None:
        for deg in range(1, max_degree + 1):
            trial = design(VolumetricModel(ranges, deg), readings, level, level_weight)
            cv.append((deg, cv_error(trial, folds)))
        best = min(e for _, e in cv)
        degree = next(deg for deg, e in cv if e <= best * (1.0 + 1e-6) + 1e-12)
    model = VolumetricModel(ranges, degree)
    full = design(model, readings, level, level_weight)
    sol, rank = solve(full)
    return _result("global", model, full, sol, rank, tuple(cv))


def parameter_covariance(d: Design, dispersion: float) -> FloatArray:
    """``s²·(AᵀA)⁺`` of the design's parameters (columns scaled as in :func:`solve`)."""
    scale = np.linalg.norm(d.matrix, axis=0)
    scale[scale == 0.0] = 1.0
    pinv = np.linalg.pinv(d.matrix / scale, rcond=RANK_TOL)
    return np.asarray(dispersion**2 * (pinv @ pinv.T) / np.outer(scale, scale))


def _result(method: str, model: VolumetricModel, d: Design, sol: FloatArray, rank: int,
            cv: tuple[tuple[int, float], ...]) -> Identification:
    ident = analyse(d)
    grating = np.array([k == "grating" for k in d.kinds])
    res = (d.values - d.matrix @ sol)[grating]
    dof = max(int(np.count_nonzero(grating)) - rank, 1)
    dispersion = float(np.sqrt(res @ res / dof))
    cov = parameter_covariance(d, dispersion)[:model.size, :model.size]
    functions = []
    slope_rows: list[tuple[str, FloatArray]] = []
    for k, f in enumerate(FUNCTIONS):
        sel = model.function_selector(k)
        rng = model.ranges[f.axis]
        if ident.determined(sel):
            functions.append(FunctionResult(f, rng, sel @ sol[:model.size],
                                            covariance=sel @ cov @ sel.T))
            continue
        curved = f.lowest == 1 and len(sel) > 1 and ident.determined(sel[1:])
        functions.append(FunctionResult(f, rng, None, tuple(ident.partners(k, model)),
                                        sel[1:] @ sol[:model.size] if curved else None))
        if curved:  # slope per metre of the degree-1 coefficient
            slope_rows.append((f.name, sel[0] * 2000.0 / (rng.hi - rng.lo)))
    slopes = _slopes(ident, slope_rows, sol[:model.size])
    squareness = []
    for s in reference_setups(d.setups):
        g = model.plane_squareness(s)
        value = float(g @ sol[:model.size]) if ident.determined(g) else None
        squareness.append(SquarenessResult(SQUARENESS[s.plane], s, value))
    return Identification(method, model.degree, tuple(functions), tuple(squareness), rank,
                          d.matrix.shape[1], dispersion, cv, slopes, dof)


def _slopes(ident: Identifiability, rows: list[tuple[str, FloatArray]],
            sol: FloatArray) -> tuple[SlopeCombination, ...]:
    """The determined and undetermined combinations of confounded slopes."""
    if not rows:
        return ()
    g = np.array([r for _, r in rows])
    names = [n for n, _ in rows]
    known, unknown = combinations(ident, g)
    out = [SlopeCombination(_terms(names, w), float(w @ g @ sol)) for w in known]
    out += [SlopeCombination(_terms(names, w), None) for w in unknown]
    return tuple(out)


def _terms(names: list[str], weights: FloatArray) -> tuple[tuple[str, float], ...]:
    return tuple((n, round(float(w), 6)) for n, w in zip(names, weights, strict=True)
                 if abs(w) > 1e-6)


def reference_setups(setups: Sequence[SetupKey]) -> list[SetupKey]:
    """The first setup of each plane (where its squareness is reported), XY, XZ, YZ."""
    out = []
    for plane in PLANES:
        first = next((s for s in setups if s.plane == plane), None)
        if first is not None:
            out.append(first)
    return out


# ---------------------------------------------------------------- truth, for tests


def raw_parameters(errors: ErrorModel, model: VolumetricModel) -> FloatArray:
    """The model's parameters (Legendre coefficients 0..d, squareness) of a planted error
    model; exact when its polynomials are of degree ≤ ``model.degree``."""
    raw = np.zeros(model.size)
    for k, f in enumerate(FUNCTIONS):
        def values(q: FloatArray, f: ErrorFunction = f) -> FloatArray:
            d, e = errors.axis(AXIS[f.axis]).evaluate(q, errors.scale)
            unit = 1e6 if f.angular else 1e3
            return np.asarray((e if f.angular else d)[:, f.component] * unit)

        raw[model.block(k)] = project(model.ranges[f.axis], values, model.degree)
    for pair, value in (("xy", errors.sxy), ("xz", errors.sxz), ("yz", errors.syz)):
        raw[model.squareness_column(pair)] = value * 1e6
    return raw


def truth(errors: ErrorModel, ranges: Sequence[AxisRange], setups: Sequence[SetupKey],
          degree: int = 10) -> Identification:
    """A planted error model in the reported terms (every function "determined").

    Args:
        errors: the planted model (its polynomials must be of degree ≤ ``degree``).
        ranges: axis ranges, mm.
        setups: the setups (for the squareness references).
        degree: Legendre degree of the projection.
    """
    model = VolumetricModel(ranges, degree)
    raw = raw_parameters(errors, model)
    functions = tuple(FunctionResult(f, model.ranges[f.axis],
                                     model.function_selector(k) @ raw)
                      for k, f in enumerate(FUNCTIONS))
    squareness = tuple(SquarenessResult(SQUARENESS[s.plane], s,
                                        float(model.plane_squareness(s) @ raw))
                       for s in reference_setups(setups))
    return Identification("truth", degree, functions, squareness, model.size, model.size, 0.0)
