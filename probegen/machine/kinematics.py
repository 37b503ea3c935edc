"""Kinematic chains: where the tool point really is, given the axis positions.

The chain runs from the **workpiece** to the **tool** and gives the pose of the tool
(spindle) frame in the workpiece frame as a product of 4x4 homogeneous transforms, one
per axis, each the nominal motion followed by that axis' error motion (relative, tool
to workpiece: see :mod:`probegen.machine.errors_model`).  Everything is computed with
full transforms (exact rotations); to first order the result is the sum of the error
terms with their Abbe offsets, spelled out for each topology below.

Topologies:

``vmc-xyfz`` (3-axis vertical machining centre, "W-X-Y-F-Z-T"): the workpiece sits on
the X table, which slides on the Y saddle, which slides on the bed; a fixed column
carries the Z head with the spindle.  Chain ``L_X(x)·L_Y(y)·L_Z(z)`` where
``L_j(q) = Trans(d_j·q)·Trans(δ_j(q))·Rot(ε_j(q))`` and ``d_j`` is the axis direction
with the squareness errors.  First order, with ``t`` the tool offset and
``ŷ = (0, y, 0)``, ``ẑ = (0, 0, z)``::

    e = δ_X + ε_X × (ŷ + ẑ + t) + δ_Y + ε_Y × (ẑ + t) + δ_Z + ε_Z × t
        + (S_xy·y + S_xz·z, S_yz·z, 0)

So the yaw of X shows up as ``−ε_zx·y`` in x and the pitch of Y as ``−ε_xy·(z + t_z)``
in y; the yaw of Y acts only through the tool offset (the X table does not ride on it
relative to the tool: it rides on the saddle, which the yaw turns as a whole).  The
rotation of a rigid body moves the point under the tool by ``ε × (tool − pivot)``, and
the tool's position relative to the saddle does not change with x.  Method M5's seed
(003) assumes a lever arm across the plane for the second axis of every plane (yaw of Y
from the lines at x10 and x11, and likewise for Z in XZ and YZ); on this layout those
line pairs differ by a constant only, and the Z axis' angles act through the tool
offset alone (``ε_Z × t``).  ``docs/m5.md`` derives the consequences (what a grating
plan can identify); :mod:`probegen.calibrate.identify_model` is this model, linearised.

``five-axis-bc`` (method M4's machine): the workpiece sits on a C rotary table on the
bed; X, Y, Z carry a B axis that tilts the spindle head.  Chain
``C(c)·L_X(x)·L_Y(y)·L_Z(z)·B(b)``.  X, Y, Z position the **pivot point** (the nominal
B axis point) and ``tool_offset`` runs from the pivot to the tool point at ``B = 0``
(e.g. ``(0, 0, -l1)``).  Sign conventions (ISO 841 style): ``+B`` turns the tool
right-handed about +Y, so the tool point ``(0, 0, -L)`` goes to
``(-L·sin b, 0, -L·cos b)``; ``+C`` turns the tool relative to the workpiece
right-handed about +Z (the table itself turns by ``-c``).  The workpiece frame is fixed
to the table with its origin on the actual C axis (where a part centred on the table
sits) and its axes parallel to the machine's at ``C = 0``.  Rotary location errors
(position-independent) turn each rotary axis about its actual line; at ``B = C = 0``
only the C-axis position shows: the tool point is off by ``-position_C``, i.e. by
``+δ`` along X (M4: ``x1 + δ = l1 + r1 + R1``).

Angles are radians, lengths mm.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from enum import StrEnum
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

from probegen.errors import ProbegenError
from probegen.files import Table, load_toml
from probegen.machine.errors_model import ErrorModel, FloatArray, read_errors


class Topology(StrEnum):
    """The machine layouts the kinematic model knows (see the module docstring)."""

    VMC = "vmc-xyfz"
    FIVE_AXIS_BC = "five-axis-bc"


AXES: dict[Topology, tuple[str, ...]] = {
    Topology.VMC: ("X", "Y", "Z"),
    Topology.FIVE_AXIS_BC: ("X", "Y", "Z", "B", "C"),
}
"""Axis order of each topology: the columns of an axis-position array."""

PLANES: dict[str, tuple[int, int, int]] = {"XY": (0, 1, 2), "XZ": (0, 2, 1), "YZ": (1, 2, 0)}
"""The machine's coordinate planes: name → (first axis, second axis, normal) as indices
into x, y, z (a planar grating in that plane reads along the first two)."""
PLANE_OUTWARD: dict[str, float] = {"XY": 1.0, "XZ": -1.0, "YZ": -1.0}
"""Sign, along each plane's normal axis, of the side a grating's reading head is on (the
plate lies on the other side): above an XY plate, in front (−Y) of an XZ plate, on the
−X side of a YZ plate."""

AxisInput = Mapping[str, ArrayLike] | ArrayLike


@dataclass(frozen=True)
class Machine:
    """A kinematic chain with its geometric errors.

    Attributes:
        topology: the machine layout.
        errors: the geometric errors (zero for a perfect machine).
        pivot_length: five-axis only: the distance from the B axis (the pivot point)
            down to the stylus ball centre at ``B = 0``, mm (method M4's ``l1``); the
            tool offset is then ``(0, 0, -pivot_length)``.
    """

    topology: Topology = Topology.VMC
    errors: ErrorModel = field(default_factory=ErrorModel.zero)
    pivot_length: float = 0.0

    @property
    def axes(self) -> tuple[str, ...]:
        """Axis names in the order of an axis-position array's columns."""
        return AXES[self.topology]

    def positions(self, axes: AxisInput) -> FloatArray:
        """Axis positions as an (n, k) array in :attr:`axes` order.

        Args:
            axes: a mapping from every axis name to a position or (n,) positions, or
                an array (k,) or (n, k).

        Raises:
            ProbegenError: an axis is missing or unknown, or the shapes disagree.
        """
        names = self.axes
        if isinstance(axes, Mapping):
            extra = sorted(set(axes) - set(names))
            missing = [n for n in names if n not in axes]
            if extra or missing:
                raise ProbegenError(f"{self.topology} axes: expected {', '.join(names)}, "
                                    f"missing {missing or '-'}, unknown {extra or '-'}")
            columns = np.broadcast_arrays(*(np.asanyarray(axes[n], dtype=np.float64)
                                            for n in names))
            q = np.stack([np.atleast_1d(c) for c in columns], axis=-1)
        else:
            q = np.atleast_2d(np.asanyarray(axes, dtype=np.float64))
        if q.ndim != 2 or q.shape[1] != len(names) or not np.all(np.isfinite(q)):
            raise ProbegenError(f"{self.topology} axes: expected finite positions of shape "
                                f"(n, {len(names)}), found shape {q.shape}")
        return q

    def tool_transforms(self, axes: AxisInput, *, actual: bool = True) -> FloatArray:
        """Poses of the tool frame in the workpiece frame.

        Args:
            axes: axis positions (see :meth:`positions`).
            actual: with the errors (True) or nominal (False).

        Returns:
            (n, 4, 4) float homogeneous transforms.
        """
        q = self.positions(axes)
        e = self.errors if actual else ErrorModel.zero()
        chain = _linear(e, q[:, 0], q[:, 1], q[:, 2])
        if self.topology is Topology.FIVE_AXIS_BC:
            chain = _rotary_c(e, q[:, 4]) @ chain @ _rotary_b(e, q[:, 3])
        return chain

    def actual_tool_point(self, axes: AxisInput, tool_offset: ArrayLike) -> FloatArray:
        """Where the tool point really is, in the workpiece frame.

        Args:
            axes: axis positions: a mapping or an array (k,) or (n, k).
            tool_offset: (3,) or (n, 3) float, from the spindle reference point (3-axis:
                the gauge point; five-axis: the B pivot) to the tool point, mm.

        Returns:
            (3,) float for a single position, else (n, 3) float, mm.
        """
        return self._point(axes, tool_offset, actual=True)

    def nominal_tool_point(self, axes: AxisInput, tool_offset: ArrayLike) -> FloatArray:
        """Where the tool point should be (no errors); shapes as :meth:`actual_tool_point`."""
        return self._point(axes, tool_offset, actual=False)

    def volumetric_error(self, axes: AxisInput, tool_offset: ArrayLike) -> FloatArray:
        """Actual minus nominal tool point, (3,) or (n, 3) float, mm."""
        return self.actual_tool_point(axes, tool_offset) - self.nominal_tool_point(
            axes, tool_offset)

    def nominal_axes(self, point: ArrayLike, tool_offset: ArrayLike, *, b: ArrayLike = 0.0,
                     c: ArrayLike = 0.0) -> FloatArray:
        """Axis positions that put the tool point at ``point`` on a perfect machine.

        Args:
            point: (3,) or (n, 3) float, workpiece frame, mm.
            tool_offset: (3,) float, mm.
            b, c: rotary positions (five-axis only), rad, scalar or (n,).

        Returns:
            (k,) or (n, k) float in :attr:`axes` order.
        """
        p = np.atleast_2d(np.asanyarray(point, dtype=np.float64))
        t = np.asanyarray(tool_offset, dtype=np.float64)
        single = np.ndim(point) == 1
        if self.topology is Topology.VMC:
            out = p - t
        else:
            bb, cc = np.broadcast_to(b, len(p)), np.broadcast_to(c, len(p))
            machine = np.einsum("nji,nj->ni", _rotation(np.array([0.0, 0.0, 1.0]), cc), p)
            tool = np.einsum("nij,nj->ni", _rotation(np.array([0.0, 1.0, 0.0]), bb),
                             np.broadcast_to(t, p.shape))
            out = np.column_stack([machine - tool, bb, cc])
        return np.asarray(out[0] if single else out)

    def _point(self, axes: AxisInput, tool_offset: ArrayLike, *, actual: bool) -> FloatArray:
        """Tool points through the actual or nominal chain (see :meth:`actual_tool_point`)."""
        chain = self.tool_transforms(axes, actual=actual)
        t = np.broadcast_to(np.asanyarray(tool_offset, dtype=np.float64), (len(chain), 3))
        out = np.einsum("nij,nj->ni", chain[:, :3, :3], t) + chain[:, :3, 3]
        return np.asarray(out[0] if _single(axes) and np.ndim(tool_offset) == 1 else out)


def head_shift(b_deg: float, pivot_length: float) -> tuple[float, float, float]:
    """``five-axis-bc``: the nominal ball centre less the commanded point at head tilt
    ``b_deg`` (deg), mm.

    X, Y, Z command the ball centre as it is at ``B = 0`` (the pivot ``pivot_length``
    above it, no tool-centre-point control); ``+B`` turns the tool right-handed about
    +Y through the pivot: ``(−L·sin b, 0, L·(1 − cos b))``.
    """
    b = math.radians(b_deg)
    return (-pivot_length * math.sin(b), 0.0, pivot_length * (1.0 - math.cos(b)))


def _single(axes: AxisInput) -> bool:
    """Whether ``axes`` names one machine position (not a batch)."""
    if isinstance(axes, Mapping):
        return all(np.ndim(v) == 0 for v in axes.values())
    return bool(np.ndim(axes) == 1)


# --------------------------------------------------------------------- transforms


def _rotation(axis: FloatArray, angle: ArrayLike) -> FloatArray:
    """Rotations by ``angle`` (n,) about the unit ``axis`` (3,) or (n, 3): (n, 3, 3)."""
    theta = np.asanyarray(angle, dtype=np.float64).reshape(-1)
    k = np.broadcast_to(axis, (len(theta), 3))
    return _rodrigues(k * theta[:, None])


def _rodrigues(vector: FloatArray) -> FloatArray:
    """Exact rotations for rotation vectors (n, 3): (n, 3, 3).

    First order this is ``I + [v]×``, the small-angle form the error model is stated in.
    """
    v = np.asanyarray(vector, dtype=np.float64)
    theta = np.linalg.norm(v, axis=1)
    small = theta < 1e-4
    safe = np.where(small, 1.0, theta)
    # sin(θ)/θ and (1 − cos θ)/θ², with series where θ is tiny (no cancellation)
    a = np.where(small, 1.0 - theta**2 / 6.0, np.sin(safe) / safe)
    b = np.where(small, 0.5 - theta**2 / 24.0, (1.0 - np.cos(safe)) / safe**2)
    k = np.zeros((len(v), 3, 3))
    k[:, 0, 1], k[:, 0, 2], k[:, 1, 2] = -v[:, 2], v[:, 1], -v[:, 0]
    k[:, 1, 0], k[:, 2, 0], k[:, 2, 1] = v[:, 2], -v[:, 1], v[:, 0]
    return np.eye(3) + a[:, None, None] * k + b[:, None, None] * (k @ k)


def _homogeneous(rotation: FloatArray, translation: FloatArray) -> FloatArray:
    """(n, 4, 4) transforms from rotations (n, 3, 3) and translations (n, 3)."""
    out = np.zeros((len(rotation), 4, 4))
    out[:, :3, :3] = rotation
    out[:, :3, 3] = translation
    out[:, 3, 3] = 1.0
    return out


def _linear(e: ErrorModel, x: FloatArray, y: FloatArray, z: FloatArray) -> FloatArray:
    """``L_X(x)·L_Y(y)·L_Z(z)`` for n positions: (n, 4, 4)."""
    chain = np.broadcast_to(np.eye(4), (len(x), 4, 4))
    for name, q in zip("XYZ", (x, y, z), strict=True):
        d, eps = e.axis(name).evaluate(q, e.scale)
        move = q[:, None] * e.direction(name) + d
        chain = chain @ _homogeneous(_rodrigues(eps), move)
    return np.asarray(chain)


def _about_line(point: FloatArray, direction: FloatArray, angle: FloatArray) -> FloatArray:
    """Rotations by ``angle`` (n,) about the line through ``point``: (n, 4, 4)."""
    rot = _rotation(direction / np.linalg.norm(direction), angle)
    shift = point - np.einsum("nij,j->ni", rot, point)
    return _homogeneous(rot, shift)


def _rotary_b(e: ErrorModel, b: FloatArray) -> FloatArray:
    """The B axis (tool side): turn by ``b`` about the actual B line, (n, 4, 4)."""
    axis = _rodrigues(e.b.tilt[None])[0] @ np.array([0.0, 1.0, 0.0])
    return _about_line(e.b.position, axis, b)


def _rotary_c(e: ErrorModel, c: FloatArray) -> FloatArray:
    """The C axis (workpiece side): machine frame → workpiece frame, (n, 4, 4).

    ``p_work = R(c about the actual C line)·(p_machine − position_C)``.
    """
    axis = _rodrigues(e.c.tilt[None])[0] @ np.array([0.0, 0.0, 1.0])
    rot = _rotation(axis / np.linalg.norm(axis), c)
    return _homogeneous(rot, -np.einsum("nij,j->ni", rot, e.c.position))


# ------------------------------------------------------------------------ loading


def load_machine(path: str | Path) -> Machine:
    """Load a machine (topology and errors) from TOML.

    The file has ``[kinematics] topology = "vmc-xyfz"`` (or ``"five-axis-bc"``, with
    ``pivot_length`` in mm: B axis to ball centre, see :attr:`Machine.pivot_length`) and an
    ``[errors]`` table (see :func:`probegen.machine.errors_model.load_errors`);
    ``samples/machines/errors-example.toml`` and ``five-axis-bc.toml`` are examples.

    Raises:
        SpecError: a missing or malformed file or key; the message names the key path.
    """
    root = Table(load_toml(path), str(path), "")
    k = root.table("kinematics", required=True)
    name = k.get_str("topology", required=True, choices=tuple(t.value for t in Topology))
    topology = Topology(name or Topology.VMC.value)
    pivot = 0.0
    if topology is Topology.FIVE_AXIS_BC:
        pivot = k.get_float("pivot_length", 0.0, minimum=0.0) or 0.0
    k.done()
    errors = read_errors(root.table("errors")) if root.has("errors") else ErrorModel.zero()
    root.done()
    return Machine(topology, errors, pivot)
