"""Benchmark: the height map's disc dilation (planning/heightmap.py) in single precision
on the heights rounded up (``heightmap.SINGLE``), against double precision (before
stop 33), in one process.

Run:  PYTHONPATH=. .venv/bin/python benchmarks/bench_dilation_single.py [MODEL ...]

Default: NIST CTC 4 and CTC 2.  Per model, the part as loaded and turned as a head index
turns it (Euler ZXZ 30, 60, -45), its height map dilated by the radii the fast check asks
of the CMM sample's styli (each ball, shank and the probe body, plus the required
clearance and half a cell), each way three times; prints the least CPU time of each,
their ratio, the memory of the dilated grids, and how far the single-precision grids lie
above the double ones where these are within the part's height range (a steep
triangle's plane bound may lie far below it, where float32 is coarser), and that they
never lie below (they stay upper bounds).
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

from probegen.machine.profile import load_profile  # noqa: E402
from probegen.planning import heightmap  # noqa: E402
from probegen.planning.collision import MESH_TOLERANCE, MIN_STEP, probe_stylus  # noqa: E402

sys.path.insert(0, str(REPO / "benchmarks"))
from bench_heightmap import MODELS, model_frames  # noqa: E402


def dilate(hmap: heightmap.HeightMap, radii: list[float], single: bool
           ) -> tuple[float, list[np.ndarray]]:
    """The least CPU time of three dilations by every radius, and the grids."""
    best, grids = np.inf, []
    saved = heightmap.SINGLE
    heightmap.SINGLE = single
    try:
        for _ in range(3):
            hmap._dilated.clear()
            t = time.process_time()
            grids = [hmap.dilated(r + hmap.cell / 2.0)[0] for r in radii]
            best = min(best, time.process_time() - t)
    finally:
        heightmap.SINGLE = saved
    return best, grids


def main() -> None:
    models = [Path(a) for a in sys.argv[1:]] or MODELS
    machine = load_profile(REPO / "samples/machines/cmm.toml")
    q = machine.margin / 2.0 + MESH_TOLERANCE + MIN_STEP / 2.0 + heightmap.FCL_SLACK
    radii: set[float] = set()
    for s in machine.styli():
        stylus = probe_stylus(machine.with_stylus(s), s.ball_diameter / 2.0)
        radii |= {max(stylus.ball, stylus.shank) + q, stylus.shank + q}
        radii |= {r + q for r, _, _ in stylus.cylinders()[1:]}
    ordered = sorted(radii)
    print(f"radii (mm, before half a cell): {', '.join(f'{r:.3f}' for r in ordered)}")
    print("| model | frame | cells | double s | single s | ratio | double MB | single MB | "
          "single above double, most mm | never below |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for model, name, p in model_frames(models):
        mesh = p.mesh(MESH_TOLERANCE)
        hmap = heightmap.HeightMap(np.asarray(mesh.vertices, dtype=np.float64),
                                   np.asarray(mesh.faces, dtype=np.int64))
        t64, g64 = dilate(hmap, ordered, False)
        t32, g32 = dilate(hmap, ordered, True)
        # the heights the stylus meets: the part's own z range (a steep triangle's
        # plane bound can lie far below it, where single precision is coarser)
        floor = float(mesh.bounds[0][2]) - 1.0
        above = max(float((b.astype(np.float64)[a >= floor] - a[a >= floor]).max(
            initial=0.0)) for a, b in zip(g64, g32, strict=True))
        below = all(np.all(b.astype(np.float64) >= a) for a, b in zip(g64, g32, strict=True))
        print(f"| {model.stem} | {name} | {hmap.height.size} | {t64:.2f} | {t32:.2f} | "
              f"{t64 / t32:.2f} | {sum(a.nbytes for a in g64) / 1e6:.0f} | "
              f"{sum(b.nbytes for b in g32) / 1e6:.0f} | {above:.1e} | "
              f"{'yes' if below else 'NO'} |", flush=True)


if __name__ == "__main__":
    main()
