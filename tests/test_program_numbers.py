"""Program numbers: O9000-O9999 are protected on Fanuc and Haas controls, so ``compile``
(and ``rotary plan``) refuse them unless the machine profile's ``[controller]
program_numbers = [first, last]`` lets them in (docs/spec.md, "Machine profile")."""

from __future__ import annotations

from pathlib import Path

import pytest
from conftest import REPO
from fuzzing import examples
from hypothesis import given, settings
from hypothesis import strategies as st

from probegen.cli.app import ExitCode, main
from probegen.errors import SpecError
from probegen.machine.profile import load_profile

PROFILE = (REPO / "samples/machines/vmc-fanuc.toml").read_text(encoding="utf-8")
SPEC = (REPO / "samples/sphere25/sphere_test_iso.toml").read_text(encoding="utf-8")


def write_profile(folder: Path, controller: str = "", dialect: str = "fanuc") -> Path:
    """The sample profile with ``controller`` lines added to ``[controller]``."""
    text = PROFILE.replace('dialect = "fanuc"', f'dialect = "{dialect}"').replace(
        "[controller]\n", f"[controller]\n{controller}\n")
    path = folder / "profile.toml"
    path.write_text(text, encoding="utf-8")
    return path


def write_spec(folder: Path, number: int, controller: str = "", dialect: str = "fanuc") -> Path:
    profile = write_profile(folder, controller, dialect)
    text = SPEC.replace("number = 1002", f"number = {number}").replace(
        '"../machines/vmc-fanuc.toml"', f'"{profile}"')
    path = folder / "spec.toml"
    path.write_text(text, encoding="utf-8")
    return path


def compile_(spec: Path, folder: Path, *dialect: str) -> int:
    argv = ["compile", str(spec), "-o", str(folder / "out"), "-q"]
    return main(argv + [w for d in dialect for w in ("-d", d)])


@pytest.mark.parametrize("dialect", ["fanuc", "haas"])
def test_o9001_is_refused_by_default(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                     dialect: str) -> None:
    spec = write_spec(tmp_path, 9001, dialect=dialect)
    assert compile_(spec, tmp_path) == ExitCode.SPEC
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err
    assert f"{spec}: program.number: expected a program number in O1-O8999" in err
    assert "controller.program_numbers), found 9001: O9000-O9999 are protected" in err
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("number", [8999, 1, 1002])
def test_numbers_below_the_protected_range_pass(tmp_path: Path, number: int) -> None:
    spec = write_spec(tmp_path, number)
    assert compile_(spec, tmp_path) == ExitCode.OK
    assert f"\nO{number:04d}(SPHERE TEST ISO)\n" in (tmp_path / "out/spec.nc").read_text()


@pytest.mark.parametrize(("controller", "number", "ok"), [
    ("program_numbers = [1, 9999]", 9001, True),
    ("program_numbers = [9000, 9099]\nlibrary_number = 9090", 9001, True),
    ("program_numbers = [9000, 9099]\nlibrary_number = 9090", 9100, False),
    ("program_numbers = [1000, 1999]", 2001, False),
    ("program_numbers = [1000, 1999]", 999, False),
])
def test_the_profile_range_decides(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                   controller: str, number: int, ok: bool) -> None:
    spec = write_spec(tmp_path, number, controller)
    assert (compile_(spec, tmp_path, "fanuc", "haas") == ExitCode.OK) is ok
    err = capsys.readouterr().err
    if ok:
        assert f"\nO{number}(SPHERE TEST ISO)\n" in (tmp_path / "out/spec.haas.nc").read_text()
    else:
        lo, hi = controller.split("[")[1].split("]")[0].split(", ")
        assert f"expected a program number in O{lo}-O{hi}" in err
        assert ("are protected" in err) is (number >= 9000)


def test_the_library_needs_a_number_in_the_range(tmp_path: Path,
                                                 capsys: pytest.CaptureFixture[str]) -> None:
    """The compact form (compile's default) writes the macro library O8000-O8002 too: a
    range without them is refused, naming the key that moves the library; the inline
    form calls nothing and passes."""
    spec = write_spec(tmp_path, 9001, "program_numbers = [9000, 9099]")
    assert compile_(spec, tmp_path) == ExitCode.SPEC
    err = capsys.readouterr().err
    assert "controller.library_number (O8000): expected a program number in O9000-O9099" in err
    assert not (tmp_path / "out").exists()
    assert main(["compile", str(spec), "--inline", "-o", str(tmp_path / "out"), "-q"]) == 0
    assert [p.name for p in (tmp_path / "out").iterdir()] == ["spec.nc"]


@pytest.mark.parametrize("dialect", ["linuxcnc", "dmis"])
def test_controls_without_protected_programs_default_to_every_number(
        tmp_path: Path, dialect: str) -> None:
    profile = load_profile(write_profile(tmp_path, dialect=dialect))
    assert profile.controller.program_numbers == (1, 9999)
    profile.check_program_number(9001, "here")


@pytest.mark.parametrize("value", ["[9000, 10]", "[0, 10]", "[1, 10000]", "[1, 2, 3]",
                                   '["1", 10]', "[1.0, 10]", "true", "[true, 10]", "9001"])
def test_bad_ranges_name_the_key(tmp_path: Path, value: str) -> None:
    path = write_profile(tmp_path, f"program_numbers = {value}")
    with pytest.raises(SpecError, match=r"profile.toml: controller.program_numbers: expected "
                                        r"\[first, last\] program numbers with 1 <= first "
                                        r"<= last <= 9999, found "):
        load_profile(path)


def test_rotary_plan_refuses_a_protected_number(tmp_path: Path,
                                                capsys: pytest.CaptureFixture[str]) -> None:
    profile = write_profile(tmp_path)
    text = (REPO / "samples/rotary/m4.toml").read_text(encoding="utf-8").replace(
        "number = 4001", "number = 9500").replace('"../machines/vmc-fanuc.toml"', f'"{profile}"')
    spec = tmp_path / "m4.toml"
    spec.write_text(text, encoding="utf-8")
    argv = ["rotary", "plan", str(spec), "-o", str(tmp_path / "out"), "-q"]
    assert main(argv) == ExitCode.SPEC
    assert "program.number: expected a program number in O1-O8999" in capsys.readouterr().err


WORDS = st.text("abc019 -", max_size=4)


def toml(value: object) -> str:
    """``value`` (lists, integers, numbers, booleans, plain strings) as a TOML value."""
    if isinstance(value, list):
        return "[" + ", ".join(toml(v) for v in value) + "]"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return {"nan": "nan", "inf": "inf", "-inf": "-inf"}.get(repr(value), repr(value))
    return f'"{value}"' if isinstance(value, str) else str(value)


@settings(max_examples=examples(60))
@given(value=st.one_of(
    st.lists(st.integers(-5, 10_005), min_size=0, max_size=3),
    st.lists(st.one_of(st.integers(1, 9999), st.floats(), WORDS, st.booleans()),
             min_size=2, max_size=2),
    st.integers(), WORDS, st.booleans()))
def test_any_program_numbers_value_is_a_range_or_a_spec_error(tmp_path_factory: pytest.
                                                              TempPathFactory,
                                                              value: object) -> None:
    """Random ``program_numbers`` values: a valid range that then decides, or a SpecError."""
    folder = tmp_path_factory.mktemp("p")
    path = write_profile(folder, f"program_numbers = {toml(value)}")
    try:
        profile = load_profile(path)
    except SpecError as exc:
        assert "controller.program_numbers: expected [first, last]" in str(exc)
        return
    first, last = profile.controller.program_numbers
    assert value == [first, last] and 1 <= first <= last <= 9999
    for number in (first - 1, first, last, last + 1):
        inside = first <= number <= last
        try:
            profile.check_program_number(number, "spec.toml: program.number")
            assert inside
        except SpecError:
            assert not inside


def test_linuxcnc_library_subroutines_take_no_program_number(tmp_path: Path) -> None:
    """LinuxCNC's library is named subroutine files: a program range that leaves out
    ``library_number`` still compiles the compact form, and writes the files; on Fanuc the
    same range is refused (test_the_library_needs_a_number_in_the_range)."""
    spec = write_spec(tmp_path, 100, "program_numbers = [1, 999]", dialect="linuxcnc")
    argv = ["compile", str(spec), "-d", "linuxcnc", "--compact", "-o", str(tmp_path / "out"),
            "-q"]
    assert main(argv) == ExitCode.OK
    names = sorted(p.name for p in (tmp_path / "out").iterdir())
    assert "spec.ngc" in names and len(names) > 1
    assert all(n == "spec.ngc" or n.endswith(".ngc") for n in names)
