"""Benchmark: ``plan --all-revolved`` with every frame's collision queries on the loaded
part's FCL and ray trees placed by the frame's rotation (``collision.SHARED_TREE``),
against trees built per frame (before stop 33), in one process.

Run:  PYTHONPATH=. .venv/bin/python benchmarks/bench_shared_tree.py [--profile cmm|5axis]
      MODEL.step [MODEL.step ...]

Per model and profile (``bench_memory.PROFILES``; default both) it plans what ``probegen
plan MODEL --all-revolved`` plans twice, each on a fresh load (``bench_memory.child``):
first with ``SHARED_TREE`` off (a tree per frame, the most recently used kept:
``cad.part.RECENT_KEPT``), then as shipped.  It prints both plan times (wall clock, s),
their ratio, the FCL trees built in each and whether the programs' text is the same
bytes (SHA-256, first 12 digits).  The distances agree to fcl's precision, not to the
last bit: a face named in a left-out reason may be another at a tie (the ball as deep
in both), so the digests may differ where the programs name such a face.
"""

from __future__ import annotations

import sys

from bench_memory import REPO, compare_main


def main(argv: list[str]) -> int:
    def swaps() -> list[tuple[object, str, object]]:
        sys.path.insert(0, str(REPO))
        from probegen.planning import collision

        return [(collision, "SHARED_TREE", False)]

    return compare_main(argv, __doc__ or "", "own trees s | shared s", swaps,
                        lambda a, b: f"{a['trees_built']} -> {b['trees_built']}",
                        "trees built")


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
