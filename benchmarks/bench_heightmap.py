"""Benchmark: building the fast collision check's height map (``planning/heightmap.py``)
with the plane of each large triangle worked out once for all of them
(``heightmap._planes``), against the triangle-by-triangle ``HeightMap._bound`` it
replaced (the baseline, run in this process): the same map, cell for cell.

Run:  PYTHONPATH=. .venv/bin/python benchmarks/bench_heightmap.py [MODEL ...]

Default: NIST CTC 4 and CTC 2 (their planning with the CMM sample builds a height map per
head index and frame: 136 in the first 25 minutes of CTC 4's, 40 % of its time).  Per
model, the part as loaded and turned as a head index turns it (Euler ZXZ 30, 60, -45),
each built three times; prints the least CPU time of each way and their ratio.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Iterator
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

from probegen import cad  # noqa: E402
from probegen.ir import frames  # noqa: E402
from probegen.planning import heightmap  # noqa: E402

SHARED = REPO.parent / "shared" / "ref"
MODELS = [SHARED / "nist-step/nist_ctc_04_asme1_rd.stp",
          SHARED / "nist-step/nist_ctc_02_asme1_rc.stp"]


def one_by_one(hmap: heightmap.HeightMap, tri: np.ndarray) -> np.ndarray:
    """The baseline: every large triangle through ``_bound`` on its own (the code
    before), the small ones as now."""
    out = np.full(hmap.shape, -np.inf)
    lo, hi = hmap._cells(tri)
    counts = (hi - lo + 1).prod(axis=1)
    for t in np.flatnonzero(counts > heightmap.BIG):
        i = np.arange(lo[t, 0], hi[t, 0] + 1)
        j = np.arange(lo[t, 1], hi[t, 1] + 1)
        block = hmap._bound(tri[t:t + 1], i[:, None], j[None, :])
        view = out[i[0]:i[-1] + 1, j[0]:j[-1] + 1]
        np.maximum(view, block, out=view)
    small = tri[counts <= heightmap.BIG]
    rest = hmap._rasterise(small)  # small triangles only: the same path as now
    return np.maximum(out, rest)


def model_frames(models: list[Path]) -> Iterator[tuple[Path, str, cad.Part]]:
    """Per model, the part as loaded and turned as a head index turns it (Euler ZXZ 30,
    60, -45): (model, frame name, part)."""
    for model in models:
        part = cad.load_part(model)
        yield model, "as loaded", part
        yield model, "turned", part.turned(frames.from_euler_zxz(30.0, 60.0, -45.0))


def main() -> None:
    models = [Path(a) for a in sys.argv[1:]] or MODELS
    print("| model | frame | triangles | large | cells of the large ones' boxes | "
          "one by one s | planes once s | ratio | same map |")
    print("|---|---|---|---|---|---|---|---|---|")
    for model, name, p in model_frames(models):
        mesh = p.mesh()
        v = np.asarray(mesh.vertices, dtype=np.float64)
        f = np.asarray(mesh.faces, dtype=np.int64)
        tri = v[f]
        hmap = heightmap.HeightMap(v, f)
        lo, hi = hmap._cells(tri)
        counts = (hi - lo + 1).prod(axis=1)
        large = counts > heightmap.BIG
        times: dict[str, float] = {}
        maps = {}
        for way in ("old", "new"):
            best = float("inf")
            for _ in range(3):
                t = time.process_time()
                maps[way] = one_by_one(hmap, tri) if way == "old" else hmap._rasterise(tri)
                best = min(best, time.process_time() - t)
            times[way] = best
        same = np.array_equal(maps["old"], maps["new"])
        print(f"| {model.stem} | {name} | {len(tri)} | {int(large.sum())} | "
              f"{int(counts[large].sum())} | {times['old']:.2f} | {times['new']:.2f} | "
              f"{times['old'] / times['new']:.2f} | {'yes' if same else 'NO'} |", flush=True)


if __name__ == "__main__":
    main()
