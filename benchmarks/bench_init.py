"""Benchmark: ``probegen init`` on the samples, the NIST models and the DCX part, and the
skeleton compiled unchanged (issue 17, item 3).

Run:  PYTHONPATH=. .venv/bin/python benchmarks/bench_init.py [MODEL ...]

Without arguments: the four sample models, every ``../shared/ref/nist-step/*.stp`` and
the DCX part, with ``samples/machines/vmc-fanuc.toml``.  Per model: ``probegen init``
into a temporary folder, then ``probegen compile`` of that spec to Fanuc and DMIS
(unchanged).  Prints per model the features of the skeleton (revolved, planes,
free-form), the ones left out, whether both programs compiled (``yes``, else the
error), and the times of init and compile (wall clock).
"""

from __future__ import annotations

import contextlib
import io
import sys
import tempfile
import time
import warnings
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

MACHINE = REPO / "samples/machines/vmc-fanuc.toml"
SAMPLES = [REPO / f"samples/{s}/{s}.step"
           for s in ("sphere25", "bore_block", "revolved_block", "freeform")]
SHARED = REPO.parent / "shared" / "ref"
DCX = SHARED / "nist-ippdme/DCXpart/STEP_AP214/DaimlerChryslerTestPartAP214.stp"


def models(args: list[str]) -> list[Path]:
    """The models named, or the samples, the NIST models and the DCX part."""
    if args:
        return [Path(a) for a in args]
    return [*SAMPLES, *sorted((SHARED / "nist-step").glob("*.stp")), DCX]


def run(model: Path, folder: Path) -> str:
    """One table row: init, then compile the skeleton to Fanuc and DMIS."""
    from probegen.cli.app import main
    from probegen.spec.model import load_spec

    spec = folder / f"{model.stem}.toml"
    out = io.StringIO()
    start = time.perf_counter()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(out):
        code = main(["-q", "init", str(model), "--machine", str(MACHINE), "-o", str(spec)])
    init_s = time.perf_counter() - start
    if code:
        return f"| {model.stem} | init failed: {out.getvalue().strip()[:80]} |"
    kinds = {"RevolvedSpec": 0, "PlanarSpec": 0, "FreeformSpec": 0}
    left = sum(1 for line in spec.read_text().splitlines() if line.startswith("#   "))
    if "\n[[feature]]\n" not in spec.read_text():  # nothing measurable: no spec to load
        return f"| {model.stem} | 0 | 0 | 0 | 0 | {left} | no feature to compile | " \
               f"{init_s:.1f} | - |"
    for f in load_spec(spec).features:
        kinds[type(f).__name__] += 1
    out = io.StringIO()
    start = time.perf_counter()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(out):
        code = main(["-q", "compile", str(spec), "-d", "fanuc", "-d", "dmis", "-o",
                     str(folder / model.stem)])
    compile_s = time.perf_counter() - start
    compiled = "yes" if code == 0 else f"no: {out.getvalue().strip()[:80]}"
    total = sum(kinds.values())
    return (f"| {model.stem} | {total} | {kinds['RevolvedSpec']} | {kinds['PlanarSpec']} | "
            f"{kinds['FreeformSpec']} | {left} | {compiled} | {init_s:.1f} | {compile_s:.1f} |")


def main(args: list[str]) -> int:
    warnings.simplefilter("ignore")
    print("| model | features | revolved | planes | free-form | left out | compiled "
          "(Fanuc, DMIS) | init s | compile s |")
    print("|---|---|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        for model in models(args):
            print(run(model, Path(tmp)), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
