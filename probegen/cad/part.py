"""The part: a STEP model loaded once, with everything derived from it built once.

Owns :class:`Part` and :func:`load_part`.  A command (or a public entry such as
``planning.plan_program``) loads the part once and hands the object down to planning,
the collision check, post and the virtual machine; each of them asks the part for what
it needs (face records, a mesh at a chordal tolerance, exact face queries) and the part
builds it on first use and keeps it.  Values only one consumer needs (planning's
collision obstacle, its plans, the recognised revolved features) are kept with
:meth:`Part.memo`, so that no module keeps a cache of its own: what is derived from a part
lives and dies with the part.
"""

from __future__ import annotations

import os
from collections import OrderedDict
from collections.abc import Callable, Hashable
from dataclasses import dataclass, field, replace
from functools import cached_property
from typing import Any, TypeVar, cast

import numpy as np
import trimesh
from build123d import Compound
from OCP.Bnd import Bnd_Box
from OCP.BRepBndLib import BRepBndLib
from OCP.gp import gp_Trsf
from OCP.TopLoc import TopLoc_Location
from OCP.TopoDS import TopoDS, TopoDS_Face

from probegen.cad.exact import ExactFaces
from probegen.cad.faces import FaceRecord, Model, Vec3, _vec3, _xyz
from probegen.cad.loading import load_step
from probegen.cad.mesh import CHORDAL_TOLERANCE, tessellate

T = TypeVar("T")
Rotation = tuple[Vec3, Vec3, Vec3]
"""A rotation as rows (``probegen.ir.frames``): its columns are a frame's X, Y, Z axes in
work coordinates."""
TURN_KEY_DECIMALS = 9
"""A turned part is kept per rotation rounded to this many decimals (two rotations that
agree to 1e-9 are one frame)."""
RECENT_KEPT = 8
"""How many values of one kind :meth:`Part.recent` keeps: the most recently used (8:
NIST CTC 1 with the CMM plans in 8 frames; with 4 it built 26 height maps, not 8, and
planned 1.6 times slower; ``benchmarks/bench_recent_kept.py``)."""


class Recent:
    """Large values of one kind derived from a part, the :data:`RECENT_KEPT` most recently
    used kept, the others dropped (a value asked for again is built again: the same value,
    for values that are a function of their key alone).

    For what a part builds once per frame and cannot keep for every frame: planning turns
    the part into a frame per head index, tilt, setup and off-grid feature axis
    (:meth:`Part.turned`), and the height maps of each frame (up to 300 MB with their
    dilations) kept for every frame, with an FCL tree per frame (some 140 MB on NIST
    CTC 2, now built once and placed by each frame's rotation), went past 20 GB on
    CTC 2."""

    def __init__(self) -> None:
        self._values: OrderedDict[Hashable, Any] = OrderedDict()

    def __len__(self) -> int:
        return len(self._values)

    def values(self) -> list[Any]:
        """The values kept, the least recently used first."""
        return list(self._values.values())

    def get(self, key: Hashable, build: Callable[[], T]) -> T:
        """The value kept under ``key``, built by ``build()`` when it is not kept; then
        the least recently used dropped until :data:`RECENT_KEPT` are left."""
        hit = self._values.pop(key, None)
        if hit is None:
            hit = build()
        self._values[key] = hit
        while len(self._values) > RECENT_KEPT:
            self._values.popitem(last=False)
        return cast(T, hit)


@dataclass(frozen=True, eq=False)
class Part:
    """A loaded part model and what is derived from it, each built once on first use.

    Build it with :func:`load_part` (or ``Part(model)`` around a model already loaded).
    Equality and hashing are by identity: two loads of one file are two parts.

    Attributes:
        model: the loaded model (face records and the private shape handle).
    """

    model: Model
    _memo: dict[Hashable, Any] = field(default_factory=dict, init=False, repr=False)
    _turn: tuple[Part, Rotation] | None = field(default=None, repr=False)
    raised: float = 0.0
    """How far the part's lowest point stands above the machine table (a fixture,
    parallels), mm: the collision check keeps every stylus off the table that far below
    it (:mod:`probegen.planning.table`); 0: the part stands on the table."""

    @property
    def path(self) -> str:
        """The file path as the caller gave it (quoted in messages)."""
        return self.model.path

    @property
    def faces(self) -> tuple[FaceRecord, ...]:
        """The face records, ``faces[i].id == i + 1``."""
        return self.model.faces

    @property
    def bbox_min(self) -> Vec3:
        """Lower corner of the box around the faces, mm."""
        return self.model.bbox_min

    @property
    def bbox_max(self) -> Vec3:
        """Upper corner of the box around the faces, mm."""
        return self.model.bbox_max

    @property
    def warnings(self) -> tuple[str, ...]:
        """What was ignored while loading (:attr:`Model.warnings`)."""
        return self.model.warnings

    @cached_property
    def exact(self) -> ExactFaces:
        """Exact queries on the trimmed faces (in-face test, distance, boundary, inside)."""
        return ExactFaces(self.model)

    def mesh(self, tolerance: float = CHORDAL_TOLERANCE) -> trimesh.Trimesh:
        """The triangle mesh at chordal ``tolerance`` (mm), tessellated once per tolerance
        (:func:`probegen.cad.tessellate`); a turned part's is the original part's mesh
        turned (no second tessellation).  Shared: copy it before changing it."""
        if self._turn is not None:
            base, rotation = self._turn
            return self.memo(("mesh", tolerance),
                             lambda: _turned_mesh(base.mesh(tolerance), rotation))
        return self.memo(("mesh", tolerance), lambda: tessellate(self.model, tolerance))

    @property
    def rotation(self) -> Rotation | None:
        """The rotation of a turned part's frame (:meth:`turned`); None for a part as
        loaded."""
        return None if self._turn is None else self._turn[1]

    @property
    def original(self) -> Part:
        """The part as loaded (a turned part's original; the part itself otherwise)."""
        return self if self._turn is None else self._turn[0]

    def turned(self, rotation: Rotation) -> Part:
        """The same model in the frame of ``rotation``: every coordinate is
        ``p_frame = Rᵀ·p_work`` (:mod:`probegen.ir.frames`: the frame's +Z is the probe's
        tool axis), face ids unchanged.

        Kept on the original part per rotation (rounded to :data:`TURN_KEY_DECIMALS`):
        its mesh is the original mesh turned (no second tessellation), its exact queries
        run on the OCP shape moved by a location (no copy of the geometry), its face
        records are the original ones turned, each face's box taken again on the moved
        face (an axis-aligned box does not turn).  A turned part's own :meth:`turned`
        turns the original (the rotation is always from work coordinates).
        """
        base = self.original
        key = ("turned", tuple(round(x, TURN_KEY_DECIMALS) + 0.0
                               for row in rotation for x in row))
        return base.memo(key, lambda: Part(_turned_model(base.model, rotation),
                                           _turn=(base, rotation), raised=base.raised))

    def recent(self, kind: str) -> Recent:
        """The :class:`Recent` values of ``kind`` of the part as loaded and of all its
        turned parts together (kept on the original): at most :data:`RECENT_KEPT` of
        them alive whatever the number of frames."""
        return self.original.memo(("recent", kind), Recent)

    def memo(self, key: Hashable, build: Callable[[], T]) -> T:
        """The value kept under ``key``, built by ``build()`` the first time.

        For values derived from this part alone (plus the hashable inputs in ``key``):
        the consumer names its values by a key of its own (a tuple beginning with a
        name), the part keeps them as long as it lives.
        """
        if key not in self._memo:
            self._memo[key] = build()
        return cast(T, self._memo[key])


def _transpose_trsf(rotation: Rotation) -> gp_Trsf:
    """The OCCT transformation ``p -> Rᵀ·p``."""
    r = rotation
    trsf = gp_Trsf()
    trsf.SetValues(r[0][0], r[1][0], r[2][0], 0.0, r[0][1], r[1][1], r[2][1], 0.0,
                   r[0][2], r[1][2], r[2][2], 0.0)
    return trsf


def _turn(rotation: Rotation, v: Vec3) -> Vec3:
    """``Rᵀ·v``."""
    return _vec3(np.asarray(v, dtype=np.float64) @ np.asarray(rotation, dtype=np.float64))


def _turned_model(model: Model, rotation: Rotation) -> Model:
    """``model`` in the frame of ``rotation`` (see :meth:`Part.turned`)."""
    location = TopLoc_Location(_transpose_trsf(rotation))
    faces = tuple(TopoDS.Face(face.Moved(location)) for face in model._topo_faces)
    records = tuple(_turned_record(record, face, rotation)
                    for record, face in zip(model.faces, faces, strict=True))
    corners = np.array([(*r.bbox_min, *r.bbox_max) for r in records])
    lo, hi = _vec3(corners[:, :3].min(axis=0)), _vec3(corners[:, 3:].max(axis=0))
    shape = Compound(model._shape.wrapped.Moved(location))
    return Model(model.path, records, lo, hi, shape, faces, model.warnings)


def _turned_record(record: FaceRecord, face: TopoDS_Face, rotation: Rotation) -> FaceRecord:
    """A face record turned: points and directions by ``Rᵀ``, sizes and sides kept, the
    box taken on the moved face (exact geometry, as :func:`probegen.cad.faces._record`)."""
    box = Bnd_Box()
    BRepBndLib.AddOptimal_s(face, box, False, False)
    return replace(record, origin=_turn(rotation, record.origin),
                   axis=_turn(rotation, record.axis), centre=_turn(rotation, record.centre),
                   bbox_min=_xyz(box.CornerMin()), bbox_max=_xyz(box.CornerMax()))


def _turned_mesh(mesh: trimesh.Trimesh, rotation: Rotation) -> trimesh.Trimesh:
    """``mesh`` with every vertex ``v`` moved to ``Rᵀ·v``, its triangles and their face ids
    kept."""
    vertices = np.asarray(mesh.vertices) @ np.asarray(rotation, dtype=np.float64)
    turned = trimesh.Trimesh(vertices, np.asarray(mesh.faces), process=False)
    turned.metadata["face_ids"] = mesh.metadata["face_ids"]
    return turned


def load_part(path: str | os.PathLike[str], raised: float = 0.0) -> Part:
    """Read the STEP file ``path`` into a :class:`Part` (:func:`probegen.cad.load_step`),
    its lowest point ``raised`` mm above the machine table (:attr:`Part.raised`).

    Load it once, at the top (the command, or a public entry given a spec), and hand the
    part down.

    Raises:
        ModelError: the file is missing, not STEP, corrupt or holds no faces.
    """
    return Part(load_step(path), raised=raised)
