"""The Fanuc Macro B interpreter of the virtual machine: grammar, expressions, control flow,
calls, coordinates, DPRNT, alarms, the shared reference programs and our own goldens."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import pytest
from conftest import assert_golden
from fuzzing import examples
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from probegen.errors import ProbegenError, ProgramParseError
from probegen.results import parse_dprnt
from probegen.sim.alarms import SimAlarm
from probegen.sim.macrob import ast
from probegen.sim.macrob.base import control_settings
from probegen.sim.macrob.dprnt import format_value
from probegen.sim.macrob.machine import (
    FreeMachine,
    Machine,
    Point,
    RunResult,
    Settings,
    run_program,
)
from probegen.sim.macrob.parse import parse_program, read_program

TESTS = Path(__file__).resolve().parent
DATA = TESTS / "data" / "macrob"
REF = Path(__file__).resolve().parents[2] / "shared" / "ref" / "macro-b"
REF_FILES = tuple(sorted(REF.glob("*.NC")))
GOLDENS = tuple(sorted(p for p in (TESTS / "golden").glob("*/*.nc")
                       if p.parent.name not in ("macros", "split", "orient", "setups")))
"""The golden inline programs (the macro library and the compact program that calls it:
tests/test_macro_library.py, which runs them against the inline form; a split program's
driver and part: tests/test_program_limits.py, which runs them against the unsplit one;
the hand-made orientation and stylus-change programs, short and compact:
tests/test_orient_dialects.py; the setup programs, compact: tests/test_setups.py, which
runs them on the virtual machine)."""
HAAS = control_settings("haas")
"""Haas goldens cancel mirror imaging with G100 where Fanuc writes G50.1."""


def settings_for(path: Path) -> Settings | None:
    """The control settings a golden program needs (Haas codes read as Fanuc's)."""
    return HAAS if path.name.endswith(".haas.nc") else None
BROTHER = Settings(g_aliases={100: 0, 131: 31})
"""The reference programs are for a Brother control: G100 = tool change with
positioning, G131 = skip; read as G0 and G31 they run on the virtual Fanuc."""

needs_ref = pytest.mark.skipif(not REF_FILES, reason="shared reference programs not present")


class Recorder:
    """A machine with no part that records every call (kind, start, end, feed)."""

    def __init__(self) -> None:
        self.moves: list[tuple[str, Point, Point, float]] = []

    def rapid(self, start: Point, end: Point) -> None:
        self.moves.append(("rapid", start, end, 0.0))

    def feed(self, start: Point, end: Point, feed_mm_min: float) -> None:
        self.moves.append(("feed", start, end, feed_mm_min))

    def skip(self, start: Point, end: Point, feed_mm_min: float) -> Point | None:
        self.moves.append(("skip", start, end, feed_mm_min))
        return None


class Fraction:
    """Fires the skip at ``fraction`` of every G31 slower than ``below`` mm/min."""

    def __init__(self, fraction: float = 0.5, below: float = 1000.0) -> None:
        self.fraction, self.below = fraction, below
        self.hits: list[Point] = []

    def rapid(self, start: Point, end: Point) -> None:
        pass

    def feed(self, start: Point, end: Point, feed_mm_min: float) -> None:
        pass

    def skip(self, start: Point, end: Point, feed_mm_min: float) -> Point | None:
        if feed_mm_min >= self.below:
            return None
        f = self.fraction
        x, y, z = (a + (b - a) * f for a, b in zip(start, end, strict=True))
        self.hits.append((x, y, z))
        return x, y, z

    def rotate(self, start: dict[str, float], end: dict[str, float], at: Point) -> None:
        pass


class FirstSkip(Fraction):
    """Fires on the very first G31 move only (the first protected move of our programs)."""

    def skip(self, start: Point, end: Point, feed_mm_min: float) -> Point | None:
        if self.hits:
            return None
        self.hits.append(start)
        return start


class Crash:
    """Raises a collision alarm on the first rapid move."""

    def rapid(self, start: Point, end: Point) -> None:
        raise SimAlarm(4000, "STYLUS HITS PART")

    def feed(self, start: Point, end: Point, feed_mm_min: float) -> None:
        pass

    def skip(self, start: Point, end: Point, feed_mm_min: float) -> Point | None:
        return None


def run(text: str, machine: Machine | None = None, **kwargs: Any) -> RunResult:
    return run_program(text, machine or FreeMachine(), **kwargs)


def value(expression: str) -> float | None:
    return run(f"#1={expression}").variables.get(1)


def alarm_of(text: str, **kwargs: Any) -> int:
    result = run(text, **kwargs)
    assert result.stopped == "alarm" and result.alarm is not None, result
    return result.alarm.number


def parse_error(text: str) -> str:
    with pytest.raises(ProgramParseError) as info:
        parse_program(text, source="t.nc")
    return str(info.value)


# --- expressions -------------------------------------------------------------------------

@pytest.mark.parametrize(("expression", "expected"), [
    ("2+3*4", 14.0),
    ("1 OR 2 AND 0", 1.0),          # AND groups with *, OR with +
    ("[1 OR 2] AND 0", 0.0),
    ("2*3 MOD 4", 2.0),
    ("10-2-3", 5.0),
    ("12/3/2", 2.0),
    ("-2*-3", 6.0),
    ("2-[3-4]", 3.0),
    ("-[2+3]", -5.0),
    ("1+2 XOR 3", 0.0),
    ("1 XOR 2+3", 6.0),
    ("6 AND 3", 2.0),
    ("5 OR 2", 7.0),
    ("7 MOD 3", 1.0),
    ("-7 MOD 3", -1.0),
    ("7.6 MOD 3", 2.0),
    ("ATAN[1]/[1]", 45.0),
    ("ATAN[1,-1]", 135.0),
    ("ATAN[-1,-1]", 225.0),
    ("ATAN[-1]/[1]", 315.0),
    ("ATAN[1]", 45.0),
    ("ROUND[2.5]", 3.0),
    ("ROUND[-2.5]", -3.0),
    ("ROUND[-2.4]", -2.0),
    ("FIX[1.7]", 1.0),
    ("FIX[-1.2]", -1.0),
    ("FUP[1.2]", 2.0),
    ("FUP[-1.2]", -2.0),
    ("FUP[3]", 3.0),
    ("SIN[30]", 0.5),
    ("SIN[-90]", -1.0),
    ("COS[90]", 0.0),
    ("COS[180]", -1.0),
    ("TAN[45]", 1.0),
    ("ASIN[0.5]", 30.0),
    ("ASIN[-0.5]", 330.0),
    ("ACOS[-1]", 180.0),
    ("SQRT[16]", 4.0),
    ("ABS[-3]", 3.0),
    ("LN[1]", 0.0),
    ("EXP[0]", 1.0),
    ("POW[2,10]", 1024.0),
    ("BIN[18]", 12.0),
    ("BCD[12]", 18.0),
    ("#0+1", 1.0),
    ("#0*3", 0.0),
    ("-#0", 0.0),
    ("SIN[[[[1+29]]]]", 0.5),
])
def test_expression_values(expression: str, expected: float) -> None:
    assert value(expression) == pytest.approx(expected, abs=1e-12)


def test_functions_of_general_angles_and_roots() -> None:
    assert value("SIN[10]") == pytest.approx(math.sin(math.radians(10)), abs=1e-15)
    assert value("ATAN[2]/[3]") == pytest.approx(math.degrees(math.atan2(2, 3)))
    assert value("SQRT[2]*SQRT[2]") == pytest.approx(2.0)


def test_blanks_and_lower_case_are_ignored() -> None:
    assert value(" 2 + 3 * 4 ") == 14.0
    assert run("# 1 = atan [ 1 ] / [ 1 ]").variables[1] == 45.0
    assert run("#1 = 1 0 0 . 5").variables[1] == 100.5


@pytest.mark.parametrize(("text", "number"), [
    ("#1=1/0", 112),
    ("#1=1 MOD 0", 112),
    ("#1=SQRT[-1]", 119),
    ("#1=ASIN[2]", 119),
    ("#1=LN[0]", 119),
    ("#1=EXP[200]", 111),
    ("#1=TAN[90]", 111),
    ("#1=" + "9" * 60, 111),
    ("#1=" + "1" + "0" * 30 + "*" + "1" + "0" * 30, 111),
    ("#1=#[-1]", 115),
    ("#1=#9999", 115),
    ("#5001=1", 116),
    ("#0=1", 116),
])
def test_expression_alarms(text: str, number: int) -> None:
    assert alarm_of(text) == number


# --- vacant variables ---------------------------------------------------------------------

def test_vacant_differs_from_zero_only_in_eq_and_ne() -> None:
    result = run("""#1=#0
#2=0
IF[#1EQ#0]THEN#10=1
IF[#2EQ#0]THEN#11=1
IF[#1EQ0]THEN#12=1
IF[#1NE0]THEN#13=1
IF[#1GE0]THEN#14=1
IF[#1LT1]THEN#15=1
IF[#2EQ0]THEN#16=1
IF[#1GT#0]THEN#17=1
#3=#1
#4=#1*3
""")
    assert result.variables == {2: 0.0, 4: 0.0, 10: 1.0, 13: 1.0, 14: 1.0, 15: 1.0, 16: 1.0}


def test_a_vacant_variable_drops_its_word() -> None:
    machine = Recorder()
    run("G0 X#1 Y5.\nG0 X[#1+2.]", machine)
    assert [m[2] for m in machine.moves] == [(0.0, 5.0, 0.0), (2.0, 5.0, 0.0)]


# --- control flow --------------------------------------------------------------------------

def test_nested_loops_and_a_bare_do_left_by_goto() -> None:
    result = run("""#1=0
#2=0
WHILE[#1LT3]DO1
#3=0
WHILE[#3LT2]DO2
#2=#2+1
#3=#3+1
END2
#1=#1+1
END1
#4=0
DO3
#4=#4+1
IF[#4GE5]GOTO10
END3
N10 #5=1
""")
    assert result.variables == {1: 3.0, 2: 6.0, 3: 2.0, 4: 5.0, 5: 1.0}
    assert result.stopped == "end"


def test_goto_forms_and_if_then() -> None:
    result = run("""#1=0
N5 #1=#1+1
IF[#1LT10]GOTO5
#2=20
GOTO#2
#3=1
N20 GOTO[#2+1]
#4=1
N21 IF[#1EQ10]THEN#5=7 (A COMMENT AFTER THEN)
IF[[#1EQ10]AND[#5EQ7]]THEN#6=1
IF[[#1EQ0]OR[#5EQ7]]THEN#7=1
IF[[#1EQ10]XOR[#5EQ7]]THEN#8=1
""")
    assert result.variables == {1: 10.0, 2: 20.0, 5: 7.0, 6: 1.0, 7: 1.0}


@pytest.mark.parametrize(("text", "number", "line"), [
    ("#1=1\nGOTO 5", 78, 2),
    ("GOTO 0", 128, 1),
    ("#1=1\nWHILE[#1EQ2]DO1\n#2=1", 124, 2),
    ("#1=1\nEND1", 124, 2),
])
def test_control_flow_alarms(text: str, number: int, line: int) -> None:
    result = run(text)
    assert result.alarm is not None
    assert (result.alarm.number, result.alarm.line) == (number, line)


def test_max_blocks_stops_an_endless_loop() -> None:
    result = run("N1 #1=#1+1\nGOTO1", max_blocks=1000)
    assert result.alarm is not None and result.alarm.number == 9000
    assert result.blocks_executed == 1000 and result.variables[1] == 500.0


def test_max_blocks_also_guards_repeated_empty_subprograms() -> None:
    result = run("O1\nM98 P2 L99999999\nM30\nO2\nO3", max_blocks=5000)
    assert result.alarm is not None and result.alarm.number == 9000


def test_tool_change_and_m_codes_are_recorded() -> None:
    result = run("T5 M6\nM19\nT7\nM01\nM30")
    assert (result.tool, result.m_codes) == (5, (6, 19, 1, 30))


@pytest.mark.parametrize(("code", "stopped"), [("M30", "M30"), ("M02", "M02"), ("M2", "M02"),
                                               ("M99", "M99"), ("M05", "end")])
def test_how_a_run_ends(code: str, stopped: str) -> None:
    result = run(f"#1=1\n{code}\n#2=2")
    assert result.stopped == stopped
    assert (2 in result.variables) == (stopped == "end")


def test_m00_continues_unless_asked_to_stop() -> None:
    assert run("M00\n#1=1\nM30").variables == {1: 1.0}
    result = run("M00\n#1=1\nM30", settings=Settings(stop_at_m00=True))
    assert (result.stopped, result.variables, result.m_codes) == ("M00", {}, (0,))


def test_block_delete() -> None:
    text = "/#1=1\n/ #2=2 (DELETED WHEN BLOCK DELETE IS ON)\n#3=3"
    assert run(text).variables == {1: 1.0, 2: 2.0, 3: 3.0}
    assert run(text, block_delete=True).variables == {3: 3.0}


# --- calls ---------------------------------------------------------------------------------

MACRO_COPY = """O100
#30=1
WHILE[#30LE26]DO1
#[500+#30]=#[#30]
#30=#30+1
END1
M99
"""


def test_g65_maps_every_argument_letter() -> None:
    letters = "A B C D E F H I J K M Q R S T U V W X Y Z".split()
    args = " ".join(f"{letter}{i}." for i, letter in enumerate(letters, 1))
    result = run(f"O1\nG65 P100 {args}\nM30\n{MACRO_COPY}")
    locals_ = {n - 500: v for n, v in result.variables.items() if 500 < n <= 526}
    expected = {"A": 1, "B": 2, "C": 3, "I": 4, "J": 5, "K": 6, "D": 7, "E": 8, "F": 9,
                "H": 11, "M": 13, "Q": 17, "R": 18, "S": 19, "T": 20, "U": 21, "V": 22,
                "W": 23, "X": 24, "Y": 25, "Z": 26}
    assert locals_ == {n: float(letters.index(k) + 1) for k, n in expected.items()}


def test_g65_argument_specification_two() -> None:
    result = run(f"O1\nG65 P100 A1. I2. J3. K4. I5. J6. K7. I8.\nM30\n{MACRO_COPY}")
    assert {n - 500: v for n, v in result.variables.items() if 500 < n <= 526} == {
        1: 1.0, 4: 2.0, 5: 3.0, 6: 4.0, 7: 5.0, 8: 6.0, 9: 7.0, 10: 8.0}


def test_g65_local_levels_and_vacant_arguments() -> None:
    result = run("""O1
#1=5.
G65 P2 A1. T#101
#100=#1
M30
O2
IF[#20EQ#0]THEN#500=1
#501=#1
#1=99.
G65 P3 B2.
#502=#1
M99
O3
#503=#2
#504=#1
#1=77.
M99
""")
    assert result.variables == {1: 5.0, 100: 5.0, 500: 1.0, 501: 1.0, 502: 99.0, 503: 2.0}


def test_g65_repeats_and_its_alarms() -> None:
    assert run("O1\nG65 P2 L3\nM30\nO2\n#500=#500+1\nM99").variables == {500: 3.0}
    assert alarm_of("O1\nG65 P1\nM30") == 77           # endless recursion: nesting limit
    assert alarm_of("O1\nG65 P2 G1\nM30\nO2\nM99") == 129
    assert alarm_of("G65 P77") == 76


def test_m98_in_the_same_text_and_from_the_program_directory() -> None:
    text = (DATA / "calls.nc").read_text()
    result = run(text, source="calls.nc", program_dir=DATA)
    assert result.stopped == "M30" and result.alarm is None
    assert result.variables == {1: 14.0, 100: 6.0, 101: 13.0, 102: 13.0, 103: 6.0}


def test_program_files_are_found_by_number(tmp_path: Path) -> None:
    (tmp_path / "O0200.NC").write_text("#500=200\nM99\n")
    (tmp_path / "O300").write_text("%\nO300\n#501=300\nM99\n%\n")
    (tmp_path / "O4000.nc").write_text("O4000 (FOUR)\n#502=4000\nM99\n")
    result = run("M98 P200\nM98 P300\nG65 P4000\nM30", program_dir=tmp_path)
    assert result.variables == {500: 200.0, 501: 300.0, 502: 4000.0}
    missing = run("M98 P201", program_dir=tmp_path)
    assert missing.alarm is not None and missing.alarm.number == 76
    assert "O201" in missing.alarm.message


def test_an_alarm_in_a_subprogram_file_names_that_file(tmp_path: Path) -> None:
    (tmp_path / "O0010.nc").write_text("#1=1\n#3000=5 (IN THE SUB)\nM99\n")
    result = run("M98 P10", program_dir=tmp_path)
    assert result.alarm is not None
    assert (result.alarm.number, result.alarm.line, result.alarm.message) == (3005, 2,
                                                                              "IN THE SUB")
    assert result.alarm.source == str(tmp_path / "O0010.nc")


def test_m99_p_returns_to_a_sequence_number_and_m98_repeats() -> None:
    result = run("O1\nM98 P2\n#1=1\nN50 #2=2\nM98 P3 L4\nM30\nO2\nM99 P50\nO3\n#3=#3+1\nM99")
    assert result.variables == {2: 2.0, 3: 4.0}
    assert alarm_of("O1\nM98 P1") == 77


# --- coordinates and motion -----------------------------------------------------------------

def test_g10_l2_then_g54_and_g55_moves() -> None:
    machine = Recorder()
    result = run("""G21 G90
G10 L2 P1 X100. Y50. Z-200.
G10 L2 P2 X10. Y20. Z30.
G54 G0 X1. Y2. Z3.
#100=#5021
#101=#5041
#102=#5001
G55 G0 X0 Y0
#103=#5041
#104=#5023
#105=#4014
""", machine)
    assert [m[2] for m in machine.moves] == [(101.0, 52.0, -197.0), (10.0, 20.0, -197.0)]
    assert result.variables == {100: 101.0, 101: 1.0, 102: 1.0, 103: 0.0, 104: -197.0,
                                105: 55.0, 5221: 100.0, 5222: 50.0, 5223: -200.0,
                                5241: 10.0, 5242: 20.0, 5243: 30.0}


def test_work_offset_variables_g10_l20_and_g54_1() -> None:
    machine = Recorder()
    result = run("""#5221=5.
G10 L20 P2 X7. Y8.
G91 G10 L20 P2 X1.
G90 G54 G0 X1.
G54.1 P2 G0 X1. Y1.
#100=#4130
#101=#7022
#5222=3.
G54 G0 Y0
""", machine)
    assert [m[2] for m in machine.moves] == [(6.0, 0.0, 0.0), (9.0, 9.0, 0.0), (9.0, 3.0, 0.0)]
    assert result.variables[100] == 2.0 and result.variables[101] == 8.0
    assert result.variables[14021] == 8.0


def test_g91_incremental_moves() -> None:
    machine = Recorder()
    result = run("G90 G0 X1. Y1.\nG91 G0 X2.\nG1 Y-3. Z4. F100.\n#1=#5041\n#2=#4003", machine)
    assert [m[2] for m in machine.moves] == [(1.0, 1.0, 0.0), (3.0, 1.0, 0.0),
                                             (3.0, -2.0, 4.0)]
    assert result.variables == {1: 3.0, 2: 91.0}


def test_g20_inch_moves_are_converted_and_variables_stay_inch() -> None:
    machine = Recorder()
    result = run("G20 G90 G0 X1. Y2.\nG1 Z-1. F10.\n#1=#5041\n#2=#5023\n#3=#4006\n#4=#4109",
                 machine)
    assert machine.moves[0][2] == pytest.approx((25.4, 50.8, 0.0))
    assert machine.moves[1][2] == pytest.approx((25.4, 50.8, -25.4))
    assert machine.moves[1][3] == pytest.approx(254.0)
    assert result.variables == pytest.approx({1: 1.0, 2: -1.0, 3: 20.0, 4: 10.0})


def test_integer_axis_values_count_input_increments_unless_calculator_input() -> None:
    machine = Recorder()
    run("G0 X10 Y10.\nG20 G0 Z10", machine)
    assert [c for m in machine.moves for c in m[2]] == pytest.approx([0.01, 10.0, 0.0,
                                                                      0.01, 10.0, 0.0254])
    machine = Recorder()
    run("G0 X10 Y10.", machine, settings=Settings(calculator_input=True))
    assert machine.moves[0][2] == (10.0, 10.0, 0.0)


def test_tool_length_g43_g44_g49_g53_g28() -> None:
    machine = Recorder()
    result = run("""G43 H20 G0 Z10.
#100=#5023
#101=#5043
#102=#5083
G44 H20 Z10.
G49 Z10.
G53 Z-5.
#103=#5043
G28 Z20.
""", machine, variables={11020: 150.0, 2020: 0.5})
    assert [m[2][2] for m in machine.moves] == [160.5, -140.5, 10.0, -5.0, 20.0, 0.0]
    assert {k: result.variables[k] for k in (100, 101, 102, 103)} == {
        100: 160.5, 101: 10.0, 102: 150.5, 103: -5.0}


def test_g10_tool_offsets() -> None:
    result = run("G10 L10 P3 R100.\nG10 L11 P3 R0.5\nG91 G10 L11 P3 R0.25\n#1=#11003+#10003")
    assert result.variables[1] == 100.75


@pytest.mark.parametrize(("text", "number"), [
    ("G1 X1.", 11),
    ("G31 X1.", 11),
    ("G2 X1. Y1. I1. F100.", 9010),
    ("G41 D1", 9010),
    ("G51 X0 Y0 P2.", 9010),
    ("G18 G68 X0 Z0 R10.", 9010),
    ("G0 A90.", 9010),
    ("G100 X1.", 10),
    ("G10 L2 P9 X1.", 9011),
])
def test_motion_alarms(text: str, number: int) -> None:
    assert alarm_of(text) == number


def test_machine_alarms_stop_the_run_at_the_program_line() -> None:
    result = run("#1=1\nG0 X10.\n#2=2", Crash())
    assert result.alarm is not None
    assert (result.alarm.number, result.alarm.message, result.alarm.line) == (
        4000, "STYLUS HITS PART", 2)
    assert result.variables == {1: 1.0}


def test_skip_positions_convert_back_to_work_coordinates() -> None:
    machine = Fraction(0.25)
    result = run("G54 G43 H1 G0 X0 Y0 Z10.\nG31 X8. Z2. F100.\n#1=#5061\n#2=#5063\n"
                 "G31 X8. Z2. F5000.\n#3=#5061\n#4=#5063", machine,
                 variables={5221: 100.0, 5223: -50.0, 11001: 20.0})
    assert machine.hits == [(102.0, 0.0, -22.0)]
    assert {k: result.variables[k] for k in (1, 2, 3, 4)} == {1: 2.0, 2: 8.0, 3: 8.0, 4: 2.0}


def test_timer_and_modal_variables() -> None:
    result = run("#3001=0\nG1 X100. F1000.\n#100=#3001\n#101=#4001\n#102=#4109\n#103=#4003")
    assert result.variables == {100: 6000.0, 101: 1.0, 102: 1000.0, 103: 90.0}


# --- DPRNT and system alarms ----------------------------------------------------------------

@pytest.mark.parametrize(("number", "fmt", "suppressed", "blanks"), [
    (12.3456, "53", "12.346", "    12.346"),
    (-0.5, "53", "-.500", "     -.500"),
    (0.0, "53", ".000", "      .000"),
    (None, "44", ".0000", "     .0000"),
    (12345.678, "53", "12345.678", " 12345.678"),
    (12345.678, "33", "345.678", " 345.678"),      # too large: the high digits are lost
    (123.456, "20", "23", " 23"),
    (-0.0001, "43", ".000", "     .000"),           # never '-.000'
    (2.5, "10", "3", " 3"),
    (-12.3456, "44", "-12.3456", "  -12.3456"),
])
def test_dprnt_number_format(number: float | None, fmt: str, suppressed: str,
                             blanks: str) -> None:
    digits, decimals = int(fmt[0]), int(fmt[1])
    assert format_value(number, digits, decimals) == suppressed
    assert format_value(number, digits, decimals, blanks=True) == blanks


def test_popen_dprnt_pclos_output() -> None:
    text = """#100=12.3456
#101=-0.5
POPEN
DPRNT[A#100[53]*B#101[53]*C#102[53]]
dprnt[**x*#100[20]]
DPRNT[]
PCLOS
"""
    assert run(text).output == "%\nA12.346 B-.500 C.000\n  X 12\n\n%\n"
    blanks = run(text, settings=Settings(dprnt_blanks=True, dprnt_eol="\r\n")).output
    assert blanks == "%\r\nA    12.346 B     -.500 C      .000\r\n  X  12\r\n\r\n%\r\n"


def test_dprnt_before_popen_is_an_alarm() -> None:
    assert alarm_of("DPRNT[X]") == 9001
    assert alarm_of("POPEN\nPCLOS\nDPRNT[X]") == 9001


def test_macro_alarm_3000_with_its_message() -> None:
    result = run("POPEN\nDPRNT[BEFORE]\n#3000=1(PROBE DID NOT TOUCH)\nDPRNT[AFTER]",
                 source="p.nc")
    assert result.alarm is not None and result.stopped == "alarm"
    assert (result.alarm.number, result.alarm.message, result.alarm.line) == (
        3001, "PROBE DID NOT TOUCH", 3)
    assert str(result.alarm) == "p.nc:3: alarm 3001 PROBE DID NOT TOUCH"
    assert result.output == "%\nBEFORE\n"


def test_3006_stops_with_a_message() -> None:
    result = run("#1=1\n#3006=1 (TURN THE PART OVER)\n#2=2")
    assert (result.stopped, result.message, result.alarm) == ("message", "TURN THE PART OVER",
                                                              None)
    assert result.variables == {1: 1.0}


def test_presetting_variables() -> None:
    result = run("#1=#3700+#500+#1", variables={3700: 5.0, 500: 2.0, 1: 1.0})
    assert result.variables == {1: 8.0, 500: 2.0, 3700: 5.0}
    with pytest.raises(ValueError, match="#5001"):
        run("", variables={5001: 1.0})


# --- the grammar ----------------------------------------------------------------------------

def test_blocks_parse_into_nodes() -> None:
    parsed = parse_program("%\nO1 (MAIN)\nn10 g1 x[#101 + 1.5] F300.(FEED)\n"
                           "IF [#1 EQ #0] THEN #2 = #[#3] (NOTE)\n/GOTO#4\n%\nGARBAGE AFTER %")
    (program,) = parsed.programs
    assert program.number == 1
    first, second, third = program.blocks
    assert first == ast.Block(3, False, 10, ast.Words((
        ast.Word("G", ast.Num(1.0, False)),
        ast.Word("X", ast.Binary("+", ast.Var(101), ast.Num(1.5))),
        ast.Word("F", ast.Num(300.0)))), "FEED")
    assert second.statement == ast.IfThen(
        ast.Compare("EQ", ast.Var(1), ast.Var(0)),
        ast.Assign(ast.Var(2), ast.Indirect(ast.Var(3))))
    assert second.comment == "NOTE"
    assert third.delete and third.statement == ast.Goto(ast.Var(4))


def test_several_programs_and_an_unnumbered_one() -> None:
    parsed = parse_program("(HEAD)\n#1=1\nO2\n#2=2\n:3\n#3=3\n")
    assert [(p.number, len(p.blocks)) for p in parsed.programs] == [(None, 1), (2, 1), (3, 1)]
    assert parsed.find(3) is parsed.programs[2] and parsed.find(4) is None


def test_dprnt_text_keeps_its_numbers() -> None:
    (block,) = parse_program("DPRNT[PT*SPH1*12*X#5061[44]*.5*1.]").programs[0].blocks
    assert block.statement == ast.Dprnt(("PT*SPH1*12*X", ast.DprntVar(5061, 4, 4), "*.5*1."))


def test_syntax_errors_are_golden() -> None:
    with pytest.raises(ProgramParseError) as info:
        read_program(DATA / "errors.nc")
    assert len(info.value.diagnostics) == 10
    assert_golden(DATA / "errors.txt", str(info.value).replace(str(DATA), "DATA") + "\n")


def test_a_syntax_error_names_line_column_expected_and_found() -> None:
    assert parse_error("#1=1\nG0 X1.\nIF[#1 EQ 1] GOTO") == (
        "t.nc:3:17: expected '#', a whole number or '[', found end of block\n"
        "    IF[#1 EQ 1] GOTO\n"
        "                    ^")
    assert "comments do not nest" in parse_error("(A (B) C)")
    assert "at most 256 characters" in parse_error("#1=" + "1+" * 200 + "1")


@needs_ref
@pytest.mark.parametrize("path", REF_FILES, ids=lambda p: p.name)
def test_reference_programs_parse(path: Path) -> None:
    parsed = read_program(path)
    assert len(parsed.programs) == 1 and parsed.programs[0].blocks


@pytest.mark.parametrize("path", GOLDENS, ids=lambda p: f"{p.parent.name}/{p.name}")
def test_golden_programs_parse(path: Path) -> None:
    (program,) = read_program(path).programs
    assert program.number and len(program.blocks) > 100


# --- the shared reference programs (Brother tool setter macros) ------------------------------

REF_VARIABLES = {20: 3.0, 8: 0.05, 3700: 5.0, 11005: 150.0}
"""T3 to measure (#20), break-check tolerance E (#8), the tool in the spindle (#3700,
a Brother variable) and its length offset, as the programs' comments ask."""
REF_ENDS = {
    "O8500.NC": ("M30", None), "O8501.NC": ("M99", None), "O8502.NC": ("M99", None),
    "O8503.NC": ("M99", None), "O8504.NC": ("M30", None), "O8505.NC": ("alarm", 3001),
}


@needs_ref
@pytest.mark.parametrize("path", REF_FILES, ids=lambda p: p.name)
@pytest.mark.parametrize("touching", [False, True], ids=["free", "touching"])
def test_reference_programs_run(path: Path, touching: bool) -> None:
    machine = Fraction(0.25, below=math.inf) if touching else FreeMachine()
    result = run(path.read_text(), machine, source=str(path), program_dir=REF,
                 variables=REF_VARIABLES, settings=BROTHER)
    stopped, number = REF_ENDS[path.name]
    assert result.stopped == stopped
    assert (result.alarm.number if result.alarm else None) == number
    if path.name == "O8501.NC":  # writes the measured length of T3 (#11003)
        assert 11003 in result.variables


@needs_ref
def test_reference_programs_stop_cleanly_on_a_plain_fanuc() -> None:
    path = REF / "O8501.NC"
    result = run(path.read_text(), source=str(path), program_dir=REF, variables=REF_VARIABLES)
    assert result.alarm is not None and result.alarm.number == 10
    assert "G100" in result.alarm.message and result.alarm.source == str(path)


# --- our own emitted programs -----------------------------------------------------------------

DECISION_ALARMS = (3010, 3011)
"""Out of tolerance, tool correction too large (docs/actions.md)."""
GOLDEN_VARIABLES = {5221: 10.0, 5222: -20.0, 5223: -300.0, 11020: 150.0}
"""G54 and the probe's length offset (H20): skip points come back through both."""


@pytest.mark.parametrize("path", GOLDENS, ids=lambda p: f"{p.parent.name}/{p.name}")
@pytest.mark.parametrize("fraction", [0.3, 0.7])
def test_golden_programs_print_one_point_per_touch(path: Path, fraction: float) -> None:
    machine = Fraction(fraction)
    text = path.read_text()
    result = run(text, machine, source=str(path), variables=GOLDEN_VARIABLES,
                 settings=settings_for(path))
    log = parse_dprnt(result.output, strict=True)
    if result.alarm is not None:  # a setup program judged the arbitrary touches (actions)
        assert "(CHECK " in text and result.alarm.number in DECISION_ALARMS
        assert [e.code for e in log.errors] in (["OUTTOL"], ["BIGCORR"])
    else:
        assert result.stopped == "M30" and log.complete and not log.errors
    assert len(log.touches) == len(machine.hits) > 0
    offset = (10.0, -20.0, -300.0 + 150.0)
    for touch, hit in zip(log.touches, machine.hits, strict=True):
        work = tuple(h - o for h, o in zip(hit, offset, strict=True))
        # half a unit of the 4th decimal, plus float slack for exact ties (x.xxxx5)
        assert touch.xyz == pytest.approx(work, abs=5e-5 + 1e-9)


@pytest.mark.parametrize("path", GOLDENS, ids=lambda p: f"{p.parent.name}/{p.name}")
def test_golden_programs_stop_when_the_probe_never_touches(path: Path) -> None:
    result = run(path.read_text(), source=str(path), settings=settings_for(path))
    assert result.alarm is not None
    assert (result.alarm.number, result.alarm.message) == (3001, "PROBE DID NOT TOUCH")
    assert result.output.splitlines()[-1].startswith("ERR NOTOUCH ")


@pytest.mark.parametrize("path", GOLDENS, ids=lambda p: f"{p.parent.name}/{p.name}")
def test_golden_programs_stop_on_contact_during_a_protected_move(path: Path) -> None:
    result = run(path.read_text(), FirstSkip(), source=str(path), settings=settings_for(path))
    assert result.alarm is not None
    assert (result.alarm.number, result.alarm.message) == (3002, "UNEXPECTED PROBE TRIGGER")
    assert result.output.splitlines()[-1].startswith("ERR COLLISION ")


# --- robustness and speed ---------------------------------------------------------------------

TOKENS = ["G0", "G1", "G31", "G91", "G90", "G20", "G65", "G10L2P1", "M98", "M99", "M30", "P1",
          "X", "Y", "Z", "F", "#1", "#100", "#[", "[", "]", "=", "+", "-", "*", "/", "1", "2.5",
          "-3", "IF", "WHILE", "DO1", "END1", "GOTO", "GOTO1", "THEN", "EQ", "LT", "AND", "MOD",
          "SIN", "ATAN", ",", "DPRNT[", "POPEN", "PCLOS", "(", ")", "%", "N1", "O1", "/", " ",
          "\n", "\n", "\n", "#3000=1", "#0", "#5061", "L2"]


class Chance:
    """Fires the skip at mid-move on a fixed pattern of G31 moves."""

    def __init__(self, pattern: list[bool]) -> None:
        self.pattern, self.calls = pattern or [False], 0

    def rapid(self, start: Point, end: Point) -> None:
        pass

    def feed(self, start: Point, end: Point, feed_mm_min: float) -> None:
        pass

    def skip(self, start: Point, end: Point, feed_mm_min: float) -> Point | None:
        self.calls += 1
        if not self.pattern[self.calls % len(self.pattern)]:
            return None
        x, y, z = ((a + b) / 2 for a, b in zip(start, end, strict=True))
        return x, y, z


def _outcome(text: str, machine: Machine) -> None:
    try:
        result = run(text, machine, max_blocks=20_000)
    except ProbegenError:
        return
    assert isinstance(result, RunResult)
    assert result.stopped in ("M30", "M02", "M99", "end", "message", "alarm")


@settings(max_examples=examples(150), suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(st.sampled_from(TOKENS), max_size=60), st.lists(st.booleans(), max_size=5))
def test_random_text_runs_or_fails_cleanly(tokens: list[str], pattern: list[bool]) -> None:
    _outcome("".join(tokens), Chance(pattern))


@st.composite
def _mutated_golden(draw: st.DrawFn) -> str:
    lines = draw(st.sampled_from(GOLDENS)).read_text().splitlines()
    for _ in range(draw(st.integers(1, 4))):
        i = draw(st.integers(0, len(lines) - 1))
        action = draw(st.sampled_from(["drop", "copy", "swap", "char", "token"]))
        if action == "drop":
            del lines[i]
        elif action == "copy":
            lines.insert(draw(st.integers(0, len(lines))), lines[i])
        elif action == "swap":
            j = draw(st.integers(0, len(lines) - 1))
            lines[i], lines[j] = lines[j], lines[i]
        else:
            at = draw(st.integers(0, len(lines[i])))
            new = draw(st.sampled_from(TOKENS)) if action == "token" else draw(
                st.characters(min_codepoint=32, max_codepoint=126))
            lines[i] = lines[i][:at] + new + lines[i][at + 1:]
    return "\n".join(lines)


@settings(max_examples=examples(60), suppress_health_check=[HealthCheck.too_slow])
@given(_mutated_golden(), st.lists(st.booleans(), max_size=5))
def test_mutated_golden_programs_run_or_fail_cleanly(text: str, pattern: list[bool]) -> None:
    _outcome(text, Chance(pattern))


def touch_program(touches: int) -> str:
    """A program in the shape our Fanuc dialect emits: per touch a protected approach, a
    measuring G31, the checks and a PT line (the benchmark of the brief)."""
    out = ["%", "O1001(BENCH)", "G21", "G90 G17 G40 G49 G80 G94 G69 G15 G50.1", "T20 M6",
           "G54", "G0 G43 H20 Z100.0000", "POPEN", "DPRNT[PGSTART*O1001*V1]",
           "#104=0.0000", "#107=0.0000", "#109=0.0000"]
    for i in range(1, touches + 1):
        angle = 2 * math.pi * i / touches
        ax, ay = 17.5 * math.cos(angle), 17.5 * math.sin(angle)
        tx, ty = 13.5 * math.cos(angle), 13.5 * math.sin(angle)
        out += [f"#190=#104+{ax:.4f}", f"#191=#107+{ay:.4f}", "#192=#109+5.0000",
                "G31 X#190 Y#191 Z#192 F2000.",
                "#193=ABS[#5061-#190]+ABS[#5062-#191]+ABS[#5063-#192]",
                f"IF[#193LT0.0050]GOTO{2 * i}", f"DPRNT[ERR*COLLISION*SPH1*{i}]",
                "#3000=2(UNEXPECTED PROBE TRIGGER)", f"N{2 * i}",
                f"#190=#104+{tx:.4f}", f"#191=#107+{ty:.4f}", "#192=#109+5.0000",
                "G31 X#190 Y#191 Z#192 F300.",
                "#193=ABS[#5061-#190]+ABS[#5062-#191]+ABS[#5063-#192]",
                f"IF[#193GE0.0050]GOTO{2 * i + 1}", f"DPRNT[ERR*NOTOUCH*SPH1*{i}]",
                "#3000=1(PROBE DID NOT TOUCH)", f"N{2 * i + 1}",
                f"DPRNT[PT*SPH1*{i}*X#5061[44]*Y#5062[44]*Z#5063[44]]",
                f"G1 X[#104+{ax:.4f}] Y[#107+{ay:.4f}] Z[#109+5.0000] F2000."]
    return "\n".join([*out, "DPRNT[PGEND*O1001]", "PCLOS", "M30", "%"]) + "\n"


def test_a_thousand_touches_run_to_the_end() -> None:
    # Speed is measured by benchmarks/bench_sim.py, not asserted here.
    result = run(touch_program(1_000), Fraction(0.5))
    assert (result.stopped, result.alarm) == ("M30", None)
    assert result.output.count("\nPT SPH1 ") == 1_000



def test_g68_rotates_program_coordinates_about_its_centre() -> None:
    m = FreeMachine(record=True)
    res = run("G90 G21 G54\nG17 G68 X10. Y0 R90.\nG0 X20. Y0 Z5.\n#1=#5041\n#2=#5042\n"
              "G69\nG0 X20. Y0\n#3=#5021\n#4=#5022\nM30\n", m,
              variables={5221: 100.0, 5222: 200.0})
    assert res.stopped == "M30"
    # (20, 0) turned 90 degrees about (10, 0) is (10, 10); G54 adds (100, 200)
    end = m.moves[0][2]
    assert end == pytest.approx((110.0, 210.0, 5.0))
    assert res.variables[1] == pytest.approx(20.0) and res.variables[2] == pytest.approx(0.0)
    assert (res.variables[3], res.variables[4]) == pytest.approx((120.0, 200.0))  # G69
    assert res.rotation is None


def test_g68_stays_in_the_result_and_a_block_with_it_does_not_move() -> None:
    m = FreeMachine(record=True)
    res = run("G90 G17 G21\nG68 X50. Y50. R0.5\nM30\n", m)
    assert res.rotation == (50.0, 50.0, 0.5) and m.moves == []


# --- rotary axes (B, C of a five-axis machine) -------------------------------------------


def turns(text: str, **kwargs: Any) -> tuple[RunResult, list[tuple[dict[str, float],
                                                                   dict[str, float]]]]:
    machine = FreeMachine(record=True)
    result = run(text, machine, **kwargs)
    assert result.alarm is None, result.alarm
    return result, machine.turns


def test_rotary_moves_reach_the_machine_and_read_back() -> None:
    result, done = turns("G0 B90. C10.\nG1 B-45. F1000.\n#1=#5024\n#2=#5025\n#3=#5044")
    assert done == [({"B": 0.0, "C": 0.0}, {"B": 90.0, "C": 10.0}),
                    ({"B": 90.0, "C": 10.0}, {"B": -45.0, "C": 10.0})]
    assert [result.variables[k] for k in (1, 2, 3)] == [-45.0, 10.0, -45.0]


def test_c_rolls_over_the_short_way_and_b_does_not() -> None:
    result, done = turns("G0 C350.\nG0 C10.\nG91 G0 C-30.\nG90 G0 B170.\nG0 B-170.\n"
                         "#1=#5025")
    assert [d[1] for d in done] == [
        {"B": 0.0, "C": -10.0}, {"B": 0.0, "C": 370.0}, {"B": 0.0, "C": -20.0},
        {"B": 170.0, "C": 340.0}, {"B": -170.0, "C": 340.0}]
    assert result.variables[1] == 340.0  # C reads back in [0, 360)


def test_rotary_work_offsets_and_machine_positioning() -> None:
    result, done = turns("G10 L2 P1 C30.\nG54 G0 C0\n#1=#5025\n#2=#5045\nG53 C0\n#3=#5045\n"
                         "G0 C45\n")
    assert [d[1]["C"] for d in done] == [30.0, 0.0, 30.045]  # C45 counts 0.001 deg steps
    assert [result.variables[k] for k in (1, 2, 3)] == [30.0, 0.0, -30.0]


@pytest.mark.parametrize(("text", "number"), [
    ("G31 B10. F100.", 9010),
    ("G0 X1. B10.", 9010),
    ("G28 C0", 9010),
    ("G1 B10.", 11),
])
def test_rotary_alarms(text: str, number: int) -> None:
    assert alarm_of(text) == number


def test_a_machine_without_rotary_axes_refuses_them() -> None:
    result = run("G0 B90.", Recorder())
    assert result.alarm is not None and result.alarm.number == 9010
    assert "AXIS B" in result.alarm.message


def test_c_rollover_follows_the_fanuc_manual_example() -> None:
    """Fanuc 0i manual B-63534EN/02, 20.2.1 (ROA = 1, RAB = 0), with C for its A axis:
    the movements -150, -30, -80, +380, -840 and the coordinates 210, 180, 100, 120, 0."""
    result, done = turns("G90 C0\nG90 C-150.\nG90 C540.\nG90 C-620.\nG91 C380.\nG91 C-840.\n"
                         "#1=#5025")
    moved = [round(end["C"] - start["C"], 9) for start, end in done[1:]]
    assert moved == [-150.0, -30.0, -80.0, 380.0, -840.0]
    assert [round(end["C"] % 360.0, 9) for _, end in done[1:]] == [210.0, 180.0, 100.0, 120.0,
                                                                  0.0]
    assert result.variables[1] == 0.0
