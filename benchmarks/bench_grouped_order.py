"""Benchmark: ``plan --all-revolved`` with the features planned grouped by the frame that
first reaches them (``planning.revolved_spec.planning_order``), against the order they
were recognised in (before stop 33), in one process.

Run:  PYTHONPATH=. .venv/bin/python benchmarks/bench_grouped_order.py [--profile cmm|5axis]
      MODEL.step [MODEL.step ...]

Per model and profile (``bench_memory.PROFILES``; default both) it plans what ``probegen
plan MODEL --all-revolved`` plans twice, each on a fresh load of the model
(``bench_memory.child``): first with ``revolved_spec.GROUPED`` off (the recognised
order), then as shipped.  The part keeps the collision geometry of its most recently used
frames (``cad.part.RECENT_KEPT``): a frame the planner comes back to after others is
built again, and the order decides how often.  It prints the plan time of each (wall
clock, s), their ratio, the height maps and FCL trees built in each, and whether the
programs' text is the same bytes (SHA-256, first 12 digits): the order must not change
what is planned.
"""

from __future__ import annotations

import sys

from bench_memory import REPO, compare_main


def main(argv: list[str]) -> int:
    def swaps() -> list[tuple[object, str, object]]:
        sys.path.insert(0, str(REPO))
        from probegen.planning import revolved_spec

        return [(revolved_spec, "GROUPED", False)]

    return compare_main(argv, __doc__ or "", "recognised order s | grouped s", swaps,
                        lambda a, b: (f"{a['maps_built']} / {a['trees_built']} -> "
                                      f"{b['maps_built']} / {b['trees_built']}"),
                        "maps / trees built")


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
