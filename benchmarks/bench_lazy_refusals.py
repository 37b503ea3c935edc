"""Benchmark: planning with what a refused move ran into described only when a message
is read (``reroute.Text``: the stylus's measured depth in the part, for the messages a
user sees) and the probe body's grown collision test (``collision.GROWN_FIRST``), against
the code before both (each refused move described at once, the body's distance queried),
in one process.

Run:  PYTHONPATH=. .venv/bin/python benchmarks/bench_lazy_refusals.py [--profile cmm|5axis]
      MODEL.step [MODEL.step ...]

Per model and profile (default both), what ``probegen plan MODEL --all-revolved`` plans,
twice, each on a fresh load (``bench_memory.child``): first with ``reroute.LAZY`` and
``collision.GROWN_FIRST`` false, then as shipped.  It prints both plan times (wall
clock, s), their ratio and whether the programs are the same bytes (SHA-256, first 12
digits: the left-out features' reasons are in the programs' headers, so the texts read
are compared too).  ``benchmarks/bench_grown_first.py`` times the grown test alone.
"""

from __future__ import annotations

import sys
from typing import Any

from bench_memory import compare_main


def swaps() -> list[Any]:
    """The baseline: every refused move described at once, the body's distance
    queried wherever the Lipschitz and table skips do not apply."""
    from probegen.planning import collision, reroute

    return [(reroute, "LAZY", False), (collision, "GROWN_FIRST", False)]


if __name__ == "__main__":
    sys.exit(compare_main(sys.argv[1:], __doc__, "before s | lazy texts, grown test s",
                          swaps))
