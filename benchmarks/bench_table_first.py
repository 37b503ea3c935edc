"""Benchmark: the collision check asks the machine table first (``MeshObstacle.clearance``
and ``face_of``: a stylus element the table's plane puts at least as deep as the part's
distance query can report needs no such query), against the same planning with the
part's query made everywhere (the code before, below), in one process.

Run:  PYTHONPATH=. .venv/bin/python benchmarks/bench_table_first.py [--profile cmm|5axis]
      MODEL.step [MODEL.step ...]

Per model and profile (default both), what ``probegen plan MODEL --all-revolved`` plans,
twice, each on a fresh load (``bench_memory.child``): first with the part's distance
queried for every element (:func:`clearance_before`, :func:`face_of_before`: the methods
as they were before the change), then as shipped.  It prints both plan times (wall clock,
s), their ratio and whether the programs are the same bytes (SHA-256, first 12 digits).
The change pays where the table refuses moves: a probe body's distance query next to the
part costs milliseconds (a 40 mm body beside a 16 000-triangle mesh: about 7 ms).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

import numpy as np
from bench_memory import PROFILES, REPO, compare_rows


def clearance_before(self: Any, centre: np.ndarray, stylus: Any) -> tuple[float, float]:
    """``MeshObstacle.clearance`` before the change: the part's distance always."""
    from probegen.planning.collision import SKIP_SLACK

    ball, cylinders = self._stylus(stylus)
    ball.setTranslation(centre)
    b = self._to(ball)
    table = self.table
    if table is not None:
        b = min(b, table.clearance(centre, stylus.ball))
    last = self._last.get(stylus)
    measured: list[tuple[np.ndarray, float]] = []
    least = np.inf
    dims = stylus.cylinders()
    for k, (obj, mid) in enumerate(cylinders):
        if last is not None and k:
            at, d = last[k]
            if d - float(np.linalg.norm(centre - at)) >= least + SKIP_SLACK:
                measured.append(last[k])
                continue
        obj.setTranslation(centre + np.array([0.0, 0.0, mid]))
        d = self._to(obj)
        if table is not None:
            d = min(d, table.clearance(centre, *dims[k]))
        measured.append((np.array(centre, dtype=np.float64), d))
        least = min(least, d)
    self._last[stylus] = measured
    return b, least


def face_of_before(self: Any, centre: np.ndarray, e: Any) -> str:
    """``MeshObstacle.face_of`` before the change: the nearest face queried even with the
    element in the table."""
    from probegen.planning.collision import TABLE

    fcl = self.fcl
    obj = self._shape(centre, e)
    hit = fcl.CollisionResult()
    fcl.collide(self.part, obj, fcl.CollisionRequest(num_max_contacts=16,
                                                     enable_contact=True), hit)
    tris = [(c.penetration_depth, max(int(c.b1), int(c.b2))) for c in hit.contacts]
    table = self._table_clearance(centre, e)
    if tris:
        if -table > max(tris)[0]:
            return TABLE
        tri = max(tris)[1]
    else:
        near = fcl.DistanceResult()
        fcl.distance(self.part, obj, fcl.DistanceRequest(enable_nearest_points=True), near)
        if table < near.min_distance:
            return TABLE
        tri = int(near.b1)
    return f"triangle {tri}" if self.face_ids is None else f"face {int(self.face_ids[tri])}"


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--profile", choices=sorted(PROFILES), action="append")
    parser.add_argument("models", nargs="+", type=Path)
    args = parser.parse_args(argv)
    sys.path.insert(0, str(REPO))
    from probegen.planning.collision import MeshObstacle

    print("| model | profile | part queried s | table first s | ratio | same programs |")
    print("|---|---|---|---|---|---|")
    compare_rows(args.models, args.profile or sorted(PROFILES),
                 [(MeshObstacle, "clearance", clearance_before),
                  (MeshObstacle, "face_of", face_of_before)])
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
