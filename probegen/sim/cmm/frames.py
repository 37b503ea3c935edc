"""Coordinate systems of the virtual CMM: the part coordinate system (PCS) and its edits.

A :class:`Frame` is the active PCS as seen from the machine coordinate system (MCS):
``rotation`` holds the PCS unit axes as *rows* (expressed in MCS) and ``origin`` is the
PCS origin in MCS, so ``p_pcs = rotation @ (p_mcs - origin)``; :attr:`Frame.matrix`
is the same map as a 4x4 homogeneous transform (MCS -> PCS).  Every frame is
right-handed, as DMIS datums are.

The DMIS edits, all relative to the active frame:

* ``TRANS/XORIG,v``: the new origin lies at ``x = v`` of the current frame, so every
  x coordinate drops by ``v`` (``D(P)=TRANS/XORIG,355`` from the MCS puts the part
  origin at machine x 355).  ``TRANS/XORIG,FA(f)`` puts the origin at the feature: at
  its location's coordinate, or where the axis meets the plane for a plane feature.
* ``ROTATE/ZAXIS,a``: the axes turn by ``a`` about the current Z axis, right-handed
  (+X towards +Y); so coordinates of a fixed point turn by ``-a``.  ``ROTATE/ZAXIS,
  FA(f),XDIR`` turns until +X points along the feature's direction projected onto the
  current XY plane (``YDIR``: +Y does; ``-XDIR``: -X does).
* ``DATSET/DAT(a),ZDIR[,ZORIG][,DAT(b),XDIR[,XORIG]][,DAT(c)[,YORIG]]``: the primary
  datum's direction is the named axis; the secondary's direction, made square to it,
  is the second named axis; the third axis completes a right-handed frame.  With a
  primary alone the next axis in the cycle X -> Y -> Z -> X keeps the current frame's
  axis as nearly as possible.  ``?ORIG`` moves the origin along that new axis onto the
  datum; without any the origin stays where it is.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from probegen.geometry.frames import FloatArray, unit

AXES = {"X": 0, "Y": 1, "Z": 2}
"""Axis letter -> row index of :attr:`Frame.rotation`."""

_PARALLEL = 1e-9
"""Sines below this mean two directions are parallel (cannot define a frame)."""


class FrameError(ValueError):
    """A frame edit that is geometrically impossible (parallel datums, axis in a plane)."""


@dataclass(frozen=True, slots=True, eq=False)
class Frame:
    """A part coordinate system in machine coordinates (millimetres).

    Attributes:
        rotation: ``(3, 3)`` float, the PCS unit axes as rows, in MCS.
        origin: ``(3,)`` float, the PCS origin in MCS.
    """

    rotation: FloatArray
    origin: FloatArray

    @staticmethod
    def machine() -> Frame:
        """Return the machine coordinate system itself (``DATSET/MCS``)."""
        return Frame(np.eye(3), np.zeros(3))

    @property
    def matrix(self) -> FloatArray:
        """``(4, 4)`` float homogeneous transform taking MCS points to PCS points."""
        out = np.eye(4)
        out[:3, :3] = self.rotation
        out[:3, 3] = -self.rotation @ self.origin
        return out

    def to_pcs(self, point: FloatArray) -> FloatArray:
        """Return the PCS coordinates of the MCS point ``point : (3,) float``."""
        return np.asarray(self.rotation @ (point - self.origin), dtype=np.float64)

    def to_mcs(self, point: FloatArray) -> FloatArray:
        """Return the MCS coordinates of the PCS point ``point : (3,) float``."""
        return np.asarray(self.rotation.T @ point + self.origin, dtype=np.float64)

    def vector_to_pcs(self, vector: FloatArray) -> FloatArray:
        """Return the PCS components of the MCS direction ``vector : (3,) float``."""
        return np.asarray(self.rotation @ vector, dtype=np.float64)

    def vector_to_mcs(self, vector: FloatArray) -> FloatArray:
        """Return the MCS components of the PCS direction ``vector : (3,) float``."""
        return np.asarray(self.rotation.T @ vector, dtype=np.float64)

    def translated(self, axis: int, distance: float) -> Frame:
        """Return the frame whose origin moved ``distance`` mm along its own ``axis``."""
        return Frame(self.rotation, self.origin + distance * self.rotation[axis])

    def rotated(self, axis: int, angle: float) -> Frame:
        """Return the frame whose axes turned by ``angle`` rad about its own ``axis``."""
        j, k = (axis + 1) % 3, (axis + 2) % 3
        c, s = math.cos(angle), math.sin(angle)
        rows = self.rotation.copy()
        rows[j] = c * self.rotation[j] + s * self.rotation[k]
        rows[k] = -s * self.rotation[j] + c * self.rotation[k]
        return Frame(rows, self.origin)


def parse_direction(word: str) -> tuple[int, float]:
    """Return ``(axis index, sign)`` of ``XDIR``, ``-YDIR`` ... (``ValueError`` otherwise)."""
    sign = -1.0 if word.startswith("-") else 1.0
    letter = word.removeprefix("-").removesuffix("DIR")
    if letter not in AXES or not word.endswith("DIR"):
        raise ValueError(f"expected XDIR, YDIR or ZDIR (optionally negated), found {word!r}")
    return AXES[letter], sign


def alignment_angle(frame: Frame, axis: int, target: int, sign: float,
                    direction: FloatArray) -> float:
    """Angle (rad) to turn ``frame`` about ``axis`` so axis ``target`` follows ``direction``.

    Args:
        frame: the active frame.
        axis: index of the rotation axis.
        target: index of the axis to align; must differ from ``axis``.
        sign: ``-1`` to align the negative ``target`` axis instead.
        direction: ``(3,)`` MCS direction; only its part square to ``axis`` counts.

    Raises:
        FrameError: ``target == axis`` or ``direction`` is parallel to the rotation axis.
    """
    j, k = (axis + 1) % 3, (axis + 2) % 3
    if target not in (j, k):
        raise FrameError("the aligned axis must differ from the rotation axis")
    local = frame.vector_to_pcs(sign * direction)
    if math.hypot(local[j], local[k]) < _PARALLEL:
        raise FrameError("the feature's direction is parallel to the rotation axis")
    angle = math.atan2(local[k], local[j])
    return angle if target == j else angle - math.pi / 2.0


def frame_from_axes(placed: dict[int, FloatArray], current: Frame) -> FloatArray:
    """Complete one or two placed unit axes into a right-handed rotation (rows = axes).

    Args:
        placed: ``{axis index: (3,) MCS direction}`` in priority order, one or two
            entries; the second is made square to the first.
        current: the active frame; with one axis placed, the next axis in the cycle
            keeps the current frame's axis as nearly as possible.

    Raises:
        FrameError: the directions are parallel (no frame).
    """
    order = list(placed)
    first = order[0]
    rows = np.zeros((3, 3))
    rows[first] = unit(placed[first], what="datum direction")
    if len(order) == 1:
        second = (first + 1) % 3
        guess = current.rotation[second]
        if _square_part_norm(guess, rows[first]) < _PARALLEL:
            guess = np.cross(rows[first], current.rotation[(first + 2) % 3])
    else:
        second = order[1]
        guess = placed[second]
    if _square_part_norm(guess, rows[first]) < _PARALLEL:
        raise FrameError("the secondary datum's direction is parallel to the primary's")
    rows[second] = unit(guess - (guess @ rows[first]) * rows[first], what="datum direction")
    third = 3 - first - second
    rows[third] = np.cross(rows[(third + 1) % 3], rows[(third + 2) % 3])
    return rows


def _square_part_norm(vector: FloatArray, axis: FloatArray) -> float:
    """Length of the part of ``vector`` square to the unit ``axis``, relative to its length."""
    norm = float(np.linalg.norm(vector))
    if norm == 0.0:
        return 0.0
    return float(np.linalg.norm(vector - (vector @ axis) * axis)) / norm


def offset_to_plane(frame: Frame, axis: int, point: FloatArray, normal: FloatArray) -> float:
    """Distance along ``frame``'s ``axis`` from its origin to the plane (point, normal).

    Raises:
        FrameError: the axis lies in the plane (never meets it).
    """
    along = float(frame.rotation[axis] @ normal)
    if abs(along) < _PARALLEL:
        raise FrameError("the axis is parallel to the datum plane")
    return float((point - frame.origin) @ normal) / along


def offset_to_point(frame: Frame, axis: int, point: FloatArray) -> float:
    """Coordinate of the MCS ``point`` along ``frame``'s ``axis``."""
    return float(frame.rotation[axis] @ (point - frame.origin))
