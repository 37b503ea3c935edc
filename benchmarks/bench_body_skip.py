"""Benchmark: planning with the probe body's distance query skipped where a previous
distance proves it cannot be the least (``MeshObstacle.clearance``), against the same
planning querying it everywhere, in one process.

Run:  PYTHONPATH=. .venv/bin/python benchmarks/bench_body_skip.py [--profile cmm|5axis]
      MODEL.step [MODEL.step ...]

Per model and profile (the CMM ``samples/machines/cmm.toml`` to DMIS, the five-axis
``samples/machines/vmc-5axis-fanuc.toml`` to Fanuc; default both, both state a probe
body), it plans what ``probegen plan MODEL --all-revolved`` plans twice, each on a fresh
load of the model (no cache shared; ``bench_memory.child``): first with the query
everywhere (``collision.SKIP_SLACK`` set to infinity, so no bound ever skips it), then as
shipped.  It prints the plan time of each (wall clock, s), their ratio, and whether the
programs' text is the same bytes (SHA-256, first 12 digits).
"""

from __future__ import annotations

import sys
from typing import Any

from bench_memory import compare_main


def swaps() -> list[Any]:
    """The baseline: no bound ever skips the body's query."""
    from probegen.planning import collision

    return [(collision, "SKIP_SLACK", float("inf"))]


if __name__ == "__main__":
    sys.exit(compare_main(sys.argv[1:], __doc__, "every query s | skipped s", swaps))
