"""Benchmark: planning 10,000 guide points on a B-spline face (method M3).

Run:  .venv/bin/python benchmarks/bench_freeform_plan.py [N_U N_V] [--exact-all]

The freeform sample's B-spline top face (``samples/freeform/freeform.step``, face 6,
with the 8 mm bore through it), a ``uv`` grid of ``N_U x N_V`` (default 101 x 101,
about 10,000 guide points after the 1 mm margin), vector probing with the VMC profile
(6 mm ball).  Prints the time of each stage and points per second:

1. guide points (grid, trimmed-face classification, margin from every edge);
2. theoretical ball centres (the offset-surface Newton solve of every guide line) and
   the touches;
3. the whole ``plan_freeform`` without the collision check (1 + 2 + IR);
4. ``plan_freeform`` with the collision checks of every guide point and link: the fast
   conservative check (height map + swept volumes, ``planning.heightmap``) with the exact
   check where it is unsure; the mesh's height map is built in this stage (once per
   mesh); then ``plan_program`` for the same feature (plans it again and checks the
   whole program: the segments the fast check cleared are in the sweep cache);
5. the baseline: the exact check alone (``fast=False``, sphere tracing, about a
   millisecond per stylus-to-mesh query) on a sub-grid (``CHECKED`` points; the whole
   grid with ``--exact-all``, about a minute), and the fast check on the same grid: the
   ratio of the two, and whether both plans are the same.

The model and its mesh are loaded once before timing (they are cached per process).
"""

from __future__ import annotations

import dataclasses
import sys
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

SPEC = REPO / "samples/freeform/freeform.toml"
CHECKED = (21, 21)
"""Sub-grid planned with the collision checks."""


def main(counts: tuple[int, int], exact_all: bool) -> None:
    from probegen.cad.freeform import FaceSurface, guide_points
    from probegen.planning import make_setup, part_of, plan_program
    from probegen.planning.collision import MeshObstacle, obstacle_for
    from probegen.planning.freeform import plan_touches
    from probegen.planning.freeform_spec import plan_freeform
    from probegen.spec.model import FreeformSpec, load_spec

    spec = load_spec(SPEC)
    base = spec.features[0]
    assert isinstance(base, FreeformSpec) and spec.model is not None
    feature = dataclasses.replace(base, counts=counts, margin=1.0)
    part = part_of(spec)
    assert part is not None
    model = part.model
    obstacle = obstacle_for(part, [])
    assert isinstance(obstacle, MeshObstacle)
    setup = make_setup(spec)
    r = spec.machine.probe.ball_radius

    t0 = time.perf_counter()
    grid = guide_points(model, 6, counts=counts, margin=1.0)
    t1 = time.perf_counter()
    surface = FaceSurface(model, 6)
    groups, failed = plan_touches(
        surface, surface.normal_sign, np.array([g.point for g in grid.points]),
        np.array([g.normal for g in grid.points]), np.array([g.uv for g in grid.points]),
        d=(0.0, 0.0, 1.0), method="vector", spacing=0.5, r=r)
    t2 = time.perf_counter()
    plan = plan_freeform(feature, part, spec.machine, setup, check=False)
    t3 = time.perf_counter()
    sweeps = obstacle.sweeps  # cleared before each checked run: nothing checked before
    sweeps.clear()
    checked = plan_freeform(feature, part, spec.machine, setup)
    t4 = time.perf_counter()
    program = plan_program(dataclasses.replace(spec, features=(feature,)),
                           runtime_variables=True, part=part)
    t5 = time.perf_counter()
    sub = counts if exact_all else CHECKED
    small = dataclasses.replace(feature, counts=sub)
    sweeps.clear()
    t6 = time.perf_counter()
    exact = plan_freeform(small, part, spec.machine, setup, fast=False)
    t7 = time.perf_counter()
    sweeps.clear()
    t8 = time.perf_counter()
    quick = plan_freeform(small, part, spec.machine, setup)
    t9 = time.perf_counter()

    n = len(grid.points)
    print(f"grid {counts[0]} x {counts[1]}: {n} guide points, {len(grid.skipped)} grid "
          f"points left out (margin, hole)")
    print(f"1 guide points          {t1 - t0:7.3f} s  {n / (t1 - t0):9.0f} points/s")
    print(f"2 ball centres, touches {t2 - t1:7.3f} s  {n / (t2 - t1):9.0f} points/s  "
          f"({sum(len(g) for g in groups)} touches, {len(failed)} failed)")
    print(f"3 plan, no check        {t3 - t2:7.3f} s  {len(plan.guides) / (t3 - t2):9.0f} "
          f"points/s  ({len(plan.guides)} guide points planned)")
    print(f"4 plan, checked         {t4 - t3:7.3f} s  {n / (t4 - t3):9.0f} "
          f"points/s  ({len(checked.guides)} planned, {len(checked.left_out)} left out; "
          f"height map built here)")
    print(f"  plan_program          {t5 - t4:7.3f} s  {n / (t5 - t4):9.0f} points/s  "
          f"(plan again + check the whole program: {len(program.clearance.segments)} "
          f"segments)")
    m = len(exact.guides) + sum(1 for x in exact.left_out if x.guide)
    print(f"5 exact check alone     {t7 - t6:7.3f} s  {m / (t7 - t6):9.0f} points/s  "
          f"({sub[0]} x {sub[1]} grid: {m} guide points)")
    print(f"  fast check, same grid {t9 - t8:7.3f} s  {m / (t9 - t8):9.0f} points/s  "
          f"speed-up {(t7 - t6) / (t9 - t8):.1f}x, same plan: "
          f"{exact.nodes == quick.nodes and exact.left_out == quick.left_out}")

if __name__ == "__main__":
    args = [int(a) for a in sys.argv[1:] if a != "--exact-all"]
    main((args[0], args[1]) if len(args) == 2 else (101, 101), "--exact-all" in sys.argv)
