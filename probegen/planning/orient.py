"""Probe orientations and styli (issue 17): which orientation of the machine reaches an
approach direction, the ``ir.Orient`` node of it, the ``ir.SelectStylus`` node of a
stylus (which stylus: :func:`probegen.planning.styli.pick_stylus`, re-exported here), and
the order of the (stylus, orientation) groups of a program.

Conventions:

* The approach direction ``a`` is a unit vector in work coordinates from the feature
  outwards, towards where the probe comes from; the frame of ``a`` is
  :func:`probegen.ir.frames.frame_for` (frame +Z = ``a``), one convention for every
  machine.  A feature is planned in that frame on ``part.turned(R)`` exactly as a
  vertical-probe feature is today.
* A CMM's indexable head (``machine.head``): ``A`` is the angle of the stylus from straight
  down (0: vertical, 90: horizontal), ``B`` the azimuth about the vertical, counter-clockwise
  seen from above, with ``B = 0`` pointing the stylus towards -Y, in ``(-180, 180]``.
  The approach direction (from the ball towards the head) is then
  ``a = (-sin A·sin B, sin A·cos B, cos A)``: ``A90B0`` probes faces facing +Y,
  ``A90B-90`` faces facing +X, ``A90B90`` faces facing -X, ``A90B180`` faces facing -Y.
  The DMIS dialect writes these angles as ``SNSDEF/PROBE,INDEX,POL,A,B,...``.  Both angles
  must lie on the head's ``step`` grid (within :data:`GRID_SNAP` deg) and in its ranges.
  An approach between the grid's indexes is taken at the nearest index (both angles
  snapped, within the ranges) when the stylus there stands at most
  :func:`tilt_bound` (:data:`TILT_OF_STEP` of the step) off the feature's axis, as a
  CMM programmer probes such a feature: the feature is planned in its own frame
  (:attr:`Orientation.exact`, touches along its normals) and probed with the stylus
  along the index's axis (:attr:`Orientation.rotation`).
* A five-axis machine's tilted work plane (``machine.tilt``): the tilt angle is the
  angle of ``a`` from +Z (G68.2 ``J``), within ``tilt_range`` (either sign: the rotary axis
  turns the other half round), the rotary angle any (G68.2 ``I``).
* The identity orientation is named ``A0B0`` on a head, ``TILT0`` on a tilt; other tilted
  planes ``TILT1``, ``TILT2`` ... in the order the program takes them.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Hashable, Sequence
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any

import numpy as np

from probegen import ir
from probegen.errors import CollisionError, PlanningError
from probegen.ir import frames
from probegen.machine.profile import Head, MachineProfile, Stylus
from probegen.planning.styli import pick_stylus as pick_stylus  # the one choice, re-exported

if TYPE_CHECKING:
    from probegen.cad import Part

GRID_SNAP = 1e-6
"""A head angle within this (deg) of the step grid is on it (snapped)."""
LEAST_GAP = 10.0
"""A frame's clearance level is at least this far above the turned part, mm."""
EXACT_ORDER = 7
"""Up to this many (stylus, orientation) groups are ordered by trying every order."""
TILT_OF_STEP = 0.5
"""A feature whose axis lies between a head's indexes is probed at the nearest index when
the stylus there stands at most this fraction of the head's step off the feature's axis
(half the step: 3.75 deg on a 7.5 deg head, the most a snap of the tilt angle A alone
leaves): the touches stay square to the feature's axis, the stylus is tilted from it.
Farther off (both angles between steps near the horizontal: up to 5.3 deg) the feature
is left out for a setup."""


@dataclass(frozen=True, slots=True)
class Orientation:
    """An orientation the machine takes: the frame's rotation and the machine's angles.

    Attributes:
        rotation: the frame (:func:`probegen.ir.frames.frame_for` of the approach; of the
            head index's approach when the head takes the nearest index).
        head: a CMM head's ``(A, B)``, deg, on its grid; None on a machine tool.
        rotary: the tilted plane's ``((tilt axis, J), (rotary axis, I))``, deg (G68.2
            ``J`` and ``I``); () on a CMM.
        exact: the frame of the approach itself when the head takes the nearest index
            off it (the feature is planned there, then its plan expressed in
            ``rotation``'s frame); None when ``rotation`` is the approach's frame.
    """

    rotation: frames.Rotation
    head: tuple[float, float] | None = None
    rotary: tuple[tuple[str, float], ...] = ()
    exact: frames.Rotation | None = None

    @property
    def plan_rotation(self) -> frames.Rotation:
        """The frame a feature is planned in: :attr:`exact` when set, else
        :attr:`rotation`."""
        return self.rotation if self.exact is None else self.exact

    @property
    def tilt(self) -> float:
        """The angle between the stylus (frame Z of :attr:`rotation`) and the approach
        (frame Z of :attr:`plan_rotation`), deg; 0 when they are one."""
        if self.exact is None:
            return 0.0
        return _angle(_column_z(self.rotation), _column_z(self.exact))

    @property
    def identity(self) -> bool:
        """Whether this is the vertical probe."""
        return frames.is_identity(self.rotation)

    @property
    def key(self) -> Hashable:
        """What tells two orientations apart (the rotation, rounded)."""
        return tuple(round(x, 9) + 0.0 for row in self.rotation for x in row)


def can_orient(machine: MachineProfile) -> bool:
    """Whether the machine turns its probe (a CMM head or a five-axis tilt)."""
    return machine.head is not None or machine.tilt is not None


def head_angles(a: ir.Vec3) -> tuple[float, float]:
    """The head's ``(A, B)`` (deg) of approach direction ``a`` (see the module docstring);
    ``B = 0`` for a vertical ``a``."""
    z = max(-1.0, min(1.0, a[2]))
    big_a = math.degrees(math.acos(z))
    if math.hypot(a[0], a[1]) < frames.VERTICAL:
        return big_a, 0.0
    big_b = math.degrees(math.atan2(-a[0], a[1])) + 0.0
    return big_a, (180.0 if big_b <= -180.0 + GRID_SNAP else big_b)


def head_direction(big_a: float, big_b: float) -> ir.Vec3:
    """The approach direction of head angles ``A``, ``B`` (deg): the inverse of
    :func:`head_angles` (:func:`probegen.ir.frames.head_approach`)."""
    return frames.head_approach(big_a, big_b)


def _on_grid(value: float, step: float) -> float | None:
    """``value`` snapped to the grid of ``step`` (deg), or None when it is off it."""
    k = round(value / step)
    return k * step + 0.0 if abs(value - k * step) <= GRID_SNAP else None


def orientation_for(machine: MachineProfile, a: ir.Vec3) -> Orientation | str:
    """The orientation of ``machine`` that probes along approach direction ``a`` (unit,
    work coordinates), or the reason none does, in words the user can act on."""
    rotation = frames.frame_for(a)
    if frames.is_identity(rotation):
        return identity_of(machine)
    if machine.head is not None:
        return _head(machine, a, rotation)
    if machine.tilt is not None:
        tilt = machine.tilt
        i, j, _ = frames.euler_zxz(rotation)
        reach = max(tilt.tilt_range[1], -tilt.tilt_range[0])
        if j > reach + GRID_SNAP:
            return (f"tilt {j:.1f} deg: beyond the {tilt.tilt_axis} axis's range "
                    f"{tilt.tilt_range[0]:g}..{tilt.tilt_range[1]:g}: needs a setup")
        return Orientation(rotation, None, ((tilt.tilt_axis, j), (tilt.rotary_axis, i)))
    return ("no orientation reaches this face: the probe stays vertical (add a [head] "
            "or [tilt] to the machine profile, or a setup)")


def _head(machine: MachineProfile, a: ir.Vec3, rotation: frames.Rotation
          ) -> Orientation | str:
    head = machine.head
    assert head is not None
    big_a, big_b = head_angles(a)
    if not head.a[0] - GRID_SNAP <= big_a <= head.a[1] + GRID_SNAP:
        return (f"axis at A {big_a:.1f} B {big_b:.1f}: beyond the head's A range "
                f"{head.a[0]:g}..{head.a[1]:g}: no orientation reaches this face: needs a "
                "setup")
    sa, sb = _on_grid(big_a, head.step), _on_grid(big_b, head.step)
    if sa is None or sb is None:
        return _nearest_index(machine, a, rotation)
    b = _b_in_range(head, sb)
    if b is None:
        return (f"axis at A {sa:g} B {sb:g}: beyond the head's B range "
                f"{head.b[0]:g}..{head.b[1]:g}: no orientation reaches this face: add "
                "the B range or a setup")
    return Orientation(rotation, (sa, b), ())


def tilt_bound(head: Head) -> float:
    """The largest angle (deg) the stylus at a head's index may stand off a feature's
    axis: :data:`TILT_OF_STEP` of the step."""
    return TILT_OF_STEP * head.step


def _b_in_range(head: Head, b: float) -> float | None:
    """Head angle ``B`` (deg) in the head's B range, turned by a whole turn if need be;
    None when no turn brings it in."""
    for value in (b, b - 360.0, b + 360.0):
        if head.b[0] - GRID_SNAP <= value <= head.b[1] + GRID_SNAP:
            return value + 0.0
    return None


def _grid_around(value: float, step: float) -> list[float]:
    """The grid values (deg) of ``step`` either side of ``value``, ascending."""
    low = math.floor(value / step)
    return sorted({low * step + 0.0, (low + 1) * step + 0.0})


def _nearest_index(machine: MachineProfile, a: ir.Vec3, rotation: frames.Rotation
                   ) -> Orientation | str:
    """The head's index nearest approach ``a`` (off its grid; ``rotation`` its frame):
    of the grid angles either side of ``A`` and ``B`` within the ranges, the one whose
    approach is closest in angle to ``a`` (``A0``: the vertical probe); the reason when
    none lies within :func:`tilt_bound`."""
    head = machine.head
    assert head is not None
    big_a, big_b = head_angles(a)
    where = f"axis at A {big_a:.1f} B {big_b:.1f}: not on the head's {head.step:g} deg grid"
    best: tuple[float, float, float] | None = None
    for ka in _grid_around(big_a, head.step):
        if not head.a[0] - GRID_SNAP <= ka <= head.a[1] + GRID_SNAP:
            continue
        for kb in ([0.0] if ka == 0.0 else _grid_around(big_b, head.step)):
            b = _b_in_range(head, kb)
            if b is None:
                continue
            tilt = _angle(a, head_direction(ka, b))
            if best is None or tilt < best[0] - 1e-12:
                best = (tilt, ka, b)
    if best is None:
        return (f"{where}: no index of the head's B range {head.b[0]:g}..{head.b[1]:g} "
                "beside it: add the B range or a setup")
    tilt, ka, b = best
    bound = tilt_bound(head)
    if tilt > bound + GRID_SNAP:
        return (f"{where}: the nearest index A{ka:g} B{b:g} stands {tilt:.1f} deg off the "
                f"axis, more than {bound:g} deg: needs a setup")
    index = frames.frame_for(head_direction(ka, b))
    if frames.is_identity(index):
        return replace(identity_of(machine), exact=rotation)
    return Orientation(index, (ka, b), (), rotation)


def _column_z(rotation: frames.Rotation) -> ir.Vec3:
    """A frame's Z axis in work coordinates (the rotation's third column)."""
    return (rotation[0][2], rotation[1][2], rotation[2][2])


def _angle(u: ir.Vec3, v: ir.Vec3) -> float:
    """The angle between unit vectors ``u`` and ``v``, deg (accurate near 0)."""
    cross = np.cross(u, v)
    return math.degrees(math.atan2(float(np.linalg.norm(cross)), float(np.dot(u, v))))


def identity_of(machine: MachineProfile) -> Orientation:
    """The vertical probe's orientation (head ``A0 B0``, tilt 0)."""
    if machine.head is not None:
        return Orientation(frames.IDENTITY, (0.0, 0.0), ())
    if machine.tilt is not None:
        t = machine.tilt
        return Orientation(frames.IDENTITY, None, ((t.tilt_axis, 0.0), (t.rotary_axis, 0.0)))
    return Orientation(frames.IDENTITY)


def _angle_text(value: float) -> str:
    """A head angle in a label: ``90``, ``M90``, ``37_5``."""
    text = f"{abs(value):.4f}".rstrip("0").rstrip(".").replace(".", "_")
    return ("M" if value < 0.0 else "") + text


def orient_name(o: Orientation, number: int) -> str:
    """The ``ir.Orient`` label: ``A90BM90`` on a head; ``TILT<number>`` on a tilt (the
    identity ``TILT0``); ``FRAME<number>`` otherwise."""
    if o.head is not None:
        return f"A{_angle_text(o.head[0])}B{_angle_text(o.head[1])}"
    if o.rotary:
        return f"TILT{0 if o.identity else number}"
    return "VERTICAL" if o.identity else f"FRAME{number}"


def orientation_label(o: Orientation) -> str:
    """A short text of an orientation for tables: ``A90BM90`` on a head, ``A45C90`` (the
    tilt and rotary angles) on a tilt, ``-`` for the vertical probe."""
    if o.identity:
        return "-"
    if o.head is not None:
        return orient_name(o, 0)
    return "".join(f"{axis}{_angle_text(round(angle, 3))}" for axis, angle in o.rotary)


def frame_clearance(part: Part | None, o: Orientation, clearance_z: float) -> float:
    """The clearance level (frame Z, mm) of orientation ``o``: the turned part's top plus
    the gap the spec's clearance plane ``clearance_z`` has above the part, at least
    :data:`LEAST_GAP`; ``clearance_z`` itself for the vertical probe."""
    if o.identity or part is None:
        return clearance_z
    gap = max(clearance_z - part.bbox_max[2], LEAST_GAP)
    return part.turned(o.rotation).bbox_max[2] + gap


def orient_node(o: Orientation, name: str, clearance_z: float) -> ir.Orient:
    """The ``ir.Orient`` of orientation ``o`` (origin at the work zero)."""
    return ir.Orient(name, o.rotation, (0.0, 0.0, 0.0), o.head, o.rotary, clearance_z)


def select_node(s: Stylus) -> ir.SelectStylus:
    """The ``ir.SelectStylus`` of stylus ``s``."""
    return ir.SelectStylus(s.label, s.tool_number, s.ball_diameter, s.shank_diameter,
                           s.length)


# ------------------------------------------------------- the moves of a change

LEVEL_SLACK = 1e-6
"""A position this far (mm) below a clearance level is at it."""


def to_frame(frame: ir.Orient | None, p: np.ndarray) -> np.ndarray:
    """Work point ``p`` in ``frame``'s coordinates (None: the work frame)."""
    return np.asarray(frames.to_frame(frame, (float(p[0]), float(p[1]), float(p[2]))))


def to_work(frame: ir.Orient | None, p: np.ndarray) -> np.ndarray:
    """Point ``p`` of ``frame`` in work coordinates (None: the work frame)."""
    return np.asarray(frames.to_work(frame, (float(p[0]), float(p[1]), float(p[2]))))


def index_height(top: float, length: float, ball: float, machine: MachineProfile) -> float:
    """The work Z where the probe changes orientation (or, on a CMM with a head, takes
    another stylus), mm: the top of what stands on the table (``top``, work Z: the
    part's, :func:`top_of`) plus the whole stylus (``length`` and ``ball`` radius, mm),
    the head's body on a CMM and the margin, so that the stylus clears the part's
    bounding box in every direction it turns to."""
    body = machine.head.body_length if machine.head is not None else 0.0
    return top + length + ball + body + machine.margin


def top_of(part: Part | None, spheres: Sequence[Any] = ()) -> float | None:
    """The work Z of the top of what stands on the table, mm: the part's bounding box;
    without a model the highest reference sphere of the sphere tests (``spheres``:
    :class:`probegen.planning.sphere_test.SphereTestPlan`, each with the distance its
    centre may be off when it is located); None when neither is known."""
    if part is not None:
        return float(part.bbox_max[2])
    tops = [p.sphere.centre[2] + p.sphere.diameter / 2.0
            + (p.feature.locate_uncertainty if p.feature.locate else 0.0) for p in spheres]
    return max(tops) if tops else None


def needs_index(node: ir.Node, machine: MachineProfile) -> bool:
    """Whether change ``node`` is taken at the index height: every ``Orient``, and a
    ``SelectStylus`` on a CMM with a head (the CMM leaves for its rack and comes back
    with another stylus turned as the head stands: clear of the part's bounding box
    only at the index height).  A machine tool's stylus change retracts along the tool
    axis and comes back to the same point at the clearance level (the dialect's
    ``G53 Z0`` ... ``G43 H Z``)."""
    return isinstance(node, ir.Orient) or (isinstance(node, ir.SelectStylus)
                                           and machine.head is not None)


def over_point(target: np.ndarray, height: float, rotation: frames.Rotation) -> np.ndarray:
    """Where the probe goes at the index height after a change, work coordinates: over
    ``target`` (the first point after the change, work coordinates) at work Z
    ``height``; when the new tool axis ``a`` (``rotation``'s frame Z) points below the
    horizontal, pushed out along ``a`` too, so that the point is as high in the frame as
    ``target`` (``target + u·ẑ + v·a`` with ``v = -u·a_z``, ``u = (height - z) / (1 -
    a_z²)``): the probe comes down to the over point from above the frame's clearance
    level whether it stands at the index point (a CMM head) or where the table's turn
    left it (a five-axis trunnion)."""
    a = np.array([rotation[0][2], rotation[1][2], rotation[2][2]])
    rise = max(height - float(target[2]), 0.0)
    if a[2] >= 0.0:
        return np.array([target[0], target[1], target[2] + rise])
    u = rise / (1.0 - a[2] * a[2])
    return np.asarray(target + u * np.array([0.0, 0.0, 1.0]) - u * a[2] * a)


def change_name(node: ir.Orient | ir.SelectStylus) -> str:
    """``orientation change to A90B90`` or ``stylus change to D2``."""
    if isinstance(node, ir.Orient):
        return f"orientation change to {node.name}"
    return f"stylus change to {node.label}"


def first_after(change: ir.Orient | ir.SelectStylus, frame: ir.Orient | None,
                 target: np.ndarray, part: Part | None, top: float, stylus: Any,
                 machine: MachineProfile, clear: float) -> None:
    """The first move after a change taken at the index height goes to a point at that
    height (the over point: the probe moves level at the index height, then down).
    ``target``: the move's target in ``frame``; ``top``: :func:`top_of` the part (an
    ``Orient`` needs ``part`` itself); ``stylus``: the collision check's
    (``ball`` radius and ``length``, mm); ``clear``: half the margin, mm.

    After a five-axis ``Orient`` (rotary axes, no head: the table turns under the
    spindle, and the dialect's length-offset block brings the probe down the new tool
    axis to the frame's clearance level at whatever point of the frame the turn left it
    over, ``G0 G43 H Z``) the over point and that level must also lie above the turned
    part's top by the ball and half the margin, so that any move between them is clear.

    Raises:
        PlanningError: the move goes below the index height.
        CollisionError: the five-axis levels are too low.
    """
    height = index_height(top, stylus.length, stylus.ball, machine)
    work = to_work(frame, target)
    if work[2] < height - LEVEL_SLACK:
        raise PlanningError(f"{change_name(change)}: the first move after it goes to work "
                            f"z = {work[2]:.3f}, expected the index height {height:.3f} "
                            "(the over point)")
    if not isinstance(change, ir.Orient) or change.head is not None or not change.rotary:
        return
    assert part is not None, "an Orient is checked against the part"
    floor = part.turned(change.rotation).bbox_max[2] + stylus.ball + clear
    for what, z in (("its clearance level", change.clearance_z),
                    ("the over point", float(target[2]))):
        if z < floor - LEVEL_SLACK:
            raise CollisionError(f"{change_name(change)}: {what} is at frame z = {z:.3f}, "
                                 f"expected {floor:.3f} or above (the turned part's top "
                                 "plus the ball and half the margin): the probe comes down "
                                 "the tool axis there after the table turns")


Group = tuple[str, Hashable]
"""A (stylus label, orientation key) group of features."""


def changes(order: Sequence[Group], start: Group, identity: Hashable) -> tuple[int, int]:
    """Stylus changes and orientation changes of visiting ``order`` from ``start``, then
    back to the identity orientation and the start stylus."""
    path = [start, *order, start]
    path[-1] = (start[0], identity)
    stylus = sum(1 for x, y in itertools.pairwise(path) if x[0] != y[0])
    orient = sum(1 for x, y in itertools.pairwise(path) if x[1] != y[1])
    return stylus, orient


def order_groups(groups: Sequence[Group], start: Group, identity: Hashable
                 ) -> tuple[Group, ...]:
    """``groups`` in the order with the fewest stylus and orientation changes
    (:func:`changes`, summed) from ``start`` and back; among equals the one closest to
    the given order.  Every order is tried up to :data:`EXACT_ORDER` groups; beyond,
    the nearest group next (fewest changes from the last one, given order on ties)."""
    def cost(order: Sequence[Group]) -> int:
        return sum(changes(order, start, identity))

    if len(groups) <= EXACT_ORDER:
        return min(itertools.permutations(groups), key=cost)
    left, out, here = list(groups), [], start
    while left:
        nxt = min(left, key=lambda g: (g[0] != here[0]) + (g[1] != here[1]))
        out.append(nxt)
        left.remove(nxt)
        here = nxt
    return tuple(out)
