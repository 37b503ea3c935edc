"""Benchmark: the virtual machine checking the whole probe (the shank and the probe body,
``sim/stem.py``) against the ball alone, on the programs ``plan --all-revolved`` writes.

Run:  PYTHONPATH=. .venv/bin/python benchmarks/bench_stem.py [--profile cmm|5axis] [MODEL ...]

Without models: our parts (``samples/parts/*.step``).  Per model and profile (the CMM
sample to DMIS, the five-axis sample to Fanuc), ``probegen plan MODEL --all-revolved
--machine PROFILE -d DIALECT -o DIR`` writes one program per setup; each runs as
``probegen sim PROGRAM --part MODEL --machine PROFILE [--setup NAME]`` twice in this
process: the ball alone (``vm.STEM = False``, the baseline) and the whole probe.  Prints
per program its lines, the two runs' CPU times (each loads the model, as ``probegen sim``
does), their ratio and what each run ended in (an alarm is a finding: a move the
planner cleared that the virtual machine does not).
"""

from __future__ import annotations

import argparse
import contextlib
import io
import sys
import tempfile
import time
import warnings
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

PROFILES = {"cmm": (REPO / "samples/machines/cmm.toml", "dmis"),
            "5axis": (REPO / "samples/machines/vmc-5axis-fanuc.toml", "fanuc")}


def _cli(args: list[str]) -> tuple[int, str]:
    """``probegen ARGS`` in this process: exit code and what it printed."""
    from probegen.cli.app import main

    out = io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(out):
        try:
            code = main(args)
        except SystemExit as exc:
            code = int(exc.code or 0)
    return code or 0, out.getvalue()


def run(model: Path, key: str) -> list[str]:
    """The rows of one model and profile."""
    from probegen.sim import vm

    profile, dialect = PROFILES[key]
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        code, said = _cli(["-q", "plan", str(model), "--all-revolved", "--machine",
                           str(profile), "-d", dialect, "-o", tmp])
        if code:
            return [f"| {model.stem} | {key} | plan exit {code}: {said.strip()[:80]} |"]
        for program in sorted(p for p in Path(tmp).iterdir() if p.suffix in (".nc", ".dmi")):
            setup = program.stem.split("_")[-1] if "_" in program.stem else ""
            args = ["-q", "sim", str(program), "--part", str(model), "--machine",
                    str(profile), "-o", str(Path(tmp) / "sim.log")]
            if setup.isupper() and setup != model.stem.upper():
                args += ["--setup", setup]
            ends, times = [], []
            for stem in (False, True):
                vm.STEM = stem
                t = time.process_time()
                code, said = _cli(args)
                times.append(time.process_time() - t)
                ends.append("no alarm" if code == 0 else " ".join(said.split())[:120])
            vm.STEM = True
            lines = len(program.read_text(encoding="utf-8").splitlines())
            rows.append(f"| {model.stem} | {key} | {program.name} | {lines} | {times[0]:.1f} | "
                        f"{times[1]:.1f} | {times[1] / times[0]:.2f} | {ends[0]} | {ends[1]} |")
    return rows


def main() -> None:
    warnings.simplefilter("ignore")
    parser = argparse.ArgumentParser()
    parser.add_argument("--profile", choices=sorted(PROFILES), action="append")
    parser.add_argument("models", nargs="*", type=Path)
    args = parser.parse_args()
    models = args.models or sorted((REPO / "samples/parts").glob("*.step"))
    print("| model | profile | program | lines | ball alone CPU s | whole probe CPU s | ratio | "
          "ball alone | whole probe |")
    print("|---|---|---|---|---|---|---|---|---|")
    for model in models:
        for key in args.profile or sorted(PROFILES):
            for row in run(model, key):
                print(row, flush=True)


if __name__ == "__main__":
    main()
