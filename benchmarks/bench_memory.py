"""Benchmark: the peak memory of planning a model (issue 17: CTC 2 and CTC 4 planned with a
bounded memory).

Run:  PYTHONPATH=. .venv/bin/python benchmarks/bench_memory.py [--profile cmm|5axis]
      [--limit-gb G] MODEL.stp [MODEL.stp ...]

Per model and profile (the CMM ``samples/machines/cmm.toml`` to DMIS, the five-axis
``samples/machines/vmc-5axis-fanuc.toml`` to Fanuc; default both), one child process does
what ``probegen plan MODEL --all-revolved --machine PROFILE -d DIALECT -o DIR`` does (the
same functions as ``benchmarks/bench_real_parts.py``: ``all_revolved_setups``,
``plan_setups``, ``cli.plan.program_text``) and the parent prints:

* *max RSS*: the child's peak resident memory (``wait4``'s ``ru_maxrss``), MB;
* *turned parts*: the turned parts alive at the end (``Part.turned`` frames kept on the
  part and on each setup's part);
* *height maps*: the collision height maps kept at the end and their size with their
  dilations (``planning.heightmap``, kept by ``Part.recent``), MB;
* the planned features, the plan time (wall clock) and the SHA-256 of the programs'
  text (its first 12 digits): two runs whose digests agree wrote the same bytes.

``--limit-gb G`` (default 12) stops a child whose resident memory passes ``G`` GB (read
from ``/proc`` every half second): the row then says ``killed above G GB``.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import signal
import subprocess
import sys
import time
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parent.parent
PROFILES = {"cmm": ("samples/machines/cmm.toml", "dmis"),
            "5axis": ("samples/machines/vmc-5axis-fanuc.toml", "fanuc")}
"""Profile key: (the sample profile, the dialect its programs are written in)."""
POLL_S = 0.5
"""How often the parent reads the child's resident memory, s."""


def child(model: str, key: str) -> dict[str, Any]:
    """Plan ``model`` with profile ``key`` in this process; the figures as a dict."""
    sys.path.insert(0, str(REPO))
    import probegen.cli.progress
    from probegen import cad
    from probegen.cli.plan import program_text
    from probegen.dialects import get_dialect
    from probegen.machine.profile import load_profile
    from probegen.planning import heightmap
    from probegen.planning.collision import MeshObstacle
    from probegen.planning.setups import all_revolved_setups, plan_setups

    probegen.cli.progress.ENABLED = False
    warnings.simplefilter("ignore")
    sample, dialect = PROFILES[key]
    machine = load_profile(REPO / sample)
    part = cad.load_part(model)
    built = {"maps": 0, "trees": 0}
    map_init, tree_build = heightmap.HeightMap.__init__, MeshObstacle._build

    def counted_map(*args: Any, **kwargs: Any) -> None:
        built["maps"] += 1
        map_init(*args, **kwargs)

    def counted_tree(self: Any) -> Any:
        built["trees"] += 1
        return tree_build(self)

    heightmap.HeightMap.__init__ = counted_map  # type: ignore[method-assign]
    MeshObstacle._build = counted_tree  # type: ignore[method-assign]
    try:
        t0, c0 = time.perf_counter(), time.process_time()
        spec, notes = all_revolved_setups(part, machine)
        setups = plan_setups(spec, runtime_variables=get_dialect(dialect).RUNTIME_VARIABLES,
                             part=part)
        plan_s, plan_cpu_s = time.perf_counter() - t0, time.process_time() - c0
    finally:
        heightmap.HeightMap.__init__ = map_init  # type: ignore[method-assign]
        MeshObstacle._build = tree_build  # type: ignore[method-assign]
    digest = hashlib.sha256()
    for _setup, planned in setups:
        digest.update(program_text(dialect, planned, notes).encode("utf-8"))
    parts = turned_parts(part)
    maps = [m for p in (part, *parts) if ("recent", "height map") in p._memo
            for m in p.recent("height map").values()]
    return {"planned": sum(len(p.revolved) for _s, p in setups),
            "plan_s": round(plan_s, 1),
            "plan_cpu_s": round(plan_cpu_s, 1),
            "turned_alive": len(parts),
            "maps_alive": len(maps),
            "maps_mb": round(sum(map_bytes(m) for m in maps) / 1e6, 1),
            "maps_built": built["maps"],
            "trees_built": built["trees"],
            "sha256": digest.hexdigest()[:12]}


Swap = tuple[Any, str, Any]
"""A baseline's setting: ``(owner, name, before)``: ``owner.name`` (a module's constant, a
class's method) is ``before`` in the baseline run."""


def before_and_after(model: str, key: str,
                     swaps: list[Swap]) -> tuple[dict[str, Any], dict[str, Any]]:
    """:func:`child` twice, each on a fresh load: first with every ``owner.name`` of
    ``swaps`` set to its ``before``, then as shipped (restored whatever happens); a
    benchmark's baseline and its figure in one process."""
    shipped = [(owner, name, getattr(owner, name)) for owner, name, _ in swaps]
    for owner, name, before in swaps:
        setattr(owner, name, before)
    try:
        first = child(model, key)
    finally:
        for owner, name, value in shipped:
            setattr(owner, name, value)
    return first, child(model, key)


def compare_rows(models: list[Path], keys: list[str], swaps: list[Swap],
                 extra: Callable[[dict[str, Any], dict[str, Any]], str] | None = None
                 ) -> None:
    """Per model and profile, :func:`before_and_after` as a Markdown row: model, profile,
    both plan times (s; wall clock, then in brackets CPU: the figure to compare on a
    loaded machine), their ratios, ``extra`` of the two runs' figures where given, and
    whether the programs are the same bytes (their digests)."""
    for model in models:
        for key in keys:
            a, b = before_and_after(str(model), key, swaps)
            cells = [model.stem, key] + [f"{r['plan_s']:.1f} ({r['plan_cpu_s']:.1f})"
                                          for r in (a, b)]
            cells.append(f"{a['plan_s'] / b['plan_s']:.2f} "
                         f"({a['plan_cpu_s'] / b['plan_cpu_s']:.2f})")
            cells += [extra(a, b)] if extra is not None else []
            same = "yes" if a["sha256"] == b["sha256"] else "NO"
            cells.append(f"{same} ({a['sha256']}, {b['sha256']})")
            print("| " + " | ".join(cells) + " |", flush=True)


def compare_main(argv: list[str], doc: str, header: str,
                 swaps: Callable[[], list[Swap]],
                 extra: Callable[[dict[str, Any], dict[str, Any]], str] | None = None,
                 extra_header: str = "") -> int:
    """The command line of a before-and-after benchmark: ``[--profile P ...] MODEL ...``;
    prints the Markdown table (``header``: the two timed columns' names, e.g. ``every
    query s | skipped s``) with a row per model and profile (:func:`compare_rows`) of
    the ``swaps`` (made after the repository is on the path), with a column
    ``extra_header`` of ``extra`` of the two runs' figures where given."""
    parser = argparse.ArgumentParser(description=doc.split("\n\n")[0])
    parser.add_argument("--profile", choices=sorted(PROFILES), action="append")
    parser.add_argument("models", nargs="+", type=Path)
    args = parser.parse_args(argv)
    sys.path.insert(0, str(REPO))
    more = f" {extra_header} |" if extra is not None else ""
    print(f"| model | profile | {header} | ratio |{more} same programs |")
    print("|---|---|---|---|---|---|" + ("---|" if extra is not None else ""))
    compare_rows(args.models, args.profile or sorted(PROFILES), swaps(), extra)
    return 0


def turned_parts(part: Any) -> list[Any]:
    """The turned parts kept on ``part`` and on the parts of its setups (their memos'
    ``turned`` and ``setup`` entries), each once."""
    out: dict[int, Any] = {}
    todo = [part]
    while todo:
        p = todo.pop()
        for key, value in list(p._memo.items()):
            if isinstance(key, tuple) and key[0] in ("turned", "setup") \
                    and id(value) not in out:
                out[id(value)] = value
                todo.append(value)
    return list(out.values())


def map_bytes(hmap: Any) -> int:
    """The bytes of a height map's grid and its dilations."""
    return int(hmap.height.nbytes + sum(d[0].nbytes for d in hmap._dilated.values()))


def rss_kb(pid: int) -> int:
    """The resident memory of process ``pid`` now, kB (0 once it is gone)."""
    try:
        with open(f"/proc/{pid}/status", encoding="ascii") as f:
            for line in f:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1])
    except OSError:
        pass
    return 0


def measure(model: Path, key: str, limit_gb: float) -> dict[str, Any]:
    """Run :func:`child` for ``model`` and ``key`` in a child process; its figures with
    its peak resident memory (``max_rss_mb``), or ``killed`` when it passed
    ``limit_gb``."""
    cmd = [sys.executable, __file__, "--child", key, str(model)]
    with subprocess.Popen(cmd, stdout=subprocess.PIPE, text=True,
                          env={**os.environ, "PYTHONPATH": str(REPO)}) as proc:
        killed = False
        while True:
            pid, status, usage = os.wait4(proc.pid, os.WNOHANG)
            if pid:
                break
            if not killed and rss_kb(proc.pid) > limit_gb * 1024 * 1024:
                proc.send_signal(signal.SIGKILL)
                killed = True
            time.sleep(POLL_S)
        out = proc.stdout.read() if proc.stdout else ""
        proc.returncode = os.waitstatus_to_exitcode(status)
    row: dict[str, Any] = {"model": model.stem, "profile": key,
                           "max_rss_mb": usage.ru_maxrss // 1024}
    if killed:
        return {**row, "error": f"killed above {limit_gb:g} GB"}
    lines = out.strip().splitlines()
    if proc.returncode != 0 or not lines:
        return {**row, "error": f"exit {proc.returncode}"}
    return {**row, **json.loads(lines[-1])}


def text(row: dict[str, Any]) -> str:
    """One row as a table line."""
    if "error" in row:
        return f"| {row['model']} | {row['profile']} | {row['max_rss_mb']} | {row['error']} |"
    return (f"| {row['model']} | {row['profile']} | {row['max_rss_mb']} | "
            f"{row['turned_alive']} | {row['maps_alive']} "
            f"({row['maps_mb']} MB) | {row['planned']} | {row['plan_s']} | {row['sha256']} |")


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("models", nargs="+", type=Path)
    parser.add_argument("--profile", choices=sorted(PROFILES), action="append")
    parser.add_argument("--limit-gb", type=float, default=12.0)
    parser.add_argument("--child", choices=sorted(PROFILES), help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.child:
        print(json.dumps(child(str(args.models[0]), args.child)), flush=True)
        return 0
    print("| model | profile | max RSS MB | turned parts alive | height maps alive "
          "| planned | plan s | programs sha256 |")
    print("|---|---|---|---|---|---|---|---|")
    for model in args.models:
        for key in args.profile or ["cmm", "5axis"]:
            print(text(measure(model, key, args.limit_gb)), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
