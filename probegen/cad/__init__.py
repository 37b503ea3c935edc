"""The CAD boundary: STEP loading, face records, face picking and tessellation.

This is the only package of probegen that imports build123d / OCP.  Everything it hands
out is plain Python (floats and tuples, millimetres and radians) except the private
shape handle inside :class:`Model`, which only functions of this package use.

The public names are re-exported here from :mod:`probegen.cad.loading` (reading a STEP
file in a forked child process), :mod:`probegen.cad.faces` (face records and queries)
and :mod:`probegen.cad.mesh` (tessellation); :class:`~probegen.cad.part.Part`
(:mod:`probegen.cad.part`) is the model loaded once with its mesh and exact queries,
the object every stage after loading is handed.
"""

from __future__ import annotations

from probegen.cad.faces import (
    DEFAULT_PICK_DISTANCE,
    FACE_TYPES,
    FaceRecord,
    Model,
    Vec3,
    face_at,
    face_by_id,
    features_table,
)
from probegen.cad.loading import STEP_HEADER, STEP_TERMINATOR, load_step
from probegen.cad.mesh import tessellate
from probegen.cad.part import Part, Recent, load_part

__all__ = [
    "DEFAULT_PICK_DISTANCE",
    "FACE_TYPES",
    "STEP_HEADER",
    "STEP_TERMINATOR",
    "FaceRecord",
    "Model",
    "Part",
    "Recent",
    "Vec3",
    "face_at",
    "face_by_id",
    "features_table",
    "load_part",
    "load_step",
    "tessellate",
]
