"""The README's quick tour runs as written, line by line, in a fresh clone after ``make demo``.

The clone is ``git clone`` of this repository checked out at its HEAD commit, so the test
runs what is committed: uncommitted changes to README.md, the Makefile, the samples or the
package are not seen (commit first).  ``../shared`` (the reference data) is linked beside
the clone, as on a developer's disk.

Affordable rather than brand new: instead of making a virtual environment (``pip install``
takes minutes), ``probegen`` is a shim on ``PATH`` that runs the clone's package with this
interpreter (``python -m probegen.cli.app``, the clone first on ``PYTHONPATH``), and
``make demo BIN=<shim folder> STAMP=<a fresh file>`` runs the Makefile's demo commands
through it.  Then every line of the README's quick-tour block runs verbatim in a shell with
the clone as the working folder, except the serial capture line (it needs a machine on a
port; the README says so on that line).  Each line must exit 0 (or the code its comment
names as ``exit code N``) and must write every output it names (``-o``, ``--out``,
``--write-calibration``, ``--compensation``): a file written anew, or a folder with
something written in it.
"""

from __future__ import annotations

import os
import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from probegen.cli.app import _OUTPUT_OPTIONS, build_parser

REPO = Path(__file__).resolve().parents[1]
SHARED = REPO.parent / "shared"

pytestmark = pytest.mark.skipif(not SHARED.is_dir(), reason="../shared (reference data) "
                                "is not beside the repository")


def tour_lines(readme: str) -> list[str]:
    """The command lines of the first code block after ``## Quick tour``."""
    section = readme.split("\n## Quick tour\n", 1)[1]
    block = section.split("```\n", 2)[1]
    return [line for line in block.splitlines() if line.strip()]


def is_capture(line: str) -> bool:
    """Whether ``line`` is the serial capture (the one line the test cannot run)."""
    return shlex.split(line, comments=True)[1:2] == ["capture"]


def expected_code(line: str) -> int:
    """0, or the ``exit code N`` the line's comment names."""
    comment = line.partition("#")[2]
    match = re.search(r"exit code (\d+)", comment)
    return int(match.group(1)) if match else 0


def named_outputs(line: str) -> list[str]:
    """The files and folders ``line`` says it writes (stdout, ``-``, excluded); none for a
    line that does not parse (running it then fails with its usage message)."""
    try:
        args = build_parser().parse_args(shlex.split(line, comments=True)[1:])
    except SystemExit:
        return []
    return [v for k, v in sorted(vars(args).items())
            if k in _OUTPUT_OPTIONS and k != "pty" and isinstance(v, str) and v != "-"
            and v in line]


def snapshot(path: Path) -> dict[Path, int]:
    """Every file at or under ``path`` with its modification time (ns)."""
    files = [path] if path.is_file() else [p for p in path.rglob("*") if p.is_file()]
    return {p: p.stat().st_mtime_ns for p in files}


def written(before: dict[Path, int], path: Path) -> bool:
    """Whether something at or under ``path`` is new or changed since ``before``."""
    return any(before.get(p) != t for p, t in snapshot(path).items())


def test_tour_lines_are_commands() -> None:
    """The block holds only ``probegen`` lines, the capture line among them and marked."""
    lines = tour_lines((REPO / "README.md").read_text(encoding="utf-8"))
    assert len(lines) >= 10
    assert all(line.startswith("probegen ") for line in lines), lines
    captures = [line for line in lines if is_capture(line)]
    assert len(captures) == 1 and "serial port" in captures[0].partition("#")[2]


def test_io_table_names_every_command() -> None:
    """The README's reads/writes table has one row per command, and only those."""
    readme = (REPO / "README.md").read_text(encoding="utf-8")
    rows = re.findall(r"^\| `([a-z -]+)` \|", readme, flags=re.MULTILINE)
    commands: list[str] = []
    sub = next(a for a in build_parser()._actions if a.choices and isinstance(a.choices, dict))
    for name, parser in sub.choices.items():
        nested = [a for a in parser._actions if isinstance(a.choices, dict)]
        commands += [f"{name} {leaf}" for leaf in nested[0].choices] if nested else [name]
    assert sorted(rows) == sorted(commands)


@pytest.fixture(scope="module")
def clone(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict[str, str]]:
    """A clone of HEAD with ../shared beside it and ``make demo`` run; its environment."""
    if shutil.which("git") is None or shutil.which("make") is None:
        pytest.fail("the tour test needs git and make")
    root = tmp_path_factory.mktemp("tour")
    head = subprocess.run(["git", "-C", str(REPO), "rev-parse", "HEAD"], check=True,
                          capture_output=True, text=True).stdout.strip()
    work = root / "probegen"
    subprocess.run(["git", "clone", "--quiet", "--no-checkout", str(REPO), str(work)],
                   check=True)
    subprocess.run(["git", "-C", str(work), "checkout", "--quiet", head], check=True)
    (root / "shared").symlink_to(SHARED)
    shim = root / "bin"
    shim.mkdir()
    (shim / "probegen").write_text(f'#!/bin/sh\nexec {shlex.quote(sys.executable)} '
                                   '-m probegen.cli.app "$@"\n')
    (shim / "probegen").chmod(0o755)
    stamp = root / "installed"  # newer than the clone's pyproject.toml: no venv is made
    stamp.touch()
    env = {**os.environ, "PATH": f"{shim}{os.pathsep}{os.environ['PATH']}",
           "PYTHONPATH": str(work)}
    env.pop("PROBEGEN_REGEN", None)
    where = subprocess.run(["probegen", "--version"], cwd=work, env=env,
                           capture_output=True, text=True)
    assert where.returncode == 0, where.stderr
    found = subprocess.run([sys.executable, "-c", "import probegen; print(probegen.__file__)"],
                           cwd=root, env=env, capture_output=True, text=True).stdout
    assert Path(found.strip()).is_relative_to(work), found  # the clone's package runs
    demo = subprocess.run(["make", "demo", f"BIN={shim}", f"STAMP={stamp}"], cwd=work,
                          env=env, capture_output=True, text=True, timeout=300)
    assert demo.returncode == 0, demo.stdout[-2000:] + demo.stderr[-2000:]
    assert (work / "out" / "report.html").is_file()
    return work, env


def test_quick_tour_runs(clone: tuple[Path, dict[str, str]]) -> None:
    """Every line of the README's quick tour (the capture excepted), verbatim, in order."""
    work, env = clone
    lines = tour_lines((work / "README.md").read_text(encoding="utf-8"))
    ran = 0
    for line in lines:
        if is_capture(line):
            continue
        outputs = [work / p for p in named_outputs(line)]
        before = {p: snapshot(p) if p.exists() else {} for p in outputs}
        done = subprocess.run(["bash", "-c", line], cwd=work, env=env, capture_output=True,
                              text=True, timeout=300)
        assert done.returncode == expected_code(line), (line, done.stdout[-1500:],
                                                        done.stderr[-1500:])
        assert "Traceback" not in done.stderr, (line, done.stderr)
        for path in outputs:
            assert path.exists() and written(before[path], path), (line, path)
        if not outputs:
            assert done.stdout.strip(), (line, "prints nothing")
        ran += 1
    assert ran == len(lines) - 1
