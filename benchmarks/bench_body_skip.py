"""Benchmark: planning with the probe body's distance query skipped where a previous
distance proves it cannot be the least (``MeshObstacle.clearance``), against the same
planning querying it everywhere, in one process.

Run:  PYTHONPATH=. .venv/bin/python benchmarks/bench_body_skip.py [--profile cmm|5axis]
      MODEL.step [MODEL.step ...]

Per model and profile (the CMM ``samples/machines/cmm.toml`` to DMIS, the five-axis
``samples/machines/vmc-5axis-fanuc.toml`` to Fanuc; default both, both state a probe
body), it plans what ``probegen plan MODEL --all-revolved`` plans twice, each on a fresh
load of the model (no cache shared): first with the query everywhere
(``collision.SKIP_SLACK`` set to infinity, so no bound ever skips it), then as shipped.
It prints the CPU seconds of each, their ratio, and whether the programs' text (and the
left-out notes) are the same bytes (SHA-256, first 12 digits).
"""

from __future__ import annotations

import argparse
import hashlib
import sys
import time
import warnings
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
PROFILES = {"cmm": ("samples/machines/cmm.toml", "dmis"),
            "5axis": ("samples/machines/vmc-5axis-fanuc.toml", "fanuc")}
"""Profile key: (the sample profile, the dialect its programs are written in)."""


def plan_once(model: Path, key: str) -> tuple[float, str]:
    """CPU seconds of planning ``model`` with profile ``key``, and the digest of the
    programs' text and notes."""
    from probegen import cad
    from probegen.cli.plan import program_text
    from probegen.dialects import get_dialect
    from probegen.machine.profile import load_profile
    from probegen.planning.setups import all_revolved_setups, plan_setups

    sample, dialect = PROFILES[key]
    machine = load_profile(REPO / sample)
    part = cad.load_part(model)
    t0 = time.process_time()
    spec, notes = all_revolved_setups(part, machine)
    setups = plan_setups(spec, runtime_variables=get_dialect(dialect).RUNTIME_VARIABLES,
                         part=part)
    cpu = time.process_time() - t0
    digest = hashlib.sha256("\n".join(notes).encode("utf-8"))
    for _setup, planned in setups:
        digest.update(program_text(dialect, planned, notes).encode("utf-8"))
    return cpu, digest.hexdigest()[:12]


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--profile", choices=sorted(PROFILES), action="append")
    parser.add_argument("models", nargs="+", type=Path)
    args = parser.parse_args(argv)
    sys.path.insert(0, str(REPO))
    import probegen.cli.progress
    from probegen.planning import collision

    probegen.cli.progress.ENABLED = False
    warnings.simplefilter("ignore")
    shipped = collision.SKIP_SLACK
    print("| model | profile | every query CPU s | skipped CPU s | ratio | same programs |")
    print("|---|---|---|---|---|---|")
    for model in args.models:
        for key in args.profile or sorted(PROFILES):
            collision.SKIP_SLACK = float("inf")
            every, a = plan_once(model, key)
            collision.SKIP_SLACK = shipped
            skipped, b = plan_once(model, key)
            print(f"| {model.stem} | {key} | {every:.1f} | {skipped:.1f} | "
                  f"{every / skipped:.2f} | {'yes' if a == b else 'NO'} ({a}, {b}) |",
                  flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
