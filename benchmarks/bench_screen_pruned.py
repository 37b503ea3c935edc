"""Benchmark: the head-index screen stops testing where its best indices cannot change
(``tilted.screen`` with ``best``: least tilt first, an index left as soon as its
untested touches could not lift it above the ``TRIED``-th kept one, the screen ended
once that one has every touch clear), against the same planning with every index and
touch tested (the code before), in one process.

Run:  PYTHONPATH=. .venv/bin/python benchmarks/bench_screen_pruned.py [--profile cmm|5axis]
      MODEL.step [MODEL.step ...]

Per model and profile (default both), what ``probegen plan MODEL --all-revolved`` plans,
twice, each on a fresh load (``bench_memory.child``): first with ``tilted.PRUNED``
false, then as shipped.  It prints both plan times (wall clock, s), their ratio and
whether the programs are the same bytes (SHA-256, first 12 digits).  Only a machine
with an indexable head screens (the CMM sample); the five-axis profile plans the same
way both times.
"""

from __future__ import annotations

import sys
from typing import Any

from bench_memory import compare_main


def swaps() -> list[Any]:
    """The baseline: every head index and touch tested."""
    from probegen.planning import tilted

    return [(tilted, "PRUNED", False)]


if __name__ == "__main__":
    sys.exit(compare_main(sys.argv[1:], __doc__, "every index s | pruned s", swaps))
