"""Controller options, the override lock around touches, extended work offsets and the
program size limits of a machine profile (``[controller]``, ``docs/spec.md``)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from conftest import REPO
from fuzzing import examples
from hypothesis import given, settings
from hypothesis import strategies as st

from probegen.cli.plan import checked_library
from probegen.dialects import get_dialect
from probegen.errors import SpecError, UnsupportedError
from probegen.machine.probe_model import ProbeModel
from probegen.machine.profile import DEFAULT_OPTIONS, OPTIONS, load_profile
from probegen.planning import check_options, plan_program
from probegen.sim.contact import PlacedPart
from probegen.sim.macrob.base import control_settings
from probegen.sim.macrob.machine import run_program
from probegen.sim.vm import VirtualMachine, run_text
from probegen.spec.model import load_spec

MACHINES = REPO / "samples" / "machines"
SAMPLE = (MACHINES / "vmc-fanuc.toml").read_text(encoding="utf-8")
SPHERE_SPEC = REPO / "samples" / "sphere25" / "sphere_test_iso.toml"
ACTIONS_SPEC = REPO / "samples" / "bore_block" / "bore_block_actions.toml"


def profile_text(machine: str = "", controller: str = "", options: str | None = None) -> str:
    """The sample profile with lines added to ``[machine]`` and ``[controller]`` and its
    ``options`` line replaced (``options=None``: the line removed, the default)."""
    text = SAMPLE
    line = re.search(r"^options = .*$", text, re.M)
    assert line is not None
    text = text.replace(line[0], "" if options is None else f"options = {options}")
    for key in re.findall(r"^(\w+) = ", machine + "\n" + controller, re.M):
        text = re.sub(rf"^{key} = .*\n", "", text, flags=re.M)
    text = text.replace("[machine]\n", f"[machine]\n{machine}\n")
    return text.replace("[controller]\n", f"[controller]\n{controller}\n")


def write_spec(tmp: Path, source: Path, profile: str) -> Path:
    """``source`` with its machine profile replaced by ``profile`` (and its model, if any,
    found where it was)."""
    (tmp / "machine.toml").write_text(profile, encoding="utf-8")
    text = source.read_text(encoding="utf-8").replace("../machines/vmc-fanuc.toml",
                                                      (tmp / "machine.toml").as_posix())
    text = re.sub(r'^model = "(.*)"$', lambda m: f'model = "{(source.parent / m[1]).as_posix()}"',
                  text, flags=re.M)
    spec = tmp / "spec.toml"
    spec.write_text(text, encoding="utf-8")
    return spec


def program(tmp: Path, dialect: str = "fanuc", **profile: str | None) -> str:
    spec = load_spec(write_spec(tmp, SPHERE_SPEC, profile_text(**profile)))  # type: ignore[arg-type]
    return get_dialect(dialect).generate(plan_program(spec, runtime_variables=True).program)


def compact(tmp: Path, options: str | None) -> tuple[str, Path]:
    """The compact program of the sphere spec and the folder holding its library, both
    as ``compile --compact`` writes them for the profile with ``options``."""
    spec = load_spec(write_spec(tmp, SPHERE_SPEC, profile_text(options=options)))
    d = get_dialect("fanuc")
    d.compact = True
    text = d.generate(plan_program(spec, runtime_variables=True).program)
    lib = tmp / "lib"
    lib.mkdir()
    for name, body in checked_library(d, spec.machine).items():
        (lib / name).write_text(body, encoding="ascii")
    return text, lib


def vm() -> VirtualMachine:
    """A 25 mm sphere near the origin, a 3 mm ball (the spec's sphere)."""
    return VirtualMachine(PlacedPart.from_spheres([[0.1, -0.2, 0.05]], [12.5]), ProbeModel(3.0))


# -- the options ------------------------------------------------------------------------

@pytest.mark.parametrize(("dialect", "expected"), [
    ("fanuc", ("G68", "#3004")), ("haas", ("G68", "G50.1", "G154")), ("linuxcnc", ())])
def test_default_options_by_dialect(tmp_path: Path, dialect: str,
                                    expected: tuple[str, ...]) -> None:
    text = profile_text(machine=f'dialect = "{dialect}"')
    (tmp_path / "m.toml").write_text(text, encoding="utf-8")
    assert load_profile(tmp_path / "m.toml").controller.options == expected
    assert DEFAULT_OPTIONS.get(dialect, ()) == expected


def test_declared_options_are_kept_sorted_once(tmp_path: Path) -> None:
    (tmp_path / "m.toml").write_text(profile_text(options='["G50.1", "G15", "G15"]'),
                                     encoding="utf-8")
    assert load_profile(tmp_path / "m.toml").controller.options == ("G15", "G50.1")


@pytest.mark.parametrize(("value", "message"), [
    ('["G86"]', "did you mean 'G68'"), ('"G68"', "an array of"), ('["3004"]', "#3004")])
def test_unknown_options_are_refused(tmp_path: Path, value: str, message: str) -> None:
    (tmp_path / "m.toml").write_text(profile_text(options=value), encoding="utf-8")
    with pytest.raises(SpecError, match=f"controller.options: expected .*{re.escape(message)}"):
        load_profile(tmp_path / "m.toml")


@settings(max_examples=examples(40))
@given(st.lists(st.sampled_from([*OPTIONS, "G16", "G68.1", "", "#3003"]), max_size=5))
def test_any_option_list_loads_or_is_refused(names: list[str]) -> None:
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "m.toml"
        path.write_text(profile_text(options=str(names).replace("'", '"')), encoding="utf-8")
        try:
            options = load_profile(path).controller.options
        except SpecError as exc:
            assert "controller.options" in str(exc)
            assert any(n not in OPTIONS for n in names)
        else:
            assert options == tuple(sorted(set(names)))


@pytest.mark.parametrize(("options", "dialect", "reset"), [
    (None, "fanuc", "G90 G17 G40 G49 G80 G94 G69"),
    ('["G68", "G15", "G50.1"]', "fanuc", "G90 G17 G40 G49 G80 G94 G69 G15 G50.1"),
    ('["G68.2"]', "fanuc", "G90 G17 G40 G49 G80 G94 G69"),
    ("[]", "fanuc", "G90 G17 G40 G49 G80 G94"),
    ('["G68", "G15", "G50.1"]', "haas", "G90 G17 G40 G49 G80 G94 G69 G100"),
    ('["G50.1"]', "haas", "G90 G17 G40 G49 G80 G94 G100"),
])
def test_reset_block_holds_only_declared_options(tmp_path: Path, options: str | None,
                                                 dialect: str, reset: str) -> None:
    """The sample lists G69, G15 and G50.1 among its reset codes: each is written only
    when its option (G68 or G68.2, G15, G50.1) is declared."""
    lines = program(tmp_path, dialect, options=options).splitlines()
    assert [line for line in lines if line.startswith("G90 G17")] == [reset]


def test_g68_align_needs_the_rotation_option(tmp_path: Path) -> None:
    spec = load_spec(write_spec(tmp_path, ACTIONS_SPEC, profile_text(options='["#3004"]')))
    with pytest.raises(SpecError, match=r"spec.toml: feature\[0\].align.mode: align = .* needs "
                                        r"the controller option G68 \(coordinate rotation "
                                        r"G68/G69\), which .*machine.toml does not declare; "
                                        r"add 'G68' to \[controller\] options"):
        check_options(spec)
    check_options(load_spec(write_spec(tmp_path, ACTIONS_SPEC, profile_text())))


def test_compile_refuses_an_undeclared_option(tmp_path: Path,
                                              capsys: pytest.CaptureFixture[str]) -> None:
    from probegen.cli.app import main

    spec = write_spec(tmp_path, ACTIONS_SPEC, profile_text(options="[]"))
    assert main(["compile", str(spec), "-o", str(tmp_path), "-q"]) == SpecError.exit_code
    assert "needs the controller option G68" in capsys.readouterr().err
    assert not list(tmp_path.glob("*.nc"))


# -- the override lock around touches ---------------------------------------------------

def test_each_touch_is_locked_and_released(tmp_path: Path) -> None:
    """#3003=1 and #3004=2 right before each touch's G31 (F300), both back to 0 right
    after it; protected positioning moves (F2000) stay under the operator's override."""
    lines = program(tmp_path).splitlines()
    touches = [k for k, line in enumerate(lines) if line.startswith("G31") and "F300." in line]
    assert len(touches) == 25
    for k in touches:
        assert lines[k - 2:k] == ["#3003=1", "#3004=2"]
        assert lines[k + 1:k + 3] == ["#3004=0", "#3003=0"]
    assert sum(line.startswith("#3004=") for line in lines) == 2 * len(touches)
    assert not any(line.startswith(("#3003", "#3004"))
                   for line in program(tmp_path, options="[]").splitlines())


@pytest.mark.parametrize("options", [None, '["#3004"]', "[]"])
def test_the_library_locks_where_the_inline_program_does(tmp_path: Path,
                                                        options: str | None) -> None:
    """The compact form: the touch's G31 in O8001 and O8002 (F#190, the probing feed)
    sits between the same lock and unlock blocks as an inline touch; the protected moves'
    G31 (F#191) and the main program have none; without #3004 nothing is locked."""
    text, lib = compact(tmp_path, options)
    locked = options != "[]"
    assert "#3003" not in text and "#3004" not in text
    for name in ("O8000.nc", "O8001.nc", "O8002.nc"):
        lines = (lib / name).read_text().splitlines()
        skips = [k for k, line in enumerate(lines) if line.startswith("G31")]
        for k in skips:
            before, after = lines[k - 2:k], lines[k + 1:k + 3]
            touch = lines[k].endswith("F#190")
            assert (before == ["#3003=1", "#3004=2"]) == (touch and locked), (name, k)
            assert (after == ["#3004=0", "#3003=0"]) == (touch and locked), (name, k)
        held = sum(line.startswith(("#3003", "#3004")) for line in lines)
        assert held == (4 if locked and name != "O8000.nc" else 0), name


@pytest.mark.parametrize("form", ["inline", "compact"])
@pytest.mark.parametrize(("options", "touch_feed"), [(None, 300.0), ("[]", 150.0)])
def test_the_lock_holds_the_touch_feed_on_the_virtual_machine(
        tmp_path: Path, options: str | None, touch_feed: float, form: str) -> None:
    """The operator's override at 50 %: the touches run at the programmed 300 mm/min
    only while #3004 holds it; the protected moves after them run at 1000, so the lock
    was released (in the inline program, or in the library the compact one calls)."""
    text, lib = compact(tmp_path, options) if form == "compact" else \
        (program(tmp_path, options=options), None)
    res = run_program(text, vm(), variables={10020: 0.0, 11020: 0.0}, program_dir=lib,
                      settings=control_settings("fanuc", home=(0.0, 0.0, 500.0),
                                                feed_override=50.0))
    assert res.alarm is None, res.alarm
    feeds = sorted(set(res.skip_feeds))
    assert feeds == sorted({touch_feed, 1000.0})
    assert res.skip_feeds.count(touch_feed) == 25


# -- extended work offsets --------------------------------------------------------------

@pytest.mark.parametrize(("dialect", "offset", "options", "word"), [
    ("fanuc", "G54.1 P12", '["G54.1", "G68", "#3004"]', "G54.1 P12"),
    ("haas", "G154 P12", None, "G154 P12"),
    ("haas", "G154 P99", None, "G154 P99"),
])
def test_extended_offsets_are_written_and_run(tmp_path: Path, dialect: str, offset: str,
                                              options: str | None, word: str) -> None:
    """The program selects the offset; on the virtual machine it runs with that offset in
    force: zero, all 25 touches; 100 mm in X (``#7001 + 20 (P - 1)``), it misses."""
    text = program(tmp_path, dialect, options=options,
                   machine=f'work_offset = "{offset}"\ndialect = "{dialect}"')
    assert f"\n{word}\nG0 G43" in text
    assert run_text(text, vm(), kind="macrob", control=dialect).touches == 25
    p = int(offset.split("P")[1])
    moved = run_program(text, vm(), variables={10020: 0.0, 11020: 0.0,
                                               14001 + 20 * (p - 1): 100.0},
                        settings=control_settings(dialect, home=(0.0, 0.0, 500.0)))
    assert moved.alarm is not None and moved.alarm.number == 3001


def test_haas_writes_g154_for_a_fanuc_extended_offset(tmp_path: Path) -> None:
    text = program(tmp_path, "haas", options='["G54.1"]', machine='work_offset = "G54.1 P7"')
    assert "\nG154 P7\n" in text and "G54.1" not in text
    with pytest.raises(UnsupportedError, match="'linuxcnc' has no extended work offsets"):
        program(tmp_path, "linuxcnc", options='["G54.1"]', machine='work_offset = "G54.1 P7"')


@pytest.mark.parametrize(("machine", "options", "message"), [
    ('work_offset = "G54.1 P12"', None, "work offset G54.1 P12 needs the controller option "
                                        "G54.1"),
    ('work_offset = "G154 P12"', None, 'expected G54 to G59 or "G54.1 Pn" .n 1-300.'),
    ('work_offset = "G54.1 P301"', '["G54.1"]', "found 'G54.1 P301'"),
    ('work_offset = "G154 P100"\ndialect = "haas"', None, 'or "G154 Pn" .n 1-99.'),
    ('work_offset = "G54.1 P1"\ndialect = "linuxcnc"', None, "has no extended work offsets"),
    ('work_offset = "G54.1"', '["G54.1"]', "machine.work_offset: expected G54 to G59"),
])
def test_bad_extended_offsets_are_refused(tmp_path: Path, machine: str, options: str | None,
                                          message: str) -> None:
    text = profile_text(machine=machine, options=options)
    (tmp_path / "m.toml").write_text(text, encoding="utf-8")
    with pytest.raises(SpecError, match=message):
        load_profile(tmp_path / "m.toml")


# -- line length and program memory -----------------------------------------------------

def test_a_line_longer_than_the_profile_allows_is_refused(tmp_path: Path) -> None:
    """The skip check after a G31 is 52 characters: a 50-character control refuses it,
    naming the line, its length and the profile key; 60 takes the program."""
    text = program(tmp_path, controller="line_length = 60")
    assert max(len(line) for line in text.splitlines()) > 50
    with pytest.raises(UnsupportedError, match=r"line \d+ is 5\d characters, expected at "
                                               r"most 50 \(.*machine.toml: "
                                               r"controller.line_length\): '#193=ABS"):
        program(tmp_path, controller="line_length = 50")


def test_a_program_larger_than_the_memory_is_refused(tmp_path: Path) -> None:
    size = len(program(tmp_path).encode("ascii"))
    assert program(tmp_path, controller=f"program_memory = {size}")
    with pytest.raises(UnsupportedError, match=f"the program is {size} bytes, expected at most "
                                               f"{size - 1} .*controller.program_memory"):
        program(tmp_path, controller=f"program_memory = {size - 1}")
    assert "ENDFIL" in program(tmp_path, "dmis", controller="program_memory = 1000")


def test_sim_takes_the_operators_feed_override(in_repo: Path, tmp_path: Path) -> None:
    """``probegen sim --feed-override 50`` runs the locked program to the same log (the
    touches at the held feed); a dial at 0 is a usage error."""
    from probegen.cli.app import ExitCode, main

    spec = "samples/sphere25/sphere_test_iso.toml"
    assert main(["compile", spec, "-o", str(tmp_path), "-q"]) == 0
    logs = []
    for pct in ("100", "50"):
        log = tmp_path / f"{pct}.log"
        assert main(["sim", str(tmp_path / "sphere_test_iso.nc"), "--spec", spec,
                     "--feed-override", pct, "-o", str(log), "-q"]) == 0
        logs.append(log.read_text(encoding="ascii"))
    assert logs[0] == logs[1] and logs[0].count("\nPT ") == 25
    assert main(["sim", str(tmp_path / "sphere_test_iso.nc"), "--spec", spec,
                 "--feed-override", "0", "-o", "-"]) == ExitCode.USAGE


@settings(max_examples=examples(60))
@given(st.sampled_from(["fanuc", "haas", "linuxcnc", "dmis"]),
       st.one_of(st.sampled_from(["G54", "G59", "G54.1 P1", "G54.1 P300", "G154 P99",
                                  "G154 P1", "G54.1 P0", "G154 P100", "G54.1 P301"]),
                 st.text(alphabet="G54.1 P0239", max_size=10)))
def test_any_work_offset_is_accepted_or_refused(dialect: str, name: str) -> None:
    """A work offset is one of the six, or the dialect's own extended code with P in its
    range; anything else is a SpecError naming the key."""
    from probegen.machine.profile import EXTENDED_CODE, EXTENDED_MAX, check_work_offset

    code = EXTENDED_CODE.get(dialect)
    found = re.fullmatch(r"(G54\.1|G154) P([1-9][0-9]*)", name)
    ok = name in ("G54", "G55", "G56", "G57", "G58", "G59") or bool(
        code and found and found[1] == code and int(found[2]) <= EXTENDED_MAX[code])
    try:
        assert check_work_offset(name, dialect, "m.toml: machine.work_offset") == name
    except SpecError as exc:
        assert not ok and str(exc).startswith("m.toml: machine.work_offset: expected G54")
    else:
        assert ok
