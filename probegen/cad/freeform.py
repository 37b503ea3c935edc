"""Free-form faces (method M3): guide-point grids, the exact surface, mesh seeds.

Any face of a model (B-spline, Bézier, offset or analytic alike) is handled through
its parametric surface ``S(u, v)`` (``BRepAdaptor_Surface``, location applied) and its
trimmed boundary:

* :func:`guide_points` lays a grid in the face's parameter space (``grid = "uv"``) or
  projects an XY grid onto the face along the guide direction (``grid = "xy"``), by
  count or by spacing, and keeps only points inside the trimmed face (the exact 2-D
  classifier, holes included) and at least ``margin`` mm from every boundary edge
  (outer and inner loops; seams and degenerate edges are not boundaries).  Grid
  points that miss the face or break the margin are returned as :class:`Skipped`
  records with the reason, never dropped silently.
* :class:`FaceSurface` evaluates ``S`` and its first and second derivatives in
  batches, with the outward normal (the face's orientation kept): it is the
  ``ParamSurface`` the offset-surface solver of :mod:`probegen.geometry.offset_surface`
  works on.
* :class:`FaceMesh` is the face's triangulation with the ``(u, v)`` of every node, for
  Newton seeds by ray casting (projected grids) and nearest-point queries.

Lengths are mm in the model frame; parameters are the surface's own.
Part of the ``cad`` package, the only place that imports OCP.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import trimesh
from numpy.typing import ArrayLike, NDArray
from OCP.BRep import BRep_Tool
from OCP.BRepAdaptor import BRepAdaptor_Curve, BRepAdaptor_Surface
from OCP.BRepMesh import BRepMesh_IncrementalMesh
from OCP.BRepTools import BRepTools
from OCP.GCPnts import GCPnts_AbscissaPoint
from OCP.GeomAbs import GeomAbs_SurfaceType as St
from OCP.gp import gp_Pnt, gp_Pnt2d, gp_Vec
from OCP.IntTools import IntTools_FClass2d
from OCP.TopAbs import TopAbs_EDGE, TopAbs_Orientation, TopAbs_State
from OCP.TopExp import TopExp_Explorer
from OCP.TopLoc import TopLoc_Location
from OCP.TopoDS import TopoDS, TopoDS_Face
from scipy.spatial import cKDTree

from probegen.cad import FaceRecord, Model, face_by_id
from probegen.errors import ModelError
from probegen.geometry.bspline import BSplineSurface
from probegen.geometry.offset_surface import Domain, SurfaceJet

FloatArray = NDArray[np.float64]
Vec3 = tuple[float, float, float]

GRIDS = ("uv", "xy")
"""Grid kinds: in the face's parameter space, or an XY grid projected onto the face."""
EDGE_STEP = 0.02
"""Spacing (mm) of the boundary samples the margin is measured against: the distance
to a sampled edge overstates the true one by at most ``EDGE_STEP² / (8·margin)``."""
PROBE_SAMPLES = 61
"""Samples per parameter direction of the dense probe that finds where a face keeps
the margin (the grids are laid over that region's box)."""
CLASSIFY_TOLERANCE = 1e-7
"""Tolerance of the exact in-face test, mm."""
FREEFORM_TYPES = ("bspline", "bezier", "offset", "revolution", "extrusion", "other")
"""Face types that count as free-form (no analytic feature measures them)."""


@dataclass(frozen=True, slots=True)
class GuidePoint:
    """A guide point on the face.

    Attributes:
        index: 1-based position in the grid's order (rows, serpentine).
        uv: surface parameters.
        point: the point on the face, mm.
        normal: outward unit normal there.
    """

    index: int
    uv: tuple[float, float]
    point: Vec3
    normal: Vec3


@dataclass(frozen=True, slots=True)
class Skipped:
    """A grid point that is not a guide point: ``where`` (mm, on the face or the grid
    plane) and why (outside the trimmed face, inside the margin, missed the face)."""

    where: Vec3
    reason: str


@dataclass(frozen=True, slots=True)
class GuideGrid:
    """The guide points of one face and the grid points left out."""

    face: int
    points: tuple[GuidePoint, ...]
    skipped: tuple[Skipped, ...]


def is_freeform(record: FaceRecord) -> bool:
    """Whether a face is free-form (not plane, cylinder, cone, sphere or torus)."""
    return record.type in FREEFORM_TYPES


def _topo(model: Model, face_id: int) -> TopoDS_Face:
    face_by_id(model, face_id)
    return model._topo_faces[face_id - 1]


class FaceSurface:
    """One face's surface as a ``ParamSurface`` (:mod:`probegen.geometry.offset_surface`).

    ``domain`` is the face's parameter box (its trimming lies inside it).  A
    non-periodic B-spline or Bézier face is evaluated by the numpy
    :class:`~probegen.geometry.bspline.BSplineSurface` built from its poles, knots and
    weights (location applied; batches without a Python loop); any other surface by
    ``BRepAdaptor_Surface.D2`` point by point.  ``normal_sign`` is +1 when
    ``Su × Sv`` points out of the material, -1 for a reversed face.
    """

    def __init__(self, model: Model, face_id: int) -> None:
        self.face_id = face_id
        self._face = _topo(model, face_id)
        self._surface = BRepAdaptor_Surface(self._face, True)
        reversed_ = self._face.Orientation() == TopAbs_Orientation.TopAbs_REVERSED
        self.normal_sign = -1.0 if reversed_ else 1.0
        umin, umax, vmin, vmax = BRepTools.UVBounds_s(self._face)
        self.domain: Domain = ((float(umin), float(umax)), (float(vmin), float(vmax)))
        self._classifier = IntTools_FClass2d(self._face, CLASSIFY_TOLERANCE)
        self.spline = _numpy_spline(self._surface)

    def derivatives(self, u: ArrayLike, v: ArrayLike) -> SurfaceJet:
        """``S, Su, Sv, Suu, Suv, Svv`` at ``(m,)`` u and v, each (m, 3) float, mm."""
        uu, vv = np.broadcast_arrays(np.asarray(u, dtype=np.float64).ravel(),
                                     np.asarray(v, dtype=np.float64).ravel())
        if self.spline is not None:
            return self.spline.derivatives(uu, vv)
        out = np.empty((6, len(uu), 3))
        p, du, dv, duu, dvv, duv = gp_Pnt(), gp_Vec(), gp_Vec(), gp_Vec(), gp_Vec(), gp_Vec()
        d2 = self._surface.D2
        for k, (a, b) in enumerate(zip(uu.tolist(), vv.tolist(), strict=True)):
            d2(a, b, p, du, dv, duu, dvv, duv)
            out[:, k] = ((p.X(), p.Y(), p.Z()), (du.X(), du.Y(), du.Z()),
                         (dv.X(), dv.Y(), dv.Z()), (duu.X(), duu.Y(), duu.Z()),
                         (duv.X(), duv.Y(), duv.Z()), (dvv.X(), dvv.Y(), dvv.Z()))
        return SurfaceJet(*out)

    def evaluate(self, u: ArrayLike, v: ArrayLike) -> FloatArray:
        """``S(u, v)``, (m, 3) float, mm."""
        if self.spline is not None:
            return self.spline.evaluate(u, v)
        uu, vv = np.broadcast_arrays(np.asarray(u, dtype=np.float64).ravel(),
                                     np.asarray(v, dtype=np.float64).ravel())
        value = self._surface.Value
        out = np.empty((len(uu), 3))
        for k, (a, b) in enumerate(zip(uu.tolist(), vv.tolist(), strict=True)):
            q = value(a, b)
            out[k] = (q.X(), q.Y(), q.Z())
        return out

    def point(self, uv: FloatArray) -> FloatArray:
        """``S`` at ``uv`` ((n, 2) float), (n, 3) float, mm."""
        uv = np.asarray(uv, dtype=np.float64).reshape(-1, 2)
        return self.evaluate(uv[:, 0], uv[:, 1])

    def normal(self, uv: FloatArray) -> FloatArray:
        """Outward unit normals at ``uv`` ((n, 2) float), (n, 3) float."""
        uv = np.asarray(uv, dtype=np.float64).reshape(-1, 2)
        jet = self.derivatives(uv[:, 0], uv[:, 1])
        n = self.normal_sign * np.cross(jet.su, jet.sv)
        return np.asarray(n / np.linalg.norm(n, axis=1, keepdims=True))

    def inside(self, uv: FloatArray) -> NDArray[np.bool_]:
        """Whether each ``(u, v)`` lies inside the trimmed face or on its boundary."""
        uv = np.asarray(uv, dtype=np.float64).reshape(-1, 2)
        perform = self._classifier.Perform
        ok = (TopAbs_State.TopAbs_IN, TopAbs_State.TopAbs_ON)
        return np.array([perform(gp_Pnt2d(u, v)) in ok for u, v in uv.tolist()], dtype=bool)


def _numpy_spline(surface: BRepAdaptor_Surface) -> BSplineSurface | None:
    """The face's B-spline (or Bézier) surface for numpy, or None (other or periodic)."""
    kind = surface.GetType()
    if kind not in (St.GeomAbs_BSplineSurface, St.GeomAbs_BezierSurface):
        return None
    geom = surface.BSpline() if kind == St.GeomAbs_BSplineSurface else None
    if geom is None or geom.IsUPeriodic() or geom.IsVPeriodic():
        return None
    nu, nv = geom.NbUPoles(), geom.NbVPoles()
    poles = np.array([[_xyz3(geom.Pole(i, j)) for j in range(1, nv + 1)]
                      for i in range(1, nu + 1)])
    weights = None
    if geom.IsURational() or geom.IsVRational():
        weights = np.array([[geom.Weight(i, j) for j in range(1, nv + 1)]
                            for i in range(1, nu + 1)])
    ku = np.array([geom.UKnotSequence().Value(i) for i in range(1, nu + geom.UDegree() + 2)])
    kv = np.array([geom.VKnotSequence().Value(i) for i in range(1, nv + geom.VDegree() + 2)])
    return BSplineSurface(poles, ku, kv, geom.UDegree(), geom.VDegree(), weights)


def _xyz3(p: gp_Pnt) -> Vec3:
    return (float(p.X()), float(p.Y()), float(p.Z()))


def boundary_samples(model: Model, face_id: int, step: float = EDGE_STEP) -> FloatArray:
    """Points every ``step`` mm (or closer) along every boundary edge of a face, (k, 3)."""
    face = _topo(model, face_id)
    chunks: list[FloatArray] = []
    explorer = TopExp_Explorer(face, TopAbs_EDGE)
    while explorer.More():
        edge = TopoDS.Edge(explorer.Current())
        explorer.Next()
        if BRep_Tool.Degenerated_s(edge) or BRep_Tool.IsClosed_s(edge, face):
            continue
        curve = BRepAdaptor_Curve(edge)
        first, last = curve.FirstParameter(), curve.LastParameter()
        length = GCPnts_AbscissaPoint.Length_s(curve)
        count = max(int(math.ceil(length / step)), 1) + 1
        pts = [curve.Value(t) for t in np.linspace(first, last, count).tolist()]
        chunks.append(np.array([(q.X(), q.Y(), q.Z()) for q in pts]))
    return np.concatenate(chunks) if chunks else np.zeros((0, 3))


class FaceMesh:
    """A face's triangulation with node parameters, for seeds of the exact solvers."""

    def __init__(self, model: Model, face_id: int, tolerance: float = 0.01) -> None:
        face = _topo(model, face_id)
        BRepMesh_IncrementalMesh(face, tolerance, False, 0.2, False)
        location = TopLoc_Location()
        poly = BRep_Tool.Triangulation_s(face, location)
        if poly is None or not poly.HasUVNodes():
            raise ModelError(f"{model.path}: face {face_id}: no triangulation with "
                             "parameters: expected a meshable face")
        trsf = location.Transformation()
        count = poly.NbNodes()
        nodes = [poly.Node(i).Transformed(trsf) for i in range(1, count + 1)]
        uvs = [poly.UVNode(i) for i in range(1, count + 1)]
        tris = np.array([poly.Triangle(i).Get() for i in range(1, poly.NbTriangles() + 1)])
        self.uv = np.array([(q.X(), q.Y()) for q in uvs], dtype=np.float64)
        self.mesh = trimesh.Trimesh(np.array([(q.X(), q.Y(), q.Z()) for q in nodes]),
                                    tris.reshape(-1, 3) - 1, process=False)

    def _uv_at(self, points: FloatArray, triangles: NDArray[np.int64]) -> FloatArray:
        """Parameters interpolated at points of the given triangles."""
        corners = self.mesh.vertices[self.mesh.faces[triangles]]
        bary = trimesh.triangles.points_to_barycentric(corners, points)
        return np.einsum("nk,nkj->nj", bary, self.uv[self.mesh.faces[triangles]])

    def cast(self, origins: FloatArray, direction: FloatArray
             ) -> tuple[NDArray[np.bool_], FloatArray]:
        """Cast rays ``origins + t·direction``: hit flags (n,) and the seeds (n, 2) of
        the first hit (zeros where none)."""
        origins = np.asarray(origins, dtype=np.float64).reshape(-1, 3)
        dirs = np.broadcast_to(np.asarray(direction, dtype=np.float64), origins.shape)
        locs, rays, tris = self.mesh.ray.intersects_location(origins, dirs,
                                                             multiple_hits=True)
        hit = np.zeros(len(origins), dtype=bool)
        seeds = np.zeros((len(origins), 2))
        best = np.full(len(origins), np.inf)
        t = np.einsum("nj,nj->n", locs - origins[rays], dirs[rays])
        for k in np.argsort(t, kind="stable").tolist():
            ray = int(rays[k])
            if t[k] < best[ray]:
                best[ray], hit[ray] = t[k], True
                seeds[ray] = self._uv_at(locs[k:k + 1], tris[k:k + 1])[0]
        return hit, seeds

    def nearest_uv(self, points: FloatArray) -> FloatArray:
        """Seeds (n, 2): the parameters of the nearest point of the mesh."""
        pts = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        closest, _, tris = self.mesh.nearest.on_surface(pts)
        return self._uv_at(closest, np.asarray(tris, dtype=np.int64))


def _counts(extent: tuple[float, float], count: int | None, spacing: float | None) -> int:
    """Grid lines across a usable length: the count, or as many as the spacing allows."""
    if count is not None:
        return count
    assert spacing is not None
    return max(int(math.floor(max(extent[1] - extent[0], 0.0) / spacing + 1e-9)) + 1, 1)


def _line(lo: float, hi: float, n: int) -> FloatArray:
    return np.array([(lo + hi) / 2.0]) if n == 1 else np.linspace(lo, hi, n)


def _serpentine(grid_a: FloatArray, grid_b: FloatArray) -> FloatArray:
    """All pairs, rows of ``b``, every other row reversed, (n, 2)."""
    rows = []
    for j, b in enumerate(grid_b.tolist()):
        a = grid_a if j % 2 == 0 else grid_a[::-1]
        rows.append(np.column_stack([a, np.full(len(a), b)]))
    return np.concatenate(rows)


def _usable(surface: FaceSurface, tree: cKDTree | None, margin: float
            ) -> tuple[FloatArray, FloatArray]:
    """Parameters and points of a dense sample of the face that keep the margin.

    ``PROBE_SAMPLES²`` parameters over the face's parameter box, kept where they lie
    inside the trimmed face and at least ``margin`` from its boundary: the grids are
    laid over their box, so a trimmed or unevenly parametrised face still gets its
    points where they can be.  Empty arrays when none keeps the margin.
    """
    (umin, umax), (vmin, vmax) = surface.domain
    uv = _serpentine(np.linspace(umin, umax, PROBE_SAMPLES),
                     np.linspace(vmin, vmax, PROBE_SAMPLES))
    points = surface.point(uv)
    ok = surface.inside(uv)
    if tree is not None:
        ok &= tree.query(points)[0] >= margin
    return uv[ok], points[ok]


def _uv_candidates(surface: FaceSurface, usable: tuple[FloatArray, FloatArray],
                   counts: tuple[int, int] | None, spacing: float | None) -> FloatArray:
    """Grid in ``(u, v)`` over the box of the usable parameters (the whole parameter
    box when none is usable); with ``spacing``, the lines are counted at the mean
    speed of the surface along u and v."""
    uv = usable[0]
    if not len(uv):
        (umin, umax), (vmin, vmax) = surface.domain
        uv = np.array([[umin, vmin], [umax, vmax]])
    lo, hi = uv.min(axis=0), uv.max(axis=0)
    jet = surface.derivatives(uv[:, 0], uv[:, 1])
    speed_u = float(np.linalg.norm(jet.su, axis=1).mean())
    speed_v = float(np.linalg.norm(jet.sv, axis=1).mean())
    nu = _counts((0.0, (hi[0] - lo[0]) * speed_u), counts and counts[0], spacing)
    nv = _counts((0.0, (hi[1] - lo[1]) * speed_v), counts and counts[1], spacing)
    return _serpentine(_line(lo[0], hi[0], nu), _line(lo[1], hi[1], nv))


def _xy_candidates(record: FaceRecord, usable: tuple[FloatArray, FloatArray],
                   counts: tuple[int, int] | None, spacing: float | None) -> FloatArray:
    """Grid in XY over the box of the usable points (the face's box when none)."""
    pts = usable[1]
    if not len(pts):
        pts = np.array([record.bbox_min, record.bbox_max])
    lo, hi = pts[:, :2].min(axis=0), pts[:, :2].max(axis=0)
    nx = _counts((lo[0], hi[0]), counts and counts[0], spacing)
    ny = _counts((lo[1], hi[1]), counts and counts[1], spacing)
    return _serpentine(_line(lo[0], hi[0], nx), _line(lo[1], hi[1], ny))


def project_xy(surface: FaceSurface, mesh: FaceMesh, xy: FloatArray, direction: Vec3,
               top: float) -> tuple[NDArray[np.bool_], FloatArray]:
    """Project XY points onto the face along ``-direction``: hits and exact ``(u, v)``.

    A ray from ``(x, y, top)`` along ``-direction`` seeds the parameters on the mesh;
    Newton then solves ``S(u, v) = o − t·d`` exactly (three equations in ``u, v, t``).
    """
    d = np.asarray(direction, dtype=np.float64)
    origins = np.column_stack([xy, np.full(len(xy), top)])
    hit, uv = mesh.cast(origins, -d)
    for k in np.flatnonzero(hit).tolist():
        uv[k] = _newton_line(surface, uv[k], origins[k], d)
    return hit, uv


def _newton_line(surface: FaceSurface, uv: FloatArray, origin: FloatArray,
                 d: FloatArray) -> FloatArray:
    """``(u, v)`` where the line ``origin − t·d`` meets the surface (Newton, 1e-10 mm)."""
    p0 = surface.point(uv)[0]
    x = np.array([uv[0], uv[1], float((origin - p0) @ d)])
    for _ in range(30):
        jet = surface.derivatives(x[:1], x[1:2])
        residual = jet.point[0] - (origin - x[2] * d)
        if float(np.linalg.norm(residual)) < 1e-10:
            break
        jac = np.column_stack([jet.su[0], jet.sv[0], d])
        x = x - np.linalg.solve(jac, residual)
    return x[:2]


def guide_points(model: Model, face_id: int, *, grid: str = "uv",
                 counts: tuple[int, int] | None = None, spacing: float | None = None,
                 margin: float = 1.0, direction: Vec3 = (0.0, 0.0, 1.0)) -> GuideGrid:
    """Guide points on a face, with every grid point left out and why.

    Args:
        model: the loaded model.
        face_id: the face (1-based).
        grid: ``"uv"`` (parameter space) or ``"xy"`` (an XY grid projected along
            ``-direction``).
        counts: grid points along u and v (x and y), or None with ``spacing``.
        spacing: the grid pitch, mm (``uv``: along the surface at the mean speed).
        margin: least distance from every boundary edge, mm.
        direction: the guide direction (unit, out of the material).

    Returns:
        The guide points in serpentine order, numbered from 1, and the skipped points.
    """
    if (counts is None) == (spacing is None):
        raise ValueError("give exactly one of counts and spacing")
    record = face_by_id(model, face_id)
    surface = FaceSurface(model, face_id)
    edges = boundary_samples(model, face_id)
    tree = cKDTree(edges) if len(edges) else None
    usable = _usable(surface, tree, margin)
    skipped: list[Skipped] = []
    if grid == "uv":
        uv = _uv_candidates(surface, usable, counts, spacing)
    else:
        xy = _xy_candidates(record, usable, counts, spacing)
        top = record.bbox_max[2] + 1.0
        hit, uv = project_xy(surface, FaceMesh(model, face_id), xy, direction, top)
        skipped += [Skipped((float(x), float(y), top), "the grid line misses the face")
                    for (x, y) in xy[~hit].tolist()]
        uv = uv[hit]
    points = surface.point(uv) if len(uv) else np.zeros((0, 3))
    inside = surface.inside(uv) if len(uv) else np.zeros(0, dtype=bool)
    gap = (tree.query(points)[0] if tree is not None and len(points)
           else np.full(len(points), np.inf))
    keep = inside & (gap >= margin)
    for k in np.flatnonzero(~keep).tolist():
        why = ("outside the trimmed face" if not inside[k] else
               f"{gap[k]:.3f} mm from the face's boundary, inside the margin of {margin:.3f} mm")
        skipped.append(Skipped(_v(points[k]), why))
    normals = surface.normal(uv[keep]) if keep.any() else np.zeros((0, 3))
    found = tuple(GuidePoint(i + 1, (float(a), float(b)), _v(p), _v(n))
                  for i, ((a, b), p, n) in enumerate(zip(uv[keep].tolist(), points[keep],
                                                         normals, strict=True)))
    return GuideGrid(face_id, found, tuple(skipped))


def _v(p: FloatArray) -> Vec3:
    return (float(p[0]), float(p[1]), float(p[2]))
