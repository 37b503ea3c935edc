"""Benchmark: how many revolved features ``plan --all-revolved`` gets through in a fixed
CPU time, with this stop's planning speed-ups and without them, in one process: for the
models that plan for hours (NIST CTC 4 with the CMM), where a whole run before and after
does not fit a session.

Run:  PYTHONPATH=. .venv/bin/python benchmarks/bench_features_per_cpu.py [--ungrouped]
      PROFILE MODEL CPU_SECONDS

PROFILE is ``cmm`` or ``5axis`` (``bench_memory.PROFILES``).  Twice, each on a fresh load
of the model: first the baseline (``styli.LAZY``, ``collision.SHARED_TREE`` and
``heightmap.SINGLE`` off: the message of a feature no stylus plans made at once, an FCL
tree built per frame, the height maps dilated in double precision), then as shipped;
each stopped after CPU_SECONDS of the process's CPU time (user and system: the count does
not depend on what else runs on the machine).  Prints per run the features whose
planning finished (``revolved_spec._plan_or_circle`` returned or raised), the height maps
and FCL trees built, and the ratio of the features.  Both runs plan the features in the
same order (``revolved_spec.GROUPED`` as shipped: a count in another order is of other
features, some slower to plan than others; with ``--ungrouped`` the baseline also plans
them in the order recognised, which this count cannot compare: stop 33's run on CTC 4
counted 174 features before and 162 after in 600 s, of different features).
"""

from __future__ import annotations

import signal
import sys
import tempfile
import warnings
from pathlib import Path
from typing import Any

from bench_memory import PROFILES, REPO


class _Stop(Exception):
    """Raised by the CPU timer to end a run."""


def run(model: Path, key: str, seconds: float, swaps: list[tuple[Any, str, Any]]
        ) -> dict[str, int]:
    """Plan ``model`` with profile ``key`` for ``seconds`` of CPU time with ``swaps``
    (owner, name, value) set; the counts."""
    import probegen.cli.progress
    from probegen import cad
    from probegen.machine.profile import load_profile
    from probegen.planning import heightmap, revolved_spec
    from probegen.planning.collision import MeshObstacle
    from probegen.planning.setups import all_revolved_setups

    probegen.cli.progress.ENABLED = False
    counts = {"features": 0, "maps": 0, "trees": 0}
    wraps = [(revolved_spec, "_plan_or_circle", "features"),
             (heightmap.HeightMap, "__init__", "maps"), (MeshObstacle, "_build", "trees")]
    kept = [(o, n, getattr(o, n)) for o, n, _ in wraps + [(o, n, None) for o, n, _ in swaps]]

    def counted(f: Any, name: str) -> Any:
        def wrapper(*args: Any, **kwargs: Any) -> Any:
            try:
                return f(*args, **kwargs)
            finally:
                if name != "features" or not stopping:
                    counts[name] += 1
        return wrapper

    stopping = False

    def stop(*_: object) -> None:
        nonlocal stopping
        stopping = True
        raise _Stop

    for owner, name, what in wraps:
        setattr(owner, name, counted(getattr(owner, name), what))
    for owner, name, value in swaps:
        setattr(owner, name, value)
    machine = load_profile(REPO / PROFILES[key][0])
    part = cad.load_part(model)
    signal.signal(signal.SIGPROF, stop)
    signal.setitimer(signal.ITIMER_PROF, seconds)
    try:
        with tempfile.TemporaryDirectory():
            all_revolved_setups(part, machine)
    except _Stop:
        pass
    finally:
        signal.setitimer(signal.ITIMER_PROF, 0)
        for owner, name, value in kept:
            setattr(owner, name, value)
    return counts


def main(argv: list[str]) -> int:
    ungrouped = "--ungrouped" in argv
    argv = [a for a in argv if a != "--ungrouped"]
    key, model, seconds = argv[0], Path(argv[1]), float(argv[2])
    sys.path.insert(0, str(REPO))
    warnings.simplefilter("ignore")
    from probegen.planning import collision, heightmap, revolved_spec, styli

    swaps: list[tuple[Any, str, Any]] = [(styli, "LAZY", False),
                                         (collision, "SHARED_TREE", False),
                                         (heightmap, "SINGLE", False)]
    if ungrouped:
        swaps.append((revolved_spec, "GROUPED", False))
    before = run(model, key, seconds, swaps)
    after = run(model, key, seconds, [])
    print("| model | profile | CPU s | features before | maps / trees before | "
          "features after | maps / trees after | ratio |")
    print("|---|---|---|---|---|---|---|---|")
    print(f"| {model.stem} | {key} | {seconds:g} | {before['features']} | "
          f"{before['maps']} / {before['trees']} | {after['features']} | "
          f"{after['maps']} / {after['trees']} | "
          f"{after['features'] / max(before['features'], 1):.2f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
