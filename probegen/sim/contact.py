"""Where the stylus ball first meets the part: the skip signal of the virtual machine.

The part as placed on the machine (:class:`PlacedPart`) is a loaded model under a rigid
placement, or a set of analytic spheres.  :meth:`PlacedPart.first_contact` moves the ball
centre on a straight line and returns the first touch.

Method (model parts), in the part's own frame:

1. Sphere tracing on the part mesh with python-fcl: the exact clearance of the ball is
   at least the mesh clearance less the mesh deviation, so the centre advances by that
   much per step without ever passing a contact.  It stops where the mesh clearance
   falls below :data:`GUARD` (plus the mesh deviation).
2. Exact search over a window of :data:`WINDOW` mm from there: every face whose
   bounding box, grown by the ball radius, meets the window (the face fcl found among
   them) is solved exactly.  The ball touches a face where its centre lies on the
   face's offset surface, on the outward side: a plane offset by ``r``, a sphere or
   cylinder of radius ``R ± r``, a cone with its apex moved along the axis by
   ``∓ r / sin α``, a torus with tube radius ``ρ ± r`` (``+`` when the material is
   inside the surface).  Plane, sphere, cylinder and cone give a quadratic in the arc
   length along the move, the torus a quartic (numpy roots, then Newton on the exact
   distance).  A root counts only if the ball moves into the surface there and its foot
   point ``centre − r·n`` lies on the trimmed face (OCCT's face classifier).  A ball can
   also meet a convex edge or a vertex first: straight edges give a cylinder of radius
   ``r`` around the edge, circular edges a torus with tube ``r``, vertices a sphere of
   radius ``r``, each root kept if its foot lies on the edge.  Faces of any other type,
   and faces with edges that are neither lines nor circles, are solved numerically: the
   exact distance to the trimmed face (OCCT BRepExtrema) minus ``r`` along the move,
   sphere-traced and Newton-stepped until a root is bracketed, then safeguarded Newton
   and bisection to :data:`ROOT_TOLERANCE`.
3. No contact in the window: tracing resumes at its end.

Frames: ``start``/``end`` and every result are in the work frame (the frame the machine
model's tool point is given in); the placement maps part coordinates ``p`` to work
coordinates ``rotation @ p + translation``.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from probegen.cad import Model
from probegen.cad.exact import (
    Boundary,
    ExactFaces,
    FloatArray,
    face_roots,
    line_pipe_roots,
    nearest_on_surface,
    sphere_roots,
    torus_roots,
)
from probegen.constants import tol
from probegen.errors import ProbegenError

MESH_TOLERANCE = 0.02
"""Chordal deviation of the tracing mesh, mm.  The mesh only finds where to look; the
answer comes from the exact surfaces, so a coarse mesh (few triangles, fast fcl queries)
is the better trade."""
MESH_DEVIATION_FACTOR = 2.0
"""The mesh is trusted to within this many times its nominal chordal deviation."""
GUARD = 0.5
"""Tracing stops where the mesh clearance falls below this, mm (above the mesh deviation
by far, so tracing never needs tiny steps near the part)."""
WINDOW = 2.0
"""Length of the stretch of the move solved exactly at a time, mm."""
ROOT_TOLERANCE = 1e-9
"""Numeric contact search: stop when the exact clearance is within this of zero, or the
bracket on the move is this short, mm."""
START_TOLERANCE = 1e-9
"""A root up to this far (mm) before the start of a window still counts (rounding)."""
MAX_ITERATIONS = 200
"""Iteration limit of the numeric contact search (a grazing move can need many)."""
TIE = 1e-12
"""Touches closer than this along the move (mm) are the same touch (an edge and the
vertex at its end, two faces meeting at the contact point)."""
NEWTON_CAP = 100.0
"""An unbracketed Newton step may be at most this many safe (sphere-tracing) steps."""

_KIND_ORDER = {"face": 0, "edge": 1, "vertex": 2}


@dataclass(frozen=True, slots=True, eq=False)
class ContactHit:
    """The first touch of the ball on the part (work frame, mm).

    Attributes:
        t: fraction of the move ``start → end`` at the touch, 0 to 1.
        centre: (3,) float, the ball centre at the touch.
        point: (3,) float, the touched point of the part surface.
        normal: (3,) float, unit outward surface normal there (from the point towards
            the ball centre; at an edge or vertex the normal of the offset surface).
        face_id: the model face touched (1-based; for an edge or vertex, the face whose
            boundary it is); for analytic spheres, the 1-based sphere number.
        kind: ``"face"``, ``"edge"`` or ``"vertex"``: what was touched.
    """

    t: float
    centre: FloatArray
    point: FloatArray
    normal: FloatArray
    face_id: int
    kind: str


@dataclass(frozen=True, slots=True, eq=False)
class _Hit:
    """A touch in the part frame, at arc length ``s`` along the move; ``foot`` is the
    touched point when it is not ``centre − r·normal`` (a ball that starts overlapping)."""

    s: float
    normal: FloatArray
    face: int
    kind: str
    foot: FloatArray | None = None

    def before(self, other: _Hit | None) -> bool:
        """Whether this touch comes first; within :data:`TIE` a face beats an edge, an
        edge a vertex, then the lower face id wins."""
        if other is None or self.s < other.s - TIE:
            return True
        if self.s > other.s + TIE:
            return False
        return (_KIND_ORDER[self.kind], self.face) < (_KIND_ORDER[other.kind], other.face)


class _Line:
    """The move in the part frame: ``a + s·u`` for ``s`` in ``[0, length]``."""

    def __init__(self, a: FloatArray, b: FloatArray) -> None:
        self.a = a
        self.length = float(np.linalg.norm(b - a))
        self.u = (b - a) / self.length if self.length > 0.0 else np.zeros(3)

    def at(self, s: float) -> FloatArray:
        """The point at arc length ``s``, (3,) float."""
        return self.a + s * self.u


class PlacedPart:
    """The part as placed on the machine: a model or analytic spheres, placed rigidly.

    Build it with :meth:`from_model` or :meth:`from_spheres`.
    """

    def __init__(self, solver: _Solver, rotation: ArrayLike | None,
                 translation: ArrayLike | None) -> None:
        self._solver = solver
        self.rotation = _rotation(rotation)
        self.translation = _vector(translation if translation is not None else np.zeros(3),
                                   "translation")

    @classmethod
    def from_model(cls, model: Model, *, rotation: ArrayLike | None = None,
                   translation: ArrayLike | None = None,
                   mesh_tolerance: float = MESH_TOLERANCE) -> PlacedPart:
        """Place a loaded model.

        Args:
            model: the part model (:func:`probegen.cad.load_step`).
            rotation: (3, 3) proper rotation, part to work frame; identity if omitted.
            translation: (3,) float, mm: where the part origin sits in the work frame.
            mesh_tolerance: chordal deviation of the tracing mesh, mm.
        """
        return cls(_ModelSolver(model, mesh_tolerance), rotation, translation)

    @classmethod
    def from_spheres(cls, centres: ArrayLike, radii: ArrayLike, *,
                     rotation: ArrayLike | None = None,
                     translation: ArrayLike | None = None) -> PlacedPart:
        """Place analytic spheres (a spec without a model).

        Args:
            centres: (k, 3) float, sphere centres in the part frame, mm.
            radii: (k,) float, sphere radii, mm, positive.
            rotation: (3, 3) proper rotation, part to work frame.
            translation: (3,) float, mm.
        """
        c = np.asanyarray(centres, dtype=np.float64).reshape(-1, 3)
        r = np.asanyarray(radii, dtype=np.float64).reshape(-1)
        if len(c) != len(r) or len(c) == 0 or not np.all(r > 0.0):
            raise ProbegenError(f"spheres: expected k centres and k positive radii, found "
                                f"{len(c)} centres and radii {r.tolist()}")
        return cls(_SphereSolver(c, r), rotation, translation)

    def to_part(self, points: ArrayLike) -> FloatArray:
        """Work-frame points ``(..., 3)`` in the part frame."""
        p = np.asanyarray(points, dtype=np.float64)
        return np.asarray((p - self.translation) @ self.rotation)

    def to_work(self, points: ArrayLike) -> FloatArray:
        """Part-frame points ``(..., 3)`` in the work frame."""
        p = np.asanyarray(points, dtype=np.float64)
        return np.asarray(p @ self.rotation.T + self.translation)

    def first_contact(self, start: ArrayLike, end: ArrayLike,
                      ball_radius: float) -> ContactHit | None:
        """The first touch of a ball whose centre moves from ``start`` to ``end``.

        Args:
            start: (3,) float, ball centre at the start, work frame, mm.
            end: (3,) float, ball centre at the end, work frame, mm.
            ball_radius: stylus ball radius, mm, positive.

        Returns:
            The touch, or None when the ball stays clear of the part all the way.  A
            ball that already overlaps the part at ``start`` touches at ``t = 0``.
        """
        if not ball_radius > 0.0:
            raise ProbegenError(f"ball radius: expected a positive number, found {ball_radius}")
        line = _Line(self.to_part(_vector(start, "start")), self.to_part(_vector(end, "end")))
        overlap = self._solver.overlap(line.a, ball_radius)
        hit = overlap if overlap is not None else (
            self._solver.first_hit(line, ball_radius) if line.length > 0.0 else None)
        if hit is None:
            return None
        s = min(max(hit.s, 0.0), line.length)
        centre = line.at(s)
        point = centre - ball_radius * hit.normal if hit.foot is None else hit.foot
        t = s / line.length if line.length > 0.0 else 0.0
        return ContactHit(t, self.to_work(centre), self.to_work(point),
                          hit.normal @ self.rotation.T, hit.face, hit.kind)

    def clearance(self, point: ArrayLike, ball_radius: float) -> float:
        """Exact signed clearance of a ball centred at ``point`` (work frame), mm.

        Returns:
            The distance between the ball and the part surface: positive when clear,
            zero when touching, negative (minus the penetration) when overlapping.
        """
        return self._solver.clearance(self.to_part(_vector(point, "point")), ball_radius)


class _Solver(ABC):
    """The part's geometry in its own frame (see the two implementations)."""

    @abstractmethod
    def first_hit(self, line: _Line, r: float) -> _Hit | None:
        """The first touch along ``line`` of a ball of radius ``r`` that starts clear."""

    @abstractmethod
    def nearest(self, c: FloatArray) -> tuple[float, FloatArray, int]:
        """Signed distance of ``c`` from the surface (negative inside), nearest point,
        0-based face (or sphere) index."""

    def clearance(self, c: FloatArray, r: float) -> float:
        """Signed clearance of a ball of radius ``r`` at ``c``."""
        return self.nearest(c)[0] - r

    def overlap(self, c: FloatArray, r: float) -> _Hit | None:
        """A touch at ``s = 0`` when the ball at ``c`` overlaps the part."""
        if not self.quick_clear(c, r):
            signed, foot, face = self.nearest(c)
            if signed - r < -START_TOLERANCE:
                n = c - foot
                size = float(np.linalg.norm(n))
                normal = n / size * (1.0 if signed >= 0.0 else -1.0) if size > 0.0 else n
                return _Hit(0.0, normal, face + 1, "face", foot)
        return None

    def quick_clear(self, c: FloatArray, r: float) -> bool:
        """A cheap check that the ball at ``c`` is clear (False means: do not know)."""
        return False


class _SphereSolver(_Solver):
    """Analytic spheres, material inside."""

    def __init__(self, centres: FloatArray, radii: FloatArray) -> None:
        self.centres = centres
        self.radii = radii

    def first_hit(self, line: _Line, r: float) -> _Hit | None:
        best: _Hit | None = None
        for k, (centre, radius) in enumerate(zip(self.centres, self.radii, strict=True)):
            for s, n in sphere_roots(line.a, line.u, centre, radius + r, 1.0):
                if -START_TOLERANCE <= s <= line.length and (best is None or s < best.s):
                    best = _Hit(s, n, k + 1, "face")
                    break
        return best

    def nearest(self, c: FloatArray) -> tuple[float, FloatArray, int]:
        rel = c - self.centres
        dist = np.linalg.norm(rel, axis=1) - self.radii
        k = int(np.argmin(dist))
        size = float(np.linalg.norm(rel[k]))
        direction = rel[k] / size if size > 0.0 else np.array([0.0, 0.0, 1.0])
        return float(dist[k]), self.centres[k] + self.radii[k] * direction, k


class _ModelSolver(_Solver):
    """A loaded model: fcl sphere tracing on its mesh, exact solution on its faces."""

    def __init__(self, model: Model, mesh_tolerance: float) -> None:
        import fcl

        from probegen import cad

        if not mesh_tolerance > 0.0:
            raise ProbegenError(f"mesh tolerance: expected a positive number, found "
                                f"{mesh_tolerance}")
        self.model = model
        self.exact = ExactFaces(model)
        self.low = np.array([f.bbox_min for f in model.faces])
        self.high = np.array([f.bbox_max for f in model.faces])
        mesh = cad.tessellate(model, mesh_tolerance)
        self.deviation = MESH_DEVIATION_FACTOR * mesh_tolerance
        self.face_ids = np.asarray(mesh.metadata["face_ids"])
        bvh = fcl.BVHModel()
        bvh.beginModel(len(mesh.vertices), len(mesh.faces))
        bvh.addSubModel(np.asarray(mesh.vertices, dtype=np.float64),
                        np.asarray(mesh.faces, dtype=np.int32))
        bvh.endModel()
        self._fcl = fcl
        self._mesh = fcl.CollisionObject(bvh, fcl.Transform())
        self._balls: dict[float, Any] = {}

    # ---------------------------------------------------------------- mesh tracing

    def mesh_clearance(self, c: FloatArray, r: float) -> tuple[float, int]:
        """fcl distance between the ball at ``c`` and the mesh; 0-based face near it."""
        fcl = self._fcl
        if r not in self._balls:
            self._balls[r] = fcl.CollisionObject(fcl.Sphere(r), fcl.Transform())
        ball = self._balls[r]
        ball.setTranslation(c)
        result = fcl.DistanceResult()
        d = fcl.distance(ball, self._mesh, fcl.DistanceRequest(), result)
        triangle = max(int(result.b1), int(result.b2))
        face = int(self.face_ids[triangle]) - 1 if triangle >= 0 else -1
        return float(d), face

    def quick_clear(self, c: FloatArray, r: float) -> bool:
        """Clear by more than the guard on the mesh, hence clear exactly."""
        return self.mesh_clearance(c, r)[0] > GUARD + self.deviation

    def first_hit(self, line: _Line, r: float) -> _Hit | None:
        s = 0.0
        while s <= line.length:
            clear, face = self.mesh_clearance(line.at(s), r)
            if clear > GUARD + self.deviation:
                s += clear - self.deviation  # the exact clearance is at least this
                continue
            end = min(line.length, s + WINDOW)
            hit = self.window_hit(line, s, end, r, face)
            if hit is not None or end >= line.length:
                return hit
            s = end
        return None

    # ---------------------------------------------------------------- exact window

    def candidates(self, line: _Line, s0: float, s1: float, margin: float) -> list[int]:
        """0-based faces whose bounding box, grown by ``margin``, meets ``a + s·u``."""
        lo, hi = self.low - margin, self.high + margin
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            p = (lo - line.a) / line.u
            q = (hi - line.a) / line.u
        enter = np.where(np.isnan(p), -np.inf, np.minimum(p, q))
        leave = np.where(np.isnan(q), np.inf, np.maximum(p, q))
        flat = line.u == 0.0
        outside = flat & ((line.a < lo) | (line.a > hi))
        enter = np.where(flat, -np.inf, enter)
        leave = np.where(flat, np.inf, leave)
        first = np.maximum(enter.max(axis=1), s0)
        last = np.minimum(leave.min(axis=1), s1)
        ok = (first <= last) & ~outside.any(axis=1)
        return np.flatnonzero(ok).tolist()

    def window_hit(self, line: _Line, s0: float, s1: float, r: float,
                   hint: int) -> _Hit | None:
        """The first touch for ``s`` in ``[s0, s1]`` over every face that can reach it."""
        faces = self.candidates(line, s0, s1, r + self.deviation)
        if hint in faces:  # the face fcl found first: its answer bounds the others
            faces.remove(hint)
            faces.insert(0, hint)
        best: _Hit | None = None
        for index in faces:
            limit = best.s if best is not None else s1
            hit = self.face_hit(index, line, s0, limit, r)
            if hit is not None and hit.before(best):
                best = hit
        return best

    def face_hit(self, index: int, line: _Line, s0: float, s1: float,
                 r: float) -> _Hit | None:
        """The first touch of face ``index`` (0-based) for ``s`` in ``[s0, s1]``."""
        record = self.model.faces[index]
        kind = self.exact.kind(index)
        boundary = self.exact.boundary(index)
        best: _Hit | None = None
        if kind is not None:
            for s, n in face_roots(record, line.a, line.u, r):
                if s0 - START_TOLERANCE <= s <= s1 and self.exact.contains(
                        index, line.at(s) - r * n):
                    best = _Hit(s, n, index + 1, "face")
                    break
            edge = _boundary_hit(boundary, line, s0, best.s if best else s1, r, index + 1)
            if edge is not None and edge.before(best):
                best = edge
        if kind is None or boundary.free_edges:
            numeric = self.numeric_hit(index, line, s0, best.s if best else s1, r)
            if numeric is not None and (best is None or numeric.s < best.s - ROOT_TOLERANCE):
                best = numeric
        return best

    def numeric_hit(self, index: int, line: _Line, s0: float, s1: float,
                    r: float) -> _Hit | None:
        """First root of (exact distance to the trimmed face − r) on ``[s0, s1]``."""
        s, lo, hi = s0, s0, math.inf
        for _ in range(MAX_ITERATIONS):
            c = line.at(s)
            d, foot = self.exact.distance(index, c)
            f = d - r
            n = (c - foot) / d if d > 0.0 else -line.u
            if abs(f) <= ROOT_TOLERANCE or hi - lo <= ROOT_TOLERANCE:
                return _Hit(s, n, index + 1, "face") if s <= s1 + ROOT_TOLERANCE else None
            slope = float(n @ line.u)
            if f > 0.0:
                lo = s
            else:
                hi = s
            s = _next_step(s, f, slope, lo, hi, s1)
            if s > s1:
                return None
        raise RuntimeError(f"face {index + 1}: the contact search did not converge")

    # ---------------------------------------------------------------- distances

    def nearest(self, c: FloatArray) -> tuple[float, FloatArray, int]:
        around = max(self.mesh_clearance(c, tol.zero)[0], 0.0) + self.deviation + tol.zero
        box = np.linalg.norm(np.maximum(np.maximum(self.low - c, c - self.high), 0.0), axis=1)
        best, foot, face = math.inf, c, -1
        for index in np.argsort(box).tolist():
            if box[index] > min(best, around):
                break
            d, p = self.face_distance(index, c)
            if d < best:
                best, foot, face = d, p, index
        inside = self.exact.inside(c) if best > tol.zero else False
        # a model without a solid (faces or shells only) has no inside: distances stay >= 0
        return (-best if inside else best), foot, face

    def face_distance(self, index: int, c: FloatArray) -> tuple[float, FloatArray]:
        """Exact distance from ``c`` to face ``index`` and the nearest point."""
        if self.exact.kind(index) is not None:
            foot = nearest_on_surface(self.model.faces[index], c)
            if foot is not None and self.exact.contains(index, foot):
                return float(np.linalg.norm(c - foot)), foot
        return self.exact.distance(index, c)


def _boundary_hit(boundary: Boundary, line: _Line, s0: float, s1: float, r: float,
                  face: int) -> _Hit | None:
    """The first touch on a face's straight and circular edges and its vertices."""
    best: _Hit | None = None

    def keep(s: float, n: FloatArray, kind: str) -> bool:
        nonlocal best
        hit = _Hit(s, n, face, kind)
        if s0 - START_TOLERANCE <= s <= s1 and hit.before(best):
            best = hit
            return True
        return False

    for edge in boundary.lines:
        for s, n in line_pipe_roots(line.a, line.u, edge.start, edge.end, r):
            if keep(s, n, "edge"):
                break
    for arc in boundary.circles:
        if _far(line, s0, s1, arc.centre, arc.radius + r):
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


def _far(line: _Line, s0: float, s1: float, centre: FloatArray, reach: float) -> bool:
    """Whether the stretch ``[s0, s1]`` of the move stays farther than ``reach``."""
    s = min(max(float((centre - line.a) @ line.u), s0), s1)
    return float(np.linalg.norm(line.at(s) - centre)) > reach


def _next_step(s: float, f: float, slope: float, lo: float, hi: float, end: float) -> float:
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


def _vector(value: ArrayLike, what: str) -> FloatArray:
    """``value`` as a finite (3,) float array; ``what`` names it in the error."""
    v = np.asanyarray(value, dtype=np.float64).reshape(-1)
    if v.shape != (3,) or not np.all(np.isfinite(v)):
        raise ProbegenError(f"{what}: expected 3 finite numbers, found {v.tolist()}")
    return v


def _rotation(value: ArrayLike | None) -> FloatArray:
    """A checked proper rotation matrix (3, 3); identity for None."""
    if value is None:
        return np.eye(3)
    m = np.asanyarray(value, dtype=np.float64)
    ok = m.shape == (3, 3) and np.allclose(m @ m.T, np.eye(3), atol=1e-9)
    if not ok or np.linalg.det(m) <= 0.0:
        raise ProbegenError(f"rotation: expected a proper (3, 3) rotation matrix, found "
                            f"{m.tolist()}")
    return m

