"""Every DMIS point on the model with its outward normal (issue 17, "done when").

For each ``PTMEAS/CART,x,y,z,i,j,k`` of a DMIS program (work coordinates of the part as
loaded, millimetres): the exact distance from the point to the model's nearest face
(OCCT, the face found by the mesh), and whether the vector points out of the material:
the point a little along the vector lies outside every solid and a little against it
inside one (OCCT's solid classifier), at the point or, for a point on an edge where
another face meets its own, a hair beside it on the model (:data:`EDGE_STEP`).  A model
without a solid gets the distance only.

Used by ``benchmarks/bench_real_parts.py`` (``--points``); runs alone as

    PYTHONPATH=. .venv/bin/python benchmarks/points_on_model.py PROGRAM.dmi MODEL.step
"""

from __future__ import annotations

import re
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

ON_MODEL = 1e-3
"""A point farther than this from the model (mm) is off it."""
STEP = 0.01
"""How far along and against the vector the sides are classified, mm."""
PTMEAS = re.compile(r"^\s*PTMEAS/CART,([^,]+),([^,]+),([^,]+),([^,]+),([^,]+),([^,\s]+)",
                    re.MULTILINE)


@dataclass
class PointsCheck:
    """What the check of one program found.

    Attributes:
        points: the PTMEAS points checked.
        off_model: of them, farther than :data:`ON_MODEL` from the model.
        inward: of them, with a vector that does not point out of the material.
        unclassified: of them, whose sides the solid classifier could not tell (no
            solid, or on the boundary both ways).
        worst: the largest distance to the model, mm.
    """

    points: int = 0
    off_model: int = 0
    inward: int = 0
    unclassified: int = 0
    worst: float = 0.0

    def text(self) -> str:
        if not self.points:
            return "no points"
        bad = [f"{self.off_model} off the model" if self.off_model else "",
               f"{self.inward} inward" if self.inward else "",
               f"{self.unclassified} unclassified" if self.unclassified else ""]
        said = ", ".join(b for b in bad if b) or "all on the model, outward"
        return f"{self.points} points: {said} (worst {self.worst * 1000:.2f} um)"


def dmis_points(text: str) -> tuple[np.ndarray, np.ndarray]:
    """The points and unit vectors of every ``PTMEAS/CART`` of ``text``: (n, 3) each."""
    rows = np.array([[float(v) for v in m.groups()] for m in PTMEAS.finditer(text)],
                    dtype=np.float64).reshape(-1, 6)
    vectors = rows[:, 3:]
    norms = np.linalg.norm(vectors, axis=1, keepdims=True)
    return rows[:, :3], vectors / np.where(norms > 0.0, norms, 1.0)


def check_points(text: str, part: Any) -> PointsCheck:
    """Check every PTMEAS point of DMIS program ``text`` against ``part``
    (``probegen.cad.Part``, loaded as the program measures it)."""
    import trimesh

    points, vectors = dmis_points(text)
    out = PointsCheck(points=len(points))
    if not len(points):
        return out
    mesh = part.mesh()
    face_ids = mesh.metadata["face_ids"]  # model face ids, 1-based
    nearby = trimesh.proximity.nearby_faces(mesh, points)
    exact = part.exact
    # a face the mesh lacks (OCCT left it without triangles) is a candidate everywhere
    unmeshed = set(range(len(part.faces))) - {int(k) - 1 for k in set(face_ids.tolist())}
    for p, v, triangles in zip(points, vectors, nearby, strict=True):
        faces = sorted({int(face_ids[int(t)]) - 1 for t in triangles} | unmeshed)
        distance = min(exact.distance(k, p)[0] for k in faces)
        out.worst = max(out.worst, distance)
        out.off_model += distance > ON_MODEL
        sides = _sides(exact, p, v)
        if sides != "outward":  # on an edge? the face beside it, a hair off the edge
            beside = [q for q in _beside(p, v)
                      if min(exact.distance(k, q)[0] for k in faces) <= ON_MODEL]
            if any(_sides(exact, q, v) == "outward" for q in beside):
                sides = "outward"
        out.unclassified += sides == "unclassified"
        out.inward += sides == "inward"
    return out


def _sides(exact: Any, p: np.ndarray, v: np.ndarray) -> str:
    """``outward`` when ``p`` a :data:`STEP` along ``v`` is out of the material and a
    step against it in; ``inward`` when not; ``unclassified`` when the classifier cannot
    tell (no solid, or in material both ways)."""
    along, against = exact.inside(p + STEP * v), exact.inside(p - STEP * v)
    if along is None or against is None or (along and against):
        return "unclassified"
    return "inward" if along or not against else "outward"


EDGE_STEP = 0.02
"""How far beside a point (square to its vector, mm) the sides are tried again when they
fail at the point itself: a touch on the edge where another face meets its own (a cross
hole whose rim touches a bore's section: NIST FTC 10 R137, the Prusa heatsink R20) has
air on both sides along the vector at the edge, and its own face's material a hair
beside it.  A vector that is wrong fails beside the edge too; 0.02 mm off a surface of
0.5 mm radius is 0.4 um off it, within :data:`ON_MODEL`."""


def _beside(p: np.ndarray, v: np.ndarray) -> list[np.ndarray]:
    """Four points :data:`EDGE_STEP` from ``p`` square to ``v``."""
    a = np.cross(v, [1.0, 0.0, 0.0] if abs(v[0]) < 0.9 else [0.0, 1.0, 0.0])
    a /= np.linalg.norm(a)
    b = np.cross(v, a)
    return [p + EDGE_STEP * d for d in (a, -a, b, -b)]


def main(argv: list[str]) -> int:
    from probegen.cad import load_part

    program, model = Path(argv[0]), Path(argv[1])
    print(check_points(program.read_text(encoding="ascii"), load_part(model)).text())
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
