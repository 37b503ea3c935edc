"""Results readers: the DMIS output reader, statement-level DMIS recovery, and the DPRNT
fast path (it must give exactly the log the lark parser gives)."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import pytest
from fuzzing import examples
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from mutations import mutate
from test_dprnt import CLEAN, HEAD, MALFORMED, NOISE_MOVING_LINES, NOISE_SAME_LINES, STRUCTURE

from probegen.dmis.reader import logical_statements, parse_dmis, parse_dmis_recovering
from probegen.errors import Diagnostic, ProbegenError, ResultsParseError
from probegen.results import (
    DmisOutput,
    FeatureActual,
    MeasuredPoint,
    ToleranceActual,
    parse_dmis_output,
    parse_dprnt,
    read_dmis_output,
    touches_array,
)

REF = Path(__file__).resolve().parents[2] / "shared" / "ref" / "nist-ippdme"
SIMPLE_OUT = REF / "IPlusSimplePart" / "DMIS" / "output.dms"
NIST_FILES = (
    SIMPLE_OUT,
    REF / "IPlusSimplePart" / "DMIS" / "simple_in.dms",
    REF / "DCXpart" / "DMIS" / "IMTS_M_clean.dmi",
)
needs_nist = pytest.mark.skipif(not SIMPLE_OUT.is_file(), reason="NIST reference files missing")


def close(a: Any, b: Any, tol: float = 1e-12) -> bool:
    """Compare floats or tuples of floats (None equal to None)."""
    if a is None or b is None or isinstance(a, str):
        return a == b
    if isinstance(a, tuple):
        return len(a) == len(b) and all(close(x, y, tol) for x, y in zip(a, b, strict=True))
    return math.isclose(a, b, rel_tol=tol, abs_tol=tol)


# --- the NIST output file -----------------------------------------------------------------


@needs_nist
def test_nist_simple_output_circle_actual() -> None:
    out = read_dmis_output(SIMPLE_OUT, strict=True)
    assert out.source == str(SIMPLE_OUT)
    assert out.features == (
        FeatureActual(
            "A_CIRCLE",
            "CIRCLE",
            "INNER",
            (50.0, 50.0, 40.0),
            (0.0, 0.0, 1.0),
            diameter=50.0,
            line=5,
        ),
    )
    circle = out.feature("a_circle")
    assert circle.inner and circle.radius == 25.0
    assert out.tolerances == () and out.points == () and out.diagnostics == ()


# --- each feature type ----------------------------------------------------------------------

FEATURES = [
    ("FEAT/POINT,CART,1,2,3,0,0,1", {"position": (1, 2, 3), "direction": (0, 0, 1)}),
    ("FEAT/POINT,CART,1,2,3,0,0,0", {"position": (1, 2, 3), "direction": None}),
    ("FEAT/POINT,CART,1,2,3", {"position": (1, 2, 3), "direction": None}),
    ("FEAT/PLANE,CART,4,-61,12,0,-1,0", {"position": (4, -61, 12), "direction": (0, -1, 0)}),
    ("FEAT/PLANE,CART,0,0,0,0,3,4", {"direction": (0, 0.6, 0.8)}),  # normalised
    ("FEAT/LINE,UNBND,CART,2,-47,18,1,0,0", {"position": (2, -47, 18), "direction": (1, 0, 0)}),
    (
        "FEAT/LINE,UNBND,CART,0,0,0,1,0,0,0,0,1",
        {"direction": (1, 0, 0), "normal": (0, 0, 1)},
    ),
    (
        "FEAT/LINE,BND,CART,1,1,0,1,4,4",
        {"position": (1, 1, 0), "end": (1, 4, 4), "direction": (0, 0.6, 0.8), "length": 5},
    ),
    (
        "FEAT/CIRCLE,OUTER,CART,5,6,7,0,0,-1,12.5",
        {"material": "OUTER", "direction": (0, 0, -1), "diameter": 12.5},
    ),
    ("FEAT/SPHERE,OUTER,CART,1,2,3,25", {"position": (1, 2, 3), "diameter": 25}),
    ("FEAT/SPHERE,INNER,CART,1,2,3,0,0,1,25", {"direction": (0, 0, 1), "diameter": 25}),
    (
        "FEAT/CYLNDR,INNER,CART,0,0,22,0,0,-1,27,14",
        {"position": (0, 0, 22), "direction": (0, 0, -1), "diameter": 27, "length": 14},
    ),
    ("FEAT/CYLNDR,INNER,CART,0,0,0,0,0,1,12.5", {"diameter": 12.5, "length": None}),
    ("FEAT/CONE,OUTER,CART,0,0,10,0,0,1,60", {"position": (0, 0, 10), "angle": 60}),
    (
        "FEAT/TORUS,OUTER,CART,25,25,26,0,0,1,38,8",
        {"material": "OUTER", "position": (25, 25, 26), "direction": (0, 0, 1),
         "diameter": 38, "minor_diameter": 8, "length": None},
    ),
    ("FEAT/TORUS,INNER,POL,10,90,5,0,0,-1,20,4", {"position": (0, 10, 5), "material": "INNER"}),
    ("FEAT/CIRCLE,INNER,POL,10,90,5,0,0,1,4", {"position": (0, 10, 5)}),
    ("feat/circle,inner,cart,1,2,3,0,0,1,4", {"type": "CIRCLE", "position": (1, 2, 3)}),
]


@pytest.mark.parametrize(("text", "expected"), FEATURES, ids=[f[0] for f in FEATURES])
def test_feature_types(text: str, expected: dict[str, Any]) -> None:
    out = parse_dmis_output(f"FA(F1)={text}\n", strict=True)
    (feature,) = out.features
    for name, value in expected.items():
        assert close(getattr(feature, name), value), (name, getattr(feature, name))


def test_units_convert_to_mm_and_degrees() -> None:
    text = (
        "FA(A)=FEAT/CIRCLE,INNER,CART,1,2,3,0,0,1,0.5\n"
        "UNITS/INCH,ANGRAD\n"
        "FA(B)=FEAT/CIRCLE,INNER,CART,1,2,3,0,0,1,0.5\n"
        "FA(C)=FEAT/CONE,INNER,CART,0,0,0,0,0,1,0.5\n"
        "TA(T)=TOL/DIAM,0.001,INTOL\n"
        "TA(U)=TOL/ANGLB,0.01,OUTOL\n"
        "UNITS/CM,ANGDEC,TEMPC\n"
        "FA(D)=FEAT/CIRCLE,INNER,POL,1,30,2,0,0,1,1\n"
    )
    out = parse_dmis_output(text, strict=True)
    a, b, c, d = out.features
    assert a.diameter == 0.5 and a.position == (1.0, 2.0, 3.0)
    assert close(b.diameter, 12.7) and close(b.position, (25.4, 50.8, 76.2))
    assert close(c.angle, math.degrees(0.5))
    assert close(out.tolerances[0].value, 0.0254)
    assert close(out.tolerances[1].value, math.degrees(0.01))
    assert close(d.position, (10 * math.cos(math.pi / 6), 5.0, 20.0)) and close(d.diameter, 10.0)


def test_direction_angles_are_turned_into_cosines() -> None:
    # Some vendors write the direction as three direction angles in degrees.
    text = (
        "$$ vendor output\n"
        "FA(FID_1) = FEAT/PLANE, CART,$\n"
        "0.000041726011, -0.417351206649, -2.318705529301,$\n"
        "179.985670441557, 89.985676055420, 90.000401070444\n"
    )
    (plane,) = parse_dmis_output(text, strict=True).features
    assert plane.line == 2 and close(plane.position[1], -0.417351206649)
    norm = math.hypot(-1.0, 2.5e-4, -7e-6)  # the vector the angles were made from
    assert close(plane.direction, (-1.0 / norm, 2.5e-4 / norm, -7e-6 / norm), 1e-9)


def test_tolerances() -> None:
    text = (
        "TA(T1)=TOL/DIAM,0.012,INTOL\n"
        "TA(T2)=TOL/POS,3D,0.150,OUTOL\n"
        "TA(T3)=TOL/CORTOL,XAXIS,-0.004,INTOL\n"
        "TA(T4)=TOL/FLAT,0.02,INTOL,FA(PLN1)\n"
    )
    out = parse_dmis_output(text, strict=True)
    assert out.tolerances == (
        ToleranceActual("T1", "DIAM", (0.012,), (), "INTOL", 1),
        ToleranceActual("T2", "POS", (0.15,), ("3D",), "OUTOL", 2),
        ToleranceActual("T3", "CORTOL", (-0.004,), ("XAXIS",), "INTOL", 3),
        ToleranceActual("T4", "FLAT", (0.02,), (), "INTOL", 4),
    )
    assert out.tolerances[0].intol and not out.tolerances[1].intol


def test_measured_points_from_meas_blocks_and_point_features() -> None:
    text = (
        "UNITS/MM,ANGDEC\n"
        "PTMEAS/CART,9,9,9\n"
        "MEAS/CIRCLE,F(C1),2\n"
        "  PTMEAS/CART,75.0,50.0,40.0,-1.0,0.0,0.0\n"
        "  PTMEAS/POL,25,180,40\n"
        "ENDMES\n"
        "FA(P1)=FEAT/POINT,CART,-71,-44,26,-1,0,0\n"
        "F(NOM)=FEAT/POINT,CART,0,0,0,0,0,1\n"
    )
    out = parse_dmis_output(text, strict=True)
    first, second, third, fourth = out.points
    assert first == MeasuredPoint(None, (9.0, 9.0, 9.0), None, 2)
    assert second == MeasuredPoint("C1", (75.0, 50.0, 40.0), (-1.0, 0.0, 0.0), 4)
    assert second.via == "PTMEAS" and third.feature == "C1"
    assert close(third.xyz, (-25.0, 0.0, 40.0))
    assert fourth == MeasuredPoint("P1", (-71.0, -44.0, 26.0), (-1.0, 0.0, 0.0), 7, "FEAT/POINT")
    assert [f.name for f in out.features] == ["P1"]  # nominals are read past


# --- diagnostics: the bad statement is reported, every good one is kept ----------------------

BAD = [
    (
        "FA(X)=FEAT/CIRCLE,INNER,CART,0,0,0,0,0,1",
        30,
        "FA(X)=FEAT: expected 7 (position, direction, diameter) numbers for CIRCLE, found 6",
    ),
    (
        "FA(X)=FEAT/CIRCLE,INNER,CART,0,0,0,0,0,A,1",
        40,
        "FA(X)=FEAT: expected a number (direction k), found the word 'A'",
    ),
    (
        "FA(X)=FEAT/CYLNDR,CART,0,0,0,0,0,1,5",
        24,
        "FA(X)=FEAT: expected INNER or OUTER, found the number 0",
    ),
    (
        "FA(X)=FEAT/CIRCLE,INNR,CART,0,0,0,0,0,1,5",
        19,
        "FA(X)=FEAT: expected CART, POL, INNER or OUTER, found the word 'INNR'",
    ),
    (
        "FA(X)=FEAT/ELLIPS,INNER,CART,0,0,0,0,0,1,5,1",
        12,
        "FA(X)=FEAT: expected a feature type (POINT, PLANE, LINE, CIRCLE, SPHERE, CYLNDR, "
        "CONE or TORUS), found the word 'ELLIPS'",
    ),
    (
        "FA(X)=FEAT/TORUS,OUTER,CART,0,0,0,0,0,1,38",
        29,
        "FA(X)=FEAT: expected 8 (position, direction, diameter, minor_diameter) numbers for "
        "TORUS, found 7",
    ),
    (
        "FA(X)=FEAT/TORUS,OUTER,CART,0,0,0,0,0,1,38,0",
        44,
        "FA(X)=FEAT: expected a minor diameter above 0, found the number 0",
    ),
    (
        "FA(X)=FEAT/TORUS,CART,0,0,0,0,0,1,38,8",
        23,
        "FA(X)=FEAT: expected INNER or OUTER, found the number 0",
    ),
    (
        "FA(X)=FEAT/CIRCLE,INNER,CART,0,0,0,0,0,0,5",
        36,
        "FA(X)=FEAT: expected a direction (i, j, k) other than 0, 0, 0, found the number 0",
    ),
    (
        "FA(X)=FEAT/CIRCLE,INNER,CART,0,0,0,0,0,1,-5",
        42,
        "FA(X)=FEAT: expected a diameter above 0, found the number -5",
    ),
    (
        "FA(X)=FEAT/CONE,INNER,CART,0,0,0,0,0,1,190",
        40,
        "FA(X)=FEAT: expected a cone angle between 0 and 180 degrees, found the number 190",
    ),
    (
        "FA(X)=FEAT/SPHERE,INNER,CART,1E999,0,0,5",
        30,
        "FA(X)=FEAT: expected a number (x) within range, found the number 1E999",
    ),
    (
        "FA(X)=FEAT/LINE,BND,CART,1,2,3,1,2,3",
        32,
        "FA(X)=FEAT: expected an end point other than the start point, found the number 1",
    ),
    ("TA(T)=TOL/POS,3D,0.2", 21, "TA(T)=TOL: expected one INTOL or OUTOL, found end of statement"),
    (
        "TA(T)=TOL/DIAM,INTOL",
        16,
        "TA(T)=TOL: expected the actual value (a number), found the word 'INTOL'",
    ),
    (
        "UNITS/MILS,ANGDEC",
        7,
        "UNITS: expected a length unit (MM, CM, METER, INCH or FEET), found the word 'MILS'",
    ),
    (
        "UNITS/MM,ANGDMS",
        10,
        "UNITS: expected an angle unit (ANGDEC or ANGRAD), found the word 'ANGDMS' "
        "(degrees, minutes and seconds are not supported)",
    ),
    (
        "PTMEAS/CART,1,2",
        16,
        "PTMEAS: expected 3 (x, y, z) or 6 (x, y, z, i, j, k) numbers after CART, found 2",
    ),
    ("FA(X)=FEAT/CIRCLE,INNER,CART,(1,2", 34, "expected ',' or ')', found end of line"),
    (
        "FA(X)=FEAT/CIRCLE,INNER,CART,'1,2",
        30,
        "expected a number, a word, a quoted string, '(', a sign or '.NOT.', found a quote "
        "that is not closed on its line",
    ),
]


@pytest.mark.parametrize(("line", "column", "message"), BAD, ids=[b[0] for b in BAD])
def test_bad_statement_is_a_diagnostic(line: str, column: int, message: str) -> None:
    good = "FA(G)=FEAT/CIRCLE,INNER,CART,1,2,3,0,0,1,4"
    out = parse_dmis_output(f"{good}\n{line}\n{good}\n", source="m.dmo")
    (diag,) = out.diagnostics
    assert (diag.source, diag.line, diag.column) == ("m.dmo", 2, column)
    assert diag.message == message
    assert diag.text == line
    assert [f.line for f in out.features] == [1, 3]


def test_diagnostic_on_a_continuation_line_points_at_the_parameter() -> None:
    text = "FA(X)=FEAT/CIRCLE,INNER,CART,$\n   1,2,3,$  \n  0,0,ONE,4 $$ note\nENDFIL\n"
    (diag,) = parse_dmis_output(text).diagnostics
    assert (diag.line, diag.column) == (3, 7)
    assert str(diag).endswith("    " + "  0,0,ONE,4 $$ note\n" + "    " + " " * 6 + "^")


def test_strict_raises_with_every_diagnostic() -> None:
    text = "".join(f"{line}\n" for line, _, _ in BAD)
    with pytest.raises(ResultsParseError) as info:
        parse_dmis_output(text, source="m.dmo", strict=True)
    err = info.value
    assert len(err.diagnostics) == len(BAD)
    assert all(isinstance(d, Diagnostic) for d in err.diagnostics)
    assert [d.line for d in err.diagnostics] == list(range(1, len(BAD) + 1))
    assert str(err).startswith(f"m.dmo: {len(BAD)} problems in the DMIS output\nm.dmo:1:30:")
    assert str(err).endswith(f"... and {len(BAD) - 10} more")


def test_feature_lookup_suggests_a_name() -> None:
    out = parse_dmis_output("FA(BORE_A)=FEAT/CIRCLE,INNER,CART,1,2,3,0,0,1,4\n")
    with pytest.raises(ProbegenError, match=r"no feature actual FA\(BORE_B\).*'BORE_A'"):
        out.feature("bore_b")


def test_read_dmis_output_files(tmp_path: Path) -> None:
    path = tmp_path / "out.dmo"
    path.write_bytes("$$ caf\xe9\r\nFA(A)=FEAT/SPHERE,OUTER,CART,1,2,3,4\r\n".encode("latin-1"))
    out = read_dmis_output(path)
    assert out.features[0].line == 2 and out.features[0].diameter == 4.0
    with pytest.raises(ProbegenError, match="cannot read DMIS output '.*nope.dmo'"):
        read_dmis_output(tmp_path / "nope.dmo")


# --- statement-level recovery in probegen.dmis.reader -----------------------------------------


@needs_nist
@pytest.mark.parametrize("path", NIST_FILES, ids=lambda p: p.name)
def test_recovering_parse_equals_parse_on_good_files(path: Path) -> None:
    text = path.read_text(encoding="latin-1")
    assert parse_dmis_recovering(text, source="f") == (parse_dmis(text, source="f"), ())


@needs_nist
@pytest.mark.parametrize("path", NIST_FILES, ids=lambda p: p.name)
def test_statement_by_statement_equals_whole_file(path: Path) -> None:
    text = path.read_text(encoding="latin-1")
    whole = parse_dmis(text, source="f")
    broken = text + "\nBAD/(\n"
    found, diagnostics = parse_dmis_recovering(broken, source="f")
    assert found.statements == whole.statements and found.comments == whole.comments
    (diag,) = diagnostics
    assert diag.line == text.count("\n") + 2


def test_logical_statements_keep_physical_lines() -> None:
    text = "A/1,$\n2\nB/'$'\nC/3 $$ x $\nD/4,$  \r\n 5\rE"
    assert logical_statements(text) == [
        (1, "A/1,$\n2"),
        (3, "B/'$'"),
        (4, "C/3 $$ x $"),
        (5, "D/4,$  \r\n 5"),
        (7, "E"),
    ]


# --- never another exception, never a hang --------------------------------------------------

FUZZ = settings(max_examples=examples(200), suppress_health_check=[HealthCheck.too_slow])
ALPHABET = "FAT()=/,$'.-+0123456789EINCRLUPMSODXYZ \t\r\n\x00é"


def _check_output(text: str) -> None:
    """Lenient mode returns an output; strict mode returns it or raises ResultsParseError."""
    out = parse_dmis_output(text, source="f.dmo")
    assert isinstance(out, DmisOutput)
    lines = text.count("\n") + text.count("\r") + 1
    for diag in out.diagnostics:
        assert 1 <= diag.line <= lines and diag.column >= 1
        str(diag).encode("utf-8", errors="surrogatepass")
    for feature in out.features:
        assert all(math.isfinite(v) for v in feature.position)
    try:
        strict = parse_dmis_output(text, source="f.dmo", strict=True)
    except ResultsParseError as err:
        assert err.diagnostics == out.diagnostics
    else:
        assert strict == out and not out.diagnostics


@FUZZ
@given(st.text())
def test_random_text_never_crashes(text: str) -> None:
    _check_output(text)


@FUZZ
@given(st.text(alphabet=ALPHABET, max_size=200))
def test_dmis_like_text_never_crashes(text: str) -> None:
    _check_output(text)


SEED_OUTPUT = (
    "FILNAM/'fuzz seed',5.1\n"
    "UNITS/INCH,ANGRAD\n"
    "OUTPUT/FA(BORE),TA(DIA)\n"
    "FA(BORE)=FEAT/CYLNDR,INNER,CART,1.25,-2.5,0.75,$\n"
    "  0,0,1,0.5,1.0 $$ actual\n"
    "FA(TOP)=FEAT/PLANE,POL,3,0.5,1,0,0,1\n"
    "TA(DIA)=TOL/DIAM,0.0004,INTOL\n"
    "FA(RIM)=FEAT/TORUS,OUTER,CART,0.98,1.02,1.0236,$\n"
    "  0,0,1,1.496,0.315\n"
    "MEAS/CIRCLE,F(RING),2\n"
    "PTMEAS/CART,2,0,0.5,-1,0,0\n"
    "PTMEAS/POL,2,1.5,0.5\n"
    "ENDMES\n"
    "ENDFIL\n"
)


@st.composite
def mutated_output(draw: st.DrawFn) -> str:
    """The NIST output file (read in place) or a hand-written output, mutated."""
    text = SIMPLE_OUT.read_text() if SIMPLE_OUT.is_file() else SEED_OUTPUT
    if draw(st.booleans()):
        text = SEED_OUTPUT
    return mutate(draw, text, ALPHABET)


@FUZZ
@given(mutated_output())
def test_mutated_output_never_crashes(text: str) -> None:
    _check_output(text)


# --- the DPRNT fast path gives exactly the lark log -------------------------------------------


def _same(text: str | bytes) -> None:
    fast, lark = parse_dprnt(text), parse_dprnt(text, fast=False)
    assert fast == lark


CORPUS = (
    [CLEAN]
    + [noise(CLEAN) for noise in NOISE_SAME_LINES.values()]
    + [noise(CLEAN) for noise in NOISE_MOVING_LINES.values()]
    + [HEAD + line + "\nPT OK 1 X1 Y2 Z3\n" for line, _, _ in MALFORMED]
    + [text for text, _, _, _ in STRUCTURE]
)


@pytest.mark.parametrize("text", CORPUS, ids=[str(i) for i in range(len(CORPUS))])
def test_dprnt_fast_path_equals_lark_on_the_corpus(text: str) -> None:
    _same(text)
    _same(text.encode("utf-8", errors="surrogateescape"))


BLANK = st.sampled_from(["", " ", "  ", "\t"])
DIGITS = st.text(alphabet="0123456789", min_size=1, max_size=5)


@st.composite
def dprnt_number(draw: st.DrawFn) -> str:
    """A number as controls print it, and some they do not."""
    sign = draw(st.sampled_from(["", "-", "+", "- ", "+ ", "--"]))
    whole, frac = draw(DIGITS), draw(DIGITS)
    forms = [f"{whole}.{frac}", f"{whole}.", f".{frac}", whole, "0.0000"]
    odd = [".", "9" * 400, f"{whole}.{frac}.{whole}", f"..{frac}", "1" + "0" * 308]
    body = draw(st.sampled_from(forms + odd))
    return sign + body


@st.composite
def dprnt_line(draw: st.DrawFn) -> str:
    """A PT, LOC, CTR or other record with blanks, case and field variants."""
    kind = draw(st.sampled_from(["PT", "LOC", "CTR", "pt", "PTX", "PGSTART", "PGEND", "ERR", "%"]))
    feature = draw(
        st.sampled_from(
            ["SPH1", "X", "PT", "B7", "ABCDEFGHIJKLMNOP", "ABCDEFGHIJKLMNOPQ", "s1", "1A", "S_1"]
        )
    )
    index = draw(st.sampled_from(["1", "12.", "012", "0", "999999", "1234567", "1.5", "7X"]))
    b = [draw(BLANK) for _ in range(8)]
    xyz = "".join(f"{axis}{b[k]}{draw(dprnt_number())}{b[k + 3]}" for k, axis in enumerate("XYZ"))
    if kind in ("PGSTART", "PGEND", "ERR", "%"):
        return draw(st.sampled_from(["PGSTART O1001 V1", "PGEND O1001", "ERR NOTOUCH SPH1 3", "%"]))
    middle = f"{feature} " if kind == "CTR" else f"{feature} {index}{b[6] or ' '}"
    return f"{b[7]}{kind} {middle}{xyz}{draw(st.sampled_from(['', ' ', ' %', ' Q']))}"


@settings(max_examples=examples(300), suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(dprnt_line(), max_size=12), st.sampled_from(["\n", "\r\n", "\r", "\n\x00"]))
def test_dprnt_fast_path_equals_lark_on_generated_logs(lines: list[str], end: str) -> None:
    _same(end.join(lines))


def test_dprnt_fast_path_is_taken_and_arrays() -> None:
    log = parse_dprnt(CLEAN)
    array = touches_array(log)
    assert array.shape == (5, 3) and array.dtype.name == "float64"
    assert array.tolist() == [list(t.xyz) for t in log.touches]
    assert touches_array(()).shape == (0, 3)
