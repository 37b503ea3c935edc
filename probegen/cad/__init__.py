"""The CAD boundary: STEP loading, face records, face picking and tessellation.

This is the only module of probegen that imports build123d / OCP.  Everything it hands
out is plain Python (floats and tuples, millimetres and radians) except the private
shape handle inside :class:`Model`, which only functions of this module use.
"""

from __future__ import annotations

import faulthandler
import io
import math
import os
import pickle
import re
import signal
import traceback
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import NoReturn, cast

import numpy as np
import trimesh
from build123d import Compound, Shape
from OCP.BinTools import BinTools
from OCP.Bnd import Bnd_Box
from OCP.BRep import BRep_Tool
from OCP.BRepAdaptor import BRepAdaptor_Surface
from OCP.BRepBndLib import BRepBndLib
from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeVertex
from OCP.BRepExtrema import BRepExtrema_DistShapeShape
from OCP.BRepGProp import BRepGProp
from OCP.BRepLProp import BRepLProp_SLProps
from OCP.BRepMesh import BRepMesh_IncrementalMesh
from OCP.BRepTools import BRepTools
from OCP.GeomAbs import GeomAbs_SurfaceType as St
from OCP.gp import gp_Ax1, gp_Pnt
from OCP.GProp import GProp_GProps
from OCP.IFSelect import IFSelect_ReturnStatus
from OCP.Message import Message
from OCP.STEPControl import STEPControl_Reader
from OCP.TopAbs import TopAbs_FACE, TopAbs_Orientation
from OCP.TopExp import TopExp_Explorer
from OCP.TopLoc import TopLoc_Location
from OCP.TopoDS import TopoDS, TopoDS_Face, TopoDS_Shape

from probegen.constants import tol
from probegen.errors import ModelError

Vec3 = tuple[float, float, float]

STEP_HEADER = "ISO-10303-21;"
STEP_TERMINATOR = "END-ISO-10303-21;"

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

_UNIT_ENTITY = re.compile(r"StepBasic_\w*Unit\w*")


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
    """

    path: str
    faces: tuple[FaceRecord, ...]
    bbox_min: Vec3
    bbox_max: Vec3
    _shape: Shape = field(repr=False, compare=False)
    _topo_faces: tuple[TopoDS_Face, ...] = field(repr=False, compare=False)


# --------------------------------------------------------------------------- loading


def load_step(path: str | os.PathLike[str]) -> Model:
    """Read a STEP file into a :class:`Model` in millimetres.

    Where ``os.fork`` exists the OCCT reader runs in a child process: some corrupt
    files (a 2-D CARTESIAN_POINT used as a vertex) crash OCCT outright, and that must
    end in a :class:`ModelError`, not end the program.

    Args:
        path: the STEP file; messages quote it exactly as given.

    Returns:
        The model, one :class:`FaceRecord` per face, in a stable face order.

    Raises:
        ModelError: the file is missing, empty, not STEP, truncated, corrupt, crashes
            the reader, or holds no faces.
    """
    name = os.fspath(path)
    _check_file(name)
    brep, records = _isolated(name)
    shape = TopoDS_Shape()
    BinTools.Read_s(shape, io.BytesIO(brep))
    faces = tuple(_unique_faces(shape))
    if len(faces) != len(records):
        raise RuntimeError(f"{name}: {len(records)} faces read, {len(faces)} after the copy")
    corners = np.array([(*r.bbox_min, *r.bbox_max) for r in records])
    lo, hi = _vec3(corners[:, :3].min(axis=0)), _vec3(corners[:, 3:].max(axis=0))
    return Model(name, records, lo, hi, Compound(shape), faces)


def _check_file(name: str) -> None:
    """Check existence, size, header and terminator of a STEP file before OCCT sees it."""
    file = Path(name)
    if not file.exists():
        raise ModelError(f"{name}: no such file")
    if not file.is_file():
        raise ModelError(f"{name}: not a regular file: expected a STEP file")
    try:
        size = file.stat().st_size
        with file.open("rb") as stream:
            head = stream.read(256)
            stream.seek(max(size - 256, 0))
            tail = stream.read()
    except OSError as exc:
        raise ModelError(f"{name}: cannot read file ({exc.strerror})") from None
    if size == 0:
        raise ModelError(f"{name}: file is empty (0 bytes)")
    first = head.removeprefix(b"\xef\xbb\xbf").lstrip().split(b"\n", 1)[0].strip()
    if not first.startswith(STEP_HEADER.encode()):
        raise ModelError(
            f"{name}: not a STEP file: expected '{STEP_HEADER}' on the first line, "
            f"found '{_show(first[:40])}'"
        )
    last = tail.rstrip(b" \t\r\n\x00\x1a")
    if not last.endswith(STEP_TERMINATOR.encode()):
        raise ModelError(
            f"{name}: truncated STEP file ({size} bytes): expected '{STEP_TERMINATOR}' "
            f"at the end, found '{_show(last[-40:])}'"
        )


def _show(raw: bytes) -> str:
    """Bytes as printable ASCII, anything else escaped as ``\\xNN``."""
    return "".join(ch if " " <= ch <= "~" else f"\\x{ord(ch):02x}" for ch in raw.decode("latin-1"))


_Loaded = tuple[bytes, tuple[FaceRecord, ...]]


def _isolated(name: str) -> _Loaded:
    """Run :func:`_load` in a forked child; a child killed by a signal is a ModelError."""
    if not hasattr(os, "fork"):
        return _load(name)
    read_end, write_end = os.pipe()
    pid = os.fork()
    if pid == 0:  # the child never returns and never runs the parent's exit handlers
        os.close(read_end)
        faulthandler.disable()  # a crash here is reported by the parent, not dumped
        null = os.open(os.devnull, os.O_WRONLY)
        os.dup2(null, 1)
        os.dup2(null, 2)
        try:
            reply: tuple[str, object] = ("ok", _load(name))
        except ModelError as exc:
            reply = ("error", str(exc))
        except BaseException:
            reply = ("bug", traceback.format_exc())
        with os.fdopen(write_end, "wb") as pipe:
            pickle.dump(reply, pipe)
        os._exit(0)
    os.close(write_end)
    with os.fdopen(read_end, "rb") as pipe:
        data = pipe.read()
    _, status = os.waitpid(pid, 0)
    if not data:
        how = signal.Signals(os.WTERMSIG(status)).name if os.WIFSIGNALED(status) else "exit"
        raise ModelError(
            f"{name}: the STEP reader crashed ({how}): expected STEP data OCCT can transfer,"
            " found data that kills it (check the file with a STEP validator)"
        )
    kind, value = pickle.loads(data)
    if kind == "error":
        raise ModelError(value)
    if kind == "bug":
        raise RuntimeError(f"loading {name} failed in the reader process:\n{value}")
    return cast(_Loaded, value)


def _load(name: str) -> _Loaded:
    """Read and transfer the model; return its BRep bytes and its face records."""
    shape = _read_shape(name)
    faces = _unique_faces(shape)
    if not faces:
        raise ModelError(f"{name}: empty shape: expected at least one face, found none")
    records = []
    for index, face in enumerate(faces, start=1):
        try:
            records.append(_record(index, face))
        except Exception as exc:
            _reraise_occt(f"{name}: face {index}", exc)
    brep = io.BytesIO()
    BinTools.Write_s(shape, brep)
    return brep.getvalue(), tuple(records)


def _reraise_occt(where: str, exc: Exception) -> NoReturn:
    """Turn an OCCT exception (geometry OCCT refuses) into a ModelError; re-raise others."""
    if isinstance(exc, ModelError):
        raise ModelError(f"{where}: {exc}") from None
    if not type(exc).__module__.startswith("OCP"):
        raise exc
    raise ModelError(
        f"{where}: OCCT raised {type(exc).__name__}: expected consistent STEP geometry, "
        f"found '{' '.join(str(exc).split())}'"
    ) from None


@contextmanager
def _quiet_occt() -> Iterator[None]:
    """Keep OCCT's reader chatter off stdout; the messages we raise say it better."""
    messenger = Message.DefaultMessenger_s()
    printers = list(messenger.Printers())
    for printer in printers:
        messenger.RemovePrinter(printer)
    try:
        yield
    finally:
        for printer in printers:
            messenger.AddPrinter(printer)


def _read_shape(name: str) -> TopoDS_Shape:
    """Run OCCT's STEP reader and check every status it returns."""
    reader = STEPControl_Reader()
    reader.SetSystemLengthUnit(1.0)  # OCCT scales lengths to this unit: 1.0 = mm
    try:
        with _quiet_occt():
            status = reader.ReadFile(name)
            if status != IFSelect_ReturnStatus.IFSelect_RetDone:
                raise ModelError(
                    f"{name}: the STEP reader failed ({status.name}): expected a readable "
                    "ISO-10303-21 exchange structure"
                )
            _check_parsed(name, reader)
            if (roots := reader.NbRootsForTransfer()) == 0:
                raise ModelError(
                    f"{name}: no shape to transfer: expected at least one product or shape "
                    f"representation, found none among {reader.StepModel().NbEntities()} "
                    "entities"
                )
            transferred = reader.TransferRoots()
            shape = reader.OneShape()
    except ModelError:
        raise
    except Exception as exc:
        _reraise_occt(name, exc)
    if transferred == 0 or shape.IsNull():
        raise ModelError(
            f"{name}: transfer failed: expected a shape from {roots} root entities, found none"
        )
    return shape


def _check_parsed(name: str, reader: STEPControl_Reader) -> None:
    """Refuse syntax errors, dangling ``#`` references and ill-typed parameters.

    OCCT transfers such data regardless and crashes on the null reference left behind
    (seen with a deleted ORIENTED_EDGE and with ``(65)`` for ``(#65)``).  Failures on
    unit entities are let through: real files carry them (NIST CTC 2, 5 and FTC 9
    write ``*`` for derived unit dimensions) and the reader falls back safely.
    """
    model = reader.StepModel()
    check = model.GlobalCheck()
    found = [" ".join(check.CFail(i).split()) for i in range(1, check.NbFails() + 1)]
    checks = reader.WS().ModelCheckList()
    checks.Start()
    while checks.More():
        number = checks.Number()  # 0 is the global check, already counted
        kind = model.Value(number).DynamicType().Name() if number > 0 else ""
        if number > 0 and checks.Value().NbFails() and not _UNIT_ENTITY.fullmatch(kind):
            found.append(f"DATA entity {number} ({kind}): {checks.Value().CFail(1)}")
        checks.Next()
    if found:
        raise ModelError(
            f"{name}: corrupt STEP data: expected every entity to parse, with every "
            "#reference resolved to an entity of the right type, found "
            f"{len(found)} error(s), the first: {found[0]}"
        )


def _unique_faces(shape: TopoDS_Shape) -> list[TopoDS_Face]:
    """Faces of ``shape`` in explorer order, each shared face once."""
    seen: dict[int, list[TopoDS_Shape]] = {}
    faces: list[TopoDS_Face] = []
    explorer = TopExp_Explorer(shape, TopAbs_FACE)
    while explorer.More():
        item = explorer.Current()
        same = seen.setdefault(hash(item), [])
        if not any(item.IsSame(other) for other in same):
            same.append(item)
            faces.append(TopoDS.Face(item))
        explorer.Next()
    return faces


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


def tessellate(model: Model, tolerance: float = 0.01) -> trimesh.Trimesh:
    """Triangulate the model for collision checks.

    Any earlier triangulation is discarded first, so the mesh depends on ``tolerance``
    alone.  Triangles are wound so that their normals point out of the part.

    Args:
        model: the loaded model.
        tolerance: largest chordal deviation from the exact surface, mm.

    Returns:
        The mesh in mm, vertices along face borders merged and degenerate triangles
        dropped, so that a closed solid gives a watertight mesh.  ``metadata["face_ids"]``
        holds, for each triangle, the id of the model face it came from.
    """
    shape = model._shape.wrapped
    BRepTools.Clean_s(shape)
    BRepMesh_IncrementalMesh(shape, tolerance, False, 0.5, False)
    vertices: list[np.ndarray] = []
    triangles: list[np.ndarray] = []
    ids: list[np.ndarray] = []
    for record, face in zip(model.faces, model._topo_faces, strict=True):
        nodes, tris = _face_mesh(face)
        triangles.append(tris + sum(len(v) for v in vertices))
        vertices.append(nodes)
        ids.append(np.full(len(tris), record.id, dtype=np.int64))
    mesh = trimesh.Trimesh(np.concatenate(vertices), np.concatenate(triangles), process=True)
    face_ids = np.concatenate(ids)
    if len(face_ids) != len(mesh.faces):
        raise ModelError(f"{model.path}: tessellation lost triangles while merging vertices")
    keep = mesh.nondegenerate_faces()  # slivers at sphere poles, cone apexes
    mesh.update_faces(keep)
    mesh.remove_unreferenced_vertices()
    mesh.metadata["face_ids"] = face_ids[keep]
    return mesh


def _face_mesh(face: TopoDS_Face) -> tuple[np.ndarray, np.ndarray]:
    """Nodes (n, 3) float and triangles (m, 3) int of one meshed face, located."""
    location = TopLoc_Location()
    poly = BRep_Tool.Triangulation_s(face, location)
    if poly is None:
        return np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64)
    trsf = location.Transformation()
    nodes = [_xyz(poly.Node(i).Transformed(trsf)) for i in range(1, poly.NbNodes() + 1)]
    tris = np.array([poly.Triangle(i).Get() for i in range(1, poly.NbTriangles() + 1)]) - 1
    if face.Orientation() == TopAbs_Orientation.TopAbs_REVERSED:
        tris = tris[:, [0, 2, 1]]
    return np.array(nodes).reshape(-1, 3), tris.reshape(-1, 3).astype(np.int64)
