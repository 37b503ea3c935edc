"""DPRNT log reader: exact values, serial noise, diagnostics, restarts, fuzzing."""

from __future__ import annotations

import dataclasses
import math
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
from fuzzing import examples
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from mutations import mutate

from probegen.errors import Diagnostic, ProbegenError, ResultsParseError
from probegen.results import Centre, DprntLog, ProgramError, Touch, parse_dprnt, read_dprnt
from probegen.results.dprnt import Run

CLEAN = (
    "%\n"
    "PGSTART O1001 V1\n"
    "LOC SPH1 1 X-12.3456 Y0.0000 Z5.0000\n"
    "LOC SPH1 2 X12.3456 Y0.0000 Z5.0000\n"
    "CTR SPH1 X0.0012 Y-0.0003 Z0.0020\n"
    "PT SPH1 1 X-12.3456 Y0.0000 Z5.0000\n"
    "PT SPH1 2 X0.0000 Y12.5 Z-3.25\n"
    "PT BORE7 1 X100. Y-.5 Z-20.\n"
    "PGEND O1001\n"
    "%\n"
)

EXPECTED = DprntLog(
    source="<string>",
    program=1001,
    touches=(
        Touch("LOC", "SPH1", 1, (-12.3456, 0.0, 5.0), 3),
        Touch("LOC", "SPH1", 2, (12.3456, 0.0, 5.0), 4),
        Touch("PT", "SPH1", 1, (-12.3456, 0.0, 5.0), 6),
        Touch("PT", "SPH1", 2, (0.0, 12.5, -3.25), 7),
        Touch("PT", "BORE7", 1, (100.0, -0.5, -20.0), 8),
    ),
    centres=(Centre("SPH1", (0.0012, -0.0003, 0.002), 5),),
    errors=(),
    complete=True,
    restarts=0,
    diagnostics=(),
    runs=(Run(0, 2, 9, 1001, None),),
)


def test_clean_log_exact() -> None:
    assert parse_dprnt(CLEAN) == EXPECTED


def test_clean_log_strict_and_bytes() -> None:
    assert parse_dprnt(CLEAN.encode("ascii"), strict=True) == EXPECTED


def test_read_dprnt_file(tmp_path: Path) -> None:
    path = tmp_path / "run.log"
    path.write_bytes(CLEAN.encode("ascii"))
    log = read_dprnt(path)
    assert log.source == str(path)
    assert log.touches == EXPECTED.touches


def test_read_dprnt_missing_file(tmp_path: Path) -> None:
    with pytest.raises(ProbegenError, match="cannot read DPRNT log '.*nope.log'"):
        read_dprnt(tmp_path / "nope.log")


# --- serial noise: each kind gives exactly the clean log --------------------------------


def _each_line(fn: Callable[[str], str]) -> Callable[[str], str]:
    return lambda text: "\n".join(fn(line) if line else line for line in text.split("\n"))


NOISE_SAME_LINES: dict[str, Callable[[str], str]] = {
    "CRLF": lambda t: t.replace("\n", "\r\n"),
    "CR": lambda t: t.replace("\n", "\r"),
    "LFCR": lambda t: t.replace("\n", "\n\r"),
    "LF CR CR": lambda t: t.replace("\n", "\n\r\r"),
    "blanks around": _each_line(lambda line: "  " + line + " \t "),
    "POPEN/PCLOS codes": lambda t: "\x12" + t + "\x14",
    "NUL feed": lambda t: "\x00" * 5 + t.replace("\n", "\n\x00") + "\x00" * 5,
    "XON/XOFF inside words": lambda t: (
        t.replace("12.3456", "12\x13.34\x1156")
        .replace("PGSTART", "PG\x11START")
        .replace("SPH1", "SP\x00H1")
    ),
    "lower case": str.lower,
    "mixed case": lambda t: t.replace("PT SPH1", "Pt sph1"),
}

NOISE_MOVING_LINES: dict[str, Callable[[str], str]] = {
    "no % lines": lambda t: t.replace("%\n", ""),
    "% on record lines": lambda t: t.replace("%\nPGSTART", "%PGSTART").replace("1001\n%", "1001 %"),
    "blank lines": lambda t: t.replace("\n", "\n \n\n"),
}


@pytest.mark.parametrize("kind", sorted(NOISE_SAME_LINES))
def test_noise_is_tolerated(kind: str) -> None:
    assert parse_dprnt(NOISE_SAME_LINES[kind](CLEAN)) == EXPECTED


def _without_lines(log: DprntLog) -> DprntLog:
    def strip(records: tuple[Any, ...]) -> tuple[Any, ...]:
        return tuple(dataclasses.replace(r, line=0) for r in records)

    return dataclasses.replace(
        log, touches=strip(log.touches), centres=strip(log.centres), errors=strip(log.errors),
        runs=tuple(dataclasses.replace(r, start=0, end=int(r.complete)) for r in log.runs),
    )


@pytest.mark.parametrize("kind", sorted(NOISE_MOVING_LINES))
def test_noise_moving_lines_is_tolerated(kind: str) -> None:
    log = parse_dprnt(NOISE_MOVING_LINES[kind](CLEAN))
    assert _without_lines(log) == _without_lines(EXPECTED)


def test_blank_lines_shift_line_numbers_only() -> None:
    log = parse_dprnt(CLEAN.replace("\n", "\n\n"))
    assert not log.diagnostics and log.complete
    assert [t.line for t in log.touches] == [5, 7, 11, 13, 15]
    assert [t.xyz for t in log.touches] == [t.xyz for t in EXPECTED.touches]


def test_blank_lines_with_crlf_count_once_each() -> None:
    log = parse_dprnt(CLEAN.replace("\n", "\r\n\r\n"))
    assert [t.line for t in log.touches] == [5, 7, 11, 13, 15]


def test_all_noise_at_once() -> None:
    text = CLEAN
    for noise in NOISE_SAME_LINES.values():
        text = noise(text)
    assert parse_dprnt(text) == EXPECTED


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("X-12.3456", -12.3456),
        ("X -12.3456", -12.3456),
        ("X-  12.3456", -12.3456),
        ("X   12.3456", 12.3456),
        ("X+12.3456", 12.3456),
        ("X+ 12.3456", 12.3456),
        ("X12.", 12.0),
        ("X.5", 0.5),
        ("X-.5", -0.5),
        ("X12", 12.0),
        ("X0012.5000", 12.5),
        ("X-0.0000", 0.0),
        ("X   .0000", 0.0),
    ],
)
def test_dprnt_number_variants(field: str, value: float) -> None:
    log = parse_dprnt(f"PGSTART O1 V1\nPT A 1 {field} Y1. Z1.\n")
    (touch,) = log.touches
    assert touch.xyz[0] == value
    assert math.copysign(1.0, touch.xyz[0]) == math.copysign(1.0, value)  # never -0.0
    assert not log.diagnostics


@pytest.mark.parametrize("index", ["12", "12.", "  12", "012"])
def test_dprnt_index_variants(index: str) -> None:
    log = parse_dprnt(f"PGSTART O1 V1\nPT A {index} X1. Y1. Z1.\nERR NOTOUCH A {index}\n")
    assert [t.index for t in log.touches] == [12] and log.errors[0].index == 12
    assert not log.diagnostics


def test_feature_id_like_keywords() -> None:
    log = parse_dprnt("PGSTART O7 V1\nPT X 1 X1 Y2 Z3\nLOC PT 2 X1 Y2 Z3\nCTR Z X0 Y0 Z0\n")
    assert [(t.kind, t.feature) for t in log.touches] == [("PT", "X"), ("LOC", "PT")]
    assert log.centres[0].feature == "Z" and not log.diagnostics


# --- diagnostics: message, line, column, caret --------------------------------------------

HEAD = "PGSTART O1001 V1\n"

RECORD = "a record (PGSTART, PGCAL, PGSERIAL, FEAT, LOC, CTR, PT, RES, ERR or PGEND)"
MALFORMED = [
    ("PT SPH1 13 X1 Y2", 17, "expected 'Z', found end of line"),
    ("PT SPH1 1 X1.5.5 Y2 Z3", 15, "expected 'Y', found '.5'"),
    ("PT SPH1 1 X1 Y2 Z3 Q4", 20, "expected end of line, found 'Q4'"),
    ("CTR SPH1 1 X1 Y2 Z3", 10, "expected 'X', found '1'"),
    ("PT SPH1 X1 Y2 Z3", 9, "expected an index, found 'X1'"),
    ("PT SPH1 12X1 Y2 Z3", 9, "expected an index, found '12X1'"),
    ("PT SPH1 12.5 X1 Y2 Z3", 9, "expected an index, found '12.5'"),
    ("PT S_1 1 X1 Y2 Z3", 4, "expected a feature id or a feature number, found 'S_1'"),
    ("PT 1A 1 X1 Y2 Z3", 4, "expected a feature id or a feature number, found '1A'"),
    ("PT", 3, "expected a feature id or a feature number, found end of line"),
    ("PT SPH1 12 X- Y2 Z3", 15, "expected a number, found 'Y2'"),
    ("PTX SPH1 1 X1 Y2 Z3", 1, f"expected {RECORD}, found 'PTX'"),
    ("%PX 1", 2, f"expected {RECORD}, found 'PX'"),
    ("ERR NOTUCH SPH1 1", 5,
     "expected an error code (NOTOUCH, COLLISION, OUTTOL, BIGCORR or BADFIT), found 'NOTUCH'"),
    ("ERR NOTOUCH SPH1", 17, "expected an index, found end of line"),
    ("PGEND", 6, "expected a program number (O and digits), found end of line"),
    ("PT SPH1 0 X1 Y2 Z3", 9, "expected an index from 1 to 999999, found '0'"),
    ("PT SPH1 1234567 X1 Y2 Z3", 9, "expected an index from 1 to 999999, found '1234567'"),
    (
        "PT ABCDEFGHIJKLMNOPQ 1 X1 Y2 Z3",
        4,
        "expected a feature id of at most 16 characters, found 'ABCDEFGHIJKLMNOPQ' (17 characters)",
    ),
    ("PT SPH1 1 X1\x07 Y2 Z3", 13, "expected 'Y', found control character 0x07"),
    ("PT SPH1 1 X1 Yé2 Z3", 15, "expected a number, found non-ASCII character 'é' (U+00E9)"),
    ("PT SPH1 1 X" + "9" * 400 + " Y2 Z3", 12, "number '" + "9" * 400 + "' is out of range"),
    ("PT SPH1 1 X1 Y2 Z3 " + "J" * 30, 20, "expected end of line, found '" + "J" * 24 + "...'"),
]


@pytest.mark.parametrize(("line", "column", "message"), MALFORMED)
def test_malformed_line_diagnostic(line: str, column: int, message: str) -> None:
    log = parse_dprnt(HEAD + line + "\nPT OK 1 X1 Y2 Z3\n", source="run.log")
    (diag,) = log.diagnostics
    assert (diag.source, diag.line, diag.column, diag.message) == ("run.log", 2, column, message)
    assert [t.feature for t in log.touches] == ["OK"]  # the next good line is kept


def test_diagnostic_caret_display() -> None:
    log = parse_dprnt(HEAD + "  PT SPH1 13 X1 Y2\n")
    assert str(log.diagnostics[0]) == (
        "<string>:2:19: expected 'Z', found end of line\n"
        "      PT SPH1 13 X1 Y2\n"
        "                      ^"
    )


def test_control_characters_shown_as_pictures() -> None:
    (diag,) = parse_dprnt(HEAD + "PT A 1 X1\x07 Y2 Z3\n").diagnostics
    assert diag.text == "PT A 1 X1\u2407 Y2 Z3"
    assert str(diag).endswith("    PT A 1 X1\u2407 Y2 Z3\n             ^")


def test_undecodable_byte_diagnosed_by_value() -> None:
    log = parse_dprnt(b"PGSTART O1001 V1\nPT A 1 X1 Y\xc12 Z3\nPT B 1 X1 Y2 Z3\n")
    (diag,) = log.diagnostics
    assert (diag.line, diag.column) == (2, 12)
    assert diag.message == (
        "expected a number, found undecodable byte 0xC1 "
        "(not 7-bit ASCII: check the port is set to 7 data bits, even parity)"
    )
    assert diag.text == "PT A 1 X1 Y\ufffd2 Z3"
    str(diag).encode("utf-8")  # printable: no lone surrogates leak out
    assert [t.feature for t in log.touches] == ["B"]


def test_every_line_accounted_for() -> None:
    lines = CLEAN.splitlines()
    lines[3] = "LOC SPH1 2 X12.3456 Y0.0000"
    lines[6] = "PT SPH1 2 X0.0000 Y12.5 Z-3.25 garbage"
    log = parse_dprnt("\n".join(lines))
    assert [d.line for d in log.diagnostics] == [4, 7]
    assert [t.line for t in log.touches] == [3, 6, 8]
    assert log.complete


# --- structure: header, end marker, restarts -------------------------------------------


def test_restart_keeps_both_runs() -> None:
    text = (
        "PGSTART O1001 V1\n"
        "PT SPH1 1 X1 Y1 Z1\n"
        "PT SPH1 2 X2 Y2 Z2\n"
        "ERR NOTOUCH SPH1 3\n"
        "%\n%\n"
        "PGSTART O1001 V1\n"
        "PT SPH1 2 X2.5 Y2 Z2\n"
        "PT SPH1 3 X3 Y3 Z3\n"
        "PGEND O1001\n"
    )
    log = parse_dprnt(text, strict=True)
    assert log.restarts == 1 and log.complete and log.program == 1001
    assert log.errors == (ProgramError("NOTOUCH", "SPH1", 3, 4, 0),)
    assert [(t.index, t.run, t.line) for t in log.touches] == [
        (1, 0, 2),
        (2, 0, 3),
        (2, 1, 8),
        (3, 1, 9),
    ]
    assert [(t.index, t.xyz[0]) for t in log.latest_touches()] == [(1, 1.0), (2, 2.5), (3, 3.0)]


def test_restart_without_end_is_incomplete() -> None:
    log = parse_dprnt("PGSTART O5 V1\nPGEND O5\nPGSTART O5 V1\nPT A 1 X1 Y1 Z1\n")
    assert log.restarts == 1 and not log.complete and not log.diagnostics
    assert log.touches[0].run == 1


def test_log_without_end_marker() -> None:
    log = parse_dprnt(CLEAN.replace("PGEND O1001\n", ""))
    assert not log.complete and not log.diagnostics
    assert log.touches == EXPECTED.touches


def test_error_record_codes() -> None:
    log = parse_dprnt(HEAD + "ERR collision BORE7 4\n")
    assert log.errors == (ProgramError("COLLISION", "BORE7", 4, 2),)


STRUCTURE = [
    (
        "PT A 1 X1 Y2 Z3\n" + HEAD,
        1,
        1,
        "expected the PGSTART header before the first record (was the capture started late?)",
    ),
    (
        HEAD + "PGEND O1001\nPT A 1 X1 Y2 Z3\n",
        3,
        1,
        "expected PGSTART to begin a new run, found a record after PGEND (line 2)",
    ),
    (HEAD + "PGEND O1002\n", 2, 1, "expected PGEND O1001 (the program started), found PGEND O1002"),
    (
        HEAD + "PGSTART O1002 V1\n",
        2,
        1,
        "expected program O1001 (as in the first header), found O1002: one log per program",
    ),
    ("PGSTART O1001 V3\n", 1, 15, "expected format version V1 to V2, found V3"),
    ("PGSTART O0 V1\n", 1, 9, "expected a program number from O1 to O99999999, found 'O0'"),
]


@pytest.mark.parametrize(("text", "line", "column", "message"), STRUCTURE)
def test_structure_diagnostics(text: str, line: int, column: int, message: str) -> None:
    (diag,) = parse_dprnt(text).diagnostics
    assert (diag.line, diag.column, diag.message) == (line, column, message)


def test_headless_log_reported_once_and_kept() -> None:
    log = parse_dprnt("PT A 1 X1 Y2 Z3\nPT A 2 X1 Y2 Z3\nPGEND O9\n")
    assert len(log.diagnostics) == 1
    assert len(log.touches) == 2 and log.complete and log.program == 9


def test_strict_raises_with_every_diagnostic() -> None:
    text = HEAD + "".join(f"PT A {i} X1 Y2\n" for i in range(1, 13))
    with pytest.raises(ResultsParseError) as info:
        parse_dprnt(text, source="m.log", strict=True)
    err = info.value
    assert len(err.diagnostics) == 12
    assert all(isinstance(d, Diagnostic) for d in err.diagnostics)
    message = str(err)
    assert message.startswith("m.log: 12 problems in the DPRNT log\nm.log:2:13: expected 'Z'")
    assert message.endswith("... and 2 more")


# --- no surprise exceptions, no hangs ---------------------------------------------------

ALPHABET = "PGSTARTENDLOCXYZ0123456789.-+ %\t\r\n\x00\x11\x12\x13\x14\x07é_o"


def _check(log: DprntLog, text: str | bytes) -> None:
    lines = len(text.splitlines()) + 1
    for diag in log.diagnostics:
        assert 1 <= diag.line <= lines
        assert diag.column >= 1
        str(diag).encode("utf-8")
    for touch in log.touches:
        assert all(math.isfinite(v) for v in touch.xyz)


def _parse_both(text: str | bytes) -> None:
    _check(parse_dprnt(text), text)
    try:
        parse_dprnt(text, strict=True)
    except ResultsParseError as err:
        assert err.diagnostics


FUZZ = settings(max_examples=examples(150), suppress_health_check=[HealthCheck.too_slow])


@FUZZ
@given(st.text())
def test_random_text_never_crashes(text: str) -> None:
    _parse_both(text)


@FUZZ
@given(st.binary())
def test_random_bytes_never_crash(data: bytes) -> None:
    _parse_both(data)


@st.composite
def mutated_log(draw: st.DrawFn) -> str:
    return mutate(draw, CLEAN, ALPHABET)


@FUZZ
@given(mutated_log())
def test_mutated_log_never_crashes(text: str) -> None:
    _parse_both(text)
    log = parse_dprnt(text)
    assert len(log.touches) + len(log.diagnostics) >= 1


def test_import_loads_no_cad_or_templates() -> None:
    code = (
        "import sys, probegen.results\n"
        "bad = [m for m in sys.modules if m.split('.')[0] in ('OCP', 'build123d', 'jinja2')]\n"
        "assert not bad, bad\n"
    )
    subprocess.run([sys.executable, "-c", code], check=True)


def test_header_after_headless_records_is_a_restart() -> None:
    log = parse_dprnt("PT A 1 X1 Y1 Z1\nPGSTART O5 V1\nPT A 1 X2 Y1 Z1\nPGEND O5\n")
    assert log.restarts == 1 and log.complete
    assert [(t.run, t.xyz[0]) for t in log.touches] == [(0, 1.0), (1, 2.0)]
    assert [t.xyz[0] for t in log.latest_touches()] == [2.0]


def test_pgcal_names_the_programs_calibration() -> None:
    log = parse_dprnt("PGSTART O1003 V1\nPGCAL C61E692BB\nPT B 1 X1. Y2. Z3.\nPGEND O1003\n")
    assert [(m.fingerprint, m.line) for m in log.calibrations] == [("C61E692BB", 2)]
    assert not log.diagnostics
    bad = parse_dprnt("PGSTART O1003 V1\nPGCAL\nPGEND O1003\n")
    assert bad.calibrations == () and len(bad.diagnostics) == 1
    assert bad.diagnostics[0].line == 2


def test_pgserial_names_the_parts_serial() -> None:
    log = parse_dprnt("PGSTART O1003 V1\nPGSERIAL   4711.\nPT B 1 X1. Y2. Z3.\nPGEND O1003\n"
                      "PGSTART O1003 V1\npgserial sn-0042/b\nPGEND O1003\n")
    assert [(m.serial, m.line, m.run) for m in log.serials] == [("4711", 2, 0),
                                                                ("SN-0042/B", 6, 1)]
    assert log.serial == "SN-0042/B" and not log.diagnostics
    long = "PGSTART O1003 V1\nPGSERIAL " + "9" * 33 + "\nPGEND O1003\n"
    bad = parse_dprnt(long)
    assert bad.serials == () and bad.serial is None
    assert [(d.line, d.column) for d in bad.diagnostics] == [(2, 10)]
    assert "at most 32 characters" in bad.diagnostics[0].message
    empty = parse_dprnt("PGSTART O1003 V1\nPGSERIAL\nPGEND O1003\n")
    assert "expected a serial number" in empty.diagnostics[0].message


SERIAL_LOG = ("PGSTART O1001 V1\nPGSERIAL SN-0042\nPT SPH1 1 X1. Y2. Z3.\nPGEND O1001\n"
              "PGSTART O1001 V1\nPGSERIAL 4711.\nPGEND O1001\n")


@st.composite
def mutated_serial_log(draw: st.DrawFn) -> str:
    return mutate(draw, SERIAL_LOG, "PGSERIAL0123456789.-_/ \n\t%é")


@FUZZ
@given(mutated_serial_log())
def test_mutated_serial_lines_give_a_serial_or_a_diagnostic(text: str) -> None:
    _parse_both(text)
    log = parse_dprnt(text)
    allowed = set("ABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789._/-")
    for mark in log.serials:
        assert 1 <= len(mark.serial) <= 32 and set(mark.serial) <= allowed
    assert log.serial is None or log.serial in {m.serial for m in log.serials}
