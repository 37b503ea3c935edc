"""The tilted working plane of the virtual control: ``G68.2``, ``G53.1``, ``G69`` (Fanuc)
and ``G268``, ``G253``, ``G269`` (Haas NGC, read as the Fanuc codes), on a trunnion
table (A tilts the table about machine X, or B about Y; C turns it about the table's own
axis).

Conventions (docs/sim.md, "Tilted working plane"):

* ``G68.2 X Y Z I J K``: the feature coordinate system, origin ``(X, Y, Z)`` in work
  coordinates (absolute, even under G91; an omitted word is 0) and Euler angles
  ``R = Rz(I)·Rx(J)·Rz(K)`` (deg), exactly :func:`probegen.ir.frames.from_euler_zxz`:
  a program point ``p`` is the work point ``origin + R·p``.  The block does not move.
  ``P``, ``Q`` or ``R`` words (other angle forms; Haas's ``Q``: another Euler order)
  are alarm 9010.  G68.2 and G53.1 each stand in a block of their own (alarm 9010).
* ``G53.1``: the rotary axes turn so that the tool axis (machine +Z, the spindle is
  vertical) is the frame's +Z.  An A/C table (``Settings.tilt_axis`` "A") turns by
  ``T = Rx(A)·Rz(C)`` with ``A = -J``, ``C = -I`` (then ``T·R = Rz(K)``); a B/C table by
  ``T = Ry(B)·Rz(C)`` with ``B = -J``, ``C = 90 - I``.  When the tilt axis's travel
  (``Settings.tilt_range``) does not hold that angle, the other solution (``+J``, C a
  half turn further); neither: alarm :data:`OUT_OF_TRAVEL`.  C is taken in (-180, 180].
  When the tool is along the frame's +Z already (a frame turned about Z only, or the
  table left there), nothing turns.
  The table turns about its pivot (``Settings.table_pivot``, machine coordinates) with
  the linear axes standing still; the machine checks the ball's path
  (:meth:`TiltMachine.tilt`).
* Machine position under a frame: ``m = P + T·(q - P) + (0, 0, tool length)`` with
  ``q = (origin + R·p + work offset) · unit`` (the control knows where its rotary axes
  stand); without a frame (after ``G69``) the table's turn is not in the mapping: the
  axes go where the numbers say, as on a control without tool centre point control.
* Position variables under a frame (``#5001``-, ``#5041``-, ``#5061``-) read feature
  coordinates, as under G68 (:mod:`probegen.sim.macrob.motion`); ``#5021``- the machine.
* A G31 is alarm :data:`NOT_ALONG_FRAME` when the tool axis is not the frame's +Z (a
  G68.2 without its G53.1, or a frame changed since), and :data:`TURNED_WITHOUT_FRAME`
  when the table is turned and no frame is in force (the skip position would not be in
  the part's coordinates).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

from probegen.ir.frames import IDENTITY, Rotation, apply, apply_t, from_euler_zxz
from probegen.sim.alarms import SimAlarm
from probegen.sim.macrob.base import UNSUPPORTED, Machine, Point, alarm

NOT_ALONG_FRAME = 9020
"""Alarm: a probing move under G68.2 with the tool axis not along the frame's +Z."""
TURNED_WITHOUT_FRAME = 9021
"""Alarm: a probing move with the table turned and no feature coordinate system."""
ALONG = 1e-9
"""Largest difference between the tool axis and the frame's +Z (unit vectors)."""
OUT_OF_TRAVEL = 9022
"""Alarm: no angle within the tilt axis's travel brings the tool along the frame."""
TILT_CODE, TOOL_AXIS_CODE = 682, 531
"""G68.2 and G53.1 in tenths."""


@dataclass(frozen=True, slots=True)
class FeatureFrame:
    """A ``G68.2`` feature coordinate system.

    Attributes:
        origin: work coordinates of its origin, program unit.
        euler: ``(I, J, K)``, deg.
        rotation: ``Rz(I)·Rx(J)·Rz(K)``: its columns are the frame's axes in work
            coordinates.
    """

    origin: tuple[float, float, float]
    euler: tuple[float, float, float]
    rotation: Rotation

    @classmethod
    def of(cls, origin: tuple[float, float, float],
           euler: tuple[float, float, float]) -> FeatureFrame:
        """The frame of a G68.2 block's words."""
        return cls(origin, euler, from_euler_zxz(*euler))

    def to_work(self, p: list[float]) -> list[float]:
        """Feature coordinates → work coordinates."""
        q = apply(self.rotation, (p[0], p[1], p[2]))
        return [q[i] + self.origin[i] for i in range(3)]

    def to_frame(self, w: list[float]) -> list[float]:
        """Work coordinates → feature coordinates."""
        o = self.origin
        return list(apply_t(self.rotation, (w[0] - o[0], w[1] - o[1], w[2] - o[2])))

    def tool_angles(self, axis: str = "A",
                    travel: tuple[float, float] | None = None) -> dict[str, float]:
        """The trunnion angles ``G53.1`` turns to, deg (module docstring): on an A/C
        table ``A = -J, C = -I``, on a B/C table ``B = -J, C = 90 - I``; when the tilt
        axis's ``travel`` does not hold that, the other solution (tilt ``+J``, C a half
        turn further); neither: alarm :data:`OUT_OF_TRAVEL`."""
        i, j = self.euler[0], self.euler[1]
        c0 = -i if axis == "A" else 90.0 - i
        for tilt, c in ((-j, c0), (j, c0 + 180.0)):
            if travel is None or travel[0] - 1e-9 <= tilt <= travel[1] + 1e-9:
                return {axis: _clean(tilt), "C": _clean(_half_turn(c))}
        low, high = travel or (0.0, 0.0)
        raise SimAlarm(OUT_OF_TRAVEL, f"G53.1: NO {axis} WITHIN {low:g}..{high:g} "
                       f"(THE TILT AXIS'S TRAVEL) REACHES THE FRAME I{i:g} J{j:g}")


def _clean(x: float) -> float:
    return x + 0.0  # no -0.0


def _half_turn(c: float) -> float:
    """``c`` in (-180, 180]."""
    c = math.fmod(c, 360.0)
    return c - 360.0 if c > 180.0 else c + 360.0 if c <= -180.0 else c


def table_rotation(angles: dict[str, float]) -> Rotation:
    """``T = Rx(A)·Rz(C)`` (an A/C table) or ``Ry(B)·Rz(C)`` (B/C): table frame →
    machine directions (deg)."""
    c = math.radians(angles["C"])
    cc, sc = math.cos(c), math.sin(c)
    if "A" in angles:
        a = math.radians(angles["A"])
        ca, sa = math.cos(a), math.sin(a)
        return ((cc, -sc, 0.0), (ca * sc, ca * cc, -sa), (sa * sc, sa * cc, ca))
    b = math.radians(angles["B"])
    cb, sb = math.cos(b), math.sin(b)
    return ((cb * cc, -cb * sc, sb), (sc, cc, 0.0), (-sb * cc, sb * sc, cb))


def turned(angles: dict[str, float]) -> bool:
    """Whether the table stands anywhere but at zero."""
    return any(v != 0.0 for v in angles.values())


def describe(angles: dict[str, float]) -> str:
    """``A-90 C-90``."""
    return " ".join(f"{k}{v:g}" for k, v in angles.items())


def table_to_machine(q: list[float], rotation: Rotation, pivot: Point) -> list[float]:
    """A table-frame point (mm) where the turned table carries it, machine mm."""
    r = apply(rotation, (q[0] - pivot[0], q[1] - pivot[1], q[2] - pivot[2]))
    return [r[i] + pivot[i] for i in range(3)]


def machine_to_table(m: Point | list[float], rotation: Rotation,
                     pivot: Point) -> list[float]:
    """The inverse of :func:`table_to_machine`."""
    r = apply_t(rotation, (m[0] - pivot[0], m[1] - pivot[1], m[2] - pivot[2]))
    return [r[i] + pivot[i] for i in range(3)]


def on_table(point: Point, sense: int, lift: float, rotation: Rotation,
             pivot: Point) -> Point:
    """A table-frame point (mm) where the turned table carries it (``sense`` 1), or back
    (-1); the tool length ``lift`` (mm) stays along the machine's Z."""
    p = [point[0], point[1], point[2] - lift]
    q = table_to_machine(p, rotation, pivot) if sense > 0 else machine_to_table(
        p, rotation, pivot)
    return q[0], q[1], q[2] + lift


def frame_of_block(addr: dict[str, tuple[float, bool]],
                   length: Callable[[float, bool], float],
                   angle: Callable[[float, bool], float]) -> FeatureFrame:
    """The frame of a G68.2 block's words (``length``/``angle`` read a value as
    written: an integer literal counts input increments)."""
    extra = [a for a in "PQR" if a in addr]
    if extra:
        raise alarm(UNSUPPORTED, f"G68.2 WITH {''.join(extra)} (ONLY X Y Z I J K: EULER "
                    "ANGLES ZXZ)")
    x, y, z = (length(*addr[a]) if a in addr else 0.0 for a in "XYZ")
    i, j, k = (angle(*addr[a]) if a in addr else 0.0 for a in "IJK")
    return FeatureFrame.of((x, y, z), (i, j, k))


def turn_table(frame: FeatureFrame | None, machine: Machine, start: dict[str, float],
               at: Point, travel: tuple[float, float] | None) -> dict[str, float]:
    """G53.1: turn the table (``machine.tilt``) from ``start`` to the frame's angles with
    the linear axes at ``at``; return the angles."""
    if frame is None:
        raise alarm(UNSUPPORTED, "G53.1 WITHOUT G68.2")
    tilt = getattr(machine, "tilt", None)
    if tilt is None:
        raise alarm(UNSUPPORTED, "G53.1: THE MACHINE HAS NO TILTING TABLE")
    if along_frame(frame, table_rotation(start)):
        return dict(start)  # the tool is along the frame's Z already: nothing turns
    end = frame.tool_angles(next(a for a in start if a != "C"), travel)
    if end != start:
        tilt(dict(start), end, at)
    return end


def tool_axis_in_work(rotation: Rotation) -> tuple[float, float, float]:
    """The tool axis (machine +Z) in table (work) directions under table turn ``rotation``."""
    return apply_t(rotation, (0.0, 0.0, 1.0))


def along_frame(frame: FeatureFrame, rotation: Rotation) -> bool:
    """Whether the tool axis is the frame's +Z (within :data:`ALONG`)."""
    tool = tool_axis_in_work(rotation)
    z = (frame.rotation[0][2], frame.rotation[1][2], frame.rotation[2][2])
    return max(abs(tool[i] - z[i]) for i in range(3)) <= ALONG


def check_probing(frame: FeatureFrame | None, angles: dict[str, float],
                  rotation: Rotation) -> None:
    """Refuse a probing move the tilted plane makes wrong (module docstring)."""
    if frame is not None and not along_frame(frame, rotation):
        i, j, k = frame.euler
        raise SimAlarm(NOT_ALONG_FRAME, f"PROBING UNDER G68.2 I{i:g} J{j:g} K{k:g} WITH THE "
                       f"TOOL AXIS NOT ALONG THE FRAME'S Z (TABLE {describe(angles)}): "
                       "G53.1 MISSING")
    if frame is None and turned(angles):
        raise SimAlarm(TURNED_WITHOUT_FRAME, f"PROBING WITH THE TABLE TURNED "
                       f"({describe(angles)}) AND NO G68.2: THE SKIP POSITION "
                       "WOULD NOT BE IN THE PART'S COORDINATES")


class TiltMachine(Machine, Protocol):
    """A machine with a trunnion table: the control calls :meth:`tilt` for G53.1."""

    def tilt(self, start: dict[str, float], end: dict[str, float], at: Point) -> None:
        """Turn the table from ``start`` to ``end`` (``{"A": deg, "C": deg}``, machine
        angles, linear in angle) with the linear axes at ``at`` (machine mm)."""
        ...


__all__ = ["IDENTITY", "FeatureFrame", "TiltMachine", "along_frame", "check_probing",
           "frame_of_block", "machine_to_table", "on_table", "table_rotation",
           "table_to_machine", "turn_table", "turned"]
