"""Face records of a loaded model: what each face is, and finding a face.

Owns :class:`FaceRecord` and :class:`Model`, the building of a face's record from its
OCCT surface (type, axis, sizes, concave or convex, box), and the queries on a loaded
model: a face by id, the face nearest a point, and the text table of the faces.
Loading is in :mod:`probegen.cad.loading`, tessellation in :mod:`probegen.cad.mesh`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from build123d import Shape
from OCP.Bnd import Bnd_Box
from OCP.BRepAdaptor import BRepAdaptor_Surface
from OCP.BRepBndLib import BRepBndLib
from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeVertex
from OCP.BRepExtrema import BRepExtrema_DistShapeShape
from OCP.BRepGProp import BRepGProp
from OCP.BRepLProp import BRepLProp_SLProps
from OCP.BRepTools import BRepTools
from OCP.GeomAbs import GeomAbs_SurfaceType as St
from OCP.gp import gp_Ax1, gp_Pnt
from OCP.GProp import GProp_GProps
from OCP.TopAbs import TopAbs_Orientation
from OCP.TopoDS import TopoDS_Face

from probegen.constants import tol
from probegen.errors import ModelError

Vec3 = tuple[float, float, float]

DEFAULT_PICK_DISTANCE = 0.5
"""How far (mm) a spec point may lie from the face it names: it is read off a drawing
or a viewer, and 0.5 mm forgives that while staying far below any probed feature."""

_SURFACE_TYPES: dict[St, str] = {
    St.GeomAbs_Plane: "plane",
    St.GeomAbs_Cylinder: "cylinder",
    St.GeomAbs_Cone: "cone",
    St.GeomAbs_Sphere: "sphere",
    St.GeomAbs_Torus: "torus",
    St.GeomAbs_BSplineSurface: "bspline",
    St.GeomAbs_BezierSurface: "bezier",
    St.GeomAbs_SurfaceOfRevolution: "revolution",
    St.GeomAbs_SurfaceOfExtrusion: "extrusion",
    St.GeomAbs_OffsetSurface: "offset",
}
FACE_TYPES = (*_SURFACE_TYPES.values(), "other")
"""Every value :attr:`FaceRecord.type` can take."""


@dataclass(frozen=True, slots=True)
class FaceRecord:
    """One face of a model as plain geometry (mm, radians).

    Attributes:
        id: 1-based index in the model's stable face order.
        type: one of :data:`FACE_TYPES`.
        origin: plane: a point on it (the centre of mass); cylinder, cone, revolution:
            the foot of the centre of mass on the axis; sphere, torus: the centre;
            other types: the centre of mass.
        axis: unit vector.  Plane and free-form: the outward normal (away from the
            material; free-form: at the middle of the parameter range); cylinder,
            cone, torus, revolution: the axis (cone: the radius grows along it);
            extrusion: the extrusion direction; sphere: from the centre towards the
            face's centre of mass (a cap's pole), else the sphere's own axis.
        radius: cylinder/sphere radius, cone radius at ``origin``, torus major radius.
        minor_radius: torus tube radius.
        half_angle: cone half angle, positive.
        centre: centre of mass of the face.
        inner: cylinder, cone, sphere, torus: True for a concave face (a bore: the
            material is outside the surface), False for a convex one (a boss).
        area: face area, mm^2.
        bbox_min: lower corner of the face's axis-aligned bounding box.
        bbox_max: upper corner of the face's axis-aligned bounding box.
    """

    id: int
    type: str
    origin: Vec3
    axis: Vec3
    radius: float | None
    minor_radius: float | None
    half_angle: float | None
    centre: Vec3
    inner: bool | None
    area: float
    bbox_min: Vec3
    bbox_max: Vec3


@dataclass(frozen=True, slots=True)
class Model:
    """A loaded part model.

    Attributes:
        path: the file path as the caller gave it (quoted in every message).
        faces: the face records, ``faces[i].id == i + 1``.
        bbox_min: lower corner of the box around the faces, mm (free curves and points
            a STEP file may carry for construction or PMI are left out).
        bbox_max: upper corner of that box, mm.
        warnings: what was ignored while loading (a colour or style entity that does not
            parse), one message each, in file order.
    """

    path: str
    faces: tuple[FaceRecord, ...]
    bbox_min: Vec3
    bbox_max: Vec3
    _shape: Shape = field(repr=False, compare=False)
    _topo_faces: tuple[TopoDS_Face, ...] = field(repr=False, compare=False)
    warnings: tuple[str, ...] = ()


# ---------------------------------------------------------------------- face records

# origin, axis, radius, minor radius, half angle, and whether inner/outer applies
_Geometry = tuple[Vec3, Vec3, float | None, float | None, float | None, bool]


def _record(index: int, face: TopoDS_Face) -> FaceRecord:
    """Build the :class:`FaceRecord` of one face."""
    surface = BRepAdaptor_Surface(face, True)
    kind = _SURFACE_TYPES.get(surface.GetType(), "other")
    props = GProp_GProps()
    BRepGProp.SurfaceProperties_s(face, props)
    centre = _xyz(props.CentreOfMass())
    point, normal = _point_and_normal(face, surface)
    geometry = _geometry(kind, surface, centre, normal)
    origin, axis, radius, minor, half, revolved = geometry
    box = Bnd_Box()
    BRepBndLib.AddOptimal_s(face, box, False, False)  # exact geometry, no tolerance gap
    return FaceRecord(
        id=index, type=kind, origin=origin, axis=axis, radius=radius, minor_radius=minor,
        half_angle=half, centre=centre, area=float(props.Mass()),
        inner=_concave(point, normal, kind, geometry) if revolved else None,
        bbox_min=_xyz(box.CornerMin()), bbox_max=_xyz(box.CornerMax()),
    )  # fmt: skip


def _geometry(kind: str, surface: BRepAdaptor_Surface, centre: Vec3, normal: Vec3) -> _Geometry:
    """Origin, axis and sizes of one face's surface (see :class:`FaceRecord`)."""
    if kind == "sphere":
        sphere = surface.Sphere()
        middle = _xyz(sphere.Location())
        offset = np.subtract(centre, middle)
        length = float(np.linalg.norm(offset))
        pole = offset / length if length > tol.merge else _xyz(sphere.Position().Direction())
        return middle, _unit(pole), float(sphere.Radius()), None, None, True
    if kind == "torus":
        torus = surface.Torus()
        axis = _unit(_xyz(torus.Axis().Direction()))
        sizes = float(torus.MajorRadius()), float(torus.MinorRadius())
        return _xyz(torus.Location()), axis, *sizes, None, True
    if kind == "cylinder":
        origin, axis, _ = _foot(surface.Cylinder().Axis(), centre)
        return origin, axis, float(surface.Cylinder().Radius()), None, None, True
    if kind == "cone":
        cone = surface.Cone()
        origin, axis, along = _foot(cone.Axis(), centre)
        half = float(cone.SemiAngle())
        radius = float(cone.RefRadius()) + along * math.tan(half)
        if half < 0.0:  # make the radius grow along the axis
            axis, half = _unit(np.negative(axis)), -half
        return origin, axis, radius, None, half, True
    if kind == "revolution":
        origin, axis, _ = _foot(surface.AxeOfRevolution(), centre)
        return origin, axis, None, None, None, False
    if kind == "extrusion":
        return centre, _unit(_xyz(surface.Direction())), None, None, None, False
    return centre, normal, None, None, None, False


def _foot(ax1: gp_Ax1, point: Vec3) -> tuple[Vec3, Vec3, float]:
    """Foot of ``point`` on an axis: (foot, unit direction, signed distance along)."""
    base = np.array(_xyz(ax1.Location()), dtype=np.float64)
    direction = np.array(_unit(_xyz(ax1.Direction())), dtype=np.float64)
    along = float(np.dot(np.subtract(point, base), direction))
    return _vec3(base + along * direction), _vec3(direction), along


def _concave(point: Vec3, normal: Vec3, kind: str, geometry: _Geometry) -> bool:
    """True when the outward normal points towards the centre, the axis or the tube."""
    origin, axis, radius = np.array(geometry[0]), np.array(geometry[1]), geometry[2]
    radial = np.subtract(point, origin)
    if kind != "sphere":
        radial -= np.dot(radial, axis) * axis  # from the axis, square to it
    if kind == "torus" and radius is not None:
        ring = origin + radius * radial / max(float(np.linalg.norm(radial)), tol.zero)
        radial = np.subtract(point, ring)  # from the tube's centre circle
    return bool(np.dot(radial, normal) < 0.0)


def _point_and_normal(face: TopoDS_Face, surface: BRepAdaptor_Surface) -> tuple[Vec3, Vec3]:
    """A point of the face's surface and the outward normal there (face orientation kept).

    Tries the middle of the parameter range, then two other interior parameters to
    step off singular points (sphere poles, cone apex).
    """
    umin, umax, vmin, vmax = BRepTools.UVBounds_s(face)
    flip = -1.0 if face.Orientation() == TopAbs_Orientation.TopAbs_REVERSED else 1.0
    for fu, fv in ((0.5, 0.5), (0.25, 0.3), (0.7, 0.8)):
        u, v = umin + fu * (umax - umin), vmin + fv * (vmax - vmin)
        props = BRepLProp_SLProps(surface, u, v, 1, tol.merge)
        if props.IsNormalDefined():
            return _xyz(props.Value()), _unit(np.multiply(flip, _xyz(props.Normal())))
    raise ModelError("degenerate surface: expected a surface normal, found none")


def _xyz(item: gp_Pnt | object) -> Vec3:
    """Coordinates of a gp_Pnt / gp_Dir / gp_Vec as floats."""
    return (float(item.X()), float(item.Y()), float(item.Z()))  # type: ignore[union-attr]


def _vec3(values: Sequence[float] | np.ndarray) -> Vec3:
    """A 3-tuple of plain floats."""
    return (float(values[0]), float(values[1]), float(values[2]))


def _unit(vector: Sequence[float] | np.ndarray) -> Vec3:
    """``vector`` scaled to length 1."""
    return _vec3(np.asarray(vector, dtype=np.float64) / math.hypot(*vector))


# -------------------------------------------------------------------------- queries


def face_by_id(model: Model, n: int) -> FaceRecord:
    """Return face ``n`` (1-based).

    Raises:
        ModelError: ``n`` is not a face id of the model; the message gives the range.
    """
    count = len(model.faces)
    if isinstance(n, bool) or not isinstance(n, int) or not 1 <= n <= count:
        raise ModelError(f"{model.path}: no face {n!r}: expected a face id from 1 to {count}")
    return model.faces[n - 1]


def face_at(
    model: Model, point: Sequence[float], *, max_distance: float = DEFAULT_PICK_DISTANCE
) -> FaceRecord:
    """Return the face nearest ``point``, by exact distance to the trimmed face.

    Faces whose bounding box is farther than the best distance so far are skipped.
    Equal distances (a point on an edge) go to the lower face id.

    Args:
        model: the loaded model.
        point: (3,) float, mm.
        max_distance: the farthest the face may be, mm.

    Raises:
        ModelError: no face lies within ``max_distance``; the message names the nearest.
    """
    p = np.asanyarray(point, dtype=np.float64).reshape(3)
    vertex = BRepBuilderAPI_MakeVertex(gp_Pnt(*p.tolist())).Vertex()
    low = np.array([f.bbox_min for f in model.faces])
    high = np.array([f.bbox_max for f in model.faces])
    bounds = np.linalg.norm(np.maximum(np.maximum(low - p, p - high), 0.0), axis=1)
    best, best_id = math.inf, 0
    for index in np.lexsort((np.arange(len(bounds)), bounds)).tolist():
        if bounds[index] > best + tol.merge:
            break
        dist = BRepExtrema_DistShapeShape(vertex, model._topo_faces[index])
        if dist.IsDone() and dist.Value() < best - tol.merge:
            best, best_id = float(dist.Value()), index + 1
        elif dist.IsDone() and abs(dist.Value() - best) <= tol.merge:
            best_id = min(best_id, index + 1)
    if best_id == 0 or best > max_distance:
        where = ", ".join(f"{c:.4f}" for c in p.tolist())
        nearest = f"face {best_id} at {best:.4f} mm" if best_id else "no face"
        raise ModelError(
            f"{model.path}: no face within {max_distance:.4f} mm of ({where}): "
            f"the nearest is {nearest}"
        )
    return model.faces[best_id - 1]


# --------------------------------------------------------------------------- output


def _num(value: float | None, decimals: int, width: int) -> str:
    """Fixed decimals right-aligned in ``width``; ``-`` for None; never ``-0.000``."""
    if value is None:
        return "-".rjust(width)
    text = f"{value:.{decimals}f}"
    return (f"{0.0:.{decimals}f}" if float(text) == 0.0 else text).rjust(width)


_TABLE_HEADER = (
    f"{'id':>4}  {'type':<10}  {'side':<5}  {'radius':>10}  {'minor':>10}  {'angle':>8}  "
    f"{'origin x':>10} {'y':>10} {'z':>10}  {'axis x':>9} {'y':>9} {'z':>9}  {'area':>13}"
)


def features_table(model: Model) -> str:
    """Return a fixed-width text table of the faces, byte-for-byte repeatable.

    Lengths have 4 decimals, the cone half angle is in degrees, axes have 6 decimals,
    areas 3; ``side`` is ``inner``/``outer`` for revolved analytic faces.
    """
    rows = [_TABLE_HEADER]
    for f in model.faces:
        side = {True: "inner", False: "outer", None: "-"}[f.inner]
        angle = None if f.half_angle is None else math.degrees(f.half_angle)
        rows.append(
            f"{f.id:>4}  {f.type:<10}  {side:<5}  {_num(f.radius, 4, 10)}  "
            f"{_num(f.minor_radius, 4, 10)}  {_num(angle, 4, 8)}  "
            f"{' '.join(_num(c, 4, 10) for c in f.origin)}  "
            f"{' '.join(_num(c, 6, 9) for c in f.axis)}  {_num(f.area, 3, 13)}"
        )
    return "\n".join(rows) + "\n"

