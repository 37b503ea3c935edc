"""Benchmark: the collision check asks the machine table first (``MeshObstacle.clearance``
and ``face_of``: a stylus element the table's plane puts at least as deep as the part's
distance query can report needs no such query), against the same planning with the
part's query made everywhere (the code before), in one process.

Run:  PYTHONPATH=. .venv/bin/python benchmarks/bench_table_first.py [--profile cmm|5axis]
      MODEL.step [MODEL.step ...]

Per model and profile (default both), what ``probegen plan MODEL --all-revolved`` plans,
twice, each on a fresh load (``bench_memory.child``): first with the part's distance
queried for every element (``collision.TABLE_FIRST`` false: the check as it was before
the change), then as shipped.  It prints both plan times (wall clock, s), their ratio and
whether the programs are the same bytes (SHA-256, first 12 digits).  The change pays
where the table refuses moves: a probe body's distance query next to the part costs
milliseconds (a 40 mm body beside a 16 000-triangle mesh: about 6 ms,
``benchmarks/bench_body_query.py``).
"""

from __future__ import annotations

import sys
from typing import Any

from bench_memory import compare_main


def swaps() -> list[Any]:
    """The baseline: the part's distance queried for every element."""
    from probegen.planning import collision

    return [(collision, "TABLE_FIRST", False)]


if __name__ == "__main__":
    sys.exit(compare_main(sys.argv[1:], __doc__, "part queried s | table first s", swaps))
