"""``RES`` records (docs/dprnt-format.md, docs/actions.md): values a program computed."""

from __future__ import annotations

from fuzzing import examples
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from mutations import mutate

from probegen.errors import ResultsParseError
from probegen.results import parse_dprnt
from probegen.results.dprnt import Result

LOG = ("PGSTART O1003 V1\n"
       "PT BORE 1 X72.7927 Y50.0000 Z25.0000\n"
       "RES EDGE P-.3745 A.500000 NG0\n"
       "RES BORE X50.7958 Y49.6344 D50.0000 F.0000 NG0\n"
       "RES BORE T12 C.0150\n"
       "ERR OUTTOL BOSS 1\n")


def test_results_are_read_in_order() -> None:
    log = parse_dprnt(LOG, strict=True)
    assert log.results == (
        Result("EDGE", (("P", -0.3745), ("A", 0.5), ("NG", 0.0)), 3),
        Result("BORE", (("X", 50.7958), ("Y", 49.6344), ("D", 50.0), ("F", 0.0),
                        ("NG", 0.0)), 4),
        Result("BORE", (("T", 12.0), ("C", 0.015)), 5))
    assert [(e.code, e.feature) for e in log.errors] == [("OUTTOL", "BOSS")]
    assert not log.complete


def test_result_values_as_a_control_pads_them() -> None:
    log = parse_dprnt("PGSTART O1 V1\nRES B X   50.7958 Y-  .3 NG 1\nPGEND O1\n", strict=True)
    assert log.results[0].values == (("X", 50.7958), ("Y", -0.3), ("NG", 1.0))


def test_a_result_without_value_is_diagnosed() -> None:
    log = parse_dprnt("PGSTART O1 V1\nRES BORE X\nRES BORE 12\n")
    assert [d.message for d in log.diagnostics] == [
        "expected a number, found end of line",
        "expected a result name (letters), found '12'"]


@st.composite
def values(draw: st.DrawFn) -> tuple[tuple[str, float], ...]:
    keys = draw(st.lists(st.text(alphabet="ABCDEFGHIJKLMNOPQRSTUVWXYZ", min_size=1,
                                 max_size=3), min_size=1, max_size=6))
    nums = draw(st.lists(st.integers(-10**8, 10**8), min_size=len(keys), max_size=len(keys)))
    return tuple((k, n / 10**4) for k, n in zip(keys, nums, strict=True))


@settings(max_examples=examples(150), suppress_health_check=[HealthCheck.too_slow])
@given(values())
def test_printed_values_round_trip(pairs: tuple[tuple[str, float], ...]) -> None:
    line = "RES F1 " + " ".join(f"{k}{v:.4f}" for k, v in pairs)
    (res,) = parse_dprnt(f"PGSTART O1 V1\n{line}\n", strict=True).results
    assert res.values == pairs


@st.composite
def mutated(draw: st.DrawFn) -> str:
    return mutate(draw, LOG, "RES XYNG.-+0123 \n")


@settings(max_examples=examples(150), suppress_health_check=[HealthCheck.too_slow])
@given(mutated())
def test_mutated_results_never_crash(text: str) -> None:
    try:
        parse_dprnt(text, strict=True)
    except ResultsParseError as err:
        assert err.diagnostics
