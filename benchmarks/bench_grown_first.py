"""Benchmark: the collision check tests the probe body grown by the shank's clearance for
a collision before it measures the body's distance (``MeshObstacle.clearance``: a body
whose grown cylinder meets no triangle is not the least, so its distance query is
needless), against the same planning with the body's distance queried wherever the
earlier skips do not apply (the code before), in one process.

Run:  PYTHONPATH=. .venv/bin/python benchmarks/bench_grown_first.py [--profile cmm|5axis]
      MODEL.step [MODEL.step ...]

Per model and profile (default both), what ``probegen plan MODEL --all-revolved`` plans,
twice, each on a fresh load (``bench_memory.child``): first with ``collision.GROWN_FIRST``
false (the check as it was before the change), then as shipped.  It prints both plan
times (wall clock, s), their ratio and whether the programs are the same bytes (SHA-256,
first 12 digits).  A body's distance query beside a part costs milliseconds, the
collision test of the grown body a few hundredths of one
(``benchmarks/bench_body_query.py``).
"""

from __future__ import annotations

import sys
from typing import Any

from bench_memory import compare_main


def swaps() -> list[Any]:
    """The baseline: the body's distance queried wherever the Lipschitz and table skips
    do not apply."""
    from probegen.planning import collision

    return [(collision, "GROWN_FIRST", False)]


if __name__ == "__main__":
    sys.exit(compare_main(sys.argv[1:], __doc__, "body queried s | grown test first s",
                          swaps))
