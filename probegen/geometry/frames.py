"""Frames and rotations: small numpy helpers shared by the fits and the planners.

Conventions: a rotation matrix ``R`` acts on column vectors (``R @ v``); for a batch of
row vectors ``points : (n, 3)`` the rotated batch is ``points @ R.T``.  A frame given as a
``(3, 3)`` matrix holds its unit axes as *rows* ``(e1, e2, e3)``, so the same matrix maps
world vectors into frame coordinates.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from probegen.errors import ProbegenError

FloatArray = NDArray[np.float64]

#: A half-turn about +X: maps +Z onto -Z and keeps +X.
HALF_TURN_X: FloatArray = np.diag([1.0, -1.0, -1.0])


def unit(vector: ArrayLike, *, what: str = "vector") -> FloatArray:
    """Return ``vector`` scaled to unit length.

    Args:
        vector: ``(3,)`` (or ``(2,)``) float, finite and not zero.
        what: name used in the error message.

    Returns:
        ``(3,)`` (or ``(2,)``) float unit vector.

    Raises:
        ProbegenError: the vector is zero, not finite or not 1-D.
    """
    v = np.asanyarray(vector, dtype=np.float64)
    if v.ndim != 1 or not np.all(np.isfinite(v)):
        raise ProbegenError(f"{what}: expected a finite 1-D vector, found {v!r}")
    scale = np.max(np.abs(v)) if v.size else 0.0
    if scale == 0.0:
        raise ProbegenError(f"{what}: expected a non-zero vector, found {v.tolist()}")
    w = v / scale  # pre-scaling keeps the norm free of overflow and underflow
    return np.asarray(w / np.linalg.norm(w), dtype=np.float64)


def _cross_matrix(k: FloatArray) -> FloatArray:
    """Return the ``(3, 3)`` matrix ``K`` with ``K @ v == cross(k, v)``."""
    return np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])


def rotation_to_z(vector: ArrayLike) -> FloatArray:
    """Return the proper rotation that takes the direction of ``vector`` onto +Z.

    The rotation is the shortest one (about ``vector x Z``) for directions in the upper
    half-space; for the lower half-space a half-turn about X is applied first, so the
    formula never divides by a small number.  Hence ``vector`` parallel to +Z gives the
    identity and ``vector`` antiparallel to +Z gives exactly the half-turn about X.

    Args:
        vector: ``(3,)`` float, finite, non-zero.

    Returns:
        ``(3, 3)`` float rotation ``R`` with ``R @ unit(vector) == (0, 0, 1)``; its rows
        are an orthonormal right-handed frame whose third axis is ``unit(vector)``.

    Raises:
        ProbegenError: ``vector`` is zero or not finite.
    """
    v = unit(vector, what="rotation_to_z")
    pre = np.eye(3)
    if v[2] < 0.0:
        pre = HALF_TURN_X
        v = pre @ v
    k = np.cross(v, (0.0, 0.0, 1.0))
    kx = _cross_matrix(k)
    rot = np.eye(3) + kx + (kx @ kx) / (1.0 + v[2])
    return np.asarray(rot @ pre, dtype=np.float64)


def orthonormal_basis(axis: ArrayLike) -> FloatArray:
    """Return a right-handed orthonormal frame whose third axis is ``axis``.

    Args:
        axis: ``(3,)`` float, finite, non-zero.

    Returns:
        ``(3, 3)`` float with rows ``(e1, e2, e3)``, ``e3 = unit(axis)``; the matrix maps
        world vectors into frame coordinates (``points @ basis.T``).  For ``axis = +Z``
        the frame is the world frame.

    Raises:
        ProbegenError: ``axis`` is zero or not finite.
    """
    return rotation_to_z(axis)
