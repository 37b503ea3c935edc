"""The exports of the history: Q-DAS AQDEF (DFQ) writer and reader, and the CSV.

The DFQ is checked three ways: whole (a golden file), by structure (every line a K-field,
every characteristic described, one value per run per characteristic, NOT EVALUATED
marked and never invented, K0100 right), read by a small independent parser written here,
and by a round trip through probegen's own reader (values to the written decimals, limits,
nominals, descriptions, serials, batches and times back).  The reader gets property tests
on random and mutated input.
"""

from __future__ import annotations

import csv
import io
import re
from collections import Counter
from datetime import UTC, datetime, timedelta

import pytest
from conftest import REPO, assert_golden
from fuzzing import examples
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from mutations import mutate

from probegen.errors import ParseError, ProbegenError
from probegen.qdas import DFQ_ENCODING, decode_dfq, dfq_series, read_dfq, to_csv, to_dfq
from probegen.qdas.table import COLUMNS
from probegen.spc.series import Series, Value

GOLDEN = REPO / "tests" / "golden" / "qdas"
K_LINE = re.compile(r"K(\d{4})(?:/(\d+))?(?: (.*))?")


def _history(runs: int = 30) -> list[Series]:
    """A part measured ``runs`` times: a bore drifting 1 µm a run with two runs NOT
    EVALUATED, its position, a flatness toleranced above only, an untoleranced angle in
    degrees, and a characteristic added to the spec from run 10 on."""
    def value(n: int, measured: float | None, status: str) -> Value:
        lot = f"LOT-{n // 10 + 1}"
        return Value(f"run{n:03d}", f"2026-11-{1 + n // 24:02d}T{n % 24:02d}:15:07+01:00",
                     f"SN {1000 + n}", measured, 0.0006, status, lot)

    def series(feature: str, name: str, nominal: float, lower: float | None,
               upper: float | None, unit: str, at: list[tuple[int, float | None]]) -> Series:
        toleranced = "-" if lower is None and upper is None else "OK"
        return Series("P-4711", feature, name, nominal, lower, upper, unit,
                      tuple(value(n, m, "NOT EVALUATED" if m is None else toleranced)
                            for n, m in at))

    skipped = {7, 19}
    bore = [(n, None if n in skipped else 25.0 + 0.001 * n + 0.0003 * (-1) ** n)
            for n in range(runs)]
    return [
        series("BORE", "D", 25.0, -0.01, 0.04, "mm", bore),
        series("BORE", "X", 40.0, -0.05, 0.05, "mm",
               [(n, 40.0 - 0.00012 * n) for n in range(runs)]),
        series("FACE", "FLATNESS", 0.0, None, 0.02, "mm",
               [(n, 0.004 + 0.0001 * (n % 5)) for n in range(runs)]),
        series("SLOT", "ANGLE", 90.0, None, None, "deg",
               [(n, 90.0 + 0.01 * (n % 3)) for n in range(runs)]),
        series("PIN", "D", 6.0, -0.008, 0.0, "mm",
               [(n, 5.9961 - 0.00001 * n) for n in range(10, runs)]),
    ]


def _fields(text: str) -> list[tuple[str, int | None, str | None]]:
    """The K-fields of a DFQ text, parsed here without probegen's reader."""
    out = []
    for line in text.split("\r\n")[:-1]:
        match = K_LINE.fullmatch(line)
        assert match, f"not a K-field: {line!r}"
        out.append((f"K{match[1]}", None if match[2] is None else int(match[2]), match[3]))
    return out


def test_dfq_golden() -> None:
    history = [s for s in _history(4) if s.unit == "mm"]  # goldens are ASCII
    text = to_dfq(history, part_description="Pump housing")
    assert "\r\n" in text and "\n" not in text.replace("\r\n", "")
    assert_golden(GOLDEN / "history.dfq", text.replace("\r\n", "\n"))


def test_dfq_structure() -> None:
    history = _history()
    text = to_dfq(history, decimals=4)
    assert text.endswith("\r\n") and "\n" not in text.replace("\r\n", "")
    text.encode(DFQ_ENCODING)
    fields = _fields(text)
    assert fields[0] == ("K0100", None, str(len(history)))
    assert ("K1001", 1, "P-4711") in fields
    desc = {(k, i): v for k, i, v in fields if k.startswith("K2")}
    runs = 30
    for i, s in enumerate(history, start=1):
        assert desc["K2001", i] == f"{s.feature}.{s.characteristic}"  # stable, not i
        assert desc["K2002", i] == f"{s.feature} {s.characteristic}"
        assert float(desc["K2101", i]) == pytest.approx(s.nominal, abs=1e-9)
        for key, limit in (("K2110", s.lsl), ("K2111", s.usl)):
            if limit is None:
                assert (key, i) not in desc  # no invented limit
            else:
                assert float(desc[key, i]) == pytest.approx(limit, abs=5e-5)
        values = [v for k, j, v in fields if k == "K0001" and j == i]
        assert len(values) == runs, f"characteristic {i}: one value per run"
        missing = [n for n, v in enumerate(values) if v is None]
        marks = [v for k, j, v in fields if k == "K0002" and j == i]
        assert marks == ["255"] * len(missing)
        times = [v for k, j, v in fields if k == "K0004" and j == i]
        assert len(times) == runs and all(re.fullmatch(
            r"\d\d\.\d\d\.\d{4}/\d\d:\d\d:\d\d", t or "") for t in times)
        serials = [v for k, j, v in fields if k == "K0014" and j == i]
        assert serials == [f"SN {1000 + n}" for n in range(runs)]
        subgroups = [v for k, j, v in fields if k == "K0080" and j == i]
        assert subgroups == [f"LOT-{n // 10 + 1}" for n in range(runs)]
        positions = [v for k, j, v in fields if k == "K0081" and j == i]
        assert positions == [str(n % 10 + 1) for n in range(runs)]
    bore = [v for k, j, v in fields if k == "K0001" and j == 1]
    assert [n for n, v in enumerate(bore) if v is None] == [7, 19]
    pin = [v for k, j, v in fields if k == "K0001" and j == 5]
    assert pin[:10] == [None] * 10 and None not in pin[10:]  # added later: marked, not made up
    assert bore[3] == "25.0027" and pin[10] == "5.9960"
    assert ("K2142", 4, "°") in fields
    assert Counter(k for k, _, _ in fields if k.startswith("K2"))["K2001"] == len(history)


def test_dfq_round_trip() -> None:
    history = _history()
    back = dfq_series(read_dfq(to_dfq(history, decimals=5), "history.dfq"), "history.dfq")
    assert [(s.part, s.feature, s.characteristic, s.unit) for s in back] == \
        [(s.part, s.feature, s.characteristic, s.unit) for s in history]
    for s, r in zip(history, back, strict=True):
        assert r.nominal == pytest.approx(s.nominal, abs=1e-9)
        for mine, theirs in ((s.lower, r.lower), (s.upper, r.upper), (s.lsl, r.lsl),
                             (s.usl, r.usl)):
            assert (mine is None) == (theirs is None)
            if mine is not None and theirs is not None:
                assert theirs == pytest.approx(mine, abs=5e-6)
        own = {v.run: v for v in s.values}
        runs = sorted({v.run for x in history for v in x.values})
        assert len(r.values) == len(runs)
        for key, got in zip(runs, r.values, strict=True):
            want = own.get(key)
            if want is None or want.measured is None:
                assert got.measured is None and got.status == "NOT EVALUATED"
            else:
                assert got.measured == round(want.measured, 5)
                assert got.status == want.status
            n = int(key[3:])
            assert got.serial == f"SN {1000 + n}" and got.subgroup == f"LOT-{n // 10 + 1}"
            assert got.time == f"2026-11-{1 + n // 24:02d}T{n % 24:02d}:15:07"


printable = st.characters(min_codepoint=32, max_codepoint=255,
                          blacklist_characters="\x7f").filter(
    lambda c: c.encode(DFQ_ENCODING, errors="ignore") != b"")
words = st.text(printable, min_size=1, max_size=12).filter(lambda t: t.strip() == t and t)
numbers = st.floats(-1e5, 1e5, allow_nan=False)


def _iso(seconds: int) -> str:
    """The ISO 8601 time ``seconds`` after 2001-01-01 00:00 UTC."""
    moment = datetime(2001, 1, 1, tzinfo=UTC) + timedelta(seconds=seconds)
    return moment.isoformat()


@st.composite
def histories(draw: st.DrawFn) -> list[Series]:
    part = draw(words)
    runs = draw(st.lists(st.tuples(st.integers(0, 10**9), st.none() | words,
                                   st.none() | words), min_size=1, max_size=6,
                         unique_by=lambda r: r[0]))
    out = []
    for k in range(draw(st.integers(1, 4))):
        nominal = draw(numbers)
        lower = draw(st.none() | st.floats(-1, 0))
        upper = draw(st.none() | st.floats(0, 1))
        values = tuple(Value(f"r{t}", _iso(t), serial, draw(st.none() | numbers), None,
                             "-", lot)
                       for t, serial, lot in runs if draw(st.booleans()))
        out.append(Series(part, f"F{k}", draw(words).replace(" ", "_"), nominal, lower,
                          upper, draw(st.sampled_from(["mm", "deg"])), values))
    return out


@settings(max_examples=examples(60), suppress_health_check=[HealthCheck.too_slow])
@given(histories())
def test_dfq_round_trip_property(history: list[Series]) -> None:
    text = to_dfq(history, decimals=6)
    back = dfq_series(read_dfq(text))
    assert len(back) == len(history)
    for s, r in zip(history, back, strict=True):
        assert (r.part, r.feature, r.characteristic, r.unit) == \
            (s.part, s.feature, s.characteristic, s.unit)
        got = [v.measured for v in r.values if v.measured is not None]
        want = [round(v.measured, 6) for v in sorted(s.values, key=lambda v: (v.time, v.run))
                if v.measured is not None]
        assert got == pytest.approx(want, abs=1.5e-6)
        assert [v.serial for v in r.values if v.measured is not None] == \
            [v.serial for v in sorted(s.values, key=lambda v: (v.time, v.run))
             if v.measured is not None]


def test_dfq_is_repeatable_and_order_of_values_free() -> None:
    history = _history()
    shuffled = [Series(s.part, s.feature, s.characteristic, s.nominal, s.lower, s.upper,
                       s.unit, tuple(reversed(s.values))) for s in history]
    assert to_dfq(history) == to_dfq(history) == to_dfq(shuffled)


@pytest.mark.parametrize(("change", "message"), [
    (lambda h: [], "expected at least one characteristic, found none"),
    (lambda h: h + [Series("P-9", "A", "B", 1.0, None, None, "mm", ())],
     "expected the characteristics of one part number .* found 2: P-4711, P-9"),
    (lambda h: h + [h[0]], "expected one series per characteristic, found BORE D twice"),
    (lambda h: [Series("P\n1", "A", "B", 1.0, None, None, "mm", ())],
     r"K1001/1: expected one line of text, found the control character U\+000A"),
    (lambda h: [Series("P-1", "A", "B", 1.0, None, None, "mm",
                       (Value("r", "2026-11-26T10:00:00", "SN→1", 1.0, None, "-"),))],
     "K0014/1: expected characters of Windows-1252 .* found '→'"),
    (lambda h: [Series("P-1", "A", "B", 1.0, None, None, "mm",
                       (Value("r", "yesterday", None, 1.0, None, "-"),))],
     "run r: expected an ISO 8601 date and time .* found 'yesterday'"),
    (lambda h: [Series("P-1", "A", "B", float("nan"), None, None, "mm", ())],
     "expected a finite number, found nan"),
])
def test_dfq_refuses(change, message: str) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(ProbegenError, match=message):
        to_dfq(change(_history(3)))


# --- the reader on other writers' files ---------------------------------------------------

OTHER = """K0100 2
K1001 08/15
K1002 Gehäuse
K2002/0 common
K2001/1 1.1
K2002/1 Länge X
K2101/1 10,00
K2110/1 9,8
K2111/1 10,2
K2001/2 1.2
K2101/2 5
K2113/2 0.1
K2142/2 mm
K0001/1 10,023
K0004/1 7.5.1992/13:43
K0001/2 5.01
K0004/0 08.05.1992/13:43:28
K0014/0 A7
"""


def test_reader_reads_other_writers() -> None:
    dfq = read_dfq(OTHER, "other.dfq")
    assert dfq.count == 2 and len(dfq.parts) == 1
    part = dfq.parts[0]
    assert part.fields == {"K1001": "08/15", "K1002": "Gehäuse"}
    one, two = part.characteristics
    assert one.fields["K2002"] == "Länge X" and two.fields["K2002"] == "common"
    assert one.values[0].measured == 10.023 and one.values[0].fields["K0014"] == "A7"
    assert one.values[0].time == "1992-05-08T13:43:28"  # K0004/0 applies to both
    series = dfq_series(dfq, "other.dfq")
    assert (series[0].feature, series[0].characteristic) == ("Länge", "X")
    assert series[0].lsl == pytest.approx(9.8) and series[0].nominal == 10.0
    assert series[1].lower is None and series[1].upper == pytest.approx(0.1)
    assert [v.status for v in series[0].values] == ["OK"]


def test_reader_attributes_other_than_valid_are_not_values() -> None:
    text = "K0100 1\nK1001 P\nK2101/1 1\n" + "".join(
        f"K0001/1 1.5\nK0002/1 {a}\n" for a in (0, 129, 255, 256, 290))
    values = dfq_series(read_dfq(text))[0].values
    assert [v.measured for v in values] == [1.5, None, None, None, None]
    assert [v.status for v in values] == ["-"] + ["NOT EVALUATED"] * 4


def test_reader_value_lines() -> None:
    line = "9.94\x140\x1412.08.1999/15:23:45\x140\x0f\x14255\x0f3\x140"
    dfq = read_dfq("K0100 3\nK1001 08/15\n" + line + "\n" + line.replace("9.94", "9.95"))
    a, b, c = dfq.parts[0].characteristics
    assert [v.measured for v in a.values] == [9.94, 9.95]
    assert a.values[0].time == "1999-08-12T15:23:45"
    assert b.values[0].missing and b.values[0].attribute == 255
    assert c.values[1].measured == 3.0


def test_reader_several_parts() -> None:
    text = ("K0100 3\nK1001/1 A\nK2001/1 a1\nK2101/1 1\nK1001/2 B\nK2002/0 shared\n"
            "K2001/2 b1\nK2101/2 2\nK2001/3 b2\nK2101/3 3\nK0001/3 3.5\n")
    dfq = read_dfq(text)
    assert [(p.fields["K1001"], [c.index for c in p.characteristics]) for p in dfq.parts] \
        == [("A", [1]), ("B", [2, 3])]
    assert [s.part for s in dfq_series(dfq)] == ["A", "B", "B"]
    assert dfq.parts[1].characteristics[1].fields["K2002"] == "shared"
    assert "K2002" not in dfq.parts[0].characteristics[0].fields


@pytest.mark.parametrize(("text", "message"), [
    ("K1001 x\n", r"x\.dfq:2: expected a K0100 line"),
    ("K0100 1\nK2001/2 b\n", r"x\.dfq:2: expected a characteristic number from 1 to 1 "
                             r"\(K0100\), found 2"),
    ("K0100 1\nK0004/1 1.1.2020/10:00\n", r"x\.dfq:2: expected K0001/1 \(a value\) before "
                                          "K0004/1, found none"),
    ("K0100 1\nK0001/1 1.2.3\n", r"x\.dfq:2: expected a number for K0001, found '1.2.3'"),
    ("K0100 1\nK0001/1 1\nK0004/1 31.02.2020/10:00\n",
     r"x\.dfq:3: expected a date and time dd.mm.yyyy/hh:mm:ss for K0004, found"),
    ("K0100 one\n", r"x\.dfq:1: expected the number of characteristics"),
    ("K0100 1\nhello\n", r"x\.dfq:2: expected a K-field .* found 'hello'"),
    ("K0100 2\n1\x0f2\x0f3\n", r"x\.dfq:2: expected a value line of 2 characteristics"),
    ("K0100 1\nK0001/1 inf\n", "expected a number for K0001, found 'inf'"),
    ("K0100 1\nK0100 2\n", r"x\.dfq:2: expected K0100 once"),
])
def test_reader_errors(text: str, message: str) -> None:
    with pytest.raises(ParseError, match=message):
        read_dfq(text, "x.dfq")


def test_series_needs_part_number_and_nominal() -> None:
    with pytest.raises(ParseError, match="expected K1001 .* of part 1, found none"):
        dfq_series(read_dfq("K0100 1\nK2001/1 1\nK2101/1 2\n"))
    with pytest.raises(ParseError, match=r"x.dfq:3: characteristic 1: expected K2101/1"):
        dfq_series(read_dfq("K0100 1\nK1001 P\nK2001/1 1\n", "x.dfq"), "x.dfq")


def test_decode_dfq() -> None:
    text = "K0100 1\r\nK1002 Gehäuse °\r\n"
    assert decode_dfq(text.encode("cp1252")) == text
    assert decode_dfq(text.encode("utf-8")) == text
    assert decode_dfq(b"\xef\xbb\xbf" + text.encode("utf-8")) == text


def test_dfq_file_bytes_round_trip() -> None:
    history = _history(3)
    text = to_dfq(history, part_description="Gehäuse Ø 25 ±0,01")
    data = text.encode(DFQ_ENCODING)
    assert "K2142/4 °".encode(DFQ_ENCODING) in data and b"\xb0" in data  # ° in one byte
    dfq = read_dfq(decode_dfq(data), "history.dfq")
    assert dfq.parts[0].fields["K1002"] == "Gehäuse Ø 25 ±0,01"
    assert [s.unit for s in dfq_series(dfq)] == [s.unit for s in history]


def _read_or_refuse(text: str) -> None:
    try:
        dfq = read_dfq(text, "fuzz.dfq")
    except ParseError as err:
        assert str(err).startswith("fuzz.dfq:") and err.diagnostics
        return
    try:
        dfq_series(dfq, "fuzz.dfq")
    except ParseError as err:
        assert str(err).startswith("fuzz.dfq")


FUZZ = settings(max_examples=examples(150), suppress_health_check=[HealthCheck.too_slow])
CLEAN = to_dfq(_history(3), part_description="Pump housing")
ALPHABET = "K0123456789/ .,-\r\n\x0f\x14:e"


@FUZZ
@given(st.text())
def test_random_text_reads_or_refuses(text: str) -> None:
    _read_or_refuse(text)


@FUZZ
@given(st.lists(st.sampled_from(CLEAN.split("\r\n")) | st.text(ALPHABET, max_size=20),
                max_size=30))
def test_random_k_lines_read_or_refuse(lines: list[str]) -> None:
    _read_or_refuse("\n".join(lines))


@FUZZ
@given(st.binary())
def test_random_bytes_read_or_refuse(data: bytes) -> None:
    _read_or_refuse(decode_dfq(data))


@st.composite
def mutated_dfq(draw: st.DrawFn) -> str:
    return mutate(draw, CLEAN, ALPHABET)


@FUZZ
@given(mutated_dfq())
def test_mutated_dfq_reads_or_refuses(text: str) -> None:
    _read_or_refuse(text)


# --- CSV ----------------------------------------------------------------------------------

def test_csv_rows_and_rfc4180() -> None:
    history = _history()
    history[1] = Series(*[getattr(history[1], f) for f in (
        "part", "feature", "characteristic", "nominal", "lower", "upper", "unit")],
        tuple(Value(v.run, v.time, 'SN "7", left', v.measured, v.u, v.status, v.subgroup)
              if v.run == "run007" else v for v in history[1].values))
    text = to_csv(history)
    assert text == to_csv(history)
    assert text.endswith("\r\n") and "\n" not in text.replace("\r\n", "")
    assert '"SN ""7"", left"' in text  # quoted as RFC 4180 says
    rows = list(csv.DictReader(io.StringIO(text, newline="")))
    assert tuple(rows[0]) == COLUMNS
    assert len(rows) == 30 * len(history)  # one row per run per characteristic
    assert Counter(r["status"] for r in rows)["NOT EVALUATED"] == 2 + 10  # bore, pin
    first = rows[0]
    assert first == {"part": "P-4711", "feature": "BORE", "characteristic": "D",
                     "run": "run000", "time": "2026-11-01T00:15:07+01:00",
                     "serial": "SN 1000", "subgroup": "LOT-1", "nominal": "25",
                     "lsl": "24.99", "usl": "25.04", "measured": "25.0003", "u": "0.0006",
                     "status": "OK"}
    flat = [r for r in rows if r["feature"] == "FACE"]
    assert flat[0]["lsl"] == "" and flat[0]["usl"] == "0.02"
    pin = [r for r in rows if r["feature"] == "PIN"]
    assert pin[0]["measured"] == "" and pin[0]["u"] == "" and pin[0]["serial"] == "SN 1000"
    assert pin[10]["measured"] == "5.996"  # 5.9961 - 0.0001, trailing zeros dropped
