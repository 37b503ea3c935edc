"""Benchmark: every revolved feature of the NIST models and the DCX part (method M2).

Run:  .venv/bin/python benchmarks/bench_revolved.py [MODEL.stp ...]

Without arguments: every ``/work/shared/ref/nist-step/*.stp`` and the DCX part.  Per
model the code path of ``probegen plan MODEL --all-revolved --machine
samples/machines/vmc-fanuc.toml`` (``all_revolved_spec`` + ``plan_program``), then the
Fanuc program on the virtual machine (the part at its nominal placement, a perfect probe
with the profile's ball radius).  Prints per model: features planned, rerouted (a path
changed by the collision check: touches dropped, lifts, other sections or retract) and
left out (with the reasons; the notes of those the collision check refused), touches,
path length and nominal cycle time of ours, of the baseline (up to the clearance plane
after every touch, travel at the clearance plane) and of the lower bound, the ratios,
the travel between features, the planning time and the virtual machine's alarm (must
be none).

Lengths and times are those of the whole tour, features and travel, from above the
first feature to above the last (:func:`probegen.planning.travel.tour_figures`).
"""

from __future__ import annotations

import sys
import time
from collections import Counter
from dataclasses import dataclass
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

MACHINE = REPO / "samples/machines/vmc-fanuc.toml"
NIST = Path("/work/shared/ref/nist-step")
DCX = Path("/work/shared/ref/nist-ippdme/DCXpart/STEP_AP214/DaimlerChryslerTestPartAP214.stp")


@dataclass
class Row:
    """One model's figures."""

    model: str
    planned: int = 0
    skipped: int = 0
    reasons: Counter[str] | None = None
    touches: int = 0
    ours: tuple[float, float] = (0.0, 0.0)
    baseline: tuple[float, float] = (0.0, 0.0)
    bound: tuple[float, float] = (0.0, 0.0)
    tour: float = 0.0
    plan_s: float = 0.0
    plan_cpu: float = 0.0
    vm_s: float = 0.0
    vm_touches: int = 0
    alarm: str | None = None
    error: str | None = None
    notes: tuple[str, ...] = ()
    rerouted: int = 0
    legs: tuple[float, float] = (0.0, 0.0)


def why_unsafe(note: str) -> str:
    """Why no touch of a feature is safe, from its note: every approach goes up (the
    surface faces down, out of reach of a vertical probe), the stylus meets only the
    feature's own faces (the feature is too small or too curved for the ball and shank),
    or other faces (the neighbours leave no room)."""
    import re

    own = set(re.search(r"faces ([\d,]+)\)", note).group(1).split(","))  # type: ignore[union-attr]
    hit = set(re.findall(r"(?:into|of) face (\d+)", note))
    ups = [float(b) > float(a) for a, b in re.findall(
        r"approach from \([^,]+, [^,]+, ([-\d.]+)\) to \([^,]+, [^,]+, ([-\d.]+)\)", note)]
    if ups and all(ups):
        return "faces down"
    return "own faces" if hit <= own else "other faces"


def reason_of(note: str) -> str:
    """A short class of a left-out note."""
    if "not along the probe" in note:
        return "axis not vertical"
    if "left out, it collides" in note:
        return "collides"
    if "blind, depth" in note:
        return "blind bore shallower than the ball"
    if "faces down" in note:
        return "no safe touch: faces down"
    if "no touch can be reached safely" in note:
        return "no safe touch: " + why_unsafe(note)
    if "closed above" in note:
        return "closed above"
    if "centre lies in material" in note:
        return "centre in material"
    if "or more: a smaller stylus" in note:
        return "bore < ball + retract"
    if "arc too short" in note:
        return "arc too short"
    if "no arc of the section" in note:
        return "not accessible (other)"
    return "does not plan (other)"


def run(model: Path) -> Row:
    """Plan, emit Fanuc and simulate one model."""
    from probegen import cad
    from probegen.dialects import get_dialect
    from probegen.errors import ProbegenError
    from probegen.machine.probe_model import ProbeModel
    from probegen.machine.profile import load_profile
    from probegen.planning import plan_program
    from probegen.planning.revolved_spec import all_revolved_spec
    from probegen.sim.contact import PlacedPart
    from probegen.sim.vm import VirtualMachine, run_text

    row = Row(model.stem)
    machine = load_profile(MACHINE)
    t0, c0 = time.perf_counter(), time.process_time()
    try:
        part = cad.load_part(model)
        spec, notes = all_revolved_spec(part, machine)
        planned = plan_program(spec, runtime_variables=True, part=part)
    except ProbegenError as exc:
        row.plan_s = time.perf_counter() - t0
        row.error = str(exc)
        row.reasons = Counter(reason_of(n) for n in str(exc).split("; ")[1:])
        row.skipped = sum(row.reasons.values())
        return row
    row.plan_s = time.perf_counter() - t0
    row.plan_cpu = time.process_time() - c0
    row.notes = notes
    row.planned = len(planned.revolved)
    row.skipped = len(notes)
    row.reasons = Counter(reason_of(n) for n in notes)
    row.touches = sum(len(p.normals) for p in planned.revolved)
    row.rerouted = sum(1 for p in planned.revolved if p.notes)
    if planned.figures is not None:
        f = planned.figures
        row.ours = (f.plan.length, f.plan.time)
        row.baseline = (f.baseline.length, f.baseline.time)
        row.bound = (f.lower_bound.length, f.lower_bound.time)
    row.tour = planned.tour.length if planned.tour is not None else 0.0
    row.legs = lifted_legs(planned.revolved, machine)
    text = get_dialect("fanuc").generate(planned.program)
    t1 = time.perf_counter()
    vm = VirtualMachine(PlacedPart.from_model(cad.load_step(model)),
                        ProbeModel(machine.probe.ball_radius))
    res = run_text(text, vm, kind="macrob", source=model.name)
    row.vm_s = time.perf_counter() - t1
    row.vm_touches = res.touches
    row.alarm = res.alarm
    return row


def lifted_legs(plans: object, machine: object) -> tuple[float, float]:
    """Nominal time (s) of the features' own lifts and clearance-level legs between two
    safe points (the bound keeps them as they are) and of the straight chords instead."""
    import math

    from probegen.planning.revolved import PathKind, Segment, cycle_time

    feeds, probe = machine.feeds, machine.probe  # type: ignore[attr-defined]
    up = (PathKind.LIFT, PathKind.CLEAR)
    ours = chord = 0.0
    for p in plans:  # type: ignore[attr-defined]
        path = p.plan.path
        for i in range(1, len(path) - 1):
            if path[i].kind in up or path[i + 1].kind not in up:
                continue
            j = i + 1
            while path[j].kind in up:
                j += 1
            if path[j].kind is PathKind.EXIT:
                continue
            for points, kind in ((path[i:j + 1], "ours"), ((path[i], path[j]), "chord")):
                t = cycle_time([Segment("protected", math.dist(a.position, b.position))
                                for a, b in zip(points, points[1:], strict=False)],
                               rapid=feeds.rapid, position_feed=feeds.position,
                               probe_feed=feeds.probe, approach=probe.approach)
                ours, chord = (ours + t, chord) if kind == "ours" else (ours, chord + t)
    return ours, chord


def table(rows: list[Row]) -> str:
    """The summary table (Markdown)."""
    head = ("| model | planned | rerouted | left out | touches | ours mm / s | "
            "baseline mm / s | bound mm / s | time ours/base | time ours/bound | travel mm | "
            "plan s (CPU) | VM |")
    out = [head, "|" + "---|" * 13]
    for r in rows:
        if r.error is not None:
            out.append(f"| {r.model} | 0 | 0 | {r.skipped} | 0 | - | - | - | - | - | - | "
                       f"{r.plan_s:.1f} | not run: {r.error[:60]} |")
            continue
        if not r.planned:
            vm = "no alarm" if r.alarm is None else f"ALARM {r.alarm}"
            out.append(f"| {r.model} | 0 | 0 | {r.skipped} | 0 | - | - | - | - | - | - | "
                       f"{r.plan_s:.1f} ({r.plan_cpu:.1f}) | {vm} (empty program) |")
            continue
        tb = r.ours[1] / r.baseline[1] if r.baseline[1] else float("nan")
        tl = r.ours[1] / r.bound[1] if r.bound[1] else float("nan")
        vm = "no alarm" if r.alarm is None else f"ALARM {r.alarm}"
        if r.alarm is None and r.vm_touches != r.touches:
            vm += f" ({r.vm_touches} of {r.touches} touches)"
        out.append(f"| {r.model} | {r.planned} | {r.rerouted} | {r.skipped} | {r.touches} | "
                   f"{r.ours[0]:.0f} / {r.ours[1]:.1f} | {r.baseline[0]:.0f} / "
                   f"{r.baseline[1]:.1f} | {r.bound[0]:.0f} / {r.bound[1]:.1f} | "
                   f"{tb:.3f} | {tl:.3f} | {r.tour:.0f} | {r.plan_s:.1f} ({r.plan_cpu:.1f}) | "
                   f"{vm} |")
    return "\n".join(out)


def main(argv: list[str]) -> int:
    import probegen.cli.progress

    probegen.cli.progress.ENABLED = False
    models = [Path(a) for a in argv] or [*sorted(NIST.glob("*.stp")), DCX]
    rows = []
    for m in models:
        r = run(m)
        rows.append(r)
        reasons = ", ".join(f"{k} {v}" for k, v in sorted((r.reasons or {}).items()))
        print(f"{r.model}: {r.planned} planned ({r.rerouted} rerouted), {r.skipped} left out "
              f"({reasons}); plan {r.plan_s:.1f} s (CPU {r.plan_cpu:.1f} s), VM {r.vm_s:.1f} s, "
              f"alarm {r.alarm}", flush=True)
        if r.legs[0] and r.bound[1]:
            print(f"  the features' own lifts and clearance-level legs: {r.legs[0]:.1f} s, "
                  f"as straight chords {r.legs[1]:.1f} s: ours/bound with chords "
                  f"{r.ours[1] / (r.bound[1] - r.legs[0] + r.legs[1]):.3f}")
        for n in r.notes:
            if reason_of(n).startswith(("collides", "no safe touch", "does not plan",
                                        "not accessible (other)")):
                print(f"  note: {n[:400]}")
    print()
    print(table(rows))
    bad = [r.model for r in rows if r.alarm is not None]
    if bad:
        print(f"\nALARM on {', '.join(bad)}")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
