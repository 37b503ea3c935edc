"""Benchmark: planning the sample sphere test, and the collision check's speed-up.

Run:  .venv/bin/python benchmarks/bench_sphere_test.py

Prints, for the bundled sample (25 mm sphere on a stem, octahedral layout, run-time
locating): the plan figures, the wall time of a full plan, and the time of the collision
check by sphere tracing with python-fcl against the baseline it replaced (dense sampling
every 0.1 mm with trimesh's signed distance, ball only), as a ratio measured in the same
process on the same segments.
"""

from __future__ import annotations

import math
import os
import sys
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]


def main() -> int:
    os.chdir(REPO)
    import trimesh

    from probegen import cad
    from probegen.planning import plan_program
    from probegen.planning.collision import MeshObstacle, Stylus, _sweep
    from probegen.spec.model import load_spec

    spec = load_spec("samples/sphere25/sphere_test.toml")
    t0 = time.perf_counter()
    planned = plan_program(spec, runtime_variables=True)
    t_plan = time.perf_counter() - t0
    p = planned.sphere_tests[0]
    print(f"layout {p.feature.layout}: {len(p.directions)} points, largest step "
          f"{math.degrees(p.alpha):.2f} deg, safe retract {p.min_retract:.3f} mm, "
          f"used {p.retract:.3f} mm")
    print(f"full plan (load STEP, mesh, plan, check {len(planned.clearance.segments)} "
          f"segments): {t_plan:.2f} s")

    mesh = cad.load_part(str(spec.model)).mesh()
    obstacle = MeshObstacle(mesh, None)
    stylus = Stylus(3.0, 2.25, 50.0)
    segs = [(np.array(s.start), np.array(s.end)) for s in planned.clearance.segments]

    t0 = time.perf_counter()
    traced = [_sweep(obstacle, a, b, 0.0, 0.0, stylus, 0.25)[0] for a, b in segs]
    t_fcl = time.perf_counter() - t0

    t0 = time.perf_counter()
    dense = []
    for a, b in segs:
        n = max(int(np.ceil(np.linalg.norm(b - a) / 0.1)), 1)
        pts = a + np.linspace(0, 1, n + 1)[:, None] * (b - a)
        dense.append(float((-trimesh.proximity.signed_distance(mesh, pts)).min()) - 3.0)
    t_dense = time.perf_counter() - t0

    worst = max(abs(x - y) for x, y in zip(traced, dense, strict=True))
    print(f"collision check, ball and shank, sphere tracing + fcl: {t_fcl:.3f} s")
    print(f"baseline, ball only, 0.1 mm samples + trimesh signed distance: {t_dense:.3f} s")
    print(f"speed-up: {t_dense / t_fcl:.1f}x (largest difference in ball clearance "
          f"{worst:.4f} mm)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
