"""Profile: where `plan --all-revolved` spends its time on one model, for at most a given
number of seconds (the largest models plan for hours).

Run:  PYTHONPATH=. .venv/bin/python benchmarks/profile_planning.py PROFILE MODEL SECONDS [OUT]

PROFILE is ``cmm`` or ``5axis`` (the sample profiles of ``bench_real_parts.py``).  Runs
``all_revolved_setups`` + ``plan_setups`` under cProfile; after SECONDS of wall clock (or
when planning ends) prints the 70 functions of most cumulative time and the 30 of most
own time, and writes the stats to OUT (default ``profile.prof``).  Stop 32's figures
(NIST CTC 4 with the CMM: 600 s of 1500 in 136 height maps) come from
``... profile_planning.py cmm ../shared/ref/nist-step/nist_ctc_04_asme1_rd.stp 1500``.
"""

from __future__ import annotations

import cProfile
import os
import pstats
import signal
import sys
import tempfile
import warnings
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))
sys.path.insert(0, str(REPO / "benchmarks"))


def main() -> None:
    import bench_real_parts as b

    import probegen.cli.progress
    from probegen import cad
    from probegen.dialects import get_dialect
    from probegen.planning.setups import all_revolved_setups, plan_setups

    warnings.simplefilter("ignore")
    probegen.cli.progress.ENABLED = False
    key, model, limit = sys.argv[1], Path(sys.argv[2]), int(sys.argv[3])
    out = sys.argv[4] if len(sys.argv) > 4 else "profile.prof"
    case = b.CASES[key]
    profiler = cProfile.Profile()

    def stop(*_: object) -> None:
        profiler.disable()
        profiler.dump_stats(out)
        stats = pstats.Stats(profiler)
        stats.sort_stats("cumulative").print_stats(70)
        stats.sort_stats("tottime").print_stats(30)
        sys.stdout.flush()
        os._exit(0)

    signal.signal(signal.SIGALRM, stop)
    with tempfile.TemporaryDirectory() as tmp:
        machine, _, _ = b.load_case(case, Path(tmp))
        part = cad.load_part(model)
        runtime = get_dialect(case.dialect).RUNTIME_VARIABLES
        signal.alarm(limit)
        profiler.enable()
        spec, _ = all_revolved_setups(part, machine)
        plan_setups(spec, runtime_variables=runtime, part=part)
        stop()


if __name__ == "__main__":
    main()
