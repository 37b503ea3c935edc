"""The command line's front door: help in a CNC programmer's words, the dialects named from
the registry, ``-q``/``--debug`` anywhere on every command, the capture's words, and one
policy for existing outputs (no output over an input, even one a spec names)."""

from __future__ import annotations

import argparse
import contextlib
import io
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from conftest import REPO

from probegen.cli.app import build_parser, main
from probegen.errors import ExitCode
from probegen.files import load_toml, write_file


def _subparsers(parser: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    action = next((a for a in parser._actions if isinstance(a, argparse._SubParsersAction)),
                  None)
    return {} if action is None else dict(action.choices)


def command_paths(parser: argparse.ArgumentParser | None = None,
                  prefix: tuple[str, ...] = ()) -> list[tuple[str, ...]]:
    """Every command and subcommand as its words (``()`` is ``probegen`` itself)."""
    parser = parser or build_parser()
    out = [prefix]
    for name, sub in _subparsers(parser).items():
        out += command_paths(sub, (*prefix, name))
    return out


def leaf_parser(path: tuple[str, ...]) -> argparse.ArgumentParser:
    parser = build_parser()
    for word in path:
        parser = _subparsers(parser)[word]
    return parser


LEAVES = [p for p in command_paths() if p and not _subparsers(leaf_parser(p))]


def minimal_line(path: tuple[str, ...]) -> list[str]:
    """The command's words and a placeholder for each required argument (parsing opens no
    file, so ``x`` serves; an argument with choices gets its first)."""
    words: list[str] = []
    for action in leaf_parser(path)._actions:
        value = str(next(iter(action.choices))) if action.choices else "x"
        if not action.option_strings and action.nargs in (None, "+"):
            words.append(value)
        elif action.option_strings and action.required:
            words += [action.option_strings[-1], value]
    return [*path, *words]


def help_text(path: tuple[str, ...]) -> str:
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        assert main([*path, "--help"]) == ExitCode.OK
    return out.getvalue()


def test_every_leaf_command_is_found() -> None:
    assert ("rotary", "identify") in LEAVES and ("grating", "simulate") in LEAVES
    assert ("post-ingest",) in LEAVES and ("rotary",) not in LEAVES
    assert ("spc",) in LEAVES and ("export",) in LEAVES
    assert len(LEAVES) == 21


@pytest.mark.parametrize("path", command_paths(), ids=lambda p: " ".join(p) or "probegen")
def test_help_speaks_a_cnc_programmers_words(path: tuple[str, ...]) -> None:
    """No internal names in any help: the methods M1-M5 and the IR are ours, not the
    user's."""
    text = help_text(path)
    assert "usage: probegen" in text
    assert not re.search(r"\bM[1-5]\b", text), text
    assert not re.search(r"\bIR\b", text), text


def test_compile_help_lists_the_registered_dialects() -> None:
    from probegen.dialects import REGISTRY

    text = " ".join(help_text(("compile",)).split())
    assert len(REGISTRY) >= 4
    for name, cls in REGISTRY.items():
        first = (cls.__doc__ or "").strip().splitlines()[0].rstrip(".")
        assert f"{name}: {first}" in text
    post = " ".join(help_text(("post",)).split())
    assert "fanuc: Fanuc Macro B" in post and "dmis:" not in post  # no DPRNT log from DMIS


@pytest.mark.parametrize("path", LEAVES, ids=" ".join)
def test_quiet_and_debug_anywhere_on_every_command(path: tuple[str, ...]) -> None:
    """``-q``/``--quiet`` and ``--debug`` parse before, between and after the command's
    words, on every command and subcommand; absent, both are false."""
    line = minimal_line(path)
    plain = build_parser().parse_args(line)
    assert (plain.quiet, plain.debug) == (False, False)
    for at in [*range(len(path) + 1), len(line)]:
        for quiet in ("-q", "--quiet"):
            words = [*line[:at], quiet, "--debug", *line[at:]]
            args = build_parser().parse_args(words)
            assert (args.quiet, args.debug) == (True, True), words
            assert args.func is plain.func


def test_capture_append_speaks_words(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                     capsys: pytest.CaptureFixture[str]) -> None:
    """``capture --append`` says it is appending and how much it added, in words."""
    import importlib

    capture_module = importlib.import_module("probegen.results.capture")  # not the function
    log = tmp_path / "run.log"
    log.write_bytes(b"%\nPGSTART O1001\n")
    seen: dict[str, object] = {}

    def fake(port: str, out: Path, **kw: object) -> capture_module.CaptureResult:
        seen.update(kw)
        return capture_module.CaptureResult(Path(out), 40, "end-marker", offset=15)

    monkeypatch.setattr(capture_module, "capture", fake)
    assert main(["capture", "--port", "loop://", "--out", str(log), "--append"]) == 0
    out, err = capsys.readouterr()
    assert seen["append"] is True
    assert f"capturing from loop:// appending to {log} (9600 baud, 7E2" in err
    assert f"40 bytes added to {log} after its 15 earlier bytes" in out
    assert "append=" not in out + err


def _sample(tmp_path: Path) -> Path:
    """A copy of the sphere sample and the machine profile its spec names."""
    shutil.copytree(REPO / "samples" / "sphere25", tmp_path / "sphere25")
    shutil.copytree(REPO / "samples" / "machines", tmp_path / "machines")
    return tmp_path / "sphere25" / "sphere_test.toml"


@pytest.mark.parametrize("victim", ["sphere25/sphere25.step", "machines/vmc-fanuc.toml"])
def test_no_output_over_a_file_the_spec_names(tmp_path: Path, victim: str,
                                              capsys: pytest.CaptureFixture[str]) -> None:
    """``compile -o`` naming the model or the machine profile the spec reads is refused
    (exit 73) and the file is untouched: an input is never overwritten, whether it is on
    the command line or named by one of its files."""
    spec = _sample(tmp_path)
    target = tmp_path / victim
    before = target.read_bytes()
    assert main(["compile", str(spec), "-d", "fanuc", "-o", str(target)]) == ExitCode.OUTPUT
    assert target.read_bytes() == before
    err = capsys.readouterr().err
    assert f"{target}: expected a new file for the fanuc program, found one of this " \
           "command's inputs" in err
    assert main(["compile", str(spec), "-d", "fanuc", "-o", str(tmp_path / "a.nc")]) == 0
    assert (tmp_path / "a.nc").read_text(encoding="ascii").startswith("%")


def test_library_use_notes_no_inputs(tmp_path: Path) -> None:
    """Outside a command, reading a file does not stop a later write to it."""
    path = tmp_path / "p.toml"
    path.write_text("a = 1\n")
    assert load_toml(path) == {"a": 1}
    write_file(path, "a = 2\n", "a test file")
    assert load_toml(path) == {"a": 2}


def test_writers_go_through_the_output_policy() -> None:
    """Every file a command writes goes through probegen.files (write_file, output_folder):
    no other module opens a file for writing, but the capture's raw log (never
    overwritten, by its own rule) and the --pty link."""
    allowed = {"probegen/files.py", "probegen/results/capture.py",
               "probegen/cad/loading.py"}  # loading: a pipe to its reader process
    write = re.compile(r"write_text\(|write_bytes\(|open\([^)]*['\"][wax]b?['\"]|"
                       r"os\.open\(|savetxt\(|\.tofile\(")
    found = []
    for path in sorted((REPO / "probegen").rglob("*.py")):
        rel = path.relative_to(REPO).as_posix()
        for k, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
            if write.search(line) and rel not in allowed and "os.devnull" not in line:
                found.append(f"{rel}:{k}: {line.strip()}")
    assert not found, found


def test_the_command_line_starts_without_the_cad_kernel_or_the_templates() -> None:
    """Building the parser (every command's start, help texts listing the dialects
    included) loads neither OCP/build123d nor jinja2: ``capture`` and ``ingest`` on a
    shop-floor PC start fast, and the dialect list comes from the registry alone."""
    code = ("import sys; from probegen.cli.app import build_parser; build_parser(); "
            "print(sorted(m for m in ('OCP', 'build123d', 'jinja2', 'trimesh') "
            "if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, cwd=REPO)
    assert out.stdout.strip() == "[]"
