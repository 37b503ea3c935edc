"""Collision check: the stylus ball and shank swept along every move, against the part.

The check walks the IR as a controller would (nominal values for run-time variables,
``LocalFrame`` offsets applied) and follows every segment by sphere tracing: the distance
between the stylus and the part changes no faster than the stylus moves (it is
1-Lipschitz in the stylus position), so from a point whose clearance exceeds the required
one by ``s`` the next ``s`` mm of the segment are clear.  Steps never go below
``MIN_STEP``; a clearance below the requirement is a collision.  This is exact up to the
mesh's chordal deviation, which is subtracted from every clearance.

Uncertain part position: a coordinate known only to ``u`` (an absolute coordinate while
the feature is still being located) adds ``u`` to the required clearance; along a segment
from an uncertain start to an exact end (relative to the found centre) the extra clearance
falls linearly from ``u`` to 0, which is exactly how far the segment can be off relative to
the part at each point.

Touches: the ball must clear the part from the touch's start until it is ``margin``
(+ the extra) short of the nominal contact; the retract that follows runs back along the
same line.  The shank must clear the part along the same stretch.  A touch that runs at
an angle to the surface normal (``Touch.surface``, M3 vertical probing of a slope) stops
``margin / cos(angle)`` short along its line, i.e. ``margin`` off a plane surface.

Many short paths at once (M3 guide points): :mod:`probegen.planning.heightmap` clears
most of them with a conservative fast check first and leaves the rest to this one.

Obstacles: the tessellated STEP model as an FCL bounding-volume hierarchy (python-fcl:
exact sphere/cylinder-to-triangle distances in C++), or analytic spheres when the spec
gives the geometry without a model.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np

from probegen import ir
from probegen.errors import CollisionError, PlanningError
from probegen.geometry.frames import rotation_to_z
from probegen.machine.profile import MachineProfile
from probegen.planning.intrusion import Element, Intrusion, deepest, elements, words
from probegen.planning.orient import (
    LEVEL_SLACK,
    change_name,
    first_after,
    index_height,
    needs_index,
    to_frame,
    to_work,
    top_of,
)
from probegen.planning.table import NAME as TABLE
from probegen.planning.table import Table

if TYPE_CHECKING:
    from probegen.cad import Part, Recent

MIN_STEP = 0.01
"""Smallest sphere-tracing step, mm; a segment closer than this to the limit is stepped
at this pitch, and the clearance between samples can be lower by at most half of it."""
MESH_TOLERANCE = 0.01
"""Chordal deviation of the part mesh, mm; subtracted from every measured clearance."""
TABLE_FIRST = True
"""Whether :class:`MeshObstacle` skips the part's queries the machine table makes needless
(:meth:`MeshObstacle.clearance`, :meth:`MeshObstacle.face_of`); the same figures either
way (``benchmarks/bench_table_first.py`` times both)."""
GROWN_FIRST = True
"""Whether :meth:`MeshObstacle.clearance` tests the probe body grown by the shank's
clearance for a collision before it queries the body's distance (:meth:`MeshObstacle.
_beyond`); the same figures either way (``benchmarks/bench_grown_first.py`` times
both)."""


@dataclass(frozen=True, slots=True)
class Stylus:
    """The parts of the probe that can touch, with the ball's centre at the origin and
    the probe along +Z: the ball (radius), the shank (radius) up to ``length`` from the
    ball's centre, and the probe body (radius ``body``) from there ``body_length`` on
    (mm; no body when ``body`` is 0).  The check's "shank" clearance is the smaller of
    the shank's and the body's."""

    ball: float
    shank: float
    length: float
    body: float = 0.0
    body_length: float = 0.0

    def cylinders(self) -> tuple[tuple[float, float, float], ...]:
        """The shank and the body as ``(radius, low, high)``: heights along the probe
        from the ball's centre, mm."""
        shank = ((self.shank, self.ball, self.length),)
        if self.body <= 0.0 or self.body_length <= 0.0:
            return shank
        return (*shank, (self.body, self.length, self.length + self.body_length))


def probe_stylus(machine: MachineProfile, ball: float, shank: float | None = None,
                 length: float | None = None) -> Stylus:
    """The collision check's stylus of ``machine``'s probe with a ball of radius ``ball``
    (mm); the ``[probe]`` stylus's shank radius and length unless given (another stylus
    of the rack), and the probe body (``[probe] body_diameter``, ``body_length``)."""
    probe = machine.probe
    return Stylus(ball, probe.shank_diameter / 2.0 if shank is None else shank,
                  probe.length if length is None else length,
                  probe.body_diameter / 2.0, probe.body_length)


class Obstacle(Protocol):
    """The part, as distances to the stylus."""

    def clearance(self, centre: np.ndarray, stylus: Stylus) -> tuple[float, float]:
        """Distances (mm) from the ball and from the shank, with the ball at ``centre``."""
        ...

    def name_at(self, point: np.ndarray) -> str:
        """A human name for the obstacle nearest ``point`` (e.g. ``face 3``)."""
        ...


@dataclass(frozen=True)
class SphereObstacle:
    """Analytic spheres: ``centres : (k, 3)``, ``radii : (k,)``."""

    centres: np.ndarray
    radii: np.ndarray

    def clearance(self, centre: np.ndarray, stylus: Stylus) -> tuple[float, float]:
        ball = np.linalg.norm(self.centres - centre, axis=1) - self.radii - stylus.ball
        rel = self.centres - centre
        shank = math.inf
        for radius, low, high in stylus.cylinders():
            axis_pt = np.zeros_like(rel)
            axis_pt[:, 2] = np.clip(rel[:, 2], low, high)
            d = np.linalg.norm(rel - axis_pt, axis=1) - self.radii - radius
            shank = min(shank, float(d.min()))
        return float(ball.min()), shank

    def name_at(self, point: np.ndarray) -> str:
        k = int(np.argmin(np.linalg.norm(self.centres - point, axis=1) - self.radii))
        return f"sphere {k + 1}"

    def _gaps(self, centre: np.ndarray, e: Element) -> np.ndarray:
        """The distance from element ``e`` (the ball's centre at ``centre``) to each
        sphere, mm (negative: they overlap)."""
        rel = self.centres - centre
        if e.low is not None and e.high is not None:
            axis_pt = np.zeros_like(rel)
            axis_pt[:, 2] = np.clip(rel[:, 2], e.low, e.high)
            rel = rel - axis_pt
        gaps: np.ndarray = np.linalg.norm(rel, axis=1) - self.radii - e.radius
        return gaps

    def beneath(self, point: np.ndarray) -> float:
        """How far ``point`` (in a sphere) lies from the sphere's surface, mm."""
        return float((self.radii - np.linalg.norm(self.centres - point, axis=1)).max())

    def overlaps(self, centre: np.ndarray, e: Element, solid: bool = True) -> bool:
        """Whether element ``e`` with the ball's centre at ``centre`` overlaps a sphere
        (``solid``: the same either way)."""
        return bool((self._gaps(centre, e) < 0.0).any())

    def clearance_of(self, centre: np.ndarray, e: Element) -> float:
        """The distance from element ``e`` (ball's centre at ``centre``) to the spheres."""
        return float(self._gaps(centre, e).min())

    def face_of(self, centre: np.ndarray, e: Element) -> str:
        """The sphere element ``e`` comes nearest (overlaps deepest), with the ball's
        centre at ``centre``."""
        return f"sphere {int(np.argmin(self._gaps(centre, e))) + 1}"


class MeshObstacle:
    """A tessellated part; ``face_ids`` maps triangles to model face ids when known.

    Its queries run on an FCL tree of the mesh (:attr:`part`) and a ray tree for the
    inside test, built on first use and kept with it.  A part turned into a frame
    (``turned``: the obstacle of the part as loaded and the frame's rotation; the part
    is turned into a frame per head index, tilt, setup and off-grid feature axis)
    builds neither: its queries run on the loaded part's trees, the FCL tree placed by
    the rotation (``p_frame = Rᵀ·p_work``) and the points of inside tests turned back.
    With ``part`` (the part the mesh is of), the other large values derived from the
    mesh (its height map) are kept among the part's most recently used ones
    (:meth:`probegen.cad.Part.recent`), else with the obstacle.  What the obstacle found
    (the sweeps, the inside tests) is kept with it whatever is dropped."""

    def __init__(self, mesh: Any, face_ids: np.ndarray | None,
                 part: Part | None = None,
                 turned: tuple[MeshObstacle, Any] | None = None) -> None:
        import fcl

        from probegen.cad import Recent

        self.fcl = fcl
        self.mesh = mesh
        self.face_ids = face_ids
        own: dict[str, Recent] = {}
        self.recent: Callable[[str], Recent] = (
            part.recent if part is not None else lambda kind: own.setdefault(kind, Recent()))
        """The kept values of a kind (:meth:`probegen.cad.Part.recent`), keyed by
        obstacle."""
        self._turned = turned
        self._keep = turned is not None or part is None or part.rotation is None
        """Whether the trees are kept with the obstacle (the loaded part's, or a turned
        part's placed ones); a turned part's own (no :data:`SHARED_TREE`) are kept
        among the part's most recently used."""
        self._geometry_kept: tuple[Any, Any, Any] | None = None
        self.request = fcl.DistanceRequest()
        self._objects: dict[Stylus, tuple[Any, list[tuple[Any, float]]]] = {}
        self._last: dict[Stylus, list[tuple[np.ndarray, float]]] = {}
        """Per stylus, where each of its cylinders' distances was last measured and that
        distance (:meth:`clearance`)."""
        self.sweeps: dict[tuple[Any, ...], tuple[float, float, np.ndarray]] = {}
        """Sweep results by (start, end, uncertainties, stylus, required): the mesh is
        shared per model, so a move checked once (one feature alone, then the whole
        program) is swept once."""
        self._inside: dict[tuple[float, float, float], bool] = {}
        self.intrusions: dict[tuple[Any, ...], Intrusion | None] = {}
        """The deepest intrusion of a stylus along a refused move, by (start, end,
        stylus) (:func:`describe`: a move refused again is not measured again)."""
        self.floor = -MESH_TOLERANCE
        """The least clearance ``clearance`` reports (the part overlaps the stylus)."""
        self.table: Table | None = None if part is None else Table.under(
            mesh.vertices, part.rotation, part.raised)
        """The machine table under the part (:mod:`probegen.planning.table`), with a
        part: every clearance is the least of the part's and the table's."""

    @property
    def part(self) -> Any:
        """The mesh as an FCL collision object (its bounding-volume tree)."""
        return self._geometry()[0]

    def _geometry(self) -> tuple[Any, Any]:
        """The FCL object of the mesh and a mesh for the inside test (whose ray tree
        trimesh keeps on it), made on first use and kept: of its own
        (:meth:`_build`), or, turned, the loaded part's tree placed by the rotation and
        the loaded part's mesh (:meth:`contains` turns the points back)."""
        if self._geometry_kept is None:
            if not self._keep:  # a frame's own trees (no SHARED_TREE): the recent kept
                return self.recent("collision tree").get(self, self._build)[:2]
            if self._turned is None:
                self._geometry_kept = self._build()
            else:
                base, rotation = self._turned
                _, rays, bvh = base._trees()
                self._geometry_kept = (self.fcl.CollisionObject(
                    bvh, self.fcl.Transform(rotation.T)), rays, bvh)
        return self._geometry_kept[0], self._geometry_kept[1]

    def _trees(self) -> tuple[Any, Any, Any]:
        """:meth:`_geometry` and the FCL tree itself (its geometry), of an obstacle
        that keeps them."""
        self._geometry()
        assert self._geometry_kept is not None, "trees kept among the recent"
        return self._geometry_kept

    def _build(self) -> tuple[Any, Any, Any]:
        import trimesh

        fcl, mesh = self.fcl, self.mesh
        vertices = np.asarray(mesh.vertices, dtype=np.float64)
        bvh = fcl.BVHModel()
        bvh.beginModel(len(mesh.vertices), len(mesh.faces))
        bvh.addSubModel(vertices, np.asarray(mesh.faces, dtype=np.int32))
        bvh.endModel()
        return (fcl.CollisionObject(bvh, fcl.Transform()),
                trimesh.Trimesh(vertices, np.asarray(mesh.faces), process=False), bvh)

    def contains(self, point: np.ndarray) -> bool:
        """Whether the mesh holds ``point`` (trimesh's ray test; turned, on the loaded
        part's mesh at the point turned back: ``p_work = R·p_frame``)."""
        rays = self._geometry()[1]
        if self._turned is not None:
            point = self._turned[1] @ point
        return bool(rays.contains(point[None])[0])

    def _stylus(self, stylus: Stylus) -> tuple[Any, list[tuple[Any, float]]]:
        """The fcl objects of ``stylus``: its ball, and its shank and body each with the
        height of its centre above the ball's."""
        if stylus not in self._objects:
            fcl = self.fcl
            self._objects[stylus] = (
                fcl.CollisionObject(fcl.Sphere(stylus.ball), fcl.Transform()),
                [(fcl.CollisionObject(fcl.Cylinder(radius, high - low), fcl.Transform()),
                  (low + high) / 2.0) for radius, low, high in stylus.cylinders()],
            )
        return self._objects[stylus]

    def clearance(self, centre: np.ndarray, stylus: Stylus) -> tuple[float, float]:
        """The ball's clearance and the least of the shank's and the body's, mm.

        The body's distance is not queried where the last one measured proves it cannot
        be the least: a distance moves no more than the stylus does (1-Lipschitz), so
        ``d_last - |centre - centre_last|`` bounds it from below, and where that bound
        exceeds the shank's clearance by :data:`SKIP_SLACK` the result is the shank's,
        the same value as with the query (a sweep's next points are near its last).  Nor
        is the part's distance of an element the table's clearance puts at or below
        :attr:`floor` (the least the part's can be): the table's is the least.  Nor,
        where a collision test of the body grown by that margin finds no triangle
        (:meth:`_beyond`, a fraction of a distance query's cost), is the body's: it is
        not the least, or the table's clearance is its own (:data:`GROWN_FIRST`)."""
        ball, cylinders = self._stylus(stylus)
        table = self.table
        b = self._with_part(ball, centre, np.inf if table is None
                            else table.clearance(centre, stylus.ball))
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
            at_k = centre + np.array([0.0, 0.0, mid])
            on_table = np.inf if table is None else table.clearance(centre, *dims[k])
            settled = self._settled(dims[k], at_k, on_table, least) \
                if k and on_table > self.floor else None
            d = self._with_part(obj, at_k, on_table) if settled is None else settled
            measured.append((np.array(centre, dtype=np.float64), d))
            least = min(least, d)
        self._last[stylus] = measured
        return b, least

    def _settled(self, cylinder: tuple[float, float, float], at: np.ndarray, table: float,
                 least: float) -> float | None:
        """What the grown test (:meth:`_beyond`) settles of the clearance of ``cylinder``
        (radius, low, high; its middle ``at``, the ``table``'s clearance of it) beside
        elements whose least is ``least``, without the part's distance query: the part is
        at least ``bound = least + SKIP_SLACK`` away, so the clearance is the table's where
        that is less (exactly), else at least ``bound`` (above ``least``: not the least).
        None where nothing is settled (:data:`GROWN_FIRST` off, no ``least`` yet, or the
        grown cylinder meets the mesh)."""
        bound = least + SKIP_SLACK
        if not GROWN_FIRST or bound == np.inf or not self._beyond(cylinder, at, bound):
            return None
        return min(table, bound)

    def _beyond(self, cylinder: tuple[float, float, float], at: np.ndarray,
                bound: float) -> bool:
        """Whether the part's distance query (:meth:`_to`) of the ``cylinder`` (radius,
        low, high) with its middle ``at`` is certainly at least ``bound``: the cylinder
        grown by ``g = bound + MESH_TOLERANCE + SKIP_SLACK`` in radius and at both ends
        holds every point within ``g`` of it, and meets no triangle of the mesh (an fcl
        collision test; :data:`SKIP_SLACK` covers fcl's tolerance)."""
        radius, low, high = cylinder
        g = max(bound, 0.0) + MESH_TOLERANCE + SKIP_SLACK
        fcl = self.fcl
        grown = fcl.CollisionObject(fcl.Cylinder(radius + g, high - low + 2.0 * g),
                                    fcl.Transform(at))
        return not fcl.collide(grown, self.part, fcl.CollisionRequest(),
                               fcl.CollisionResult())

    def _with_part(self, obj: Any, at: np.ndarray, table: float) -> float:
        """The lesser of the ``table``'s clearance and ``obj``'s distance to the part with
        ``obj`` placed ``at``; the table's alone where it is at or below :attr:`floor`
        (the least the part's can be: no query), as :data:`TABLE_FIRST` says, mm."""
        if table <= self.floor and TABLE_FIRST:
            return table
        obj.setTranslation(at)
        return min(table, self._to(obj))

    def _to(self, obj: Any) -> float:
        """The distance from ``obj`` to the part less the mesh's tolerance, mm."""
        d = self.fcl.distance(obj, self.part, self.request, self.fcl.DistanceResult())
        return max(float(d), 0.0) - MESH_TOLERANCE

    def _distance(self, shape: Any, transform: Any) -> float:
        obj = self.fcl.CollisionObject(shape, transform)
        d = self.fcl.distance(obj, self.part, self.request, self.fcl.DistanceResult())
        return max(float(d), 0.0) - MESH_TOLERANCE

    def sweep_bound(self, a: np.ndarray, b: np.ndarray,
                    stylus: Stylus) -> tuple[float, float] | None:
        """Lower bounds of the ball and shank clearances along ``a → b`` (mm) from the
        swept volumes in a few queries, or None for a move too short to shape.

        Ball: the capsule of radius ``r`` about the segment (exact).  Shank: its axis
        sweeps the parallelogram spanned by the move and the shank's extent along Z
        (a cylinder for a vertical move); the swept shank lies within that surface
        grown by the shank radius, so its distance less the radius is a lower bound.
        """
        fcl = self.fcl
        move = b - a
        length = float(np.linalg.norm(move))
        if length < 1e-6:
            return None
        rot = np.asarray(rotation_to_z(move / length)).T  # takes +Z onto the move
        ball = self._distance(fcl.Capsule(stylus.ball, length),
                              fcl.Transform(rot, (a + b) / 2.0))
        shank = min(self._swept_cylinder(a, b, radius, low, high)
                    for radius, low, high in stylus.cylinders())
        table = self.table
        if table is not None:
            ball = min(ball, table.swept(a, b, stylus.ball))
            shank = min([shank] + [table.swept(a, b, radius, low, high)
                                   for radius, low, high in stylus.cylinders()])
        return ball, shank

    def _swept_cylinder(self, a: np.ndarray, b: np.ndarray, radius: float, low: float,
                        high: float) -> float:
        """A lower bound of the clearance of a cylinder along the probe (``radius``, from
        ``low`` to ``high`` above the ball's centre) swept from ``a`` to ``b``, mm."""
        fcl = self.fcl
        move = b - a
        up = np.array([0.0, 0.0, 1.0])
        if math.hypot(move[0], move[1]) < 1e-9:
            z0 = min(a[2], b[2]) + low
            z1 = max(a[2], b[2]) + high
            centre = np.array([a[0], a[1], (z0 + z1) / 2.0])
            return self._distance(fcl.Cylinder(radius, z1 - z0), fcl.Transform(centre))
        corners = [a + low * up, b + low * up, b + high * up, a + high * up]
        side = np.cross(move, up)
        side *= SLAB / float(np.linalg.norm(side))
        slab = np.array([c - side for c in corners] + [c + side for c in corners])
        return self._distance(fcl.Convex(slab, 6, _SLAB_FACES), fcl.Transform()) \
            - radius - SLAB

    def inside(self, point: np.ndarray) -> bool:
        """Whether ``point`` lies inside the material (a mesh query, for segment starts)."""
        key = (float(point[0]), float(point[1]), float(point[2]))
        hit = self._inside.get(key)
        if hit is None:
            low, high = self.mesh.bounds
            hit = self._inside[key] = bool(
                np.all(point >= low) and np.all(point <= high)
                and not self._sees_the_sky(point, float(high[2]))
                and self.contains(point))
        return hit

    def _sees_the_sky(self, point: np.ndarray, top: float) -> bool:
        """Whether the vertical line from ``point`` up past the mesh's ``top`` (work Z)
        meets no triangle: then ``point`` lies outside (one collision query, far
        cheaper than the ray test it saves)."""
        fcl = self.fcl
        length = top + 1.0 - float(point[2])
        needle = fcl.CollisionObject(fcl.Cylinder(1e-3, length), fcl.Transform(
            point + np.array([0.0, 0.0, length / 2.0])))
        return not fcl.collide(needle, self.part, fcl.CollisionRequest(),
                               fcl.CollisionResult())

    def _shape(self, centre: np.ndarray, e: Element) -> Any:
        """The fcl object of element ``e`` with the ball's centre at ``centre``."""
        fcl = self.fcl
        if e.low is None or e.high is None:
            return fcl.CollisionObject(fcl.Sphere(e.radius), fcl.Transform(centre))
        mid = centre + np.array([0.0, 0.0, (e.low + e.high) / 2.0])
        return fcl.CollisionObject(fcl.Cylinder(e.radius, e.high - e.low), fcl.Transform(mid))

    def overlaps(self, centre: np.ndarray, e: Element, solid: bool = True) -> bool:
        """Whether element ``e`` (:mod:`probegen.planning.intrusion`) with the ball's
        centre at ``centre`` overlaps the part: it meets a triangle of the mesh, or (with
        ``solid``) lies wholly inside the material.  The point tested for the latter is
        the ball's centre or the top of a cylinder's axis, which every smaller ball or
        cylinder shortened from below of the search keeps: one inside test per place
        (memoised)."""
        fcl = self.fcl
        if self._table_clearance(centre, e) < 0.0:
            return True
        if fcl.collide(self._shape(centre, e), self.part, fcl.CollisionRequest(),
                       fcl.CollisionResult()):
            return True
        if not solid:
            return False
        top = 0.0 if e.high is None else e.high
        return self.inside(centre + np.array([0.0, 0.0, top]))

    def beneath(self, point: np.ndarray) -> float:
        """How far ``point`` (in the material: the part's or the table's) lies from the
        surface, mm."""
        fcl = self.fcl
        below = -np.inf if self.table is None else self.table.depth(point)
        if below > 0.0 and not self.inside(point):
            return below
        return max(below, self._distance(fcl.Sphere(1e-6), fcl.Transform(point))
                   + MESH_TOLERANCE)

    def _table_clearance(self, centre: np.ndarray, e: Element) -> float:
        """Element ``e``'s clearance from the table (infinite without one), mm."""
        if self.table is None:
            return np.inf
        return self.table.clearance(centre, e.radius, e.low, e.high)

    def clearance_of(self, centre: np.ndarray, e: Element) -> float:
        """The distance from element ``e`` (ball's centre at ``centre``) to the part less
        the mesh's tolerance, or to the table where that is less, mm."""
        return min(self._to(self._shape(centre, e)), self._table_clearance(centre, e))

    def nearest(self, centre: np.ndarray, parts: Sequence[Element]) -> Element:
        """The element of ``parts`` (the ball's centre at ``centre``) with the least
        :meth:`clearance_of`, the first of equals: ``min(parts, key=...)``, without the
        distance query of a cylinder whose clearance the grown test settles against the
        least so far (:meth:`_settled`)."""
        best: Element | None = None
        least = np.inf
        for e in parts:
            d = None
            if e.low is not None and e.high is not None:
                at = centre + np.array([0.0, 0.0, (e.low + e.high) / 2.0])
                d = self._settled((e.radius, e.low, e.high), at,
                                  self._table_clearance(centre, e), least)
            if d is None:
                d = self.clearance_of(centre, e)
            if best is None or d < least:
                best, least = e, d
        assert best is not None, "no element"
        return best

    def face_of(self, centre: np.ndarray, e: Element) -> str:
        """The face (or triangle) element ``e`` meets deepest with the ball's centre at
        ``centre`` (the table where it goes deeper into that), else the table where it
        reaches into it, else the nearest face (one BVH query each)."""
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
        elif table < 0.0 and TABLE_FIRST:
            return TABLE  # in the table and clear of the part: no distance query (one
            # with a probe body next to the part costs milliseconds)
        else:
            near = fcl.DistanceResult()
            fcl.distance(self.part, obj, fcl.DistanceRequest(enable_nearest_points=True),
                         near)
            if table < near.min_distance:
                return TABLE
            tri = int(near.b1)
        return f"triangle {tri}" if self.face_ids is None else f"face {int(self.face_ids[tri])}"

    def name_at(self, point: np.ndarray) -> str:
        """The face (or triangle) nearest ``point``, by one BVH distance query."""
        fcl = self.fcl
        probe = fcl.CollisionObject(fcl.Sphere(1e-6), fcl.Transform(point))
        result = fcl.DistanceResult()
        fcl.distance(self.part, probe, fcl.DistanceRequest(enable_nearest_points=True), result)
        if self.table is not None and -self.table.depth(point) < result.min_distance:
            return TABLE
        tri = int(result.b1)
        if self.face_ids is None:
            return f"triangle {tri}"
        return f"face {int(self.face_ids[tri])}"


SKIP_SLACK = 1e-3
"""How far (mm) the lower bound of the body's distance must exceed the shank's clearance
for :meth:`MeshObstacle.clearance` to skip the body's query: far above FCL's own
tolerance, so the least of the two is the one the query would have given."""
SLAB = 1e-3
"""Half thickness of the slab that stands for the parallelogram swept by the shank's
axis (a flat convex is not a shape the distance query takes), mm."""
_SLAB_FACES = np.array([4, 0, 1, 2, 3, 4, 4, 7, 6, 5, 4, 0, 4, 5, 1, 4, 1, 5, 6, 2,
                        4, 2, 6, 7, 3, 4, 3, 7, 4, 0])
"""The six quads of the slab (vertex count, then indices), for ``fcl.Convex``."""


def obstacle_for(part: Part | None, spheres: Sequence[Any]) -> Obstacle:
    """The part as an obstacle: its mesh at :data:`MESH_TOLERANCE` as a BVH, built once
    per part and kept on it (:meth:`probegen.cad.Part.memo`); the analytic spheres when
    there is no model."""
    if part is not None:
        return part.memo(("collision obstacle",), lambda: mesh_obstacle(part))
    centres = np.array([s.centre for s in spheres], dtype=np.float64).reshape(-1, 3)
    radii = np.array([s.diameter / 2.0 for s in spheres], dtype=np.float64)
    return SphereObstacle(centres, radii)


def mesh_obstacle(part: Part, offset: Sequence[float] | None = None) -> MeshObstacle:
    """A new obstacle of the part's mesh (at :data:`MESH_TOLERANCE`), translated by
    ``offset`` (mm) when given."""
    mesh = part.mesh(MESH_TOLERANCE)
    if offset is not None:
        mesh = mesh.copy()
        mesh.apply_translation(offset)
        return MeshObstacle(mesh, mesh.metadata.get("face_ids"), part)
    turned = None
    if part.rotation is not None and SHARED_TREE:
        base = obstacle_for(part.original, [])
        assert isinstance(base, MeshObstacle)
        turned = (base, np.asarray(part.rotation, dtype=np.float64))
    return MeshObstacle(mesh, mesh.metadata.get("face_ids"), part, turned)


SHARED_TREE = True
"""Whether the obstacle of a turned part queries the loaded part's FCL and ray trees
placed by its rotation (:class:`MeshObstacle`); False: each frame builds trees of its
own (before stop 33; ``benchmarks/bench_shared_tree.py`` times both)."""


@dataclass(frozen=True, slots=True)
class SegmentClearance:
    """The smallest clearance found along one segment (ball and shank), mm."""

    index: int
    kind: str
    feature: str
    start: tuple[float, float, float]
    end: tuple[float, float, float]
    ball: float
    shank: float


@dataclass(frozen=True, slots=True)
class ClearanceReport:
    """Every checked segment, and the smallest clearance of all."""

    segments: tuple[SegmentClearance, ...]

    @property
    def minimum(self) -> float:
        """The smallest clearance over all segments (ball or shank), mm."""
        return min((min(s.ball, s.shank) for s in self.segments), default=float("inf"))


@dataclass(frozen=True, slots=True)
class Located:
    """What the check needs of a feature: its id, nominal centre (mm) and how far the
    real part may be from nominal there (mm; 0 when the work offset sets it up)."""

    id: str
    centre: tuple[float, float, float]
    uncertainty: float = 0.0


def located(item: Any) -> Located:
    """A :class:`Located` from itself or from a sphere-test plan (``feature``, ``sphere``)."""
    if isinstance(item, Located):
        return item
    f = item.feature
    return Located(f.id, tuple(item.sphere.centre), f.locate_uncertainty if f.locate else 0.0)


class _Walker:
    """Evaluates IR coordinates nominally, as the controller would at run time."""

    def __init__(self, plans: Sequence[Any], r: float) -> None:
        self.values: dict[str, float] = {}
        self.frames: list[tuple[str, np.ndarray]] = []
        self.r = r
        items = [located(p) for p in plans]
        self.uncertainty = max((p.uncertainty for p in items), default=0.0)
        self.centres = {p.id: np.array(p.centre) for p in items}
        self.centres.update({f"{p.id}L": np.array(p.centre) for p in items})

    def follow(self, node: object) -> bool:
        """Track a node that sets a run-time value or a frame (``Assign``, ``LocalFrame``,
        ``RestoreFrame``) as the controller would; whether ``node`` was one."""
        if isinstance(node, ir.Assign):
            a = self.value(node.a)
            self.values[node.name] = (a + self.value(node.b)) / 2.0 if node.b is not None \
                else a + node.offset
        elif isinstance(node, ir.LocalFrame):
            self.frames.append((node.name, self.centres[node.feature]))
        elif isinstance(node, ir.RestoreFrame):
            self.frames.pop()
        else:
            return False
        return True

    def value(self, c: ir.Coord) -> float:
        if isinstance(c, ir.Var):
            if c.name not in self.values:
                raise PlanningError(f"run-time variable {c.name} is used before it is set")
            return self.values[c.name] + c.offset
        return c

    def origin(self) -> np.ndarray:
        """The current frame's origin in work coordinates."""
        return self.frames[-1][1] if self.frames else np.zeros(3)

    def point(self, p: ir.Point) -> np.ndarray:
        return self.origin() + np.array([self.value(c) for c in p])

    def exact(self, p: ir.Point) -> bool:
        """Whether the point is known exactly relative to the part."""
        if self.frames:
            return True
        return all(isinstance(c, ir.Var) and c.name[-3:] in ("_CX", "_CY", "_CZ") for c in p)

    def extra(self, p: ir.Point) -> float:
        return 0.0 if self.exact(p) else self.uncertainty


def check_program(program: ir.Program, obstacle: Obstacle, plans: Sequence[Any],
                  machine: MachineProfile, *,
                  progress: Callable[[int], None] | None = None,
                  part: Part | None = None, top: float | None = None) -> ClearanceReport:
    """Check every move of ``program``; raise ``CollisionError`` at the first bad one.

    ``plans`` are the located features: :class:`Located` records or sphere-test plans
    (their id, nominal centre and locate uncertainty); features set up by the work
    offset (revolved features) need none.

    After an ``ir.Orient`` the nodes are checked in its frame against ``part`` turned
    (``part`` is needed then); after an ``ir.SelectStylus`` with that stylus.  A change
    taken at the index height (:func:`probegen.planning.orient.needs_index`: every
    ``Orient``, a stylus change on a CMM with a head) requires the probe to stand at or
    above :func:`probegen.planning.orient.index_height` (``CollisionError``), and the
    first move after it to stay there (:func:`probegen.planning.orient.first_after`,
    ``PlanningError``): the route is the program's own moves, checked as every move is;
    nothing is assumed.  Any other stylus change is taken at the clearance level or
    above.  ``top``: the work Z of the part's top for the index height
    (:func:`probegen.planning.orient.top_of`; default ``part``'s).
    """
    setup = program.setup
    r = setup.ball_diameter / 2.0
    clear = machine.margin / 2.0
    w = _Walker(plans, r)
    stylus = probe_stylus(machine, r)
    pos: np.ndarray | None = None
    pos_extra = 0.0
    touch_start: np.ndarray | None = None
    feature = ""
    out: list[SegmentClearance] = []

    inside = getattr(obstacle, "inside", None)
    outside: set[tuple[float, float, float]] = set()
    frame: ir.Orient | None = None
    entering: ir.Orient | ir.SelectStylus | None = None

    def check(a: np.ndarray, b: np.ndarray, ea: float, eb: float, kind: str,
              touch: bool = False) -> None:
        # a start that ends or starts a segment already cleared is outside: a cleared
        # sweep never meets the surface, so both its ends lie on the same side
        if inside is not None and _t(a) not in outside and inside(a):
            raise CollisionError(f"feature {feature or '-'}: segment {len(out) + 1} ({kind}) "
                                 f"starts inside the part at {fmt(a)}")
        ball, shank, worst = swept(obstacle, a, b, ea, eb, stylus, clear, bound=not touch)
        seg = SegmentClearance(len(out) + 1, kind, feature, _t(a), _t(b), ball - clear,
                               shank - clear)
        out.append(seg)
        if min(seg.ball, seg.shank) < 0.0:
            raise CollisionError(
                f"feature {feature or '-'}: segment {seg.index} ({kind}) from "
                f"{fmt(a)} to {fmt(b)}: "
                f"{describe(obstacle, seg.ball, seg.shank, clear, worst, stylus, b)}")
        outside.update((_t(a), _t(b)))

    for node in ir.walk(program.body):
        if progress is not None:
            progress(1)
        if isinstance(node, ir.Orient | ir.SelectStylus) and needs_index(node, machine):
            top = top_of(part) if top is None else top
            if top is None or part is None and isinstance(node, ir.Orient):
                raise PlanningError(f"{change_name(node)}: the check of a change taken at the "
                                    "index height needs the part model, found none")
            before = stylus
            if isinstance(node, ir.SelectStylus):
                stylus = _stylus_of(node, machine)
            height = max(index_height(top, s.length, s.ball, machine)
                         for s in (before, stylus))
            here = None if pos is None else to_work(frame, pos)
            if here is None or here[2] < height - LEVEL_SLACK:
                found = "an unknown position" if here is None else f"work z = {here[2]:.3f}"
                raise CollisionError(f"{change_name(node)}: the probe stands at {found}, expected "
                                     f"the index height {height:.3f} or above")
            if isinstance(node, ir.Orient):
                assert part is not None
                obstacle = obstacle_for(part.turned(node.rotation), [])
                inside, outside, frame = getattr(obstacle, "inside", None), set(), node
                pos = to_frame(frame, here)
            else:
                assert pos is not None
                check(pos, pos, 0.0, 0.0, f"stylus change to {node.label}")
            entering = node
            r = stylus.ball
        elif isinstance(node, ir.SelectStylus):
            level = setup.clearance_z if frame is None else frame.clearance_z
            if pos is not None and pos[2] < level - LEVEL_SLACK:
                raise CollisionError(f"stylus change to {node.label}: the probe is at "
                                     f"z = {pos[2]:.3f}, expected the clearance level "
                                     f"{level:.3f} or above")
            stylus = _stylus_of(node, machine)
            r = stylus.ball
            if pos is not None:
                check(pos, pos, 0.0, 0.0, f"stylus change to {node.label}")
        elif isinstance(node, ir.FeatureBlock):
            feature = node.feature.id
        elif w.follow(node):
            pass
        elif isinstance(node, ir.Move):
            target, extra = w.point(node.target), w.extra(node.target)
            if node.mode is ir.MoveMode.RETRACT:
                if touch_start is None or not np.allclose(target, touch_start, atol=1e-9):
                    raise PlanningError(f"feature {feature}: a retract must return to the "
                                        f"start of its touch, found {fmt(target)}")
            else:
                if entering is not None:
                    assert top is not None
                    first_after(entering, frame, target, part, top, stylus, machine, clear)
                if pos is not None:
                    check(pos, target, pos_extra, extra, node.mode.value)
            entering = None
            pos, pos_extra, touch_start = target, extra, None
        elif isinstance(node, ir.Touch):
            feature = node.feature
            n = np.array(node.normal)
            contact = w.point(node.contact)
            start = contact + (r + node.approach) * n
            if pos is None or not np.allclose(pos, start, atol=1e-9):
                raise PlanningError(f"feature {feature}: touch {node.index} does not start at "
                                    f"its approach point {fmt(start)}")
            e = w.extra(node.contact)
            check(start, touch_check_stop(node, contact, r, clear, e), e, e,
                  f"touch {node.role.value} {node.index}", touch=True)
            for axis, name in enumerate(node.store):
                if name is not None:
                    w.values[name] = float((contact + r * n - w.origin())[axis])
            touch_start = start
    return ClearanceReport(tuple(out))


def _stylus_of(node: ir.SelectStylus, machine: MachineProfile) -> Stylus:
    """The stylus a ``SelectStylus`` takes, as the check sees it (the probe's body on
    top of it)."""
    return probe_stylus(machine, node.ball_diameter / 2.0, node.shank_diameter / 2.0,
                        node.length)


SLANT_FACTOR = 0.9
"""A slanted touch stops its check ``1 / (0.9·cos)`` times farther out: the plane-surface
figure ``1 / cos`` leaves no room for the curvature of a free-form face."""


def touch_check_stop(touch: ir.Touch, contact: np.ndarray, r: float, clear: float,
                     extra: float) -> np.ndarray:
    """Where the check of ``touch`` stops (ball centre, mm): :func:`touch_stop` with the
    required ``clear`` + ``extra`` and the touch's slant (:func:`_slant`).  ``contact`` is
    the touch's evaluated contact."""
    return touch_stop(contact, np.array(touch.normal), r, clear + extra, _slant(touch))


def _slant(touch: ir.Touch) -> float:
    """How much of the approach distance is distance from the surface: 1 for a touch
    along the surface normal, ``SLANT_FACTOR`` times the cosine between approach and
    surface normal else (at least 0.1)."""
    if touch.surface is None:
        return 1.0
    return max(SLANT_FACTOR * float(np.dot(touch.normal, touch.surface)), 0.1)


def touch_stop(contact: np.ndarray, normal: np.ndarray, ball: float,
               required: float, slant: float = 1.0) -> np.ndarray:
    """Where the check of a touch ends: the ball centre ``required`` (+ one step and the
    mesh tolerance) short of the nominal contact, along the outward ``normal``; a slanted
    touch (``slant`` < 1, see :func:`_slant`) stops that distance over ``slant`` short."""
    return contact + (ball + (required + MIN_STEP + MESH_TOLERANCE) / slant) * normal


def swept(obstacle: Obstacle, a: np.ndarray, b: np.ndarray, ea: float, eb: float,
          stylus: Stylus, required: float, *, first: bool = False,
          bound: bool = True) -> tuple[float, float, np.ndarray]:
    """:func:`_sweep`, memoised on the obstacle when it keeps ``sweeps`` (a mesh).
    ``first``: stop at the first point below ``required`` (enough to refuse a move);
    ``bound``: try the swept-volume bound first (not for touches: they end at the
    limit, so it never clears them)."""
    sweeps: dict[tuple[Any, ...], tuple[float, float, np.ndarray]] | None = getattr(
        obstacle, "sweeps", None)
    key = (_t(a), _t(b), ea, eb, stylus, required)
    hit = sweeps.get(key) if sweeps is not None else None
    if hit is None:
        hit = _sweep(obstacle, a, b, ea, eb, stylus, required, first=first, bound=bound)
        if sweeps is not None:
            sweeps[key] = hit
    return hit


def describe(obstacle: Obstacle, ball: float, shank: float, required: float,
             worst: np.ndarray, stylus: Stylus | None = None,
             end: np.ndarray | None = None) -> str:
    """What a sweep whose clearances (less ``required``) went below zero ran into.

    A clearance still positive: ``the stylus ball comes within 0.100 mm of face 3``.  One
    at or below the sweep's floor (the part met): with ``stylus`` and an obstacle that
    measures overlaps, how far the stylus cuts into the part along the move from
    ``worst`` (where the sweep found it too close) to ``end`` (the move's end; ``worst``
    itself without it), measured (:func:`probegen.planning.intrusion.deepest`): the
    element that goes deepest (ball, shank or probe body), the depth and the face it
    meets, e.g. ``the probe body cuts 5.100 mm (5.100 mm in from its side, 15.900 mm up
    from its lower end) into face 24``; ``touches face 3`` when nothing overlaps (the
    figure was within the mesh's tolerance).  Without them: the sweep's figure and the
    face nearest the ball's centre (the ball) or the stylus's axis."""
    gap = min(ball, shank) + required
    overlaps = getattr(obstacle, "overlaps", None)
    face_of = getattr(obstacle, "face_of", None)
    if gap < 0.0 and stylus is not None and overlaps is not None and face_of is not None:
        parts = elements(stylus.ball, stylus.cylinders())
        stop = worst if end is None else end
        memo: dict[tuple[Any, ...], Intrusion | None] = getattr(obstacle, "intrusions", {})
        key = (_t(worst), _t(stop), stylus)
        if key not in memo:
            memo[key] = deepest(overlaps, parts, worst, stop,
                                getattr(obstacle, "beneath", None))
        hit = memo[key]
        if hit is None:
            name = obstacle.name_at(worst)
            who = "ball" if ball < shank else "shank"
            return (f"the stylus {who} touches {name} (no overlap found: within the mesh's "
                    f"{MESH_TOLERANCE:.3f} mm); expected a clearance of at least "
                    f"{required:.3f} mm")
        e = next(p for p in parts if p.name == hit.element)
        who = "the probe body" if hit.element == "probe body" else f"the stylus {hit.element}"
        return (f"{who} cuts {words(hit, e.radius)} into {face_of(hit.at, e)}; expected a "
                f"clearance of at least {required:.3f} mm")
    part = "ball" if ball < shank else "shank"
    # a gap that rounds up to the required clearance is given to as many more digits as
    # show it short: "comes within 0.150 mm ...; expected at least 0.150 mm" reads as no
    # fault at all
    digits = 3
    while 0.0 <= gap < required and digits < 6 and round(gap, digits) >= required:
        digits += 1
    how = f"comes within {gap:.{digits}f} mm of" if gap >= 0.0 else f"cuts {-gap:.3f} mm into"
    clearance_of = getattr(obstacle, "clearance_of", None)
    if part == "shank" and stylus is not None and face_of is not None \
            and clearance_of is not None:
        parts = elements(stylus.ball, stylus.cylinders())[1:]
        nearest = getattr(obstacle, "nearest", None)
        near = nearest(worst, parts) if nearest is not None else min(
            parts, key=lambda p: clearance_of(worst, p))
        part, name = near.name, face_of(worst, near)
    else:
        name = obstacle.name_at(worst)
    who = "the probe body" if part == "probe body" else f"the stylus {part}"
    return f"{who} {how} {name}; expected a clearance of at least {required:.3f} mm"


def _sweep(obstacle: Obstacle, a: np.ndarray, b: np.ndarray, ea: float, eb: float,
           stylus: Stylus, required: float, *, first: bool = False,
           bound: bool = True) -> tuple[float, float, np.ndarray]:
    """Smallest ball and shank clearances along ``a → b`` by sphere tracing.

    Each clearance is less the uncertainty ``(1-t)·ea + t·eb``.  That function of the arc
    length ``s`` is Lipschitz with constant ``k = 1 + |ea - eb| / length``, so from a point
    where it exceeds ``required`` by ``x`` the next ``x / k`` mm stay above ``required``.
    """
    length = float(np.linalg.norm(b - a))
    bounds = getattr(obstacle, "sweep_bound", None) if bound else None
    if bounds is not None and ea == eb == 0.0:
        quick = bounds(a, b, stylus)
        if quick is not None and min(quick) >= required + MIN_STEP:
            # the swept volumes clear: no tracing; the slack covers the query's tolerance
            return quick[0] - MIN_STEP / 2.0, quick[1] - MIN_STEP / 2.0, a
    k = 1.0 + (abs(ea - eb) / length if length else 0.0)
    worst_ball = worst_shank = np.inf
    worst = a
    t = 0.0
    floor = getattr(obstacle, "floor", None) if ea == eb == 0.0 else None
    while True:
        p = a + t * (b - a)
        extra = (1.0 - t) * ea + t * eb
        ball, shank = obstacle.clearance(p, stylus)
        ball, shank = ball - extra, shank - extra
        if min(ball, shank) < min(worst_ball, worst_shank):
            worst = p
        worst_ball, worst_shank = min(worst_ball, ball), min(worst_shank, shank)
        if t >= 1.0 or length == 0.0 or (first and min(ball, shank) < required):
            break
        if floor is not None and worst_shank <= floor:
            break  # the shank reached the least clearance the obstacle reports: nothing
            # further along can change the figures (or the part named)
        step = max((min(ball, shank) - required) / k, MIN_STEP)
        t = min(t + step / length, 1.0)
    slack = MIN_STEP / 2.0
    return worst_ball - slack, worst_shank - slack, worst


def _t(v: np.ndarray) -> tuple[float, float, float]:
    return (float(v[0]), float(v[1]), float(v[2]))


def fmt(v: np.ndarray) -> str:
    """A point as ``(x, y, z)`` with 3 decimals, mm."""
    return "(" + ", ".join(f"{x:.3f}" for x in v) + ")"
