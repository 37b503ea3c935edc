"""Tessellation of a loaded model into a triangle mesh for the collision check.

Owns :func:`tessellate`: OCCT's incremental mesher at a given chordal tolerance, each
face's triangles located and wound outwards, merged into one ``trimesh`` mesh that
records, per triangle, the id of the face it came from.

OCCT's mesher fails on some valid faces (a countersink cone of a SolidWorks export whose
parameter range starts at pi: no triangulation, status ``Failure``).  Such a face, when it
is its surface's whole rectangle of parameters (the face rebuilt on those bounds has the
face's area), is meshed from that rebuilt face instead (:func:`_rebuilt_face_mesh`), so
that no face of the part is missing from the collision check, the virtual machine's
contacts and the points check; its border nodes are not shared with its neighbours' (the
mesh may have a crack along it, never a hole).  A face that fails and is not such a
rectangle stays without triangles, as before.
"""

from __future__ import annotations

import numpy as np
import trimesh
from OCP.BRep import BRep_Tool
from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeFace
from OCP.BRepGProp import BRepGProp
from OCP.BRepMesh import BRepMesh_IncrementalMesh
from OCP.BRepTools import BRepTools
from OCP.GProp import GProp_GProps
from OCP.TopAbs import TopAbs_Orientation
from OCP.TopLoc import TopLoc_Location
from OCP.TopoDS import TopoDS_Face

from probegen.cad.faces import Model, _xyz
from probegen.errors import ModelError

CHORDAL_TOLERANCE = 0.01
"""Default largest chordal deviation of a mesh from the exact surface, mm."""
ANGULAR_DEFLECTION = 0.5
"""Largest angle between the normals of neighbouring triangles, rad (OCCT's ``angle``)."""
SAME_AREA = 1e-6
"""Relative area difference under which a face rebuilt on its parameter bounds is the
face (:func:`_rebuilt_face_mesh`)."""


def tessellate(model: Model, tolerance: float = CHORDAL_TOLERANCE) -> trimesh.Trimesh:
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
    BRepMesh_IncrementalMesh(shape, tolerance, False, ANGULAR_DEFLECTION, False)
    vertices: list[np.ndarray] = []
    triangles: list[np.ndarray] = []
    ids: list[np.ndarray] = []
    for record, face in zip(model.faces, model._topo_faces, strict=True):
        nodes, tris = _face_mesh(face)
        if not len(tris):
            nodes, tris = _rebuilt_face_mesh(face, tolerance)
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


def _area(face: TopoDS_Face) -> float:
    """The area of ``face``, mm^2."""
    props = GProp_GProps()
    BRepGProp.SurfaceProperties_s(face, props)
    return float(props.Mass())


def _rebuilt_face_mesh(face: TopoDS_Face, tolerance: float) -> tuple[np.ndarray, np.ndarray]:
    """Nodes and triangles of a face OCCT's mesher left without triangles, meshed as its
    surface on the face's parameter bounds when that rebuilt face has the face's area
    (within :data:`SAME_AREA`, relative): the face is that whole rectangle of
    parameters; nothing otherwise (see the module docstring)."""
    u0, u1, v0, v1 = BRepTools.UVBounds_s(face)
    maker = BRepBuilderAPI_MakeFace(BRep_Tool.Surface_s(face), u0, u1, v0, v1, 1e-7)
    none = np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64)
    if not maker.IsDone():
        return none
    rebuilt = maker.Face()
    area = _area(face)
    if abs(_area(rebuilt) - area) > SAME_AREA * max(area, 1.0):
        return none
    rebuilt.Orientation(face.Orientation())
    BRepMesh_IncrementalMesh(rebuilt, tolerance, False, ANGULAR_DEFLECTION, False)
    return _face_mesh(rebuilt)


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
