"""The size and variable limits of a machine profile (``[controller]``, docs/dialects.md
"Controller limits"): a program larger than ``program_size`` is split into a driver and
parts that measure as the unsplit program does; what splitting cannot help is refused
with the sizes and the key; the common variables a program uses must be the control's.

The other limits have their tests beside their code: line length and program memory of
one program, the options (test_controller_options.py), program numbers
(test_program_numbers.py), alarm texts (test_alarm_texts.py).

Planted truth as in test_haas_closed_loop.py: the part off G54 by a small shift and
turn, the bore 0.03 mm oversize (a probe without lobing).
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from conftest import REPO, assert_golden
from fuzzing import examples
from hypothesis import given, settings
from hypothesis import strategies as st
from test_haas_closed_loop import WORK, oversize_bore_block, placed_part, results
from test_macro_library import library
from test_program_numbers import toml

from probegen import cad, ir
from probegen.cli.app import ExitCode, main
from probegen.dialects import get_dialect
from probegen.dialects.split import Fitted, fit
from probegen.errors import SpecError, UnsupportedError
from probegen.machine.probe_model import ProbeModel
from probegen.machine.profile import load_profile
from probegen.planning import plan_program
from probegen.sim.contact import PlacedPart
from probegen.sim.vm import SimResult, VirtualMachine, run_text
from probegen.spec.model import Spec, load_spec

DATA = REPO / "tests" / "data" / "split"
SPEC = DATA / "bore_block.toml"
GOLDEN = REPO / "tests" / "golden" / "split"
PROFILE = (DATA / "machine.toml").read_text(encoding="utf-8")
SAMPLE = REPO / "samples" / "bore_block"

__all__ = ["oversize_bore_block"]  # the fixture, imported for pytest


def spec_with(tmp: Path, controller: str = "", source: Path = SPEC) -> Path:
    """``source`` (a bore_block spec) on the split profile with ``controller`` lines
    replacing its keys (``program_size = 10000`` unless given)."""
    text = PROFILE
    for key in re.findall(r"^(\w+) = ", controller, re.M):
        text = re.sub(rf"^{key} = .*\n", "", text, flags=re.M)
    (tmp / "machine.toml").write_text(text.replace("[controller]\n",
                                                   f"[controller]\n{controller}\n"),
                                      encoding="utf-8")
    spec = source.read_text(encoding="utf-8")
    spec = re.sub(r'profile = ".*"', f'profile = "{(tmp / "machine.toml").as_posix()}"', spec)
    spec = re.sub(r'model = ".*"', f'model = "{(SAMPLE / "bore_block.step").as_posix()}"', spec)
    path = tmp / "spec.toml"
    path.write_text(spec, encoding="utf-8")
    return path


def fitted(spec: Spec, dialect: str = "fanuc", compact: bool = False) -> tuple[str, Fitted]:
    """The unsplit program text and what ``compile`` writes for ``spec``."""
    program = plan_program(spec, runtime_variables=True).program
    d = get_dialect(dialect)
    d.compact = compact
    whole = d.generate(program)
    d = get_dialect(dialect)
    d.compact = compact
    return whole, fit(d, program, d.library_files(8000, 100, "mm") if compact else None)


# -- program_size: split ---------------------------------------------------------------

def test_split_driver_and_part_match_golden(in_repo: Path) -> None:
    whole, split = fitted(load_spec(SPEC.relative_to(REPO)))
    assert len(whole) == 13948 > 10000
    assert [(p.number, p.features) for p in split.parts] == [(1003, ("BOSS",)),
                                                              (1004, ("BORE",))]
    assert all(len(p.text) <= 10000 for p in split.parts)
    assert_golden(GOLDEN / "bore_block.nc", split.main)
    assert_golden(GOLDEN / "O1003.nc", split.parts[0].text)


def test_each_part_sets_the_state_it_relies_on() -> None:
    """Units, absolute mode, plane, compensation and rotation off, the work offset and
    the length offset, in every part; the tool change, the probe-on code, POPEN and the
    log's first and last lines only in the driver, which calls the parts in order."""
    _, split = fitted(load_spec(SPEC))
    setup = ["G21", "G90 G17 G40 G49 G80 G94 G69", "G54", "G43 H20"]
    for p in split.parts:
        lines = p.text.splitlines()
        assert lines[0] == lines[-1] == "%" and lines[-2] == "M99"
        assert lines[1].startswith(f"O{p.number}(BORE BLOCK PART ")
        assert lines[2] == f"(PART {p.number - 1002} OF O1002: RUN BY IT WITH M98, NOT ALONE)"
        assert lines[6:10] == setup
        assert not {"T20 M6", "M19", "POPEN", "PCLOS", "M30"} & set(lines)
        assert not any(line.startswith(("DPRNT[PG", "G0 G43")) for line in lines)
    driver = split.main.splitlines()
    assert [line for line in driver if line.startswith("M98")] == ["M98 P1003", "M98 P1004"]
    assert driver[5:8] == ["(RUNS 2 PARTS WITH M98, FILES BESIDE IT:)", "(O1003.NC: BOSS)",
                           "(O1004.NC: BORE)"]
    order = ["T20 M6", "G54", "G0 G43 H20 Z100.0000", "M19", "POPEN", "M98 P1003",
             "M98 P1004", "PCLOS", "M30"]
    assert [line for line in driver if line in order] == order
    assert "G31" not in split.main


def on_vm(text: str, part: PlacedPart, ball: float, dialect: str, folder: Path) -> SimResult:
    """``text`` run with called programs from ``folder`` (test_haas_closed_loop's
    planted work offset; a probe without lobing, so the planted size comes back to the
    printed decimals)."""
    vm = VirtualMachine(part, ProbeModel(ball))
    return run_text(text, vm, kind="macrob", work_offset=WORK, control=dialect,
                    program_dir=folder)


@pytest.mark.parametrize(("dialect", "compact"), [("fanuc", False), ("fanuc", True),
                                                  ("haas", False)])
def test_split_program_logs_the_unsplit_bytes(dialect: str, compact: bool,
                                              oversize_bore_block: cad.Model,
                                              tmp_path: Path) -> None:
    """The driver, running its parts (and the library) from its folder, logs what the
    unsplit program logs, byte for byte, so results.json is the same; ingest finds the
    planted 0.03 mm oversize of the bore."""
    spec = load_spec(spec_with(tmp_path, "program_size = 1200" if compact else ""))
    whole, split = fitted(spec, dialect, compact)
    assert len(split.parts) == 2 and ("G65P8002" in split.parts[0].text) is compact
    folder = library(tmp_path / "run", dialect) if compact else tmp_path / "run"
    folder.mkdir(exist_ok=True)
    for p in split.parts:
        (folder / p.file_name).write_text(p.text, encoding="ascii")
    part = placed_part(spec, oversize_bore_block)
    ball = spec.machine.probe.ball_radius
    driven = on_vm(split.main, part, ball, dialect, folder)
    unsplit = on_vm(whole, part, ball, dialect, folder)
    assert driven.alarm is None and unsplit.alarm is None, (driven.alarm, unsplit.alarm)
    assert driven.touches == unsplit.touches == 22
    assert driven.output == unsplit.output and "PGEND O1002" in driven.output
    doc = results(driven, spec, tmp_path / "split")
    assert doc == results(unsplit, spec, tmp_path / "unsplit") and doc["complete"]
    bore = next(f for f in doc["features"] if f["id"] == "BORE")  # type: ignore[attr-defined]
    diameter = next(c for c in bore["characteristics"] if c["name"] == "D")
    assert diameter["measured"] == pytest.approx(50.03, abs=2e-4)


def test_cli_writes_and_sims_the_split_program(in_repo: Path, tmp_path: Path,
                                               capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "out"
    assert main(["compile", str(SPEC), "--inline", "-o", str(out)]) == ExitCode.OK
    said = capsys.readouterr().out
    assert sorted(p.name for p in out.iterdir()) == ["O1003.nc", "O1004.nc", "bore_block.nc"]
    assert "split bore_block.nc into a driver and 2 parts" in said
    assert "wrote O1003.nc, O1004.nc in" in said
    assert main(["sim", str(out / "bore_block.nc"), "--spec", str(SPEC),
                 "-o", str(tmp_path / "run.log")]) == ExitCode.OK
    log = (tmp_path / "run.log").read_text(encoding="ascii")
    assert log.count("\nPT BOSS ") == 6 and log.count("\nPT BORE ") == 16
    (out / "O1004.nc").unlink()
    assert main(["sim", str(out / "bore_block.nc"), "--spec", str(SPEC),
                 "-o", str(tmp_path / "x.log")]) == ExitCode.SIM_ALARM
    assert "PROGRAM NOT FOUND (O1004)" in capsys.readouterr().err
    assert main(["compile", str(SPEC), "-o", "-"]) == ExitCode.ERROR
    assert "split into 2 parts, written beside it" in capsys.readouterr().err


# -- what splitting cannot help ----------------------------------------------------------

def test_one_feature_larger_than_the_limit_is_refused(tmp_path: Path) -> None:
    with pytest.raises(UnsupportedError, match=r"the program is \d+ bytes, expected at most "
                       r"5000 \(.*machine.toml: controller.program_size\); split at feature "
                       r"boundaries, the part with BORE alone is 9551 bytes"):
        fitted(load_spec(spec_with(tmp_path, "program_size = 5000")))


def test_a_decision_reading_an_earlier_feature_keeps_the_program_whole(
        tmp_path: Path) -> None:
    """bore_block_actions rotates the frame by EDGE's angle at the end, after BORE and
    BOSS: no cut between EDGE and the end reads nothing measured before it."""
    spec = spec_with(tmp_path, source=SAMPLE / "bore_block_actions.toml")
    with pytest.raises(UnsupportedError, match=r"cannot be split at a feature boundary .*: "
                       r"not between EDGE and TOP \(align of feature EDGE reads EDGE.A\); "
                       r"not between TOP and BORE \(set_work_offset of feature TOP reads "
                       r"TOP.P\);"):
        fitted(load_spec(spec))


def test_the_files_together_must_fit_program_memory(tmp_path: Path) -> None:
    _, split = fitted(load_spec(spec_with(tmp_path)))
    total = sum(len(t) for t in (split.main, *(p.text for p in split.parts)))
    assert fitted(load_spec(spec_with(tmp_path, f"program_memory = {total}")))[1] == split
    memory = f"program_memory = {total - 1}"
    with pytest.raises(UnsupportedError, match=rf"the programs are {total} bytes together "
                       rf"\(the driver \d+, O1003 4\d+, O1004 9\d+\), expected at most "
                       rf"{total - 1} \(.*controller.program_memory\): splitting cannot help"):
        fitted(load_spec(spec_with(tmp_path, memory)))


def test_the_library_counts_in_program_memory(tmp_path: Path,
                                              capsys: pytest.CaptureFixture[str]) -> None:
    spec = spec_with(tmp_path, "program_size = 0\nprogram_memory = 2000")
    assert main(["compile", str(spec), "--compact", "-o", str(tmp_path / "o")]) == \
        UnsupportedError.exit_code
    err = capsys.readouterr().err
    assert re.search(r"the programs are \d+ bytes together \(the program \d+, O8000 \d+, "
                     r"O8001 \d+, O8002 \d+\), expected at most 2000", err)
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize(("controller", "number", "message"), [
    ("", 8998, "part 2 of the split program .O8998 \\+ 2.: expected a program number in "
               "O1-O8999"),
    ("program_numbers = [1, 9999]\nlibrary_number = 7000\nprogram_size = 1200", 6999,
     "part 1 of the split program .O6999 \\+ 1.: expected a number apart from the macro "
     "library's, found O7000"),
])
def test_part_numbers_are_checked(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                  controller: str, number: int, message: str) -> None:
    spec = spec_with(tmp_path, controller)
    spec.write_text(spec.read_text().replace("number = 1002", f"number = {number}"))
    argv = ["compile", str(spec), "-o", str(tmp_path / "o"), "-d", "fanuc"]
    assert main(argv + ["--compact" if "library" in message else "--inline"]) == ExitCode.SPEC
    assert re.search(message, capsys.readouterr().err)


def test_compile_refuses_two_dialects_parts_in_one_file(tmp_path: Path,
                                                        capsys: pytest.CaptureFixture[str]
                                                        ) -> None:
    """With G50.1 declared the Haas parts say G100 where Fanuc's say G50.1: both would be
    O1003.nc."""
    spec = spec_with(tmp_path, 'options = ["G68", "#3004", "G50.1"]')
    argv = ["compile", str(spec), "--inline", "-o", str(tmp_path / "o"), "-d", "fanuc", "-d",
            "haas"]
    assert main(argv) == ExitCode.ERROR
    assert "O1003.nc: expected one text per part file" in capsys.readouterr().err
    assert main(["compile", str(spec), "--inline", "-o", str(tmp_path / "h"), "-d",
                 "haas"]) == 0


# -- common variables --------------------------------------------------------------------

@pytest.mark.parametrize(("controller", "variable"), [
    ("variable_base = 150", "#240 .a scratch value; #150-#243"),
    ("variable_base = 200", "#290 .a scratch value; #200-#293"),
    ("variable_base = 500\ncommon_variables = [[100, 199]]", "#590 .a scratch value"),
])
def test_variables_outside_the_controls_are_refused(tmp_path: Path, controller: str,
                                                    variable: str) -> None:
    """The Fanuc 0i's default #100-#199, #500-#999: a base of 150 or 200 runs the scratch
    values past #199."""
    with pytest.raises(UnsupportedError, match=rf"uses {variable}.*controller.variable_base\), "
                       r"expected a common variable of the control: #\d.*controller."
                       r"common_variables\)"):
        fitted(load_spec(spec_with(tmp_path, "program_size = 0\n" + controller)))


def test_declared_ranges_let_variables_in(tmp_path: Path) -> None:
    controller = "program_size = 0\nvariable_base = 300\ncommon_variables = [[100, 499]]"
    whole, split = fitted(load_spec(spec_with(tmp_path, controller)))
    assert "(USES #300-#393)" in whole and not split.parts
    assert load_profile(tmp_path / "machine.toml").controller.common_variables == ((100, 499),)


@pytest.mark.parametrize(("ranges", "variable"), [
    ("[[100, 199]]", "#510 .the flag of feature BOSS"),
    ("[[100, 199], [500, 515]]", "#520 .the angle of feature EDGE"),
    ("[[100, 199], [100, 101], [500, 600]]", ""),
    ("[[100, 199], [510, 510], [520, 520]]", ""),
])
def test_action_variables_are_checked(tmp_path: Path, ranges: str, variable: str) -> None:
    """bore_block_actions flags BOSS in #510 and keeps EDGE's angle in #520; its
    run-time values are #100-#147 or so."""
    spec = load_spec(spec_with(tmp_path, f"program_size = 0\ncommon_variables = {ranges}",
                               SAMPLE / "bore_block_actions.toml"))
    if not variable:
        assert fitted(spec)[0].count("#520=") == 1
        return
    with pytest.raises(UnsupportedError, match=rf"uses {variable};"):
        fitted(spec)


@pytest.mark.parametrize(("dialect", "ranges"), [
    ("fanuc", ((100, 199), (500, 999))),
    ("haas", ((100, 199), (500, 549), (600, 699), (800, 999))),
    ("linuxcnc", ()), ("dmis", ())])
def test_default_common_variables(tmp_path: Path, dialect: str,
                                  ranges: tuple[tuple[int, int], ...]) -> None:
    spec_with(tmp_path)
    path = tmp_path / "machine.toml"
    path.write_text(path.read_text().replace('dialect = "fanuc"', f'dialect = "{dialect}"'))
    assert load_profile(path).controller.common_variables == ranges


def test_program_size_beyond_the_memory_is_refused(tmp_path: Path) -> None:
    spec_with(tmp_path, "program_memory = 9000")
    with pytest.raises(SpecError, match=r"controller.program_size: expected at most "
                                        r"program_memory \(9000\)"):
        load_profile(tmp_path / "machine.toml")


@settings(max_examples=examples(60))
@given(value=st.one_of(
    st.lists(st.lists(st.integers(-5, 100_005), min_size=0, max_size=3), max_size=3),
    st.lists(st.one_of(st.integers(1, 999), st.booleans(), st.text("ab1", max_size=2),
                       st.lists(st.floats(), max_size=2)), max_size=3),
    st.integers(), st.booleans(), st.text("#19", max_size=4)))
def test_any_common_variables_value_is_ranges_or_a_spec_error(
        tmp_path_factory: pytest.TempPathFactory, value: object) -> None:
    folder = tmp_path_factory.mktemp("v")
    spec_with(folder, f"common_variables = {toml(value)}")
    try:
        ranges = load_profile(folder / "machine.toml").controller.common_variables
    except SpecError as exc:
        assert "controller.common_variables: expected a non-empty array of [first, last]" \
            in str(exc)
        return
    assert isinstance(value, list) and value
    assert sorted(tuple(r) for r in value) == list(ranges)
    assert all(1 <= a <= b <= 99999 for a, b in ranges)


# -- alarm_text_length -------------------------------------------------------------------

def test_alarm_texts_follow_the_profiles_length(tmp_path: Path) -> None:
    """24 characters: probegen's own texts shorten (``HOUSINGBORE BADFIT``, whole at
    the default 26); 23: the fixed ``UNEXPECTED PROBE TRIGGER`` (24) is refused at
    compile time, naming the key."""
    def program(length: int) -> str:
        spec = spec_with(tmp_path, f"program_size = 0\nalarm_text_length = {length}",
                         SAMPLE / "bore_block_actions.toml")
        spec.write_text(spec.read_text().replace('id = "BORE"', 'id = "HOUSINGBORE"'))
        return fitted(load_spec(spec))[0]

    def messages(text: str) -> list[str]:
        return re.findall(r"^#300[06]=\d+\((.*)\)$", text, re.M)

    assert "HOUSINGBORE NO CIRCLE FIT" in messages(program(26))
    short = messages(program(24))
    assert max(len(m) for m in short) == 24
    assert "HOUSINGBORE BADFIT" in short and "HOUSINGBORE BIGCORR" in short
    with pytest.raises(UnsupportedError, match=r"expected an alarm message of at most 23 "
                       r"characters \(.*machine.toml: controller.alarm_text_length\), found "
                       r"24: 'UNEXPECTED PROBE TRIGGER'"):
        program(23)
    spec_with(tmp_path, "alarm_text_length = 11")
    with pytest.raises(SpecError, match="controller.alarm_text_length: expected"):
        load_profile(tmp_path / "machine.toml")


# -- the state a part restates -----------------------------------------------------------

def sphere_block(name: str, x: float) -> ir.FeatureBlock:
    """A two-touch sphere at ``x`` (a protected move, a touch, a retract each)."""
    nodes: list[ir.Node] = []
    for k, dx in enumerate((1.0, -1.0), start=1):
        start = (x + dx * 20.0, 0.0, 30.0)
        nodes += [ir.Move(start, ir.MoveMode.PROTECTED),
                  ir.Touch(name, k, ir.TouchRole.MEASURE, (x + dx * 12.5, 0.0, 30.0),
                           (dx, 0.0, 0.0), 2.0, 2.0),
                  ir.Move(start, ir.MoveMode.RETRACT)]
    return ir.FeatureBlock(ir.SphereDef(name, (x, 0.0, 30.0), 25.0), tuple(nodes))


def test_a_part_restates_the_rotary_pose_before_it() -> None:
    """After a head tilt every point is commanded less the head shift: the second part
    turns to the same pose itself (a null move) and commands its points as the unsplit
    program does."""
    setup = ir.Setup(
        program_number=7, program_name="T", units="mm", work_offset="G54", clearance_z=50.0,
        ball_diameter=6.0, shank_diameter=4.0, tool_number=20, tool_change=False,
        position_feed=2000.0, probe_feed=300.0, probe_on=(), probe_off=(), variable_base=500,
        reset_codes=("G17",), probe_length=40.0, program_size=1500)
    body = (ir.Rotary(30.0, None, (1.5, 0.0, -0.5)), sphere_block("A", 0.0),
            sphere_block("B", 100.0))
    whole = get_dialect("fanuc").generate(ir.Program(setup, body))
    split = fit(get_dialect("fanuc"), ir.Program(setup, body))
    assert [p.features for p in split.parts] == [("A",), ("B",)]
    second = split.parts[1].text
    assert "\nG53 B30.0000\n(FEATURE B SPHERE" in second
    touches = [line for line in whole.splitlines() if line.startswith("#590=")]
    assert "#590=118.5000" in touches  # B's first point, 120 less the 1.5 mm shift
    assert [line for line in second.splitlines() if line.startswith("#590=")] == \
        touches[len(touches) // 2:]


# -- every controller option -------------------------------------------------------------

def with_option(tmp: Path, option: str, declared: bool) -> str:
    """The program (or the SpecError) of the spec that needs ``option``, with only it
    declared or with no option at all."""
    from test_controller_options import ACTIONS_SPEC, profile_text, program, write_spec

    from probegen.planning import check_options

    options = f'["{option}"]' if declared else "[]"
    try:
        if option == "G68":
            spec = load_spec(write_spec(tmp, ACTIONS_SPEC, profile_text(options=options)))
            check_options(spec)
            return "align checked"
        dialect = "haas" if option == "G154" else "fanuc"
        machine = f'dialect = "{dialect}"'
        if option in ("G54.1", "G154"):
            machine += f'\nwork_offset = "{option} P3"'
        return program(tmp, dialect, options=options, machine=machine)
    except SpecError as exc:
        return f"SpecError: {exc}"


@pytest.mark.parametrize(("option", "used"), [
    ("G68", "align checked"), ("G68.2", " G69\n"), ("G15", " G15\n"),
    ("G50.1", " G50.1\n"), ("G54.1", "\nG54.1 P3\n"), ("G154", "\nG154 P3\n"),
    ("#3004", "\n#3004=2\n")])
def test_each_option_is_used_only_when_declared(tmp_path: Path, option: str,
                                                used: str) -> None:
    """Declared, the program uses the option; undeclared, a spec that needs it is
    refused naming it (G68 align, extended work offsets) or the program leaves it out
    (the reset codes of optional modes, the override lock)."""
    assert used in with_option(tmp_path, option, True)
    without = with_option(tmp_path, option, False)
    assert used not in without
    refused = option in ("G68", "G54.1", "G154")
    assert without.startswith("SpecError: ") is refused
    if refused:
        assert f"needs the controller option {option} " in without


def test_every_option_has_its_case() -> None:
    from probegen.machine.profile import OPTIONS

    cases = test_each_option_is_used_only_when_declared.pytestmark[0].args[1]  # type: ignore[attr-defined]
    assert {option for option, _ in cases} == set(OPTIONS)


def test_rotary_plan_refuses_a_program_too_large(tmp_path: Path,
                                                 capsys: pytest.CaptureFixture[str]) -> None:
    """``rotary plan`` writes one program (its number + 1 is the work-offset update's):
    larger than ``program_size``, it is refused, not split."""
    spec_with(tmp_path, "program_size = 2000")
    text = (REPO / "samples/rotary/m4.toml").read_text(encoding="utf-8").replace(
        '"../machines/vmc-fanuc.toml"', f'"{(tmp_path / "machine.toml").as_posix()}"')
    spec = tmp_path / "m4.toml"
    spec.write_text(text, encoding="utf-8")
    argv = ["rotary", "plan", str(spec), "-o", str(tmp_path / "out")]
    assert main(argv) == UnsupportedError.exit_code
    assert re.search(r"the program is \d+ bytes, expected at most 2000 \(.*machine.toml: "
                     r"controller.program_size\), and this command writes one program",
                     capsys.readouterr().err)
    assert not (tmp_path / "out").exists()
