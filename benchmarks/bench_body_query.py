"""Benchmark: what one distance query of the collision check costs per stylus element,
beside a real part (why ``collision.TABLE_FIRST`` pays: docs/benchmarks.md, "After stop
29").

Run:  PYTHONPATH=. .venv/bin/python benchmarks/bench_body_query.py [MODEL.step]
      (default: ../shared/ref/parts/odri_solo12_hip_aa_support.step)

The five-axis sample's stylus (ball D6, shank D4.5, the OMP40-like body 40 x 50 mm) at
150 ball centres drawn (seeded) in the model's box grown by 30 mm, where the element
clears the part, and at 150 where the body meets it: the mean CPU time of
``MeshObstacle``'s distance query (``_to``) per element, and of ``face_of`` for the body
meeting the part, ms; and, where the body clears the part, the collision test of the body
grown by 1 and by 5 mm that ``MeshObstacle.clearance`` makes before the body's query
(``_beyond``, ``collision.GROWN_FIRST``), with how often it settles the body.
"""

from __future__ import annotations

import sys
import time
import warnings
from pathlib import Path
from typing import Any

import numpy as np

REPO = Path(__file__).resolve().parent.parent
DEFAULT = REPO.parent / "shared/ref/parts/odri_solo12_hip_aa_support.step"
COUNT = 150


def centres(obstacle: Any, element: Any, meets: bool, grow: float,
            rng: np.random.Generator) -> list[np.ndarray]:
    """``COUNT`` ball centres where ``element`` meets the part (``meets``) or clears it."""
    fcl = obstacle.fcl
    low, high = obstacle.mesh.bounds
    out: list[np.ndarray] = []
    while len(out) < COUNT:
        p = rng.uniform(low - grow, high + grow)
        p[2] = rng.uniform(low[2] - 60.0, high[2])
        shape = obstacle._shape(p, element)
        hit = fcl.collide(shape, obstacle.part, fcl.CollisionRequest(),
                          fcl.CollisionResult())
        if bool(hit) == meets:
            out.append(p)
    return out


def mean_ms(call: Any, points: list[np.ndarray]) -> float:
    t = time.process_time()
    for p in points:
        call(p)
    return (time.process_time() - t) / len(points) * 1e3


def main(argv: list[str]) -> int:
    sys.path.insert(0, str(REPO))
    warnings.simplefilter("ignore")
    from probegen.cad.part import load_part
    from probegen.machine.profile import load_profile
    from probegen.planning.collision import mesh_obstacle, probe_stylus
    from probegen.planning.intrusion import elements

    model = Path(argv[0]) if argv else DEFAULT
    obstacle = mesh_obstacle(load_part(model))
    machine = load_profile(REPO / "samples/machines/vmc-5axis-fanuc.toml")
    stylus = probe_stylus(machine, machine.probe.ball_radius)
    rng = np.random.default_rng(1)
    print(f"{model.stem}: {len(obstacle.mesh.faces)} triangles")
    print("| element | query clear of the part ms | query meeting it ms |")
    print("|---|---|---|")
    for e in elements(stylus.ball, stylus.cylinders()):
        clear = centres(obstacle, e, False, 30.0, rng)
        meet = centres(obstacle, e, True, 10.0, rng)
        def query(p: np.ndarray, e: Any = e) -> float:
            return obstacle._to(obstacle._shape(p, e))
        print(f"| {e.name} | {mean_ms(query, clear):.3f} | {mean_ms(query, meet):.3f} |")
        if e.name == "probe body":
            face = mean_ms(lambda p, e=e: obstacle.face_of(p, e), meet)
            print(f"\nface_of, the body meeting the part: {face:.3f} ms")
            assert e.low is not None and e.high is not None
            dims = (e.radius, e.low, e.high)
            mid = np.array([0.0, 0.0, (e.low + e.high) / 2.0])
            for grow in (1.0, 5.0):
                def grown(p: np.ndarray, g: float = grow, dims: Any = dims,
                          mid: np.ndarray = mid) -> bool:
                    return bool(obstacle._beyond(dims, p + mid, g))
                settled = sum(grown(p) for p in clear)
                print(f"the body grown by {grow:.0f} mm, clear of the part: collision test "
                      f"{mean_ms(grown, clear):.3f} ms, settles {settled} of {len(clear)}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
