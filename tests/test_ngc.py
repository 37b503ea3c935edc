"""The LinuxCNC control of the virtual machine (``probegen.sim.ngc``): rs274ngc text as
LinuxCNC 2.9 runs it.

The expected comment texts were printed by LinuxCNC's own ``rs274`` 2.9.0~pre1 for the
same lines; where ``rs274`` is installed, ``test_log_text_is_what_rs274_writes`` runs
them through it again.  Positions on a part: a sphere of radius 12.5 mm at the origin,
a ball of radius 3 mm without pre-travel, so a touch along a horizontal line through the
centre stops with the ball centre 15.5 mm from it (exact).
"""

from __future__ import annotations

import math
import random
from pathlib import Path

import pytest
from fuzzing import examples
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from mutations import mutate
from test_linuxcnc import log_text, rs274, run_rs274  # noqa: F401

from probegen.errors import ProbegenError, ProgramParseError
from probegen.machine.probe_model import ProbeModel
from probegen.sim.contact import PlacedPart
from probegen.sim.macrob.base import Settings
from probegen.sim.macrob.machine import FreeMachine
from probegen.sim.ngc.interp import NgcResult, run_ngc
from probegen.sim.vm import VirtualMachine

FORMATS = """#1 = 3.14159265
#<_aa> = -2.5
#<b> = 7
(LOGOPEN,x.log)
(LOG,plain #1 fmt %d#1 f %f#1 p2 %.2f#1 again #1 named #<_aa> #<b> #<nope> bad %q#1 %.12f#1)
(LOG,neg %d#<_aa> %.0f#<_aa> #<_aa>)
(LOG,  leading spaces #1)
#2 = [5 MOD 3] #3 = [-5 MOD 3]
(LOG,mod %.4f#2 %.4f#3)
#4 = [2 ** 0.5]
#5 = [1 EQ 1.0000001] #6 = [3 AND 0] #7 = [FIX[-2.8]] #8 = [FUP[-2.8]] #9=[ROUND[2.5]]
#10=[ROUND[-2.5]]
(LOG,%.6f#4 #5 #6 #7 #8 #9 #10)
#11 = [ATAN[1]/[-1]] #12 = [1 XOR 1] #13=[0 OR -3] #14 = [7/2*2] #15=[2**3**2]
(LOG,%.6f#11 #12 #13 #14 #15)
#16 = [-2 ** 2] #17 = [- 3 MOD 2] #18=[EXISTS[#<_aa>]] #19=[EXISTS[#<zz>]]
(LOG,#16 #17 #18 #19 %.3f#<_aa>)
#3 = 1 #3 = 2 #4 = #3
(LOG,p #3 #4 #<_ a A>)
(LOGCLOSE)
M2
"""
FORMATS_LOG = """\
plain 3.141593 fmt 3 f 3.1416 p2 3.14 again 3.14 named -2.50 7.00 ###### bad %q3.14 .12f3.14
neg -2 -2 -2
  leading spaces 3.141593
mod 2.0000 1.0000
1.414214 1.000000 0.000000 -3.000000 -2.000000 3.000000 -3.000000
135.000000 0.000000 1.000000 7.000000 64.000000
4.000000 1.000000 1.000000 0.000000 -2.500
p 2.000000 1.000000 -2.500000
"""


def run(text: str, **kwargs: object) -> NgcResult:
    return run_ngc(text, FreeMachine(), **kwargs)  # type: ignore[arg-type]


def test_expressions_and_log_formats() -> None:
    res = run(FORMATS)
    assert res.alarm is None and res.stopped == "M2"
    assert res.output == FORMATS_LOG


def test_log_text_is_what_rs274_writes(rs274: str, tmp_path: Path) -> None:  # noqa: F811
    assert log_text(run_rs274(rs274, FORMATS, tmp_path)) == FORMATS_LOG


@pytest.mark.parametrize(("expression", "logged"), [
    ("FIX[COS[90]]", "-1"),            # long double: COS[90] is -2.5e-20 (rs274 2.9)
    ("[0 EQ 0.00009]", "1"),           # TOLERANCE_EQUAL 1e-4 in LinuxCNC 2.9
    ("[0 NE 0.0001]", "1"),
    ("[0 LT 0.00002]", "1"),           # only EQ and NE have a tolerance
    ("ATAN[FUP[-0.5]]/[-1]", "-180"),  # FUP keeps the sign of -0.0
    ("[-5 MOD 3]", "1"),
    ("-0.00004", "0"),                 # printed as 0 (within TOLERANCE_EQUAL), not -0
])
def test_values_as_rs274_computes_them(expression: str, logged: str) -> None:
    res = run(f"(LOGOPEN,v.log)\n#1 = {expression}\n(LOG,%d#1)\nM2\n")
    assert res.alarm is None and res.output == logged + "\n"


SUBS = """%
(a user's program: subroutines, named parameters, loops, messages)
o<side> sub
  #<angle> = #1
  #<r> = 25
  G0 X[#<r> * COS[#<angle>]] Y[#<r> * SIN[#<angle>]]
  G0 Z0
  G38.2 X0 Y0 F200
  #<_hits> = [#<_hits> + 1]
  (LOG,HIT %d#<_hits> X%.4f#5061 Y%.4f#5062 R%.4f#<angle>)
  G1 X[#<r> * COS[#<angle>]] Y[#<r> * SIN[#<angle>]] F1000
  G0 Z30
o<side> endsub [#5070]
G21 G90 G17 G40 G49 G94 G61 G54
(LOGOPEN,sides.log)
#<_hits> = 0
#<k> = 0
G0 Z30
o10 while [#<k> LT 4]
  o<side> call [#<k> * 90]
  o11 if [#<_value> NE 1]
    (ABORT,no contact at #<k>)
  o11 endif
  #<k> = [#<k> + 1]
o10 endwhile
o12 repeat [2]
  #31 = [#31 + 1]
o12 endrepeat
(MSG,done)
(DEBUG,k=%d#<k> #31)
(LOGCLOSE)
M30
%
"""


def on_sphere(text: str, **kwargs: object) -> tuple[NgcResult, VirtualMachine]:
    vm = VirtualMachine(PlacedPart.from_spheres([[0.0, 0.0, 0.0]], [12.5]), ProbeModel(3.0))
    return run_ngc(text, vm, settings=Settings(home=(0.0, 0.0, 500.0)),
                   **kwargs), vm  # type: ignore[arg-type]


def test_a_users_program_with_subs_loops_and_named_parameters() -> None:
    res, vm = on_sphere(SUBS, parameters={5221: 0.0})
    assert res.alarm is None and res.stopped == "M30"
    assert len(vm.touches) == 4
    lines = res.output.splitlines()
    def log(v: float) -> str:  # LinuxCNC prints a value within 1e-4 of 0 as 0.0000
        return f"{round(v, 6) + 0.0:.4f}"

    assert lines == [f"HIT {i + 1} X{log(15.5 * math.cos(math.radians(90 * i)))} "
                     f"Y{log(15.5 * math.sin(math.radians(90 * i)))} R{90 * i:.4f}"
                     for i in range(4)]
    assert lines[3].startswith("HIT 4 X0.0000 ")  # not -0.0000: cos(270 deg) is -2e-15
    assert res.messages == ("done", "k=4 2")  # a format holds for the rest of the line
    assert res.variables[31] == 2.0


def test_positions_are_in_the_selected_work_offset_and_units() -> None:
    text = """G20 G90 G55
(LOGOPEN,a.log)
G0 X2 Y0
G0 Z0.25
G38.3 X0 F10
(LOG,%.5f#5061 %d#5070 %.5f#5420 %.3f#5021)
G10 L20 P2 X0
(LOG,%.5f#5241 %.5f#<_x>)
M2
"""
    res, vm = on_sphere(text, parameters={5241: 0.5, 5243: -0.25})  # G55, inch
    assert res.alarm is None
    x = 15.5 / 25.4 - 0.5  # the ball centre 15.5 mm from the sphere's, in G55, inch
    machine = 15.5 / 25.4
    assert res.output.splitlines() == [f"{x:.5f} 1 {x:.5f} {machine:.3f}",
                                       f"{machine:.5f} 0.00000"]
    assert len(vm.touches) == 1


MODES = """G21 G90 G54
(LOGOPEN,a.log)
G0 X1 Y2 Z3
G92 X0 Y0
(LOG,%.3f#5210 #5211 #5212 #<_x> #<_y> #5420)
G0 X1
G92.2
(LOG,%.3f#5210 #5211 #<_x>)
G92.3
(LOG,%.3f#5210 #5211 #<_x>)
G92.1
(LOG,%.3f#5210 #5211 #<_x>)
G10 L2 P1 X10 R90
G0 X5 Y0
(LOG,%.3f#<_x> #<_y> #<_abs_x> #<_abs_y>)
G10 L2 P1 R0 X0
o<s> sub
M73
G91 G20
G0 X1
o<s> endsub
o<s> call
(LOG,%.3f#<_incremental> #<_metric> #<_abs_x>)
#5161 = 7
G28
(LOG,%.3f#<_abs_x> #<_abs_y> #<_abs_z>)
G55
(LOG,%d#5220 #<_coord_system>)
#5220 = 3
(LOG,%d#5220 #<_coord_system>)
M2
"""


def test_g92_rotation_modal_restore_g28_and_coordinate_systems() -> None:
    """G92 and its .1 .2 .3 with #5210/#5211; a G54 turned 90 degrees about its origin
    (10, 0); M73 gives the caller its G90 G21 back; G28 to #5161-; #5220 selects."""
    machine = FreeMachine(record=True)
    res = run_ngc(MODES, machine)
    assert res.alarm is None
    assert res.output.splitlines() == [
        "1.000 1.000 2.000 0.000 0.000 0.000", "0.000 1.000 2.000", "1.000 1.000 1.000",
        "0.000 0.000 2.000", "5.000 0.000 10.000 5.000", "0.000 1.000 35.400",
        "7.000 0.000 0.000", "2 550", "3 560"]
    assert [end for _, _, end in machine.moves] == [
        (1.0, 2.0, 3.0), (2.0, 2.0, 3.0), (10.0, 5.0, 3.0), (35.4, 5.0, 3.0), (7.0, 0.0, 0.0)]


@pytest.mark.parametrize(("text", "start"), [
    ("G0 X1\n#1 = #<nope>\nM2\n", "9300 Named parameter #<nope> not defined (line 2, column 1)"),
    ("G0 X1\n#1 = [1/0]\nM2\n", "9300 Attempt to divide by zero (line 2, column 1)"),
    ("G1 X1\nM2\n", "9300 Cannot do g1 with zero feed rate (line 1, column 1)"),
    ("G2 X1\nM2\n", "9010 NOT SUPPORTED BY THE VIRTUAL MACHINE (G2) (line 1"),
    ("G7.5 X1\nM2\n", "9300 Unknown g code used (G7.5) (line 1"),
    ("G0 G1 X1\nM2\n", "9300 Two G-codes used from same modal group (line 1"),
    ("X1\nM2\n", "9300 Cannot use axis values without a g code that uses them (line 1"),
    ("M123\nM2\n", "9010 NOT SUPPORTED BY THE VIRTUAL MACHINE (M123) (line 1"),
    ("#1 = 5\n(ABORT,stop #1)\nM2\n", "9301 stop 5.000000 (line 2, column 1)"),
    ("G0 X1\no<missing> call\nM2\n", "9300 Unable to open file for subroutine o<missing>"),
    ("G38.2 X0.1 F100\nM2\n", "9300 Start point too close to probe point (line 1"),
    ("G0 X1\n", "9300 File ended with no percent sign or program end (line 1"),
    ("o1 sub\no1 call\no1 endsub\no1 call\nM2\n",
     "9300 Too many nested subroutine calls (o1: more than 10)"),
    ("o1 while [1]\no1 endwhile\nM2\n", "9000 BLOCK LIMIT REACHED (max_lines=1000)"),
])
def test_errors_stop_the_run_with_the_line(text: str, start: str) -> None:
    res = run(text, max_lines=1000)
    assert res.alarm is not None and res.stopped == "alarm"
    assert str(res.alarm).startswith(start), str(res.alarm)


@pytest.mark.parametrize(("text", "where", "what"), [
    ("G0 X1 Y\nM2\n", ":1:8:", "expected a number, '[', '#' or a function"),
    ("G0 X[1+]\nM2\n", ":1:8:", "expected a number"),
    ("G0 X1 (a (nested) comment)\n", ":1:10:", "comments do not nest"),
    ("G0 E1\n", ":1:4:", "expected a word"),
    ("G0 X1 X2\n", ":1:7:", "a second X word"),
    ("o1 if [1]\nG0 X1\nM2\n", ":1:1:", "expected 'o1 endif'"),
    ("o2 endwhile\nM2\n", ":1:1:", "no open 'o2 while'"),
    ("o3 break\nM2\n", ":1:1:", "outside a loop"),
    ("O100\nM99\n", ":1:1:", "Fanuc-style program number"),
    ("#1=" + "[" * 50 + "1" + "]" * 50 + "\n", ":1:44:", "nested at most 40 deep"),
    ("#1=" + "#" * 50 + "1\n", ":1:45:", "nested at most 40 deep"),
])
def test_syntax_errors_name_line_and_column(text: str, where: str, what: str) -> None:
    with pytest.raises(ProgramParseError) as info:
        run(text)
    assert where in str(info.value) and what in str(info.value)


def test_called_files_are_found_beside_the_program(tmp_path: Path) -> None:
    (tmp_path / "twice.ngc").write_text("o<twice> sub\n#<_out> = [#1 * 2]\n"
                                        "o<twice> endsub\nM2\n")
    res = run("(LOGOPEN,t.log)\no<TWICE> call [21]\n(LOG,%d#<_out>)\nM2\n",
              program_dir=tmp_path)
    assert res.alarm is None and res.output == "42\n"


def test_logs_open_close_and_append() -> None:
    text = ("(LOG,lost)\n(LOGOPEN,a.log)\n(LOG,one)\n(LOGCLOSE)\n(LOG,lost)\n"
            "(LOGAPPEND,b.log)\n(LOG,two)\n(LOGAPPEND,a.log)\n(LOG,three)\n(LOGCLOSE)\nM2\n")
    res = run(text)
    assert res.logs == {"a.log": "one\nthree\n", "b.log": "two\n"}
    assert res.output == "one\nthree\ntwo\n"


TOKENS = ["G0", "G1", "G38.2", "G38.3", "G90", "G91", "G20", "G21", "G54", "G59.3", "G92",
          "G10 L2 P1", "G43 H1", "X1", "Y-2.5", "Z[#1+2]", "F100", "M2", "M6 T1", "#1=",
          "#<a>=", "#<_g>=", "[", "]", "1", "+", "*", "/", "MOD", "**", "EQ", "AND", "SIN[",
          "ATAN[1]/[", "EXISTS[#<a>]", "#1", "#<a>", "#5061", "(LOG,#1 %.3f#<a>)",
          "(ABORT,x)", "o1 if [", "o1 else", "o1 endif", "o2 while [", "o2 endwhile",
          "o3 repeat [", "o3 endrepeat", "o4 sub", "o4 endsub", "o4 call [", "o5 do",
          "o5 while [", "o2 break", "o3 continue", "(", ")", ";", "%", "\n", "\n", "\n"]


def _outcome(text: str) -> None:
    part = PlacedPart.from_spheres([[0.0, 0.0, 0.0]], [5.0])
    try:
        res = run_ngc(text, VirtualMachine(part, ProbeModel(3.0)), max_lines=2000)
    except ProbegenError:
        return
    assert res.stopped in ("M2", "M30", "end", "alarm")
    assert (res.alarm is None) == (res.stopped != "alarm")


@settings(max_examples=examples(300), suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(st.sampled_from(TOKENS), max_size=60))
def test_random_text_runs_or_fails_cleanly(tokens: list[str]) -> None:
    _outcome(" ".join(tokens))


@st.composite
def _mutated(draw: st.DrawFn) -> str:
    text = draw(st.sampled_from([SUBS, FORMATS]))
    return mutate(draw, text, "#[]<>()%;,.-+*/=0123456789GXYZMoOabcdefilnprsuw \n", most=6)


@settings(max_examples=examples(300), suppress_health_check=[HealthCheck.too_slow])
@given(_mutated())
def test_mutated_programs_run_or_fail_cleanly(text: str) -> None:
    _outcome(text)


def _random_expression(rng: random.Random, depth: int = 0) -> str:
    """A random rs274ngc expression of numbers, operators and functions."""
    if depth > 2 or rng.random() < 0.3:
        value = rng.choice([rng.randint(-9, 9), round(rng.uniform(-5.0, 5.0), 3)])
        return str(value) if value >= 0 or rng.random() < 0.5 else f"[{value}]"
    kind = rng.random()
    if kind < 0.5:
        op = rng.choice(["+", "-", "*", "/", "MOD", "**", "EQ", "NE", "GT", "GE", "LT", "LE",
                         "AND", "OR", "XOR"])
        return (f"[{_random_expression(rng, depth + 1)} {op} "
                f"{_random_expression(rng, depth + 1)}]")
    if kind < 0.9:
        name = rng.choice(["ABS", "ACOS", "ASIN", "COS", "EXP", "FIX", "FUP", "LN", "ROUND",
                           "SIN", "SQRT", "TAN"])
        return f"{name}[{_random_expression(rng, depth + 1)}]"
    return f"ATAN[{_random_expression(rng, depth + 1)}]/[{_random_expression(rng, depth + 1)}]"


def test_random_expressions_agree_with_rs274(rs274: str, tmp_path: Path) -> None:  # noqa: F811
    """200 random expressions that the virtual control evaluates without an error give
    rs274's values (printed with %.6f; 1e-9 relative for the last digit's rounding)."""
    rng = random.Random(19)
    kept: list[str] = []
    while len(kept) < 200:
        expression = _random_expression(rng)
        line = f"#1 = {expression}\n(LOG,%.6f#1)\n"
        res = run(f"(LOGOPEN,e.log)\n{line}M2\n")
        if res.alarm is None and abs(float(res.output)) < 1e12:
            kept.append(line)
    text = "(LOGOPEN,e.log)\n" + "".join(kept) + "M2\n"
    ours = run(text).output.split()
    theirs = log_text(run_rs274(rs274, text, tmp_path)).split()
    assert len(theirs) == len(ours) == 200
    for line, a, b in zip(kept, ours, theirs, strict=True):
        assert float(a) == pytest.approx(float(b), rel=1e-9, abs=1e-6), line
