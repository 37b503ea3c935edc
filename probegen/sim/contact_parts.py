"""Parts of the contact search (``sim.contact``) that do not depend on the solver: the
move as a line, a touch along it, the touches on a face's straight and circular edges
and vertices, the step of the numeric search, and input checks.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from probegen.cad.exact import Boundary, FloatArray, line_pipe_roots, sphere_roots, torus_roots
from probegen.errors import ProbegenError

START_TOLERANCE = 1e-9
"""A root up to this far (mm) before the start of a window still counts (rounding)."""
TIE = 1e-12
"""Touches closer than this along the move (mm) are the same touch (an edge and the
vertex at its end, two faces meeting at the contact point)."""
NEWTON_CAP = 100.0
"""An unbracketed Newton step may be at most this many safe (sphere-tracing) steps."""

KIND_ORDER = {"face": 0, "edge": 1, "vertex": 2}
"""Which touch wins a tie: a face, then an edge, then a vertex."""


@dataclass(frozen=True, slots=True, eq=False)
class Hit:
    """A touch in the part frame, at arc length ``s`` along the move; ``foot`` is the
    touched point when it is not ``centre − r·normal`` (a ball that starts overlapping)."""

    s: float
    normal: FloatArray
    face: int
    kind: str
    foot: FloatArray | None = None

    def before(self, other: Hit | None) -> bool:
        """Whether this touch comes first; within :data:`TIE` a face beats an edge, an
        edge a vertex, then the lower face id wins."""
        if other is None or self.s < other.s - TIE:
            return True
        if self.s > other.s + TIE:
            return False
        return (KIND_ORDER[self.kind], self.face) < (KIND_ORDER[other.kind], other.face)


class Line:
    """The move in the part frame: ``a + s·u`` for ``s`` in ``[0, length]``."""

    def __init__(self, a: FloatArray, b: FloatArray) -> None:
        self.a = a
        self.length = float(np.linalg.norm(b - a))
        self.u = (b - a) / self.length if self.length > 0.0 else np.zeros(3)

    def at(self, s: float) -> FloatArray:
        """The point at arc length ``s``, (3,) float."""
        return self.a + s * self.u


def boundary_hit(boundary: Boundary, line: Line, s0: float, s1: float, r: float,
                  face: int) -> Hit | None:
    """The first touch on a face's straight and circular edges and its vertices."""
    best: Hit | None = None

    def keep(s: float, n: FloatArray, kind: str) -> bool:
        nonlocal best
        hit = Hit(s, n, face, kind)
        if s0 - START_TOLERANCE <= s <= s1 and hit.before(best):
            best = hit
            return True
        return False

    for edge in boundary.lines:
        for s, n in line_pipe_roots(line.a, line.u, edge.start, edge.end, r):
            if keep(s, n, "edge"):
                break
    for arc in boundary.circles:
        if far(line, s0, s1, arc.centre, arc.radius + r):
            continue
        for s, n in torus_roots(line.a, line.u, arc.centre, arc.axis, arc.radius, r, 1.0):
            foot = line.at(s) - r * n - arc.centre
            if arc.holds(math.atan2(foot @ arc.ydir, foot @ arc.xdir)) and keep(s, n, "edge"):
                break
    for vertex in boundary.vertices:
        for s, n in sphere_roots(line.a, line.u, vertex, r, 1.0):
            if keep(s, n, "vertex"):
                break
    return best


def far(line: Line, s0: float, s1: float, centre: FloatArray, reach: float) -> bool:
    """Whether the stretch ``[s0, s1]`` of the move stays farther than ``reach``."""
    s = min(max(float((centre - line.a) @ line.u), s0), s1)
    return float(np.linalg.norm(line.at(s) - centre)) > reach


def next_step(s: float, f: float, slope: float, lo: float, hi: float, end: float) -> float:
    """Next arc length of the numeric search on ``[.., end]``.

    ``f`` is 1-Lipschitz in ``s``, so without a bracket a step of ``f`` (sphere tracing)
    never passes a root; a longer Newton step is taken while it stays before ``end``,
    so a step past ``end`` means no root before ``end``.
    """
    newton = s - f / slope if slope < 0.0 else math.inf
    if hi == math.inf:
        step = s + max(f, min(newton - s, NEWTON_CAP * f))
        return step if step <= end else s + f
    return newton if lo < newton < hi else 0.5 * (lo + hi)


def as_vector(value: ArrayLike, what: str) -> FloatArray:
    """``value`` as a finite (3,) float array; ``what`` names it in the error."""
    v = np.asanyarray(value, dtype=np.float64).reshape(-1)
    if v.shape != (3,) or not np.all(np.isfinite(v)):
        raise ProbegenError(f"{what}: expected 3 finite numbers, found {v.tolist()}")
    return v


def as_rotation(value: ArrayLike | None) -> FloatArray:
    """A checked proper rotation matrix (3, 3); identity for None."""
    if value is None:
        return np.eye(3)
    m = np.asanyarray(value, dtype=np.float64)
    ok = m.shape == (3, 3) and np.allclose(m @ m.T, np.eye(3), atol=1e-9)
    if not ok or np.linalg.det(m) <= 0.0:
        raise ProbegenError(f"rotation: expected a proper (3, 3) rotation matrix, found "
                            f"{m.tolist()}")
    return m
