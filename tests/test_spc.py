"""SPC: capability indices, control limits, run rules and the SPC table.

Capability is checked against numbers computed by hand and against a large normal sample
whose Cp, Cpk are known; the individuals chart against a textbook example; the X̄-R
constants against their definitions (integrals of the normal distribution).
"""

from __future__ import annotations

import csv
import io
import math
import statistics

import numpy as np
import pytest
from fuzzing import examples
from hypothesis import given, settings
from hypothesis import strategies as st
from spc_series import make_series

from probegen.spc import Series, capability, control_chart, spc_csv, spc_rows, spc_table
from probegen.spc.capability import MIN_VALUES
from probegen.spc.constants import CONSTANTS, D4_MR, E2
from probegen.spc.control import RUN_LENGTH, TREND_LENGTH
from probegen.spc.table import COLUMNS

# -- capability ---------------------------------------------------------------------------

HAND = [10.0, 12.0, 11.0, 13.0, 12.0, 11.0, 10.0, 12.0, 13.0, 11.0]
"""Ten values, nominal 11, limits 5 .. 17 (deviations -6 / +6)."""


def test_capability_of_a_hand_computed_example() -> None:
    # By hand: mean 115 / 10 = 11.5; moving ranges 2 1 2 1 1 1 2 1 2, MR̄ = 13 / 9;
    # σ̂ = MR̄ / 1.128 = 13 / 10.152 = 1.2805358; Cp = 12 / (6 σ̂) = 1.561846;
    # Cpk = min(17 - 11.5, 11.5 - 5) / (3 σ̂) = 5.5 / 3.8416075 = 1.431692.
    cap = capability(make_series(HAND, nominal=11.0, lower=-6.0, upper=6.0))
    assert cap.n == 10 and cap.not_evaluated == 0 and cap.out_of_tolerance == 0
    assert cap.mean == pytest.approx(11.5, abs=1e-12)
    assert cap.sigma == pytest.approx(1.2805358, rel=1e-6)
    assert cap.cp == pytest.approx(1.561846, rel=1e-6)
    assert cap.cpk == pytest.approx(1.431692, rel=1e-6)
    s = statistics.stdev(HAND)  # the overall s, n - 1, from the standard library
    assert cap.sigma_overall == pytest.approx(s, rel=1e-12)
    assert cap.pp == pytest.approx(12.0 / (6.0 * s), rel=1e-12)
    assert cap.ppk == pytest.approx(5.5 / (3.0 * s), rel=1e-12)
    assert cap.notes == ()


def test_cpk_converges_on_a_large_normal_sample() -> None:
    # μ = 10.002, σ = 0.001, limits 9.995 .. 10.005: Cp = 0.010 / 0.006 = 1.667,
    # Cpk = (10.005 - 10.002) / 0.003 = 1.000.
    rng = np.random.default_rng(20)
    x = 10.002 + 0.001 * rng.standard_normal(20000)
    cap = capability(make_series(list(x), nominal=10.0, lower=-0.005, upper=0.005))
    assert cap.cp == pytest.approx(10 / 6, rel=0.02)
    assert cap.cpk == pytest.approx(1.0, rel=0.02)
    assert cap.pp == pytest.approx(10 / 6, rel=0.02)
    assert cap.ppk == pytest.approx(1.0, rel=0.02)
    assert cap.sigma == pytest.approx(0.001, rel=0.02)


def test_one_sided_tolerances_give_cpu_or_cpl_only() -> None:
    mean, sigma = 11.5, 13 / 9 / 1.128
    upper = capability(make_series(HAND, nominal=11.0, lower=None, upper=6.0))
    assert upper.cp is None and upper.pp is None
    assert upper.cpk == pytest.approx((17.0 - mean) / (3 * sigma), rel=1e-9)
    assert any("USL only" in n for n in upper.notes)
    lower = capability(make_series(HAND, nominal=11.0, lower=-6.0, upper=None))
    assert lower.cp is None
    assert lower.cpk == pytest.approx((mean - 5.0) / (3 * sigma), rel=1e-9)
    assert any("LSL only" in n for n in lower.notes)
    none = capability(make_series(HAND, nominal=11.0, lower=None, upper=None))
    assert none.cp is None and none.cpk is None and none.sigma is not None
    assert any("not toleranced" in n for n in none.notes)


def test_a_constant_series_has_no_index_and_says_why() -> None:
    cap = capability(make_series([0.002] * 15))
    assert cap.sigma == 0.0 and cap.sigma_overall == 0.0
    assert (cap.cp, cap.cpk, cap.pp, ppk := cap.ppk) == (None, None, None, None) and ppk is None
    assert any("constant values" in n for n in cap.notes)
    assert cap.chart is not None and cap.chart.signals == ()


@pytest.mark.parametrize("count", [0, 1, 2, MIN_VALUES - 1])
def test_too_few_values_give_no_index(count: int) -> None:
    cap = capability(make_series([0.001 * k for k in range(count)] + [None, None]))
    assert cap.n == count and cap.not_evaluated == 2
    assert cap.cp is None and cap.cpk is None and cap.pp is None and cap.ppk is None
    assert (cap.sigma is None) == (count < 2) and (cap.mean is None) == (count == 0)
    assert cap.notes


def test_not_evaluated_values_are_left_out_and_counted() -> None:
    with_gaps = make_series([*HAND[:4], None, *HAND[4:], None], nominal=11.0, lower=-6.0,
                            upper=6.0)
    cap, ref = capability(with_gaps), capability(make_series(HAND, nominal=11.0, lower=-6.0,
                                                             upper=6.0))
    assert cap.not_evaluated == 2 and cap.n == 10
    assert (cap.mean, cap.sigma, cap.cp, cap.cpk) == (ref.mean, ref.sigma, ref.cp, ref.cpk)


def test_uncertainty_ratio_is_reported_and_flagged() -> None:
    small = capability(make_series(HAND, nominal=11.0, lower=-6.0, upper=6.0, u=0.1))
    assert small.u_mean == pytest.approx(0.1)
    assert small.u_ratio == pytest.approx(0.1 / (13 / 9 / 1.128))
    assert not any("uncertainty" in n for n in small.notes)
    big = capability(make_series(HAND, nominal=11.0, lower=-6.0, upper=6.0, u=0.8))
    assert big.u_ratio is not None and big.u_ratio > 0.3
    assert any("uncertainty" in n for n in big.notes)


def test_out_of_tolerance_values_are_counted() -> None:
    cap = capability(make_series([0.0, 0.011, -0.02, 0.01, -0.01]))
    assert cap.out_of_tolerance == 2


# -- control charts -----------------------------------------------------------------------

MONTGOMERY = [310, 288, 297, 298, 307, 303, 294, 297, 308, 306,
              294, 299, 297, 299, 314, 295, 293, 306, 301, 304]
"""Montgomery, Introduction to Statistical Quality Control (6th ed.), Example 6.5,
Table 6.6: the cost of processing mortgage loan applications, 20 weeks (typed in).
The book's individuals chart: x̄ = 300.5, MR̄ = 7.79, UCL = 321.22, LCL = 279.78;
moving range chart UCL = 25.45; the process is in control."""


def test_individuals_chart_on_montgomery_example() -> None:
    chart = control_chart(make_series([float(v) for v in MONTGOMERY], lower=None, upper=None))
    assert chart is not None and chart.kind == "I-MR" and chart.subgroup_size == 1
    assert chart.centre == pytest.approx(300.5, abs=1e-9)
    assert chart.range_centre == pytest.approx(7.79, abs=0.005)
    assert chart.ucl == pytest.approx(321.22, abs=0.005)
    assert chart.lcl == pytest.approx(279.78, abs=0.005)
    assert chart.range_ucl == pytest.approx(25.45, abs=0.005)
    assert chart.range_lcl == 0.0
    assert len(chart.ranges) == 19 and chart.signals == ()
    assert (E2, D4_MR) == (2.66, 3.267)


def _d2(n: int) -> float:
    """Mean range of n standard normal values: ∫ 1 − Φ(x)^n − (1 − Φ(x))^n dx."""
    x = np.linspace(-12.0, 12.0, 48001)
    phi = 0.5 * (1.0 + np.array([math.erf(v / math.sqrt(2.0)) for v in x]))
    f = 1.0 - phi ** n - (1.0 - phi) ** n
    return float(np.sum((f[1:] + f[:-1]) / 2.0 * np.diff(x)))


def _c4(n: int) -> float:
    return math.sqrt(2.0 / (n - 1)) * math.exp(math.lgamma(n / 2) - math.lgamma((n - 1) / 2))


@pytest.mark.parametrize("n", range(2, 11))
def test_subgroup_constants_follow_their_definitions(n: int) -> None:
    k = CONSTANTS[n]
    assert k.d2 == pytest.approx(_d2(n), abs=0.0006)
    assert k.c4 == pytest.approx(_c4(n), abs=0.00006)
    assert k.a2 == pytest.approx(3.0 / (_d2(n) * math.sqrt(n)), abs=0.0006)
    # D4 = 1 + 3 d3/d2 and D3 = max(0, 1 - 3 d3/d2): symmetric about 1 until D3 clips at 0
    assert (k.d3 + k.d4 == pytest.approx(2.0, abs=1e-9)) if k.d3 > 0 else k.d4 >= 2.0 - 1e-9
    assert (k.d3 > 0) == (n >= 7)


def test_xbar_r_chart_of_equal_subgroups() -> None:
    # Three subgroups of 4: means 2.5, 3.5, 2.0 (X̿ = 8/3), ranges 3, 2, 4 (R̄ = 3);
    # A2(4) = 0.729, D4(4) = 2.282, D3 = 0, d2(4) = 2.059.
    values = [1.0, 4.0, 2.0, 3.0, 3.0, 4.0, 3.0, 4.0 - 0.0, 0.0, 2.0, 4.0, 2.0]
    values[7] = 4.0
    groups = [g for g in "AAAABBBBCCCC"]
    chart = control_chart(make_series(values, subgroups=groups))
    assert chart is not None and chart.kind == "Xbar-R" and chart.subgroup_size == 4
    assert [p.value for p in chart.points] == [2.5, 3.5, 2.0]
    assert chart.ranges == (3.0, 1.0, 4.0)
    r_bar = 8.0 / 3.0
    assert chart.centre == pytest.approx(8.0 / 3.0)
    assert chart.ucl == pytest.approx(8.0 / 3.0 + 0.729 * r_bar)
    assert chart.lcl == pytest.approx(8.0 / 3.0 - 0.729 * r_bar)
    assert chart.range_ucl == pytest.approx(2.282 * r_bar) and chart.range_lcl == 0.0
    assert chart.sigma == pytest.approx(r_bar / 2.059)
    assert chart.points[1].runs == ("r05", "r06", "r07", "r08")
    assert chart.points[0].x == pytest.approx(2.5)


@pytest.mark.parametrize("groups, note", [
    ("AAABBC", "unequal size"),
    ("AAABB" + "-", "without subgroup"),
    ("AAAAAA", "single subgroup"),
    ("ABCDEF", ""),
])
def test_subgroups_that_cannot_make_an_xbar_r_chart_fall_back_to_individuals(
        groups: str, note: str) -> None:
    subgroups = [None if g == "-" else g for g in groups]
    chart = control_chart(make_series([0.001, 0.002, 0.0, 0.001, 0.003, 0.002],
                                      subgroups=subgroups))
    assert chart is not None and chart.kind == "I-MR" and len(chart.points) == 6
    assert (note in chart.note) if note else chart.note == ""


def test_a_not_evaluated_value_makes_its_subgroup_unequal() -> None:
    values = [0.001, 0.002, 0.0, None, 0.001, 0.003, 0.002, 0.0]
    chart = control_chart(make_series(values, subgroups=list("AAAABBBB")))
    assert chart is not None and chart.kind == "I-MR" and "unequal" in chart.note


# -- run rules ----------------------------------------------------------------------------

def _noise(count: int, seed: int) -> list[float]:
    return list(0.001 * np.random.default_rng(seed).standard_normal(count))


def _rules(values: list[float | None]) -> dict[str, list[tuple[str, ...]]]:
    chart = control_chart(make_series(values))
    assert chart is not None
    out: dict[str, list[tuple[str, ...]]] = {}
    for s in chart.signals:
        out.setdefault(s.rule, []).append(s.runs)
    return out


def test_a_planted_outlier_is_beyond_the_limits_and_named() -> None:
    values: list[float | None] = list(_noise(30, 1))
    values[17] = 0.009
    rules = _rules(values)
    assert rules["beyond"] == [("r18",)]
    assert ("r17", "r18") in rules["range"] or ("r18", "r19") in rules["range"]


def test_a_planted_drift_shows_as_trend_and_run() -> None:
    # 15 stationary values, then a drift of 0.4 σ per run for 15 runs.
    values: list[float | None] = [*_noise(15, 2),
                                  *(0.0004 * k + 0.0001 * e for k, e in
                                    enumerate(np.random.default_rng(3).standard_normal(15), 1))]
    rules = _rules(values)
    assert "trend" in rules and "run" in rules
    drifting = {f"r{k:02d}" for k in range(16, 31)}
    assert all(set(runs) <= drifting | {"r15"} for runs in rules["trend"])
    assert any(len(runs) >= RUN_LENGTH and set(runs) <= drifting for runs in rules["run"])


def test_rule_lengths_are_exact() -> None:
    base = [0.001, -0.001] * 6  # alternating about the centre: no run, no trend
    above = [0.0005] * RUN_LENGTH
    assert "run" not in _rules([*base, *above[:-1], -0.001, *base])
    hit = _rules([*base, *above, -0.001, *base])["run"]
    assert hit == [tuple(f"r{k:02d}" for k in range(13, 13 + RUN_LENGTH))]
    rising = [0.0001 * k for k in range(TREND_LENGTH)]
    high = base[::-1]  # ends high, so the rise starts at the first point of ``rising``
    assert "trend" not in _rules([*high, *rising[:-1], *high])
    assert _rules([*high, *rising, *high])["trend"] == [
        tuple(f"r{k:02d}" for k in range(13, 13 + TREND_LENGTH))]
    assert "trend" not in _rules([*base, *rising[:0:-1], *base])
    assert _rules([*base, *rising[::-1], *base])["trend"] == [
        tuple(f"r{k:02d}" for k in range(13, 13 + TREND_LENGTH))]


def test_a_stationary_series_gives_no_signal() -> None:
    chart = control_chart(make_series(_noise(40, 7)))
    assert chart is not None and chart.signals == ()


def test_false_alarms_on_stationary_series_are_rare() -> None:
    charts = [control_chart(make_series(_noise(30, seed))) for seed in range(100, 300)]
    rate = {rule: sum(1 for c in charts if c is not None and any(s.rule == rule
                                                                 for s in c.signals)) / 200
            for rule in ("beyond", "range", "run", "trend")}
    # Chance of at least one hit in 30 stationary values, about: beyond 1 - 0.9973^30 = 8 %,
    # range (29 moving ranges above 3.267 MR̄, 0.9 % each) 23 %, run and trend a few %.
    # A wrong constant or an off-by-one run length pushes these far above the bounds.
    assert rate["beyond"] < 0.16 and rate["range"] < 0.4
    assert rate["run"] < 0.12 and rate["trend"] < 0.12
    assert rate["beyond"] > 0.0 and rate["range"] > 0.0  # the limits are not too wide either


# -- the table ----------------------------------------------------------------------------

def _history() -> list[Series]:
    drift = [*_noise(15, 2), *(0.0004 * k for k in range(1, 16))]
    return [make_series(HAND, nominal=11.0, lower=-6.0, upper=6.0, u=0.05),
            make_series(drift, feature="BORE", characteristic="X", lower=None, upper=0.01),
            make_series([None, 0.001], feature="FACE", characteristic="P")]


def test_csv_header_and_rows() -> None:
    text = spc_csv(_history())
    assert text.startswith("feature,characteristic,n,mean,sigma,cp,cpk,")
    rows = list(csv.DictReader(io.StringIO(text)))
    assert list(rows[0]) == list(COLUMNS)
    assert [(r["feature"], r["characteristic"]) for r in rows] == [
        ("BORE", "D"), ("BORE", "X"), ("FACE", "P")]
    first = rows[0]
    assert (first["n"], first["mean"], first["sigma"], first["cp"], first["cpk"]) == (
        "10", "11.500000", "1.280536", "1.562", "1.432")
    assert first["lsl"] == "5.000000" and first["usl"] == "17.000000"
    assert first["chart"] == "I-MR" and first["not_evaluated"] == "0"
    assert rows[1]["cp"] == "" and rows[1]["cpk"] != "" and "trend" in rows[1]["signals"]
    assert rows[2]["n"] == "1" and rows[2]["sigma"] == "" and rows[2]["not_evaluated"] == "1"
    assert text == spc_csv(_history())  # the same bytes again
    assert text.isascii() and "\r" not in text


def test_terminal_table() -> None:
    text = spc_table(_history())
    lines = text.splitlines()
    assert lines[0].split() == ["part", "feature", "characteristic", "n", "mean", "sigma",
                                "cp", "cpk", "pp", "ppk", "chart", "signals"]
    assert lines[1].split()[:8] == ["P-100", "BORE", "D", "10", "11.500000", "1.280536",
                                    "1.562", "1.432"]
    assert any(line.startswith("FACE.P: 1 evaluated value") for line in lines)
    assert spc_table([]) .endswith("(no characteristic)\n")


def test_rows_keep_the_order_given() -> None:
    series = _history()[::-1]
    assert [r.series for r in spc_rows(series)] == series


# -- never an exception ---------------------------------------------------------------------

FINITE = st.floats(allow_nan=False, allow_infinity=False)
MEASURED = st.one_of(st.none(), FINITE, st.floats(-1e3, 1e3), st.sampled_from([0.0, 1e-300]))


@settings(max_examples=examples(300))
@given(values=st.lists(MEASURED, max_size=40),
       lower=st.one_of(st.none(), FINITE), upper=st.one_of(st.none(), FINITE),
       nominal=FINITE, u=st.one_of(st.none(), st.floats(0, 1e300)),
       subgroups=st.lists(st.one_of(st.none(), st.sampled_from("AB")), max_size=40))
def test_any_series_ends_in_a_result(values: list[float | None], lower: float | None,
                                     upper: float | None, nominal: float, u: float | None,
                                     subgroups: list[str | None]) -> None:
    groups = (subgroups * (len(values) // max(len(subgroups), 1) + 1))[:len(values)] \
        if subgroups else None
    series = make_series(values, lower=lower, upper=upper, nominal=nominal, u=u,
                         subgroups=groups)
    cap = capability(series)
    assert cap.n + cap.not_evaluated == len(values)
    for value in (cap.mean, cap.sigma, cap.sigma_overall, cap.cp, cap.cpk, cap.pp, cap.ppk,
                  cap.u_mean, cap.u_ratio):
        assert value is None or math.isfinite(value)
    if cap.sigma is not None:
        assert cap.sigma >= 0.0
    text = spc_csv([series])
    assert len(list(csv.reader(io.StringIO(text)))) == 2
    assert spc_table([series])


def test_thirty_drifting_runs_agree_with_an_independent_computation() -> None:
    # 30 runs of a bore, nominal 25, ±0.008: noise σ = 1 µm and a drift of 0.3 µm per run.
    rng = np.random.default_rng(30)
    x = 25.0 + 0.001 * rng.standard_normal(30) + 0.0003 * np.arange(30)
    row = next(csv.DictReader(io.StringIO(spc_csv(
        [make_series(list(x), nominal=25.0, lower=-0.008, upper=0.008)]))))
    mean = sum(x) / 30
    sigma = sum(abs(b - a) for a, b in zip(x[:-1], x[1:], strict=True)) / 29 / 1.128
    cpk = min(25.008 - mean, mean - 24.992) / (3 * sigma)
    assert float(row["mean"]) == pytest.approx(mean, abs=5e-7)
    assert float(row["sigma"]) == pytest.approx(sigma, abs=5e-7)
    assert float(row["cp"]) == pytest.approx(0.016 / (6 * sigma), abs=5e-4)
    assert float(row["cpk"]) == pytest.approx(cpk, abs=5e-4)
    assert float(row["ppk"]) < float(row["cpk"])  # the drift widens the overall spread
    assert "trend" in row["signals"] or "run" in row["signals"]
