"""The M5 readings and roll CSV formats: round trip, clear errors, never another exception."""

from __future__ import annotations

from pathlib import Path

import pytest
from fuzzing import examples
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from mutations import mutate

from probegen.calibrate.grating_io import (
    CalibrationDataError,
    GratingReading,
    LevelReading,
    format_level,
    format_readings,
    read_level,
    read_readings,
)
from probegen.errors import ProbegenError

ROWS = [GratingReading("XY", "L10", 0, (-100.0, -100.0, -200.0), 0.0, 100.0, 1.25, -0.5),
        GratingReading("XY", "L10", 1, (0.0, -100.0, -200.0), 50.0, 100.0, 0.75, 0.125),
        GratingReading("XZ", "L24", 3, (-100.0, 50.0, -150.0), 50.0, 100.0, -2.0, 3.5)]
CLEAN = format_readings(ROWS)


def write(tmp_path: Path, text: str | bytes, name: str = "r.csv") -> Path:
    path = tmp_path / name
    if isinstance(text, bytes):
        path.write_bytes(text)
    else:
        path.write_text(text, encoding="utf-8")
    return path


def test_round_trip_and_riser_moves_the_point_towards_the_head(tmp_path: Path) -> None:
    got = read_readings(write(tmp_path, CLEAN))
    assert [(r.plane, r.line, r.index, r.base, r.offset, r.du, r.dv) for r in got] == [
        (r.plane, r.line, r.index, r.base, r.offset, r.du, r.dv) for r in ROWS]
    assert got[1].point == (0.0, -100.0, -150.0)  # XY: riser lifts the grating (+Z)
    assert got[2].point == (-100.0, 0.0, -150.0)  # XZ: towards the head (-Y)


def test_columns_in_any_order_offset_optional(tmp_path: Path) -> None:
    text = ("# a comment\n\ndv_um,du_um,plane,line,index,x_mm,y_mm,z_mm,head_mm\n"
            "0.5,1.5,yz,L30,0,0,1,2,100\n")
    (r,) = read_readings(write(tmp_path, text))
    assert (r.plane, r.du, r.dv, r.offset, r.point) == ("YZ", 1.5, 0.5, 0.0, (0.0, 1.0, 2.0))


@pytest.mark.parametrize(("text", "message"), [
    ("", "expected a header row"),
    ("plane,line,index\n", "expected columns"),
    (CLEAN.replace("XY,L10,0", "XQ,L10,0"), r"r.csv:3: plane: expected XY, XZ or YZ"),
    (CLEAN.replace("1.25000", "nan"), r"r.csv:3: du_um: expected a finite number"),
    (CLEAN.replace("-0.50000", "1e9"), r"r.csv:3: dv_um: expected a finite number"),
    (CLEAN + CLEAN.split("\n")[2] + "\n", r"found XY L10 0 again \(first at .*r.csv:3\)"),
    (CLEAN.replace("L10,1", "L10,-1"), "index: expected an integer"),
    (CLEAN.replace("50.0000\n", "-5.0000\n", 1), "offset_mm: expected a finite number >= 0"),
    (CLEAN + "XY,L12,0,1,2\n", r"r.csv:6: expected 10 fields, found 5"),
    (CLEAN.split("\n", 2)[0] + "\n" + CLEAN.split("\n", 2)[1] + "\n", "expected at least one"),
])
def test_bad_readings_say_where_what_and_found(tmp_path: Path, text: str,
                                                message: str) -> None:
    with pytest.raises(CalibrationDataError, match=message):
        read_readings(write(tmp_path, text))


def test_not_utf8_and_missing_file(tmp_path: Path) -> None:
    with pytest.raises(CalibrationDataError, match="UTF-8"):
        read_readings(write(tmp_path, b"plane\xff\n"))
    with pytest.raises(CalibrationDataError, match="none.csv: expected a CSV file, found no "
                                                   "such file"):
        read_readings(tmp_path / "none.csv")
    with pytest.raises(CalibrationDataError, match="expected a CSV file, found a folder"):
        read_readings(tmp_path)


def test_reading_never_modifies_the_raw_file(tmp_path: Path) -> None:
    path = write(tmp_path, CLEAN)
    before = (path.read_bytes(), path.stat().st_mtime_ns)
    read_readings(path)
    assert (path.read_bytes(), path.stat().st_mtime_ns) == before


def test_level_round_trip_and_z_rejected(tmp_path: Path) -> None:
    rows = [LevelReading("X", -100.0, 1.5), LevelReading("Y", 20.0, -0.25)]
    got = read_level(write(tmp_path, format_level(rows), "l.csv"))
    assert [(r.axis, r.position, r.roll) for r in got] == [("X", -100.0, 1.5),
                                                          ("Y", 20.0, -0.25)]
    bad = format_level(rows).replace("Y,20", "Z,20")
    with pytest.raises(CalibrationDataError, match=r"l.csv:3: axis: expected X or Y"):
        read_level(write(tmp_path, bad, "l.csv"))


FUZZ = settings(max_examples=examples(150), suppress_health_check=[
    HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
ALPHABET = "0123456789.,-+eE\n\r\"# XYZLnaif_"


@st.composite
def mutated(draw: st.DrawFn) -> str:
    return mutate(draw, CLEAN, ALPHABET)


@FUZZ
@given(mutated())
def test_mutated_readings_end_in_a_result_or_a_probegen_error(tmp_path: Path,
                                                             text: str) -> None:
    try:
        read_readings(write(tmp_path, text))
    except ProbegenError:
        pass


@FUZZ
@given(st.binary(max_size=300))
def test_random_bytes_end_in_a_result_or_a_probegen_error(tmp_path: Path,
                                                         data: bytes) -> None:
    for reader in (read_readings, read_level):
        try:
            reader(write(tmp_path, data))
        except ProbegenError:
            pass


LEVEL = format_level([LevelReading("X", -100.0, 1.5), LevelReading("Y", 20.0, -0.25)])


@st.composite
def mutated_level(draw: st.DrawFn) -> str:
    return mutate(draw, LEVEL, ALPHABET)


@FUZZ
@given(mutated_level())
def test_mutated_level_ends_in_a_result_or_a_probegen_error(tmp_path: Path,
                                                           text: str) -> None:
    try:
        read_level(write(tmp_path, text))
    except ProbegenError:
        pass


SPEC_TEXT = (Path(__file__).resolve().parent.parent / "samples" / "grating"
             / "grating.toml").read_text(encoding="utf-8")


@st.composite
def mutated_spec(draw: st.DrawFn) -> str:
    return mutate(draw, SPEC_TEXT, "0123456789.-[],=\n #\"XYZuvwrise")


@FUZZ
@given(mutated_spec())
def test_mutated_grating_spec_ends_in_a_spec_or_a_probegen_error(tmp_path: Path,
                                                                text: str) -> None:
    from probegen.cli.grating import grating_programs
    from probegen.planning.grating import load_grating_spec

    try:
        spec = load_grating_spec(str(write(tmp_path, text, "g.toml")))
    except ProbegenError:
        return
    try:
        grating_programs(spec, second_offset=True)
    except ProbegenError:
        pass
