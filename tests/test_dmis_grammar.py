"""The DMIS grammar: real NIST files, hand-written samples, round trips, exact errors, fuzzing."""

from __future__ import annotations

from collections import Counter
from pathlib import Path

import pytest
from fuzzing import examples
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from probegen.dmis.reader import (
    LABEL_KINDS,
    Call,
    DmisFile,
    Expr,
    Group,
    Label,
    Param,
    Statement,
    Text,
    format_param,
    format_statement,
    parse_dmis,
    read_dmis,
)
from probegen.errors import ProgramParseError

TESTS = Path(__file__).resolve().parent
REF = Path(__file__).resolve().parents[2] / "shared" / "ref" / "nist-ippdme"
IMTS = REF / "DCXpart" / "DMIS" / "IMTS_M_clean.dmi"
SIMPLE_IN = REF / "IPlusSimplePart" / "DMIS" / "simple_in.dms"
SIMPLE_OUT = REF / "IPlusSimplePart" / "DMIS" / "output.dms"
NIST = (IMTS, SIMPLE_IN, SIMPLE_OUT)
SAMPLES = tuple(sorted((TESTS / "data" / "dmis").glob("*.dmi")))

needs_nist = pytest.mark.skipif(not IMTS.is_file(), reason="NIST reference files not present")


def majors(dmis: DmisFile) -> Counter[str]:
    return Counter(s.major for s in dmis.statements)


def only(dmis: DmisFile, label: Label) -> Statement:
    (found,) = [s for s in dmis.statements if s.label == label]
    return found


def error_of(text: str, source: str = "t.dmi") -> str:
    with pytest.raises(ProgramParseError) as info:
        parse_dmis(text, source=source)
    return str(info.value)


def shape(dmis: DmisFile) -> list[tuple[int, Label | None, str, tuple[Param, ...]]]:
    return [(s.line, s.label, s.major, s.params) for s in dmis.statements]


# --- NIST files ---------------------------------------------------------------------------


@needs_nist
def test_imts_program_statement_counts() -> None:
    dmis = read_dmis(IMTS)
    assert dmis.source == str(IMTS)
    assert len(dmis.statements) == 111
    counts = majors(dmis)
    assert counts["PTMEAS"] == 28
    assert counts["GOTO"] == 15
    assert (counts["FEAT"], counts["TOL"], counts["OUTPUT"]) == (7, 7, 7)
    assert counts["MEAS"] == counts["ENDMES"] == 5
    assert counts["TRANS"] == 7 and counts["DATDEF"] == 4


@needs_nist
def test_imts_program_header_and_end() -> None:
    dmis = read_dmis(IMTS)
    first, last = dmis.statements[0], dmis.statements[-1]
    assert (first.line, first.major, first.params) == (
        16,
        "DMISMN",
        (Text("IMTS_M_clean.dmi"), 4.0),
    )
    assert (last.line, last.major, last.params) == (150, "ENDFIL", ())  # no final newline
    assert len(dmis.comments) == 14
    assert dmis.comments[0] == (1, "This file assumes that the positive Z axis of the machine is")


@needs_nist
def test_imts_program_each_meas_block_has_its_declared_point_count() -> None:
    blocks: list[tuple[Label, int, int]] = []
    for s in read_dmis(IMTS).statements:
        if s.major == "MEAS":
            kind, feature, count = s.params
            assert isinstance(feature, Label) and isinstance(count, int)
            blocks.append((feature, count, 0))
        elif s.major == "PTMEAS":
            feature, count, seen = blocks[-1]
            blocks[-1] = (feature, count, seen + 1)
    assert [(f.name, n) for f, n, _ in blocks] == [
        ("PLN1", 4),
        ("PLN2", 4),
        ("PLN3", 4),
        ("CYL1", 8),
        ("CYL2", 8),
    ]
    assert all(n == seen for _, n, seen in blocks)


@needs_nist
def test_imts_program_parameters() -> None:
    dmis = read_dmis(IMTS)
    cyl = only(dmis, Label("F", "CYL1"))
    assert cyl.params == ("CYLNDR", "INNER", "CART", 0.0, 0.0, 26.0, 0.0, 0.0, -1.0, 31.0, 12.0)
    tol = only(dmis, Label("T", "TOL2"))
    assert tol.params == (
        "POS",
        "3D",
        0.1,
        "RFS",
        Label("DAT", "A"),
        Label("DAT", "B"),
        Label("DAT", "C"),
    )
    probe = only(dmis, Label("S", "PROBE6"))
    assert probe.params[-2:] == (50, 4.0) and isinstance(probe.params[-2], int)
    device = only(dmis, Label("DID", "OUTFILE"))
    assert device.params == ("STOR", Text("C:\\imts.dmo"))
    assert only(dmis, Label("D", "CALN1_A")).text == "D(CALN1_a)=DATSET/DAT(CALN1A),ZDIR"
    outputs = [s.params for s in dmis.statements if s.major == "OUTPUT"]
    assert outputs[0] == (Label("FA", "PLN1"), Label("TA", "TOL1"))


@needs_nist
def test_imts_program_continuation_line() -> None:
    dmis = read_dmis(IMTS)
    line = only(dmis, Label("F", "CLIN1"))
    assert line.line == 86
    assert line.params == ("LINE", "UNBND", "CART", 0.0, -52.0, 30.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0)
    assert line.text == (
        "F(CLIN1)=FEAT/LINE,UNBND,CART,0.000,-52.000,30.000,1.000,0.000,0.000, 0.000,0.000,1.000"
    )
    after = dmis.statements[dmis.statements.index(line) + 1]
    assert (after.line, after.major) == (88, "CONST")


@needs_nist
def test_simple_program() -> None:
    dmis = read_dmis(SIMPLE_IN)
    assert dmis.statements[0].params == (Text("IPP SIMPLE DMIS program"),)
    assert len(dmis.statements) == 24 and len(dmis.comments) == 9
    assert majors(dmis)["PTMEAS"] == 4 and majors(dmis)["GOTO"] == 5
    circle = only(dmis, Label("F", "A_CIRCLE"))
    assert (circle.line, circle.major) == (22, "FEAT")
    assert circle.params == ("CIRCLE", "INNER", "CART", 50.0, 50.0, 40.0, 0.0, 0.0, 1.0, 50.0)
    ptmeas = [s.params for s in dmis.statements if s.major == "PTMEAS"]
    assert ptmeas[2] == ("CART", 50.0, 75.0, 40.0, 0.0, -1.0, 0.0)
    assert only(dmis, Label("S", "PROBE6")).params[:3] == ("PROBE", "FIXED", "CART")
    assert (dmis.statements[-1].major, dmis.statements[-1].line) == ("ENDFIL", 33)


@needs_nist
def test_simple_output_file() -> None:
    dmis = read_dmis(SIMPLE_OUT)
    assert [s.major for s in dmis.statements] == [
        "FILNAM",
        "UNITS",
        "DATSET",
        "OUTPUT",
        "FEAT",
        "ENDFIL",
    ]
    actual = only(dmis, Label("FA", "A_CIRCLE"))
    assert actual.line == 5
    assert actual.params == ("CIRCLE", "INNER", "CART", 50.0, 50.0, 40.0, 0.0, 0.0, 1.0, 50.0)
    assert actual.text == (
        "FA(A_CIRCLE) = FEAT/CIRCLE, INNER, CART,  50.00000, 50.00000, 40.00000, "
        "0.00000, 0.00000, 1.00000, 50.00000"
    )
    assert dmis.statements[-1].line == 7


@needs_nist
@pytest.mark.parametrize("path", NIST, ids=lambda p: p.name)
def test_line_ends_do_not_matter(path: Path) -> None:
    text = path.read_text()
    lf = parse_dmis(text)
    for variant in (text.replace("\n", "\r\n"), text.replace("\n", "\r"), "\ufeff" + text):
        other = parse_dmis(variant)
        assert shape(other) == shape(lf)
        assert [s.text for s in other.statements] == [s.text for s in lf.statements]
        assert other.comments == lf.comments


# --- hand-written samples -----------------------------------------------------------------


def test_emitter_shaped_program() -> None:
    dmis = read_dmis(TESTS / "data" / "dmis" / "sphere_test.dmi")
    first = dmis.statements[0]
    assert (first.major, first.params) == ("DMISMN", (Text("SPHERE TEST"), 5.0))
    assert only(dmis, Label("S", "PRB1")).params == (
        "PROBE",
        "INDEX",
        "CART",
        0,
        0,
        0,
        0,
        0,
        1,
        6.0,
    )
    assert [s.params for s in dmis.statements if s.major == "SNSET"] == [
        ("APPRCH", 2.5),
        ("RETRCT", 2.5),
        ("SEARCH", 4.0),
    ]
    meas = next(s for s in dmis.statements if s.major == "MEAS")
    assert meas.params == ("SPHERE", Label("F", "SPH1"), 5)
    assert majors(dmis)["PTMEAS"] == 5
    assert dmis.comments == (
        (2, "probegen M1 probe qualification: 5 points on the reference sphere"),
    )
    assert dmis.statements[-1].major == "ENDFIL"


def test_dmis5_expressions_and_flow_control() -> None:
    dmis = read_dmis(TESTS / "data" / "dmis" / "dmis5_flow.dmi")
    by_line = {s.line: s for s in dmis.statements}
    assert by_line[2].major == "DMISMN" and by_line[2].params == (Text("flow sample"), 5.2)
    assert by_line[3].params == ("LOCAL", "DOUBLE", "V1", Expr("[]", ("RAD", 4)))
    power = Expr("**", (Group((Expr("-", (Expr("[]", ("RAD", 2)), 0.5)),)), 2))
    assert by_line[5].params == (Expr("=", ("V1", Expr("+", (-25.0, Expr("*", (3, power)))))),)
    assert by_line[6].params == (Expr("=", ("NAME", Text("it's"))),)
    condition = Expr(
        ".AND.",
        (Group((Expr(".GE.", ("V1", 0)),)), Expr(".NOT.", (Group((Expr(".EQ.", ("V1", 1.0)),)),))),
    )
    assert by_line[7].params == (Group((condition,)),)
    point = by_line[8]
    assert point.label == Label("F", "P[1]") and point.params[2:4] == (1000.0, -1.0)
    assert by_line[9].params == ("POS", "3D", 0.05, "MMC", Label("DAT", "A"))
    assert by_line[10].major == "ELSE" and by_line[10].params == ()
    assert by_line[11].params == ("OPER", Text("negative: "), Call("STR", ("V1",)))
    assert by_line[11].text == "TEXT/OPER,'negative: ',STR(V1)"
    write = by_line[14].params
    assert write[1] == Expr(":", ("V1", 8, 3))
    assert write[2] == Call("SQRT", (Call("ABS", ("V1",)),))
    assert dmis.comments == (
        (1, "DMIS 5 variables, expressions and flow control (hand-written sample)"),
        (8, "indexed label"),
    )
    assert point.text == "F(P[1])=FEAT/POINT,CART,1e3,-1.,0,0,0,1"


@pytest.mark.parametrize(
    ("written", "value"),
    [
        ("4", 4),
        ("-1.", -1.0),
        (".5", 0.5),
        ("1.0E-3", 0.001),
        ("1e3", 1000.0),
        ("+15.000", 15.0),
        ("05.0", 5.0),
        ("-0", 0),
        ("1.E2", 100.0),
    ],
)
def test_numbers(written: str, value: float) -> None:
    (param,) = parse_dmis(f"SNSET/{written}").statements[0].params
    assert param == value and type(param) is type(value)


def test_lower_case_is_upper_cased_but_text_is_kept() -> None:
    (s,) = parse_dmis("f(c1)=feat/circle,inner,cart,1,2,3,0,0,1,10 $$ Bore\n").statements
    assert (s.label, s.major, s.params[:2]) == (Label("F", "C1"), "FEAT", ("CIRCLE", "INNER"))
    assert s.text == "f(c1)=feat/circle,inner,cart,1,2,3,0,0,1,10"
    assert parse_dmis("TEXT/OPER,'Mixed Case'").statements[0].params[1] == Text("Mixed Case")


def test_blank_lines_comments_and_empty_input() -> None:
    dmis = parse_dmis("\n\n  $$ one\n\t\nENDMES $$two\n$$\n")
    assert shape(dmis) == [(5, None, "ENDMES", ())]
    assert dmis.comments == ((3, "one"), (5, "two"), (6, ""))
    assert parse_dmis("") == DmisFile("<string>", (), ())


def test_quoted_string_may_hold_dollars_and_quotes() -> None:
    (s,) = parse_dmis("TEXT/OPER,'cost $$ 5, it''s $'\n").statements
    assert s.params == ("OPER", Text("cost $$ 5, it's $"))
    assert str(s.params[1]) == "'cost $$ 5, it''s $'"


def test_read_dmis_latin1_file(tmp_path: Path) -> None:
    path = tmp_path / "latin1.dmi"
    path.write_bytes("TEXT/OPER,'\u00d8 10 \u00b5m'\r\n".encode("latin-1"))
    assert read_dmis(path).statements[0].params[1] == Text("\u00d8 10 \u00b5m")


# --- round trip -----------------------------------------------------------------------------


@pytest.mark.parametrize(
    "path", [p for p in (*NIST, *SAMPLES) if p.is_file()], ids=lambda p: p.name
)
def test_round_trip_of_files(path: Path) -> None:
    dmis = read_dmis(path)
    again = parse_dmis("\n".join(format_statement(s) for s in dmis.statements))
    assert [(s.label, s.major, s.params) for s in again.statements] == [
        (s.label, s.major, s.params) for s in dmis.statements
    ]


def test_format_statement_is_canonical() -> None:
    (s,) = parse_dmis("f(c1) = FEAT/circle, INNER ,CART,+1.50,2,3, $\n 0,0,1 , 1e1").statements
    assert format_statement(s) == "F(C1)=FEAT/CIRCLE,INNER,CART,1.5,2,3,0,0,1,10.0"
    assert format_param(Expr("-", (Group((Expr("+", ("A", 1)),)),))) == "-(A + 1)"


WORDS = st.from_regex(r"[A-Z_][A-Z0-9_]{0,7}", fullmatch=True)
LABELS = st.builds(Label, st.sampled_from(sorted(LABEL_KINDS)), WORDS | st.integers(0, 99).map(str))
LEAVES = (
    st.integers(-(10**12), 10**12)
    | st.floats(allow_nan=False, width=64)
    | WORDS
    | st.builds(Text, st.text(st.characters(blacklist_characters="\r\n"), max_size=12))
    | LABELS
)
PARAMS = st.recursive(
    LEAVES,
    lambda inner: (
        st.builds(Group, st.lists(inner, min_size=1, max_size=3).map(tuple))
        | st.builds(
            Call,
            WORDS.filter(lambda w: w not in LABEL_KINDS),
            st.lists(inner, max_size=3).map(tuple),
        )
    ),
    max_leaves=8,
)


@settings(max_examples=examples(150))
@given(st.lists(PARAMS, max_size=6).map(tuple), st.none() | LABELS)
def test_round_trip_property(params: tuple[Param, ...], label: Label | None) -> None:
    statement = Statement(1, label, "ANY", params, "")
    (again,) = parse_dmis(format_statement(statement)).statements
    assert (again.label, again.major, again.params) == (label, "ANY", params)


# --- errors ---------------------------------------------------------------------------------

OPERAND = "a number, a word, a quoted string, '(', a sign or '.NOT.'"


@pytest.mark.parametrize(
    ("text", "message"),
    [
        (
            "UNITS/MM,ANGDEC\nGOTO/1,2,3 4\n",
            "t.dmi:2:12: expected ',', an operator, a '$$' comment or end of line,"
            " found the number 4\n    GOTO/1,2,3 4\n               ^",
        ),
        (
            "F(C1)=FEAT/CIRCLE,INNER,CART,$\n  1,2,,3\n",
            f"t.dmi:2:7: expected {OPERAND}, found ','\n      1,2,,3\n          ^",
        ),
        (
            "TEXT/OPER,'not closed\n",
            f"t.dmi:1:11: expected {OPERAND}, found a quote that is not closed on its line\n"
            "    TEXT/OPER,'not closed\n              ^",
        ),
        (
            "GOTO/1,$ 2\n",
            f"t.dmi:1:8: expected {OPERAND}, found '$' (a '$' continues a statement only at"
            " the end of a line)\n    GOTO/1,$ 2\n           ^",
        ),
        (
            "ENDMES\nGOTO/1,2,$\n",
            f"t.dmi:2:11: expected {OPERAND}, found end of file\n    GOTO/1,2,$\n              ^",
        ),
        (
            "F(C1)=\n",
            "t.dmi:1:7: expected a word, found end of line\n    F(C1)=\n          ^",
        ),
        (
            "\tMEAS/CIRCLE,F(C1) 4\r\n",
            "t.dmi:1:20: expected ',', an operator, a '$$' comment or end of line,"
            " found the number 4\n    \tMEAS/CIRCLE,F(C1) 4\n    \t                  ^",
        ),
        (
            "GOTO\n/1,2,3\n",
            "t.dmi:2:1: expected a word, '(', a '$$' comment, end of line or end of file, found '/'"
            "\n    /1,2,3\n    ^",
        ),
        (
            "OUTPUT/FA(C1)?\n",
            "t.dmi:1:14: expected ',', an operator, a '$$' comment or end of line, found '?'"
            "\n    OUTPUT/FA(C1)?\n                 ^",
        ),
    ],
)
def test_error_messages(text: str, message: str) -> None:
    assert error_of(text) == message


def test_error_carries_a_diagnostic() -> None:
    with pytest.raises(ProgramParseError) as info:
        parse_dmis("A/1\nB/(2\n", source="prog.dmi")
    (diag,) = info.value.diagnostics
    assert (diag.source, diag.line, diag.column, diag.text) == ("prog.dmi", 2, 5, "B/(2")
    assert diag.message == "expected ',' or ')', found end of line"


def test_deep_nesting_is_refused_not_recursed() -> None:
    text = "ENDMES\nASSIGN/V1=" + "(" * 150 + "1" + ")" * 150
    assert error_of(text).splitlines()[0] == (
        "t.dmi:2:1: expected parameters nested at most 100 deep, found deeper nesting"
    )
    assert error_of("A/1" + "+1" * 5000).startswith("t.dmi:1:1: expected parameters nested")
    assert parse_dmis("A/" + "(" * 99 + "1" + ")" * 99).statements[0].major == "A"


def test_label_names_may_be_numbers_or_indexed() -> None:
    (s,) = parse_dmis("F(p[1,j])=FEAT/POINT,F(12),F(P[1,J]),F(P[-1]),F(A,B)").statements
    assert s.label == Label("F", "P[1,J]")
    assert s.params[1:3] == (Label("F", "12"), Label("F", "P[1,J]"))
    assert s.params[3] == Call("F", (Expr("[]", ("P", -1)),))
    assert s.params[4] == Call("F", ("A", "B"))


def test_read_dmis_refuses_binary_and_missing_files(tmp_path: Path) -> None:
    path = tmp_path / "part.dmi"
    path.write_bytes(b"GOTO/1,2,3\nEN\x00DMES\n")
    with pytest.raises(ProgramParseError) as info:
        read_dmis(path)
    assert str(info.value) == (
        f"{path}:2:3: not a DMIS text file: found a NUL byte (binary or UTF-16 data?)"
    )
    with pytest.raises(ProgramParseError, match="cannot read"):
        read_dmis(tmp_path / "missing.dmi")


# --- robustness -----------------------------------------------------------------------------

DMIS_ALPHABET = "FATSDV()=/,.$' \t\r\n0123456789+-*EQNO[]:_$"
NIST_TEXTS = [p.read_text() for p in NIST if p.is_file()] or ["GOTO/1,2,3\nENDFIL\n"]


def ends_well(text: str) -> None:
    try:
        result = parse_dmis(text, source="fuzz")
    except ProgramParseError as error:
        assert str(error).startswith("fuzz:")
        assert error.diagnostics and error.diagnostics[0].line >= 1
    else:
        assert isinstance(result, DmisFile)


@settings(max_examples=examples(200))
@given(st.text(DMIS_ALPHABET, max_size=120) | st.text(max_size=80))
def test_random_text_parses_or_fails_cleanly(text: str) -> None:
    ends_well(text)


EDITS = st.lists(
    st.tuples(st.sampled_from("DIR"), st.integers(0, 10**6), st.sampled_from(DMIS_ALPHABET)),
    min_size=1,
    max_size=4,
)


@settings(max_examples=examples(200), suppress_health_check=[HealthCheck.too_slow])
@given(st.sampled_from(NIST_TEXTS), EDITS)
def test_mutated_nist_files_parse_or_fail_cleanly(
    text: str, edits: list[tuple[str, int, str]]
) -> None:
    for op, where, char in edits:
        at = where % (len(text) + 1)
        if op == "D":
            text = text[:at] + text[at + 1 :]
        elif op == "I":
            text = text[:at] + char + text[at:]
        else:
            text = text[:at] + char + text[at + 1 :]
    ends_well(text)


def test_golden_dmis_files_parse() -> None:
    """Every emitted golden program parses (there may be none yet)."""
    for path in sorted((TESTS / "golden").rglob("*.dmi")):
        assert read_dmis(path).statements, path
