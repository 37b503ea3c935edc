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

Planted form errors (``sim.form``): a perturbed cylinder, cone, sphere or torus face is
solved with the same exact roots at the radius ``radius + δ`` of the contact's own foot
point, iterated to a fixed point (the local-radius model of ``docs/sim.md``); its
distances use the same model.  The move, the touch records, the edge and vertex
roots and the numeric search's step are in ``contact_parts``.

Frames: ``start``/``end`` and every result are in the work frame (the frame the machine
model's tool point is given in); the placement maps part coordinates ``p`` to work
coordinates ``rotation @ p + translation``.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

from probegen.cad import Model, Part
from probegen.cad.exact import FloatArray, face_roots, nearest_on_surface, sphere_roots
from probegen.constants import tol
from probegen.errors import ProbegenError
from probegen.sim.contact_parts import (
    START_TOLERANCE,
    Hit,
    Line,
    as_rotation,
    as_vector,
    boundary_hit,
    next_step,
)
from probegen.sim.form import BoundForm, FormError

if TYPE_CHECKING:
    from probegen.sim.stem import Stem

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
MAX_ITERATIONS = 200
"""Iteration limit of the numeric contact search (a grazing move can need many)."""
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

class PlacedPart:
    """The part as placed on the machine: a model or analytic spheres, placed rigidly.

    Build it with :meth:`from_model` or :meth:`from_spheres`.
    """

    def __init__(self, solver: _Solver, rotation: ArrayLike | None,
                 translation: ArrayLike | None) -> None:
        self._solver = solver
        self._stem: Stem | None = None
        self.rotation = as_rotation(rotation)
        self.translation = as_vector(translation if translation is not None else np.zeros(3),
                                   "translation")

    @classmethod
    def from_model(cls, model: Part | Model, *, rotation: ArrayLike | None = None,
                   translation: ArrayLike | None = None,
                   mesh_tolerance: float = MESH_TOLERANCE,
                   forms: tuple[FormError, ...] = ()) -> PlacedPart:
        """Place a loaded part.

        Args:
            model: the part (:func:`probegen.cad.load_part`: its mesh at
                ``mesh_tolerance`` and its exact face queries are built once per part and
                shared), or a bare model (:func:`probegen.cad.load_step`, a part of its own).
            rotation: (3, 3) proper rotation, part to work frame; identity if omitted.
            translation: (3,) float, mm: where the part origin sits in the work frame.
            mesh_tolerance: chordal deviation of the tracing mesh, mm.
            forms: planted form errors of revolved faces (``sim.form``).
        """
        part = model if isinstance(model, Part) else Part(model)
        return cls(_ModelSolver(part, mesh_tolerance, forms), rotation, translation)

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

    @property
    def stem(self) -> Stem | None:
        """The test of the probe's shank and body against the part's mesh
        (:mod:`probegen.sim.stem`), built when first asked for; None for analytic
        spheres (no mesh: the ball alone)."""
        if not isinstance(self._solver, _ModelSolver):
            return None
        if self._stem is None:
            self._stem = self._solver.stem()
        return self._stem

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
        line = Line(self.to_part(as_vector(start, "start")), self.to_part(as_vector(end, "end")))
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
        return self._solver.clearance(self.to_part(as_vector(point, "point")), ball_radius)


class _Solver(ABC):
    """The part's geometry in its own frame (see the two implementations)."""

    @abstractmethod
    def first_hit(self, line: Line, r: float) -> Hit | None:
        """The first touch along ``line`` of a ball of radius ``r`` that starts clear."""

    @abstractmethod
    def nearest(self, c: FloatArray) -> tuple[float, FloatArray, int]:
        """Signed distance of ``c`` from the surface (negative inside), nearest point,
        0-based face (or sphere) index."""

    def clearance(self, c: FloatArray, r: float) -> float:
        """Signed clearance of a ball of radius ``r`` at ``c``."""
        return self.nearest(c)[0] - r

    def overlap(self, c: FloatArray, r: float) -> Hit | None:
        """A touch at ``s = 0`` when the ball at ``c`` overlaps the part."""
        if not self.quick_clear(c, r):
            signed, foot, face = self.nearest(c)
            if signed - r < -START_TOLERANCE:
                n = c - foot
                size = float(np.linalg.norm(n))
                normal = n / size * (1.0 if signed >= 0.0 else -1.0) if size > 0.0 else n
                return Hit(0.0, normal, face + 1, "face", foot)
        return None

    def quick_clear(self, c: FloatArray, r: float) -> bool:
        """A cheap check that the ball at ``c`` is clear (False means: do not know)."""
        return False


class _SphereSolver(_Solver):
    """Analytic spheres, material inside."""

    def __init__(self, centres: FloatArray, radii: FloatArray) -> None:
        self.centres = centres
        self.radii = radii

    def first_hit(self, line: Line, r: float) -> Hit | None:
        best: Hit | None = None
        for k, (centre, radius) in enumerate(zip(self.centres, self.radii, strict=True)):
            for s, n in sphere_roots(line.a, line.u, centre, radius + r, 1.0):
                if -START_TOLERANCE <= s <= line.length and (best is None or s < best.s):
                    best = Hit(s, n, k + 1, "face")
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

    def __init__(self, part: Part, mesh_tolerance: float,
                 forms: tuple[FormError, ...] = ()) -> None:
        import fcl

        from probegen import cad

        if not mesh_tolerance > 0.0:
            raise ProbegenError(f"mesh tolerance: expected a positive number, found "
                                f"{mesh_tolerance}")
        model = part.model
        self.model = model
        self.exact = part.exact
        self.low = np.array([f.bbox_min for f in model.faces])
        self.high = np.array([f.bbox_max for f in model.faces])
        mesh = part.mesh(mesh_tolerance)
        self.forms = {f.face - 1: BoundForm(f, cad.face_by_id(model, f.face)) for f in forms}
        # a perturbed face lies up to its limit off the mesh: every bound allows for it
        self.deviation = MESH_DEVIATION_FACTOR * mesh_tolerance + max(
            (f.limit for f in forms), default=0.0)
        self.face_ids = np.asarray(mesh.metadata["face_ids"])
        bvh = fcl.BVHModel()
        bvh.beginModel(len(mesh.vertices), len(mesh.faces))
        bvh.addSubModel(np.asarray(mesh.vertices, dtype=np.float64),
                        np.asarray(mesh.faces, dtype=np.int32))
        bvh.endModel()
        self._fcl = fcl
        self._mesh = fcl.CollisionObject(bvh, fcl.Transform())
        self._bounds = np.asarray(mesh.bounds, dtype=np.float64)
        self._balls: dict[float, Any] = {}

    def stem(self) -> Stem:
        """The test of the probe's shank and body on this solver's own mesh tree."""
        from probegen.sim.stem import Stem

        return Stem(self._mesh, self.face_ids, self._bounds[0], self._bounds[1])

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

    def first_hit(self, line: Line, r: float) -> Hit | None:
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

    def candidates(self, line: Line, s0: float, s1: float, margin: float) -> list[int]:
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

    def window_hit(self, line: Line, s0: float, s1: float, r: float,
                   hint: int) -> Hit | None:
        """The first touch for ``s`` in ``[s0, s1]`` over every face that can reach it."""
        faces = self.candidates(line, s0, s1, r + self.deviation)
        if hint in faces:  # the face fcl found first: its answer bounds the others
            faces.remove(hint)
            faces.insert(0, hint)
        best: Hit | None = None
        for index in faces:
            limit = best.s if best is not None else s1
            hit = self.face_hit(index, line, s0, limit, r)
            if hit is not None and hit.before(best):
                best = hit
        return best

    def face_hit(self, index: int, line: Line, s0: float, s1: float,
                 r: float) -> Hit | None:
        """The first touch of face ``index`` (0-based) for ``s`` in ``[s0, s1]``."""
        record = self.model.faces[index]
        kind = self.exact.kind(index)
        boundary = self.exact.boundary(index)
        best: Hit | None = None
        if kind is not None:
            form = self.forms.get(index)
            roots = face_roots(record, line.a, line.u, r) if form is None else form.roots(
                line.a, line.u, r)
            for s, n in roots:
                if s0 - START_TOLERANCE <= s <= s1 and self.exact.contains(
                        index, line.at(s) - r * n):
                    if form is not None:
                        form.check(line.at(s) - r * n)
                    best = Hit(s, n, index + 1, "face")
                    break
            edge = boundary_hit(boundary, line, s0, best.s if best else s1, r, index + 1)
            if edge is not None and edge.before(best):
                best = edge
        if kind is None or boundary.free_edges:
            numeric = self.numeric_hit(index, line, s0, best.s if best else s1, r)
            if numeric is not None and (best is None or numeric.s < best.s - ROOT_TOLERANCE):
                best = numeric
        return best

    def numeric_hit(self, index: int, line: Line, s0: float, s1: float,
                    r: float) -> Hit | None:
        """First root of (exact distance to the trimmed face − r) on ``[s0, s1]``."""
        s, lo, hi = s0, s0, math.inf
        for _ in range(MAX_ITERATIONS):
            c = line.at(s)
            d, foot = self.exact.distance(index, c)
            f = d - r
            n = (c - foot) / d if d > 0.0 else -line.u
            if abs(f) <= ROOT_TOLERANCE or hi - lo <= ROOT_TOLERANCE:
                return Hit(s, n, index + 1, "face") if s <= s1 + ROOT_TOLERANCE else None
            slope = float(n @ line.u)
            if f > 0.0:
                lo = s
            else:
                hi = s
            s = next_step(s, f, slope, lo, hi, s1)
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
        form = self.forms.get(face)
        if form is not None:
            return (-best if form.inside(c, foot) else best), foot, face
        inside = self.exact.inside(c) if best > tol.zero else False
        # a model without a solid (faces or shells only) has no inside: distances stay >= 0
        return (-best if inside else best), foot, face

    def face_distance(self, index: int, c: FloatArray) -> tuple[float, FloatArray]:
        """Exact distance from ``c`` to face ``index`` and the nearest point."""
        if self.exact.kind(index) is not None:
            form = self.forms.get(index)
            foot = nearest_on_surface(self.model.faces[index], c) if form is None else (
                form.nearest(c))
            if foot is not None and self.exact.contains(index, foot):
                return float(np.linalg.norm(c - foot)), foot
        return self.exact.distance(index, c)
