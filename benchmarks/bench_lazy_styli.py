"""Benchmark: ``plan --all-revolved`` with the message of a feature no stylus plans made
when it is read (``planning.styli.LAZY``), against made at once (before stop 33), in one
process.

Run:  PYTHONPATH=. .venv/bin/python benchmarks/bench_lazy_styli.py [--profile cmm|5axis]
      MODEL.step [MODEL.step ...]

Per model and profile (``bench_memory.PROFILES``; default both) it plans what ``probegen
plan MODEL --all-revolved`` plans twice, each on a fresh load (``bench_memory.child``):
first with ``styli.LAZY`` off, then as shipped.  When no stylus plans a feature with the
probe along its axis, the message names what each stylus's refused moves ran into (how
deep the stylus cuts into the part: distance queries); a leaning head index that then
plans the feature drops it unread.  It prints both plan times (wall clock, s), their
ratio and whether the programs are the same bytes (SHA-256, first 12 digits; the
left-out features' reasons are in the programs' headers, so the texts read are compared
too).
"""

from __future__ import annotations

import sys

from bench_memory import REPO, compare_main


def main(argv: list[str]) -> int:
    def swaps() -> list[tuple[object, str, object]]:
        sys.path.insert(0, str(REPO))
        from probegen.planning import styli

        return [(styli, "LAZY", False)]

    return compare_main(argv, __doc__ or "", "made at once s | made when read s", swaps)


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
