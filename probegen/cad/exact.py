"""Exact queries on the trimmed faces of a loaded model (OCP).

The contact search (:mod:`probegen.sim.contact`) solves the stylus ball against the
analytic surfaces itself and asks this module only what needs the boundary
representation: is a point of a face's surface inside the trimmed face, what are the
face's boundary edges and vertices, how far is a point from a trimmed face (exactly,
free-form faces included), is a point inside the solid.

Part of the ``cad`` package, the only place that imports OCP.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray
from OCP.BRep import BRep_Tool
from OCP.BRepAdaptor import BRepAdaptor_Curve, BRepAdaptor_Surface
from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeVertex
from OCP.BRepClass3d import BRepClass3d_SolidClassifier
from OCP.BRepExtrema import BRepExtrema_DistShapeShape
from OCP.ElSLib import ElSLib
from OCP.Extrema import Extrema_ExtFlag
from OCP.GeomAbs import GeomAbs_CurveType as Ct
from OCP.GeomAbs import GeomAbs_SurfaceType as St
from OCP.gp import gp_Pnt, gp_Pnt2d
from OCP.IntTools import IntTools_FClass2d
from OCP.TopAbs import TopAbs_EDGE, TopAbs_SOLID, TopAbs_State, TopAbs_VERTEX
from OCP.TopExp import TopExp_Explorer
from OCP.TopoDS import TopoDS, TopoDS_Face, TopoDS_Shape

from probegen.cad.faces import FaceRecord, Model
from probegen.constants import tol

FloatArray = NDArray[np.float64]

CLASSIFY_TOLERANCE = 1e-7
"""Tolerance of the in-face test, mm (OCCT's confusion tolerance): a foot point this
close to a face's boundary counts as on the face, so a contact exactly on an edge is
found by the face and by the edge alike."""

_ANALYTIC = {
    St.GeomAbs_Plane: "plane",
    St.GeomAbs_Cylinder: "cylinder",
    St.GeomAbs_Cone: "cone",
    St.GeomAbs_Sphere: "sphere",
    St.GeomAbs_Torus: "torus",
}


@dataclass(frozen=True, slots=True)
class LineEdge:
    """A straight boundary edge from ``start`` to ``end`` (each (3,) float, mm)."""

    start: FloatArray
    end: FloatArray


@dataclass(frozen=True, slots=True)
class CircleEdge:
    """A circular boundary edge.

    Points are ``centre + radius * (cos w * xdir + sin w * ydir)`` for ``w`` from
    ``first`` to ``last`` (radians, ``first < last``); ``axis = xdir x ydir``.
    """

    centre: FloatArray
    axis: FloatArray
    xdir: FloatArray
    ydir: FloatArray
    radius: float
    first: float
    last: float

    def holds(self, angle: float) -> bool:
        """Whether the polar angle ``angle`` (radians) lies on the arc."""
        span = self.last - self.first
        if span >= 2.0 * math.pi - tol.angle:
            return True
        w = (angle - self.first) % (2.0 * math.pi)
        return w <= span + tol.angle or w >= 2.0 * math.pi - tol.angle


@dataclass(frozen=True, slots=True)
class Boundary:
    """The boundary of one face, without seam and degenerate edges.

    Attributes:
        lines: straight edges.
        circles: circular edges (full circles and arcs).
        vertices: (k, 3) float, every vertex of the face.
        free_edges: how many edges are neither lines nor circles (ellipses, splines);
            a face with any needs the numeric contact search.
    """

    lines: tuple[LineEdge, ...]
    circles: tuple[CircleEdge, ...]
    vertices: FloatArray
    free_edges: int


class ExactFaces:
    """Exact boundary-representation queries on the faces of a model.

    Faces are addressed by their 0-based index in ``model.faces``; everything is in the
    model's own frame (mm).  Per-face helpers are built on first use and cached.
    """

    def __init__(self, model: Model) -> None:
        self._faces: tuple[TopoDS_Face, ...] = model._topo_faces
        self._shape: TopoDS_Shape = model._shape.wrapped
        self._surfaces: dict[int, BRepAdaptor_Surface] = {}
        self._classes: dict[int, tuple[Any, IntTools_FClass2d]] = {}
        self._boundaries: dict[int, Boundary] = {}
        self._solids: list[BRepClass3d_SolidClassifier] | None = None

    def kind(self, index: int) -> str | None:
        """The analytic surface type of a face, or None for any other surface."""
        return _ANALYTIC.get(self._surface(index).GetType())

    def _surface(self, index: int) -> BRepAdaptor_Surface:
        """The (cached) surface adaptor of a face."""
        if index not in self._surfaces:
            self._surfaces[index] = BRepAdaptor_Surface(self._faces[index], True)
        return self._surfaces[index]

    def contains(self, index: int, point: FloatArray) -> bool:
        """Whether ``point``, a point of the face's analytic surface, lies on the face.

        Args:
            index: an analytic face (see :meth:`kind`).
            point: (3,) float on the untrimmed surface, mm.

        Returns:
            True for a point inside the trimmed face or on its boundary.
        """
        if index not in self._classes:
            surface = self._surface(index)
            primitive = getattr(surface, _ANALYTIC[surface.GetType()].capitalize())()
            classifier = IntTools_FClass2d(self._faces[index], CLASSIFY_TOLERANCE)
            self._classes[index] = (primitive, classifier)
        primitive, classifier = self._classes[index]
        p = gp_Pnt(float(point[0]), float(point[1]), float(point[2]))
        u, v = ElSLib.Parameters_s(primitive, p)
        state = classifier.Perform(gp_Pnt2d(u, v))
        return state in (TopAbs_State.TopAbs_IN, TopAbs_State.TopAbs_ON)

    def distance(self, index: int, point: FloatArray) -> tuple[float, FloatArray]:
        """Exact distance from ``point`` to the trimmed face, and the nearest point.

        Args:
            index: any face.
            point: (3,) float, mm.

        Returns:
            The distance (mm) and the nearest point of the face, (3,) float.
        """
        p = gp_Pnt(float(point[0]), float(point[1]), float(point[2]))
        vertex = BRepBuilderAPI_MakeVertex(p).Vertex()
        dist = BRepExtrema_DistShapeShape(
            vertex, self._faces[index], Extrema_ExtFlag.Extrema_ExtFlag_MIN
        )
        if not dist.IsDone() or dist.NbSolution() == 0:
            raise RuntimeError(f"exact distance to face {index + 1} failed at {point}")
        foot = dist.PointOnShape2(1)
        return float(dist.Value()), np.array([foot.X(), foot.Y(), foot.Z()])

    def boundary(self, index: int) -> Boundary:
        """The face's boundary edges and vertices (cached)."""
        if index not in self._boundaries:
            self._boundaries[index] = _boundary(self._faces[index])
        return self._boundaries[index]

    def inside(self, point: FloatArray) -> bool | None:
        """Whether ``point`` lies strictly inside one of the model's solids.

        Returns:
            True or False; None when the model holds no solid (only shells or faces).
        """
        if self._solids is None:
            self._solids = []
            explorer = TopExp_Explorer(self._shape, TopAbs_SOLID)
            while explorer.More():
                self._solids.append(BRepClass3d_SolidClassifier(explorer.Current()))
                explorer.Next()
        if not self._solids:
            return None
        p = gp_Pnt(float(point[0]), float(point[1]), float(point[2]))
        for solid in self._solids:
            solid.Perform(p, CLASSIFY_TOLERANCE)
            if solid.State() == TopAbs_State.TopAbs_IN:
                return True
        return False


def _boundary(face: TopoDS_Face) -> Boundary:
    """Collect the lines, circles, vertices and the count of other edges of a face."""
    lines: list[LineEdge] = []
    circles: list[CircleEdge] = []
    free = 0
    explorer = TopExp_Explorer(face, TopAbs_EDGE)
    while explorer.More():
        edge = TopoDS.Edge(explorer.Current())
        explorer.Next()
        if BRep_Tool.Degenerated_s(edge) or BRep_Tool.IsClosed_s(edge, face):
            continue  # a sphere's pole or a periodic surface's seam: no boundary
        curve = BRepAdaptor_Curve(edge)
        first, last = curve.FirstParameter(), curve.LastParameter()
        if curve.GetType() == Ct.GeomAbs_Line:
            lines.append(LineEdge(_xyz(curve.Value(first)), _xyz(curve.Value(last))))
        elif curve.GetType() == Ct.GeomAbs_Circle:
            circles.append(_circle(curve, first, last))
        else:
            free += 1
    points: list[FloatArray] = []
    explorer = TopExp_Explorer(face, TopAbs_VERTEX)
    while explorer.More():
        p = _xyz(BRep_Tool.Pnt_s(TopoDS.Vertex(explorer.Current())))
        if not any(np.array_equal(p, q) for q in points):
            points.append(p)
        explorer.Next()
    vertices = np.array(points, dtype=np.float64).reshape(-1, 3)
    return Boundary(tuple(lines), tuple(circles), vertices, free)


def _circle(curve: BRepAdaptor_Curve, first: float, last: float) -> CircleEdge:
    """A :class:`CircleEdge` from a circular curve adaptor (location applied)."""
    circ = curve.Circle()
    frame = circ.Position()
    return CircleEdge(
        centre=_xyz(circ.Location()), axis=_xyz(frame.Direction()),
        xdir=_xyz(frame.XDirection()), ydir=_xyz(frame.YDirection()),
        radius=float(circ.Radius()), first=min(first, last), last=max(first, last),
    )  # fmt: skip


def _xyz(item: object) -> FloatArray:
    """Coordinates of a gp_Pnt / gp_Dir as a (3,) float array."""
    return np.array([item.X(), item.Y(), item.Z()], dtype=np.float64)  # type: ignore[attr-defined]


# ------------------------------------------------------------------------------------
# Analytic offset surfaces (numpy only).
#
# A move is ``c(s) = a + s·u`` with ``u`` a unit vector and ``s`` the arc length.  Each
# ``*_roots`` function returns the roots where the ball centre crosses an offset surface
# *entering* it (moving against the outward normal ``n`` there), sorted by ``s``, as
# ``(s, n)``; the touched point is ``c(s) − r·n``.  ``sigma`` is +1 when the material is
# inside the surface (a boss: offset outwards) and -1 when it is outside (a bore).

Root = tuple[float, FloatArray]


def _monic_roots(b: float, c: float) -> list[float]:
    """Real roots of ``s² + 2·b·s + c``, ascending, without cancellation."""
    disc = b * b - c
    if disc < 0.0:
        return []
    q = -(b + math.copysign(math.sqrt(disc), b))
    if q == 0.0:
        return [0.0, 0.0]
    return sorted((q, c / q))


def _quadratic_roots(a2: float, b: float, c: float) -> list[float]:
    """Real roots of ``a2·s² + 2·b·s + c`` (a linear equation when ``a2`` vanishes)."""
    if abs(a2) <= 1e-14 * (abs(b) + 1e-300) or a2 == 0.0:
        return [] if b == 0.0 else [-c / (2.0 * b)]
    return _monic_roots(b / a2, c / a2)


def _entering(roots: list[float], a: FloatArray, u: FloatArray,
              normal: Any) -> list[Root]:
    """Keep the roots where the move enters the surface; ``normal(c)`` or None."""
    out: list[Root] = []
    for s in roots:
        n = normal(a + s * u)
        if n is not None and float(n @ u) < 0.0:
            out.append((s, n))
    return out


def _unit_or_none(v: FloatArray) -> FloatArray | None:
    """``v`` scaled to unit length, or None when it is (nearly) zero."""
    size = float(np.linalg.norm(v))
    return v / size if size > tol.zero else None


def _perp(v: FloatArray, k: FloatArray) -> FloatArray:
    """The part of ``v`` square to the unit vector ``k``."""
    return v - float(v @ k) * k


def plane_roots(a: FloatArray, u: FloatArray, origin: FloatArray, normal: FloatArray,
                r: float) -> list[Root]:
    """The plane through ``origin`` with outward unit ``normal``, offset by ``r``."""
    speed = float(u @ normal)
    if speed >= 0.0:
        return []
    return [((r - float((a - origin) @ normal)) / speed, normal)]


def sphere_roots(a: FloatArray, u: FloatArray, centre: FloatArray, radius: float,
                 sigma: float) -> list[Root]:
    """The sphere of (offset) ``radius`` about ``centre``."""
    if radius <= 0.0:
        return []
    w = a - centre
    roots = _monic_roots(float(w @ u), float(w @ w) - radius * radius)

    def normal(c: FloatArray) -> FloatArray | None:
        n = _unit_or_none(c - centre)
        return None if n is None else sigma * n

    return _entering(roots, a, u, normal)


def cylinder_roots(a: FloatArray, u: FloatArray, origin: FloatArray, axis: FloatArray,
                   radius: float, sigma: float) -> list[Root]:
    """The cylinder of (offset) ``radius`` about the line ``origin + h·axis``."""
    if radius <= 0.0:
        return []
    w, v = _perp(a - origin, axis), _perp(u, axis)
    a2 = float(v @ v)
    if a2 <= tol.zero**2:
        return []  # moving along the axis: the radius never changes
    roots = _quadratic_roots(a2, float(w @ v), float(w @ w) - radius * radius)

    def normal(c: FloatArray) -> FloatArray | None:
        n = _unit_or_none(_perp(c - origin, axis))
        return None if n is None else sigma * n

    return _entering(roots, a, u, normal)


def cone_roots(a: FloatArray, u: FloatArray, origin: FloatArray, axis: FloatArray,
               radius: float, half_angle: float, r: float, sigma: float) -> list[Root]:
    """The offset of the cone of ``radius`` at ``origin`` growing along ``axis``.

    The offset of a cone (apex ``V``, half angle ``α``) by ``r`` on the side ``sigma``
    is the cone of the same axis and angle with its apex at ``V − sigma·r/sin α``
    along the axis (only its nappe on the side where the radius grows).
    """
    tan_a, sin_a, cos_a = math.tan(half_angle), math.sin(half_angle), math.cos(half_angle)
    apex = origin - (radius / tan_a + sigma * r / sin_a) * axis
    w = a - apex
    wk, uk = float(w @ axis), float(u @ axis)
    wp, up = _perp(w, axis), _perp(u, axis)
    t2 = tan_a * tan_a
    roots = _quadratic_roots(float(up @ up) - t2 * uk * uk, float(wp @ up) - t2 * wk * uk,
                             float(wp @ wp) - t2 * wk * wk)
    roots = [s for s in roots if wk + s * uk >= 0.0]

    def normal(c: FloatArray) -> FloatArray | None:
        e = _unit_or_none(_perp(c - apex, axis))
        return None if e is None else sigma * (cos_a * e - sin_a * axis)

    return _entering(roots, a, u, normal)


def torus_roots(a: FloatArray, u: FloatArray, centre: FloatArray, axis: FloatArray,
                major: float, tube: float, sigma: float) -> list[Root]:
    """The torus of ``major`` radius about ``axis`` with (offset) ``tube`` radius.

    Solves the quartic ``(|q|² + R² − ρ²)² = 4R²·|q⊥|²`` with numpy, the move's
    parameter measured from its point nearest the centre (for conditioning), then
    polishes each real root by Newton on the exact distance to the tube's centre circle.
    """
    if tube <= 0.0:
        return []
    shift = -float((a - centre) @ u)
    w = a + shift * u - centre
    wk, uk, ww = float(w @ axis), float(u @ axis), float(w @ w)
    big = ww + major * major - tube * tube
    four_r2 = 4.0 * major * major
    coeffs = [1.0, 0.0, 2.0 * big - four_r2 * (1.0 - uk * uk), 2.0 * four_r2 * wk * uk,
              big * big - four_r2 * (ww - wk * wk)]
    found: list[float] = []
    for z in np.roots(coeffs):
        if abs(z.imag) <= 1e-6 * (1.0 + abs(z.real)):
            s = _polish_torus(float(z.real), w, u, axis, major, tube)
            if s is not None and not any(abs(s - f) <= tol.zero for f in found):
                found.append(s)
    roots = sorted(s + shift for s in found)

    def normal(c: FloatArray) -> FloatArray | None:
        e = _unit_or_none(_perp(c - centre, axis))
        n = None if e is None else _unit_or_none(c - centre - major * e)
        return None if n is None else sigma * n

    return _entering(roots, a, u, normal)


def _polish_torus(s: float, w: FloatArray, u: FloatArray, axis: FloatArray,
                  major: float, tube: float) -> float | None:
    """Newton on ``dist(w + s·u, circle) − tube``; None if it does not reach zero."""
    for _ in range(8):
        q = w + s * u
        qk = float(q @ axis)
        qp = _perp(q, axis)
        rho = float(np.linalg.norm(qp))
        d = math.hypot(rho - major, qk)
        g = d - tube
        if rho <= tol.zero or d <= tol.zero:
            return None
        slope = ((rho - major) * float(qp @ u) / rho + qk * float(u @ axis)) / d
        if slope == 0.0:
            break
        step = g / slope
        s -= step
        if abs(step) <= 1e-15 * (1.0 + abs(s)):
            break
    q = w + s * u
    rho = float(np.linalg.norm(_perp(q, axis)))
    return s if abs(math.hypot(rho - major, float(q @ axis)) - tube) <= 1e-9 else None


def line_pipe_roots(a: FloatArray, u: FloatArray, start: FloatArray, end: FloatArray,
                    r: float) -> list[Root]:
    """Points at distance ``r`` from the segment ``start → end``, foot inside it."""
    length = float(np.linalg.norm(end - start))
    if length <= tol.zero:
        return []
    d = (end - start) / length
    w, v = _perp(a - start, d), _perp(u, d)
    a2 = float(v @ v)
    if a2 <= tol.zero**2:
        return []
    roots = _quadratic_roots(a2, float(w @ v), float(w @ w) - r * r)

    def normal(c: FloatArray) -> FloatArray | None:
        along = float((c - start) @ d)
        if not -tol.zero <= along <= length + tol.zero:
            return None
        return _unit_or_none(c - start - along * d)

    return _entering(roots, a, u, normal)


def face_roots(record: FaceRecord, a: FloatArray, u: FloatArray, r: float) -> list[Root]:
    """Entering roots of the move ``a + s·u`` against a face's offset by ``r``.

    The offset is taken on the face's outward side (``record.inner`` says where the
    material is); ``record`` is of type plane, sphere, cylinder, cone or torus.
    """
    o, k = np.array(record.origin), np.array(record.axis)
    sigma = -1.0 if record.inner else 1.0
    size = record.radius or 0.0
    if record.type == "plane":
        return plane_roots(a, u, o, k, r)
    if record.type == "sphere":
        return sphere_roots(a, u, o, size + sigma * r, sigma)
    if record.type == "cylinder":
        return cylinder_roots(a, u, o, k, size + sigma * r, sigma)
    if record.type == "cone":
        return cone_roots(a, u, o, k, size, record.half_angle or 0.0, r, sigma)
    return torus_roots(a, u, o, k, size, (record.minor_radius or 0.0) + sigma * r, sigma)


def nearest_on_surface(record: FaceRecord, c: FloatArray) -> FloatArray | None:
    """The nearest point to ``c`` of a face's untrimmed analytic surface.

    Args:
        record: a :class:`probegen.cad.FaceRecord` of type plane, sphere, cylinder,
            cone or torus.
        c: (3,) float, mm.

    Returns:
        (3,) float; None where it is not unique (on an axis, at a centre) or, for a
        cone, where it would be the apex.
    """
    o, k = np.array(record.origin), np.array(record.axis)
    size = record.radius or 0.0
    if record.type == "plane":
        return np.asarray(c - float((c - o) @ k) * k)
    if record.type == "sphere":
        e = _unit_or_none(c - o)
        return None if e is None else o + size * e
    e = _unit_or_none(_perp(c - o, k))
    if e is None:
        return None
    if record.type == "cylinder":
        return o + float((c - o) @ k) * k + size * e
    if record.type == "cone":
        alpha = record.half_angle or 0.0
        apex = o - size / math.tan(alpha) * k
        g = math.sin(alpha) * e + math.cos(alpha) * k
        along = float((c - apex) @ g)
        return None if along <= 0.0 else apex + along * g
    m = o + size * e
    n = _unit_or_none(c - m)
    return None if n is None else m + (record.minor_radius or 0.0) * n
