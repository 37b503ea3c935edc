"""Legendre series on an axis range: projection, fits, cross-validated degree."""

from __future__ import annotations

import numpy as np
import pytest

from probegen.errors import CalibrationError
from probegen.geometry.orthopoly import AxisRange, basis, evaluate, fit, fit_cv, project, rms

RNG = AxisRange(-50.0, 150.0)


def test_project_recovers_legendre_coefficients() -> None:
    coefficients = np.array([0.5, -1.0, 2.0, 0.25])
    found = project(RNG, lambda q: evaluate(RNG, q, coefficients), 6)
    assert np.allclose(found, np.r_[coefficients, 0.0, 0.0, 0.0], atol=1e-12)


def test_degree_one_coefficient_is_the_least_squares_slope() -> None:
    q = np.linspace(RNG.lo, RNG.hi, 2001)
    f = 0.01 * q + 1e-5 * (q - 30.0) ** 3
    c = fit(RNG, q, f, 0, 3).coefficients
    slope = np.polyfit(q, f, 1)[0]
    assert 2.0 * c[1] / (RNG.hi - RNG.lo) == pytest.approx(slope, rel=1e-3)


def test_rms_is_the_rms_over_the_range() -> None:
    c = np.array([0.3, -0.7, 1.1])
    q = np.linspace(RNG.lo, RNG.hi, 200001)
    assert rms(RNG, c, 1) == pytest.approx(np.sqrt(np.mean(evaluate(RNG, q, c, 1) ** 2)),
                                           rel=1e-4)


def test_fit_reports_from_lowest_and_frees_the_reference_line() -> None:
    q = np.linspace(RNG.lo, RNG.hi, 21)
    straight = 3.0 + 0.02 * q  # a line only: nothing about its reference line remains
    bow = fit(RNG, q, straight + evaluate(RNG, q, [0.8], 2), 2, 3)
    assert bow.coefficients == pytest.approx([0.8, 0.0], abs=1e-12)


def test_cross_validation_picks_the_planted_degree() -> None:
    rng = np.random.default_rng(5)
    q = np.linspace(RNG.lo, RNG.hi, 41)
    truth = evaluate(RNG, q, [1.0, -2.0, 1.5, 0.8], 1)
    chosen = fit_cv(RNG, q, truth + rng.normal(0.0, 0.02, len(q)), 1, 8)
    assert 4 <= chosen.degree <= 6  # never below the planted degree; noise may add one
    assert chosen.coefficients[:4] == pytest.approx([1.0, -2.0, 1.5, 0.8], abs=0.03)
    assert chosen.cv_rms == pytest.approx(0.02, rel=0.5)


def test_too_few_samples_is_a_calibration_error() -> None:
    with pytest.raises(CalibrationError, match="expected at least"):
        fit(RNG, [0.0, 1.0], [0.0, 1.0], 1, 3)
    with pytest.raises(CalibrationError, match="cross-validation"):
        fit_cv(RNG, [0.0, 1.0, 2.0], [0.0, 1.0, 2.0], 2, 4)


def test_basis_columns_follow_the_degrees() -> None:
    b = basis(RNG, [RNG.lo, RNG.hi], [0, 1, 2])
    assert b.tolist() == [[1.0, -1.0, 1.0], [1.0, 1.0, 1.0]]
