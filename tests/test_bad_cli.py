"""The bad-input table: every command, fed bad input, prints one line and exits non-zero.

The cases are data (tests/bad_inputs/cli_cases.toml, input files under
tests/bad_inputs/cli/); each is run through ``probegen.cli.app.main`` in the repository root
and its stderr, with the temporary folder, the repository and ../shared written as
``<tmp>``, ``<repo>`` and ``<shared>``, is compared with ``tests/bad_inputs/cli/<id>.err``
(``make goldens`` rewrites them).  A case may prepare its inputs in a temporary folder:

- ``files``: name -> text; ``binary``: names of files of non-text bytes; ``dirs``: folders;
- ``derive``: a copy of a repository file with lines removed (``remove``: lines starting
  with these texts) and texts replaced (``replace``: pairs);
- ``cut``: the first ``bytes`` bytes of a file (a truncated STEP from ../shared/ref/);
- ``before``: command lines run first (they must succeed), e.g. to write a results.json;
  ``edit``: then, in one of the files made, the first occurrence of each text replaced.

Placeholders in argv and texts: ``{tmp}``, ``{repo}``, ``{shared}``.
"""

from __future__ import annotations

import contextlib
import io
import os
import tempfile
import tomllib
from pathlib import Path
from typing import Any

import pytest
from conftest import REPO, assert_golden
from fuzzing import examples
from hypothesis import given, settings
from hypothesis import strategies as st

from probegen.cli.app import main
from probegen.errors import ExitCode

TABLE = REPO / "tests" / "bad_inputs" / "cli_cases.toml"
GOLDEN = REPO / "tests" / "bad_inputs" / "cli"
SHARED = REPO.parent / "shared"
CASES: list[dict[str, Any]] = tomllib.loads(TABLE.read_text(encoding="utf-8"))["case"]
BINARY = bytes(range(256)) * 8
"""Bytes that are no text in any encoding probegen reads (NUL, control, high bytes)."""


def fill(text: str, tmp: Path) -> str:
    """``text`` with its placeholders replaced."""
    for name, path in (("tmp", tmp), ("repo", REPO), ("shared", SHARED)):
        text = text.replace("{" + name + "}", str(path))
    return text


def normalise(text: str, tmp: Path) -> str:
    """``text`` with the machine-dependent folders replaced by their placeholders."""
    for path, name in ((tmp, "<tmp>"), (SHARED.resolve(), "<shared>"), (SHARED, "<shared>"),
                       (REPO, "<repo>")):
        text = text.replace(str(path), name)
    return text


def prepare(case: dict[str, Any], tmp: Path) -> None:
    """Make the case's inputs in ``tmp``."""
    for name in case.get("dirs", []):
        (tmp / name).mkdir(parents=True)
    for name, text in case.get("files", {}).items():
        (tmp / name).write_text(fill(text, tmp), encoding="utf-8")
    for name in case.get("binary", []):
        (tmp / name).write_bytes(BINARY)
    for d in case.get("derive", []):
        lines = (REPO / d["from"]).read_text(encoding="utf-8").splitlines(keepends=True)
        text = "".join(line for line in lines
                       if not line.lstrip().startswith(tuple(d.get("remove", ["\0"]))))
        for old, new in d.get("replace", []):
            assert old in text, f"{case['id']}: {old!r} not in {d['from']}"
            text = text.replace(old, fill(new, tmp))
        (tmp / d["to"]).write_text(text, encoding="utf-8")
    for argv in case.get("before", []):
        code, err = run([fill(a, tmp) for a in argv])
        assert code == ExitCode.OK, f"{case['id']}: preparing with {argv}: {err}"
    if "edit" in case:
        target = tmp / case["edit"]["file"]
        text = target.read_text(encoding="utf-8")
        for old, new in case["edit"]["replace"]:
            assert old in text, f"{case['id']}: {old!r} not in {target}"
            text = text.replace(old, new, 1)
        target.write_text(text, encoding="utf-8")
    if "cut" in case:
        c = case["cut"]
        source = Path(fill(c["from"], tmp))
        if not source.exists():
            pytest.skip(f"reference file {source} not available")
        (tmp / c["to"]).write_bytes(source.read_bytes()[: c["bytes"]])


def run(argv: list[str]) -> tuple[int, str]:
    """``main(argv)``'s exit code and what it wrote to stderr (stdout is dropped)."""
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        code = main(argv)
    return code, err.getvalue()


def test_the_table_is_large_and_well_formed() -> None:
    ids = [c["id"] for c in CASES]
    assert len(ids) >= 50
    assert len(set(ids)) == len(ids), "case ids must be unique"
    commands = {c["argv"][0] for c in CASES}
    assert commands >= {"compile", "features", "plan", "sphere-points", "ingest", "capture",
                        "sim", "qif", "report", "post", "post-ingest", "rotary", "grating"}
    documented = {int(c) for c in ExitCode}
    for c in CASES:
        assert c["exit"] in documented - {ExitCode.OK, ExitCode.INTERNAL}, c["id"]
    stale = {p.stem for p in GOLDEN.glob("*.err")} - set(ids)
    assert not stale, f"golden messages of no case: {sorted(stale)}"


@pytest.mark.parametrize("case", CASES, ids=[c["id"] for c in CASES])
def test_bad_input(in_repo: Path, tmp_path: Path, case: dict[str, Any]) -> None:
    prepare(case, tmp_path)
    code, err = run([fill(a, tmp_path) for a in case["argv"]])
    assert "Traceback" not in err
    assert "internal error" not in err, err
    assert sum(line.startswith("probegen: error:") for line in err.splitlines()) == 1, err
    assert code == case["exit"], err
    assert_golden(GOLDEN / f"{case['id']}.err", normalise(err, tmp_path))


def test_output_folder_with_a_dot_takes_the_program(in_repo: Path, tmp_path: Path) -> None:
    """``-o`` naming an existing folder writes into it, whatever its name looks like."""
    folder = tmp_path / "run.2026"
    folder.mkdir()
    code, err = run(["compile", "samples/sphere25/sphere_test.toml", "-o", str(folder)])
    assert code == ExitCode.OK, err
    assert (folder / "sphere_test.nc").read_text(encoding="ascii").startswith("%")


@pytest.mark.parametrize("argv", [
    ["-q", "--debug", "sphere-points", "--points", "2"],
    ["sphere-points", "-q", "--points", "2", "--debug"],
    ["rotary", "--debug", "plan", "nothere.toml", "-q"],
    ["rotary", "plan", "nothere.toml", "--quiet", "--debug"],
    ["grating", "identify", "nothere.csv", "--debug", "-q"],
    ["grating", "-q", "--debug", "identify", "nothere.csv"],
])
def test_quiet_and_debug_anywhere(in_repo: Path, argv: list[str]) -> None:
    """The flags parse at every position; ``--debug`` adds the traceback of the error."""
    code, err = run(argv)
    assert code not in (ExitCode.OK, ExitCode.USAGE, ExitCode.INTERNAL), err
    assert "Traceback" in err
    assert err.rstrip().splitlines()[-1].startswith("probegen: error: ")


def test_internal_error_is_one_line(monkeypatch: pytest.MonkeyPatch) -> None:
    """A bug prints one line asking for a report and exits 70; ``--debug`` adds the
    traceback."""
    import probegen.cli.app

    def broken(_args: object) -> int:
        raise ZeroDivisionError("float division\nby zero")

    monkeypatch.setattr(probegen.cli.app, "_sphere_points", broken)
    code, err = run(["sphere-points"])
    assert code == ExitCode.INTERNAL == 70
    assert err == ("probegen: internal error: ZeroDivisionError: float division by zero "
                   "(please report this at the project's issue tracker; run again with "
                   "--debug for the traceback)\n")
    code, err = run(["sphere-points", "--debug"])
    assert code == ExitCode.INTERNAL
    assert err.startswith("Traceback") and err.count("\n") > 3
    assert err.endswith("run again with --debug for the traceback)\n")


# -- random command lines -----------------------------------------------------------------

COMMANDS = ["compile", "features", "plan", "sphere-points", "ingest", "sim", "qif", "report",
            "post", "post-ingest", "rotary", "rotary plan", "rotary sim", "rotary identify",
            "grating identify", "grating simulate", "grating", "nonsense", ""]
"""Every command but ``capture`` (a port that opens would wait for data) and the grating
commands that succeed without any input (``grating plan``: slow, and writes).  The
fragments are mostly bad inputs and option values, plus one good spec and its log so that
some lines get as far as writing their outputs (into the current folder, a temporary one)."""

FRAGMENTS = ["-o", "--output", "--spec", "--machine", "--part", "--errors", "--calibration",
             "--features", "--model", "--program", "--write-calibration", "--form", "--roll",
             "--all-revolved", "--revolved", "--points", "--layout", "-d", "--dialect",
             "--degree", "--offset", "--noise", "-q", "--debug", "--", "-", "", "0", "-1",
             "nan", "1e999", "cap", "fanuc", "x" * 300, "\u00e9\u00fc\u2603", "nothere.toml",
             "nothere.step", "empty.toml", "empty.step", "garbage.nc", "garbage.dmi",
             "garbage.toml", "garbage.json", "folder", "folder.d", "folder/x.nc",
             "empty.toml/x", "/proc/probegen-x", "/proc/probegen/",
             str(REPO / "samples" / "sphere25" / "sphere_test.toml"),
             str(REPO / "samples" / "sphere25" / "sphere_test.log")]


@settings(max_examples=examples(60))
@given(st.sampled_from(COMMANDS), st.lists(st.sampled_from(FRAGMENTS) | st.text(max_size=12),
                                           max_size=8))
def test_random_command_lines(command: str, fragments: list[str]) -> None:
    """No exception escapes ``main``; the exit code is a documented one, never 70; no
    traceback without ``--debug``."""
    argv = command.split() + fragments
    with tempfile.TemporaryDirectory() as tmp:
        here = os.getcwd()
        os.chdir(tmp)
        try:
            (Path(tmp) / "folder").mkdir()
            (Path(tmp) / "folder.d").mkdir()
            for name in ("empty.toml", "empty.step"):
                (Path(tmp) / name).write_bytes(b"")
            for name in ("garbage.nc", "garbage.dmi", "garbage.toml", "garbage.json"):
                (Path(tmp) / name).write_bytes(BINARY)
            code, err = run(argv)
        finally:
            os.chdir(here)
    assert code in {int(c) for c in ExitCode}, (argv, err)
    assert code != ExitCode.INTERNAL, (argv, err)
    debug = any(a.startswith("--de") for a in argv)  # --debug, perhaps abbreviated
    assert debug or "Traceback" not in err, (argv, err)


@pytest.mark.parametrize(("argv", "bars"), [
    (["sphere-points"], True),
    (["-q", "sphere-points"], False),
    (["sphere-points", "--quiet"], False),
    (["rotary", "-q", "plan", "samples/rotary/m4.toml", "-o", "-"], False),
    (["rotary", "plan", "samples/rotary/m4.toml", "-o", "-", "-q"], False),
])
def test_quiet_takes_effect_anywhere(in_repo: Path, monkeypatch: pytest.MonkeyPatch,
                                     argv: list[str], bars: bool) -> None:
    import probegen.cli.app
    import probegen.cli.progress

    seen: list[bool] = []
    inputs = probegen.cli.app._inputs

    def spy(args: object) -> list[str]:  # called while the command runs
        seen.append(probegen.cli.progress.ENABLED)
        return inputs(args)  # type: ignore[arg-type]

    monkeypatch.setattr(probegen.cli.app, "_inputs", spy)
    monkeypatch.setattr(probegen.cli.progress, "ENABLED", not bars)
    code, err = run(argv)
    assert code == ExitCode.OK, err
    assert seen == [bars]
    assert probegen.cli.progress.ENABLED is (not bars)  # for that command only


def test_a_warning_is_one_line(monkeypatch: pytest.MonkeyPatch) -> None:
    """A library's warning reaches the user as one line, not as a source-code excerpt."""
    import warnings

    import probegen.cli.app

    def warns(_args: object) -> int:
        warnings.warn("invalid value encountered\nin divide", RuntimeWarning, stacklevel=1)
        return 0

    monkeypatch.setattr(probegen.cli.app, "_sphere_points", warns)
    with warnings.catch_warnings():
        warnings.simplefilter("always")
        code, err = run(["sphere-points"])
    assert code == ExitCode.OK
    assert err == "probegen: warning: RuntimeWarning: invalid value encountered in divide\n"
