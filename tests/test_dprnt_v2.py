"""DPRNT log format V2 (docs/dprnt-format.md): ``FEAT <id> <n>`` binds a feature number,
after which ``PT``/``LOC``/``ERR`` may name the feature by it, as probegen's macro
library prints them.  A V2 log reads to the records of the V1 log that names every
feature by id (only the line numbers differ); a number never bound is a located error;
the fast path and lark agree; random and mutated V2 logs end in a log or a diagnostic.
"""

from __future__ import annotations

import math

import pytest
from fuzzing import examples
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from mutations import mutate

from probegen.errors import ResultsParseError
from probegen.results import DprntLog, parse_dprnt
from probegen.results.dprnt_records import FeatureBinding

V1 = ("%\nPGSTART O1001 V1 H2DAFDB55\n"
      "LOC SPH1 1 X.0000 Y.0000 Z15.5000\n"
      "CTR SPH1 X.0000 Y.0000 Z.0000\n"
      "PT SPH1 1 X.0000 Y.0000 Z15.5000\n"
      "PT BORE7 1 X100. Y-.5 Z-20.\n"
      "PT SPH1 2 X7.7500 Y.0000 Z13.4234\n"
      "ERR NOTOUCH BORE7 2\n"
      "PGEND O1001\n%\n")
V2 = ("%\nPGSTART O1001 V2 H2DAFDB55\n"
      "FEAT SPH1 1\n"
      "LOC 1 1 X.0000 Y.0000 Z15.5000\n"
      "CTR SPH1 X.0000 Y.0000 Z.0000\n"
      "PT    1      1 X.0000 Y.0000 Z15.5000\n"
      "FEAT BORE7 2\n"
      "PT 2. 1. X100. Y-.5 Z-20.\n"
      "PT 0001 2 X7.7500 Y.0000 Z13.4234\n"
      "ERR NOTOUCH 2 2\n"
      "PGEND O1001\n%\n")


def said(log: DprntLog) -> tuple[object, ...]:
    """A log's records without their line numbers."""
    return ([(t.kind, t.feature, t.index, t.xyz, t.run) for t in log.touches],
            [(c.feature, c.xyz, c.run) for c in log.centres],
            [(e.code, e.feature, e.index, e.run) for e in log.errors],
            [(r.program, r.identity, r.complete) for r in log.runs], log.program)


@pytest.mark.parametrize("fast", [True, False])
def test_v2_reads_as_v1(fast: bool) -> None:
    v1, v2 = parse_dprnt(V1, strict=True), parse_dprnt(V2, strict=True, fast=fast)
    assert said(v2) == said(v1) and v2.complete
    assert v2.features == (FeatureBinding("SPH1", 1, 3), FeatureBinding("BORE7", 2, 7))
    assert [t.line for t in v2.touches] == [4, 6, 8, 9] and v2.errors[0].line == 10
    assert not v1.features


UNBOUND = [
    ("PT 3 1 X1 Y2 Z3", 4, "expected a feature number bound by an earlier FEAT record, "
                           "found 3 (no FEAT <id> 3 before)"),
    ("ERR COLLISION  7 2", 16, "expected a feature number bound by an earlier FEAT record, "
                               "found 7 (no FEAT <id> 7 before)"),
    ("FEAT A 0", 8, "expected a feature number from 1 to 999999, found '0'"),
    ("FEAT 1 A", 6, "expected a feature id, found '1'"),
    ("FEAT A", 7, "expected a feature number, found end of line"),
    ("PT 1.5 1 X1 Y2 Z3", 4, "expected a feature id or a feature number, found '1.5'"),
]


@pytest.mark.parametrize(("line", "column", "message"), UNBOUND)
def test_bad_v2_line_is_located(line: str, column: int, message: str) -> None:
    text = "PGSTART O1 V2\nFEAT A 1\nPT 1 1 X0 Y0 Z0\n" + line + "\nPGEND O1\n"
    for fast in (True, False):
        log = parse_dprnt(text, fast=fast)
        (diag,) = log.diagnostics
        assert (diag.line, diag.column, diag.message) == (4, column, message)
        assert [t.feature for t in log.touches] == ["A"]
    with pytest.raises(ResultsParseError, match="4:"):
        parse_dprnt(text, strict=True)


def test_a_number_is_bound_before_it_is_used() -> None:
    """A binding counts from its line on, not for the lines above it."""
    log = parse_dprnt("PGSTART O1 V2\nPT 1 1 X0 Y0 Z0\nFEAT A 1\nPT 1 2 X0 Y0 Z0\n")
    assert [(t.feature, t.index) for t in log.touches] == [("A", 2)]
    assert [d.line for d in log.diagnostics] == [2]


def test_feat_needs_v2() -> None:
    log = parse_dprnt("PGSTART O1 V1\nFEAT A 1\nPT 1 1 X0 Y0 Z0\n")
    (diag,) = log.diagnostics
    assert diag.line == 2 and diag.message == ("expected format version V2 or later for a "
                                               "FEAT record, found V1 (line 1)")
    assert [t.feature for t in log.touches] == ["A"]  # still read: one diagnostic, not many


def test_a_number_stands_for_one_feature() -> None:
    log = parse_dprnt("PGSTART O1 V2\nFEAT A 1\nFEAT A 1\nFEAT B 1\nPT 1 1 X0 Y0 Z0\n")
    (diag,) = log.diagnostics
    assert (diag.line, diag.column) == (4, 8)
    assert diag.message == "expected feature number 1 to stand for A (FEAT on line 2), found B"


def test_bindings_hold_across_a_restart() -> None:
    """A resumed program prints its bindings again; a run resumed past them still reads
    (the same program binds the same numbers)."""
    text = ("PGSTART O1 V2\nFEAT A 1\nPT 1 1 X0 Y0 Z0\nERR NOTOUCH 1 2\n"
            "PGSTART O1 V2\nPT 1 2 X0 Y0 Z1\nPGEND O1\n")
    log = parse_dprnt(text, strict=True)
    assert [(t.feature, t.index, t.run) for t in log.touches] == [("A", 1, 0), ("A", 2, 1)]
    assert log.no_contact() == {} and log.restarts == 1


# --- property tests -----------------------------------------------------------------------

FUZZ = settings(max_examples=examples(150), suppress_health_check=[HealthCheck.too_slow])
IDS = st.from_regex(r"[A-Z][A-Z0-9]{0,5}", fullmatch=True)
COORD = st.integers(-999999, 999999).map(lambda k: k / 10000.0)


@st.composite
def v2_log(draw: st.DrawFn) -> tuple[str, str]:
    """A random V2 log and the V1 log that names every feature by id."""
    ids = draw(st.lists(IDS, min_size=1, max_size=5, unique=True))
    numbers = draw(st.permutations(range(1, len(ids) + 1)))
    v1, v2 = ["PGSTART O7 V1"], ["PGSTART O7 V2"]
    for feature, number in zip(ids, numbers, strict=True):
        v2.append(f"FEAT {feature} {number}")
        pad = draw(st.sampled_from(["", " ", "   "]))  # DPRNT's leading blanks, or none
        dot = draw(st.sampled_from(["", "."]))  # and its point after a whole number
        for index in range(1, draw(st.integers(0, 4)) + 1):
            kind = draw(st.sampled_from(["PT", "LOC"]))
            x, y, z = (draw(COORD) for _ in range(3))
            xyz = f"X{x:.4f} Y{y:.4f} Z{z:.4f}"
            v1.append(f"{kind} {feature} {index} {xyz}")
            v2.append(f"{kind} {pad}{number}{dot} {pad}{index}{dot} {xyz}")
        if draw(st.booleans()):
            v1.append(f"ERR COLLISION {feature} 3")
            v2.append(f"ERR COLLISION {pad}{number}{dot} 3")
    v1.append("PGEND O7")
    v2.append("PGEND O7")
    return "\n".join(v1) + "\n", "\n".join(v2) + "\n"


@FUZZ
@given(v2_log())
def test_random_v2_log_reads_as_its_v1_log(logs: tuple[str, str]) -> None:
    v1, v2 = logs
    fast, lark = parse_dprnt(v2, strict=True), parse_dprnt(v2, fast=False, strict=True)
    assert fast == lark
    assert said(fast) == said(parse_dprnt(v1, strict=True))


@st.composite
def mutated_v2(draw: st.DrawFn) -> str:
    return mutate(draw, V2, "FEATPLOCXYZ0123456789.- \n\t%")


@FUZZ
@given(mutated_v2())
def test_mutated_v2_log_gives_records_or_diagnostics(text: str) -> None:
    """Every touch names a feature some FEAT line bound (or an id); both paths agree;
    strict reading raises exactly when there is a diagnostic."""
    log = parse_dprnt(text)
    assert log == parse_dprnt(text, fast=False)
    bound = {b.feature for b in log.features}
    for touch in log.touches:
        assert touch.feature and all(math.isfinite(v) for v in touch.xyz)
        assert touch.feature in bound or f" {touch.feature} " in text
    for diag in log.diagnostics:
        assert diag.line >= 1 and diag.column >= 1
    try:
        parse_dprnt(text, strict=True)
    except ResultsParseError as err:
        assert err.diagnostics == log.diagnostics
    else:
        assert not log.diagnostics
