"""Benchmark: the height map's disc dilation (planning/heightmap.py), in place against
``np.roll``.

Run:  PYTHONPATH=. .venv/bin/python benchmarks/bench_dilation.py [MODEL] [--profile P]

The height map of MODEL (default NIST CTC 1) at the profile's mesh, dilated by the radii
the fast check asks of the profile's stylus (ball, shank and probe body, each plus the
required clearance and half a cell), twice in one process: by
:meth:`probegen.planning.heightmap.HeightMap.dilated` (each row shift a ``np.maximum`` on
slices, :func:`~probegen.planning.heightmap.shift_max`) and by the same loop with each
shift a ``np.roll`` copy of the filtered grid (the code before, kept here as the
baseline), both in double precision (``heightmap.SINGLE`` off).  Prints the CPU seconds
of each, the ratio, and whether every dilated grid is the same, element for element (it
must be: only the copies differ).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
from scipy.ndimage import maximum_filter1d

REPO = Path(__file__).resolve().parents[1]
CTC1 = REPO.parent / "shared/ref/nist-step/nist_ctc_01_asme1_rd.stp"


def rolled(hmap: object, radius: float) -> np.ndarray:
    """The dilation as it was computed before: each row shift by ``np.roll``."""
    cell, height = hmap.cell, hmap.height  # type: ignore[attr-defined]
    k = int(np.ceil(radius / cell)) + 2
    pad = np.pad(height, k, constant_values=-np.inf)
    out = np.full_like(pad, -np.inf)
    run, width = pad, -1
    for a in range(k + 1):
        da = max(a - 2, 0) * cell
        if da > radius:
            break
        w = int(np.floor(np.sqrt(radius**2 - da**2) / cell)) + 2
        if w != width:
            run, width = maximum_filter1d(pad, 2 * w + 1, axis=1, mode="constant",
                                          cval=-np.inf), w
        for shift in dict.fromkeys((a, -a)):
            np.maximum(out, np.roll(run, shift, axis=0), out=out)
    return out


def main(argv: list[str]) -> int:
    from probegen import cad
    from probegen.machine.profile import load_profile
    from probegen.planning import heightmap
    from probegen.planning.collision import (
        MESH_TOLERANCE,
        MIN_STEP,
        obstacle_for,
        probe_stylus,
    )
    from probegen.planning.heightmap import FCL_SLACK, HeightMap

    heightmap.SINGLE = False  # double precision, as np.roll made them

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("model", nargs="?", type=Path, default=CTC1)
    parser.add_argument("--profile", type=Path, default=REPO / "samples/machines/cmm.toml")
    args = parser.parse_args(argv)
    machine = load_profile(args.profile)
    part = cad.load_part(args.model)
    mesh = obstacle_for(part, []).mesh  # type: ignore[attr-defined]
    vertices = np.asarray(mesh.vertices, dtype=np.float64)
    faces = np.asarray(mesh.faces, dtype=np.int64)
    stylus = probe_stylus(machine, machine.probe.ball_radius)
    q = machine.margin / 2.0 + MESH_TOLERANCE + MIN_STEP / 2.0 + FCL_SLACK
    radii = sorted({stylus.ball + q, stylus.shank + q}
                   | {r + q for r, _, _ in stylus.cylinders()})
    new_map = HeightMap(vertices, faces)
    cells = new_map.height.size
    print(f"{args.model.stem}: height map {new_map.height.shape[0]} x "
          f"{new_map.height.shape[1]} cells of {new_map.cell:.3f} mm ({cells} cells); "
          f"radii {', '.join(f'{r + new_map.cell / 2.0:.3f}' for r in radii)} mm")
    t = time.process_time()
    base = [rolled(new_map, r + new_map.cell / 2.0) for r in radii]
    before = time.process_time() - t
    t = time.process_time()
    now = [new_map.dilated(r + new_map.cell / 2.0)[0] for r in radii]
    after = time.process_time() - t
    same = all(np.array_equal(a, b) for a, b in zip(base, now, strict=True))
    print(f"np.roll (before): {before:.2f} s CPU; in place: {after:.2f} s CPU; "
          f"{before / after:.2f}x; the same grids: {'yes' if same else 'NO'}")
    return 0 if same else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
