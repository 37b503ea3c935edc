"""Benchmark: does every reference STEP file load (issue 17, item 7)?

Run:  PYTHONPATH=. .venv/bin/python benchmarks/bench_step_load.py [FILE ...]

Without arguments: every ``*.stp`` / ``*.step`` under ``../shared/ref/nist-step``,
``../shared/ref/parts`` (recursively) and the DCX part
(``../shared/ref/nist-ippdme/DCXpart/STEP_AP214``).  Each file goes through
:func:`probegen.cad.load_step` (the loader every command uses).  Prints per file: the
outcome (``loads``, ``warnings`` = loads with colour or style entities ignored,
``refused``), the face count, the load time, and the first warning or the refusal's
reason; then the counts.
"""

from __future__ import annotations

import sys
import time
import warnings
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

SHARED = REPO.parent / "shared" / "ref"
FOLDERS = (SHARED / "nist-step", SHARED / "parts", SHARED / "nist-ippdme/DCXpart/STEP_AP214")


def files(args: list[str]) -> list[Path]:
    """The files named, or every STEP file of :data:`FOLDERS` (sorted per folder)."""
    if args:
        return [Path(a) for a in args]
    return [f for folder in FOLDERS for f in sorted(folder.rglob("*"))
            if f.suffix.lower() in (".stp", ".step")]


def main(args: list[str]) -> int:
    from probegen import cad
    from probegen.errors import ModelError

    counts = {"loads": 0, "warnings": 0, "refused": 0}
    print(f"{'file':<44} {'outcome':<9} {'faces':>6} {'s':>6}  reason")
    for path in files(args):
        start = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            try:
                model = cad.load_step(path)
            except ModelError as exc:
                outcome, faces, why = "refused", 0, str(exc).split(": ", 1)[1]
            else:
                outcome = "warnings" if model.warnings else "loads"
                faces = len(model.faces)
                why = model.warnings[0].split(": ", 1)[1] if model.warnings else ""
                if len(model.warnings) > 1:
                    why += f" (+{len(model.warnings) - 1} more)"
        counts[outcome] += 1
        print(f"{path.name:<44} {outcome:<9} {faces:>6} {time.perf_counter() - start:>6.2f}"
              f"  {why}")
    total = sum(counts.values())
    print(f"{total} files: {counts['loads']} load, {counts['warnings']} load with warnings, "
          f"{counts['refused']} refused")
    return 0 if counts["refused"] == 0 else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
