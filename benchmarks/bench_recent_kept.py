"""Benchmark: planning with the collision geometry of the 8 most recently used frames kept
(``cad.part.RECENT_KEPT``), against 4 (before stop 28), in one process.

Run:  PYTHONPATH=. .venv/bin/python benchmarks/bench_recent_kept.py [--profile cmm|5axis]
      [--before N] MODEL.step [MODEL.step ...]

Per model and profile (``bench_memory.PROFILES``; default both) it plans what ``probegen
plan MODEL --all-revolved`` plans twice, each on a fresh load of the model
(``bench_memory.child``): first with ``RECENT_KEPT`` set to ``--before`` (4), then as
shipped.  A frame whose height map (and FCL tree) was dropped is built again when the
planner comes back to it (NIST CTC 1 with the CMM: 8 frames, 26 height maps built with 4
kept).  It prints the plan time of each (wall clock, s), their ratio, the height maps
alive at the end (MB, their grids and dilations: what the larger bound costs) and
whether the programs' text is the same bytes (SHA-256, first 12 digits).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from bench_memory import PROFILES, REPO, compare_rows


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--profile", choices=sorted(PROFILES), action="append")
    parser.add_argument("--before", type=int, default=4)
    parser.add_argument("models", nargs="+", type=Path)
    args = parser.parse_args(argv)
    sys.path.insert(0, str(REPO))
    from probegen.cad import part as part_module

    shipped = part_module.RECENT_KEPT
    print(f"| model | profile | {args.before} kept s | {shipped} kept s | ratio | "
          f"maps alive MB ({args.before}, {shipped}) | same programs |")
    print("|---|---|---|---|---|---|---|")
    compare_rows(args.models, args.profile or sorted(PROFILES),
                 [(part_module, "RECENT_KEPT", args.before)],
                 lambda a, b: f"{a['maps_mb']:.0f}, {b['maps_mb']:.0f}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
