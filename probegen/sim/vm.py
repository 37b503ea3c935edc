"""The virtual machine: the interpreters driving a machine with known errors and a part.

``VirtualMachine`` implements both the Macro B interpreter's ``Machine`` protocol and the
DMIS interpreter's ``Cmm`` protocol:

* every commanded position (the ball centre, in machine coordinates) goes through the
  kinematic error model (``machine.kinematics``) to where the ball really is;
* a positioning move (G0, G1, DMIS ``GOTO``) along which the ball meets the part raises
  the stylus-collision alarm 9100, naming the face;
* a skip move (G31, a DMIS ``PTMEAS``) stops where the ball first meets the part
  (``sim.contact``, exact on analytic faces), plus the probe's direction-dependent
  pre-travel and its noise (``machine.probe_model``); the skip position reported is the
  commanded position at that moment, as the control reads its own scales.  A pre-travel
  that runs past the end of the move means the trigger never came.

Frames: the part is placed in machine coordinates (``PlacedPart``).  The probe's length
offset is zero (the controlled point is the ball centre) and the control's G54 offset is
``work_offset`` (zero by default, when machine coordinates are work coordinates).

Trunnion table (G68.2 / G53.1, :mod:`probegen.sim.macrob.tilt`): the control turns the
table by ``T = Rx(A)·Rz(C)`` (or ``Ry(B)·Rz(C)``, ``tilt_axis``) about ``pivot`` (machine
coordinates) with :meth:`tilt`, within ``tilt_range``; the part is placed in the table
frame (machine coordinates with the table at zero), so the ball at machine
position ``m`` (after the linear axes' errors) is at ``pivot + Tᵀ·(m - pivot)`` on the
part.  The spindle stays vertical: pre-travel is looked up along the machine's axes.
The turn itself is checked like a rotary move (steps of :data:`ROTARY_STEP`).

Styli (issue 17): ``rack`` holds the styli a tool change may take
(``MachineProfile.styli()``).  ``T.. M6`` takes the stylus with that tool number
(:meth:`select_tool`; one not in the rack is alarm :data:`UNKNOWN_TOOL` naming it) and
its ball touches from then on; ``G43 H..`` must name the tool in the spindle
(:meth:`check_length`, alarm :data:`WRONG_LENGTH`).  A DMIS ``SNSLCT`` takes the rack's
stylus of the sensor's ball and turns it to the sensor's direction
(:meth:`select_sensor`).  With an empty rack (the default) the probe never changes, as
before.

Rotary axes (a ``five-axis-bc`` kinematics, method M4's machine): the part sits on the
C table, placed in the table frame (machine coordinates at ``C = 0``; see
``machine.kinematics``), so it turns with C; B tilts the head.  X, Y, Z command the
ball centre as it is at ``B = 0`` (the pivot is ``pivot_length`` above it; no
tool-centre-point control), so at a tilt the nominal ball centre is the commanded
point plus ``machine.kinematics.head_shift``.  The chain with its errors gives where the
ball really is in the table frame; contact and collision are found there.  A rotary move (G0/G1/G53
with B or C, the linear axes still) is followed in steps of at most
:data:`ROTARY_STEP` deg, each step a straight chord of the ball's path, and is a
collision (alarm 9100) if the ball meets the part.  Pre-travel is looked up in the probe
frame, which tilts with B.  A machine without rotary axes refuses B and C (alarm 9010).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from probegen.ir.frames import frame_for
from probegen.machine.kinematics import Machine, Topology
from probegen.machine.probe_model import ProbeModel, tilted_probe_frame
from probegen.machine.profile import Head, Stylus
from probegen.sim.alarms import SimAlarm
from probegen.sim.contact import ContactHit, PlacedPart
from probegen.sim.macrob.tilt import table_rotation
from probegen.sim.stem import probe_cylinders

Vec3 = tuple[float, float, float]

COLLISION_ALARM = 9100
"""Alarm number of a stylus collision during a positioning move."""
LEAVE_MARGIN = 1e-6
"""How clear (mm) a ball backing away from a touch must be before contact counts again."""
UNSUPPORTED_ALARM = 9010
"""Alarm number of a command the virtual machine does not model."""
UNKNOWN_TOOL = 9012
"""Alarm number of a tool change to a tool (or a DMIS sensor's ball) not in the rack."""
WRONG_LENGTH = 9013
"""Alarm number of a G43 H that is not the tool in the spindle (with a rack)."""
HEAD_INDEX = 9014
"""Alarm number of a DMIS sensor whose head angles the CMM's head cannot index."""
SENSOR_BALL = 1e-4
"""Largest difference, mm, between a DMIS sensor's ball diameter and a rack stylus's."""
STEM = True
"""Whether the shank and the probe body are checked (:mod:`probegen.sim.stem`) where the
machine knows them; False: the ball alone (the benchmark's baseline,
``benchmarks/bench_stem.py``)."""
ROTARY_STEP = 0.25
"""Largest rotary step (deg) between the points a rotary move is checked at; the chord
misses the ball's arc by at most ``L·(1 − cos(step/2))``: 0.7 µm at L = 300 mm."""


@dataclass
class VirtualMachine:
    """A machine (kinematics with errors), a probe and a placed part.

    Attributes:
        part: the part as placed in machine coordinates.
        probe: ball radius, pre-travel and noise.
        kinematics: the kinematic chain with its errors, or None for a perfect machine.
        touches: every skip hit so far (for tests and reports).
        on_touch: called with 1 after every skip hit (progress).
    """

    part: PlacedPart
    probe: ProbeModel
    kinematics: Machine | None = None
    touches: list[ContactHit] = field(default_factory=list)
    on_touch: Callable[[int], None] | None = None
    angles: dict[str, float] = field(default_factory=lambda: {"B": 0.0, "C": 0.0})
    """Machine angles of the rotary axes, deg."""
    rack: tuple[Stylus, ...] = ()
    """The styli a tool change or a DMIS SNSLCT may take; empty: the probe never changes."""
    stylus: Stylus | None = None
    """The stylus taken from the rack, or None: ``probe``'s ball."""
    stylus_axis: tuple[float, float, float] = (0.0, 0.0, 1.0)
    """Unit vector from the ball towards the head (a CMM head's orientation), work frame."""
    pivot: tuple[float, float, float] = (0.0, 0.0, 0.0)
    """Where the trunnion table's tilt and C axes meet, machine coordinates, mm."""
    head: Head | None = None
    """A CMM's indexable head (``[head]``): SNSDEF angles must be its indices; None: any."""
    tilt_axis: str = "A"
    """The trunnion's tilt axis: ``"A"`` (about X) or ``"B"`` (about Y)."""
    tilt_range: tuple[float, float] | None = None
    """The tilt axis's travel, deg (``[tilt] tilt_range``), or None: not limited."""
    table: dict[str, float] = field(default_factory=dict)
    """Trunnion table angles, deg (G53.1); empty: at zero."""
    start: Stylus | None = None
    """The stylus in the probe when the program starts (the profile's ``[probe]``
    stylus): its shank, and that of every stylus taken after it, is checked along every
    move with the probe body (:mod:`probegen.sim.stem`); None: the ball alone."""
    body: tuple[float, float] = (0.0, 0.0)
    """The probe body's diameter and length, mm (``[probe] body_diameter``,
    ``body_length``); (0, 0): no body checked."""

    @property
    def ball_radius(self) -> float:
        """The physical stylus ball radius, mm."""
        return self.stylus.ball_radius if self.stylus is not None else self.probe.ball_radius

    def select_tool(self, number: int) -> None:
        """``T.. M6``: take the rack's stylus with tool number ``number``."""
        if not self.rack:
            return
        found = next((s for s in self.rack if s.tool_number == number), None)
        if found is None:
            raise SimAlarm(UNKNOWN_TOOL, f"TOOL T{number} IS NOT IN THE RACK ({_rack(self.rack)})")
        self.stylus = found

    def check_length(self, h: int, tool: int) -> None:
        """``G43 H``: with a rack, ``h`` must be the tool in the spindle (a wrong length
        would put the ball off by the difference of the two styli)."""
        if self.rack and tool and h != tool:
            raise SimAlarm(WRONG_LENGTH, f"G43 H{h} WITH T{tool} IN THE SPINDLE: THE LENGTH "
                           "OFFSET OF ANOTHER TOOL")

    def select_sensor(self, label: str, ball_radius: float, axis: tuple[float, float, float],
                      angles: tuple[float, float] | None = None,
                      length: float | None = None) -> None:
        """A DMIS ``SNSLCT``: take the rack's stylus of ``ball_radius`` (mm; of two with
        that ball, the one of the sensor's ``length`` where one has it, else the first)
        and turn the head so that the stylus points along ``-axis`` (``axis``: unit,
        from the ball towards the head, work frame) at head ``angles`` (A, B, deg).
        Alarm :data:`UNKNOWN_TOOL` when no stylus of the rack has that ball,
        :data:`HEAD_INDEX` when the angles are outside the head's ranges or between its
        index steps."""
        balls = [s for s in self.rack if abs(s.ball_radius - ball_radius) <= SENSOR_BALL / 2.0]
        found = next((s for s in balls
                      if length is not None and abs(s.length - length) <= SENSOR_BALL),
                     balls[0] if balls else None)
        if found is None:
            raise SimAlarm(UNKNOWN_TOOL, f"SENSOR S({label}) D{2 * ball_radius:g}: NO STYLUS "
                           f"OF THIS BALL IN THE RACK ({_rack(self.rack)})")
        if angles is not None and self.head is not None and not _indexed(self.head, angles):
            h = self.head
            raise SimAlarm(HEAD_INDEX, f"SENSOR S({label}) A{angles[0]:g} B{angles[1]:g}: NOT "
                           f"AN INDEX OF THE HEAD (A {h.a[0]:g}..{h.a[1]:g}, B {h.b[0]:g}.."
                           f"{h.b[1]:g}, STEP {h.step:g})")
        self.stylus, self.stylus_axis = found, axis

    def tilt(self, start: dict[str, float], end: dict[str, float], at: Vec3) -> None:
        """G53.1: turn the trunnion table from ``start`` to ``end`` (deg, ``A`` or ``B``,
        and ``C``) with the linear axes at ``at``; alarm 9100 if the ball meets the part."""
        if self.rotary:
            raise SimAlarm(UNSUPPORTED_ALARM, "NOT SUPPORTED BY THE VIRTUAL MACHINE (G53.1 ON "
                           "THE B/C HEAD MACHINE: ITS ROTARY AXES ARE B AND C)")
        swept = max(abs(end[a] - start[a]) for a in end)
        steps = max(1, int(np.ceil(swept / ROTARY_STEP)))
        ball = self._linear(np.asarray(at, dtype=np.float64))
        turns = [{a: start[a] + k / steps * (end[a] - start[a]) for a in end}
                 for k in range(steps + 1)]
        path = [self._on_table(ball, t) for t in turns]
        axes = [self._probe_axis(t) for t in turns]
        for k in range(steps):
            a0, a1 = axes[k], axes[k + 1]
            self._clear_actual(path[k], path[k + 1], "TABLE TILT",
                               None if a0 is None or a1 is None else (a0, a1))
        self.table = dict(end)

    def _on_table(self, m: np.ndarray, angles: dict[str, float]) -> np.ndarray:
        """Machine point ``m`` in the table frame with the table at ``angles``."""
        if not any(angles.values()):
            return m
        t = np.asarray(table_rotation(angles))
        p = np.asarray(self.pivot, dtype=np.float64)
        return np.asarray(p + (m - p) @ t)

    def _linear(self, q: np.ndarray) -> np.ndarray:
        """Where the ball really is (machine frame) at linear axes ``q``, no rotary axes."""
        if self.kinematics is None:
            return q
        return np.asarray(self.kinematics.actual_tool_point(q, np.zeros(3)))

    @property
    def rotary(self) -> bool:
        """Whether the machine has the B and C axes."""
        return self.kinematics is not None and self.kinematics.topology is Topology.FIVE_AXIS_BC

    def actual(self, p: Vec3 | np.ndarray) -> np.ndarray:
        """Where the ball centre really is (table frame) when the linear axes are
        commanded to ``p`` (the rotary axes where they are)."""
        q = np.asarray(p, dtype=np.float64)
        if not self.rotary:
            return self._on_table(self._linear(q), self.table)
        assert self.kinematics is not None
        length = self.kinematics.pivot_length
        axes = [q[0], q[1], q[2] + length, np.radians(self.angles["B"]),
                np.radians(self.angles["C"])]
        return np.asarray(self.kinematics.actual_tool_point(axes, [0.0, 0.0, -length]))

    def rotate(self, start: dict[str, float], end: dict[str, float], at: Vec3) -> None:
        """Turn B and C (deg) with the linear axes at ``at``; alarm 9100 on contact."""
        if not self.rotary:
            raise SimAlarm(UNSUPPORTED_ALARM, "NOT SUPPORTED BY THE VIRTUAL MACHINE (AXIS "
                           f"{''.join(sorted(end))}: THE MACHINE HAS NO ROTARY AXES)")
        b0, c0 = start.get("B", self.angles["B"]), start.get("C", self.angles["C"])
        b1, c1 = end.get("B", b0), end.get("C", c0)
        swept = max(abs(b1 - b0), abs(c1 - c0))
        k = np.linspace(0.0, 1.0, max(1, int(np.ceil(swept / ROTARY_STEP))) + 1)
        assert self.kinematics is not None
        length = self.kinematics.pivot_length
        n = len(k)
        axes = np.column_stack([np.full(n, at[0]), np.full(n, at[1]), np.full(n, at[2] + length),
                                np.radians(b0 + k * (b1 - b0)), np.radians(c0 + k * (c1 - c0))])
        path = np.asarray(self.kinematics.actual_tool_point(axes, np.array([0.0, 0.0, -length])))
        for previous, current in zip(path[:-1], path[1:], strict=True):
            self._clear_actual(previous, current, "ROTARY")
        self.angles = {"B": b1, "C": c1}

    def probe_frame(self, direction: np.ndarray) -> np.ndarray:
        """A machine-frame direction in the probe frame (its z tilts with B, or is the
        CMM head's stylus axis)."""
        if self.rotary:
            return tilted_probe_frame(direction, float(self.angles["B"]))
        if self.stylus_axis == (0.0, 0.0, 1.0):
            return direction
        return np.asarray(direction @ np.asarray(frame_for(self.stylus_axis)))

    def _clear(self, start: Vec3, end: Vec3, what: str) -> None:
        self._clear_actual(self.actual(start), self.actual(end), what)

    def _clear_actual(self, start: np.ndarray, end: np.ndarray, what: str,
                      axes: tuple[np.ndarray, np.ndarray] | None = None) -> None:
        a, b = self._leave_contact(start, end)
        hit = self.part.first_contact(a, b, self.ball_radius)
        if hit is not None:
            x, y, z = (float(v) for v in hit.point)
            raise SimAlarm(COLLISION_ALARM, f"STYLUS COLLISION ({what}) WITH FACE "
                           f"{hit.face_id} AT X{x:.4f} Y{y:.4f} Z{z:.4f}")
        self._clear_stem(start, end, what, axes)

    def _probe_axis(self, table: dict[str, float] | None = None) -> np.ndarray | None:
        """The probe's axis (unit, from the ball towards the head) in the table frame,
        with the trunnion table at ``table`` (default: where it is); None where the
        stem is not checked (the B/C head machine, whose head tilts with B)."""
        if self.rotary:
            return None
        angles = self.table if table is None else table
        if any(angles.values()):  # the spindle vertical, the part turned with the table
            return np.asarray(np.array([0.0, 0.0, 1.0]) @ np.asarray(table_rotation(angles)))
        return np.asarray(self.stylus_axis, dtype=np.float64)

    def _clear_stem(self, start: np.ndarray, end: np.ndarray, what: str,
                    axes: tuple[np.ndarray, np.ndarray] | None = None) -> None:
        """Alarm 9100 if the shank or the probe body meets the part while the ball's
        centre moves from ``start`` to ``end`` (table frame) with the probe along
        ``axes`` (at the start and the end; default: the axis as it stands)."""
        stylus = self.stylus if self.stylus is not None else self.start
        stem = self.part.stem if stylus is not None and STEM else None
        if stem is None or stylus is None:
            return
        if axes is None:
            axis = self._probe_axis()
            if axis is None:
                return
            axes = (axis, axis)
        rotation = self.part.rotation
        cut = stem.cut(self.part.to_part(start), self.part.to_part(end),
                       axes[0] @ rotation, axes[1] @ rotation,
                       probe_cylinders(stylus.ball_radius, stylus.shank_diameter,
                                       stylus.length, *self.body))
        if cut is not None:
            x, y, z = (float(v) for v in start)
            raise SimAlarm(COLLISION_ALARM, f"{cut[0]} COLLISION ({what}) WITH FACE {cut[1]}"
                           f" (THE BALL FROM X{x:.4f} Y{y:.4f} Z{z:.4f})")

    def _leave_contact(self, a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Skip the first part of a move that backs a touching ball away from the part.

        After a trigger the ball sits on the surface (pre-travel deep, or a rounding error
        either side of it); a move away from the surface is free until the ball is clear,
        a move into it is a collision.
        """
        depth = -self.part.clearance(a, self.ball_radius)
        if depth < -LEAVE_MARGIN:  # clear; a ball within LEAVE_MARGIN still touches (a
            return a, b            # trigger point rounds to either side of the surface)
        hit = self.part.first_contact(a, b, self.ball_radius)
        length = float(np.linalg.norm(b - a))
        if hit is None or length == 0.0:
            return a, b
        away = float(np.dot((b - a) / length, hit.normal))
        if away <= 1e-3:
            return a, b
        s = min((depth + LEAVE_MARGIN) / away, length)
        return a + s * (b - a) / length, b

    def rapid(self, start: Vec3, end: Vec3) -> None:
        """G0: raises the collision alarm if the ball meets the part."""
        self._clear(start, end, "G0")

    def feed(self, start: Vec3, end: Vec3, feed_mm_min: float) -> None:
        """G1: raises the collision alarm if the ball meets the part."""
        self._clear(start, end, "G1")

    def move(self, start: Vec3, end: Vec3) -> None:
        """DMIS positioning move."""
        self._clear(start, end, "GOTO")

    def skip(self, start: Vec3, end: Vec3, feed_mm_min: float) -> Vec3 | None:
        """G31: the commanded position where the trigger registered, or None."""
        a, b = np.asarray(start, dtype=np.float64), np.asarray(end, dtype=np.float64)
        length = float(np.linalg.norm(b - a))
        if length == 0.0:
            return None
        from_, to = self.actual(a), self.actual(b)
        hit = self.part.first_contact(from_, to, self.ball_radius)
        self._clear_stem(from_, to if hit is None else hit.centre, "PROBING")
        if hit is None:
            return None
        delay = float(self.probe.noisy_offset(self.probe_frame((b - a) / length)))
        t = hit.t + delay / length
        if t > 1.0:
            return None
        self.touches.append(hit)
        if self.on_touch is not None:
            self.on_touch(1)
        p = a + t * (b - a)
        return (float(p[0]), float(p[1]), float(p[2]))

    def probe_move(self, start: Vec3, direction: Vec3, distance: float) -> Vec3 | None:
        """A DMIS probing move from ``start`` along ``direction`` for ``distance``."""
        d = np.asarray(direction, dtype=np.float64)
        end = np.asarray(start, dtype=np.float64) + distance * d / np.linalg.norm(d)
        return self.skip(start, (float(end[0]), float(end[1]), float(end[2])), 0.0)


def _indexed(head: Head, angles: tuple[float, float]) -> bool:
    """Whether the head indexes to ``angles`` (within its ranges, on its steps; 1e-6 deg)."""
    tol = 1e-6
    for value, (low, high) in zip(angles, (head.a, head.b), strict=True):
        steps = value / head.step
        if not (low - tol <= value <= high + tol and abs(steps - round(steps)) * head.step
                <= tol):
            return False
    return True


def _rack(rack: tuple[Stylus, ...]) -> str:
    """The rack in an alarm text: ``T20 D6 BALL 6, T21 D2 BALL 2`` (tool, label, ball
    diameter in mm)."""
    return ", ".join(f"T{s.tool_number} {s.label} BALL {s.ball_diameter:g}" for s in rack)


class CmmAdapter:
    """The ``Cmm`` face of a ``VirtualMachine`` for the DMIS interpreter (a VM with a rack
    is a CMM with an indexable head and those styli: it has ``select_sensor``)."""

    def __init__(self, vm: VirtualMachine) -> None:
        self.vm = vm
        self.select_sensor: Callable[..., None] | None = (
            vm.select_sensor if vm.rack else None)

    @property
    def ball_radius(self) -> float:
        """The physical stylus ball radius, mm."""
        return self.vm.ball_radius

    def move(self, start: Vec3, end: Vec3) -> None:
        """Positioning move; the collision alarm if the ball meets the part."""
        self.vm.move(start, end)

    def probe(self, start: Vec3, direction: Vec3, distance: float) -> Vec3 | None:
        """Probing move; the ball centre where the trigger registered, or None."""
        return self.vm.probe_move(start, direction, distance)


@dataclass(frozen=True, slots=True)
class SimResult:
    """What a simulated run produced.

    Attributes:
        output: exactly what the machine sends (the DPRNT log or the DMIS output file).
        alarm: ``"number message (line n)"`` when the run stopped on an alarm, else None.
        touches: how many skip moves touched the part.
        variables: Macro B only: the control's variables at the end (offsets as
            ``#5221``-, ``#10001``-, see ``macrob.RunResult``).
        rotation: Macro B only: the G68 rotation in force at the end, or None.
        report: DMIS only: statements skipped or executed with a note, one line each
            (``skipped <line>: <statement> (<reason>)``, ``note <line>: ...``).
    """

    output: str
    alarm: str | None
    touches: int
    variables: dict[int, float] = field(default_factory=dict)
    rotation: tuple[float, float, float] | None = None
    report: tuple[str, ...] = ()


HOME: Vec3 = (0.0, 0.0, 500.0)
"""Where the ball centre is when a simulated program starts: high above the part."""


def run_text(text: str, vm: VirtualMachine, *, kind: str, source: str = "<program>",
             tool: int = 20, home: Vec3 = HOME,
             work_offset: Vec3 = (0.0, 0.0, 0.0), control: str = "fanuc",
             feed_override: float = 100.0,
             program_dir: Path | None = None,
             answers: dict[str, str | int | float] | None = None) -> SimResult:
    """Run program text (``kind`` ``"macrob"``, ``"ngc"`` or ``"dmis"``) on ``vm``.

    Args:
        text: the program.
        vm: the machine, with the part placed in machine coordinates.
        kind: ``"macrob"`` (Fanuc Macro B), ``"ngc"`` (LinuxCNC rs274ngc: the output is
            what its ``(LOG,...)`` comments wrote) or ``"dmis"``.
        source: the file name for messages.
        tool: the probe's tool number (its length offset is set to 0).
        home: where the ball centre is when the program starts (machine coordinates).
        work_offset: the G54 offset the control holds (Macro B and LinuxCNC), mm.
        control: the Macro B control the machine has, a key of
            ``sim.macrob.base.CONTROLS`` (``"fanuc"``, ``"haas"``), or ``"linuxcnc"``
            (the text runs as ``kind="ngc"``; see :func:`program_control`).
        feed_override: the operator's feed override, percent (Macro B only: scales G1
            and G31 feeds while ``#3004`` does not hold it; the virtual clock).
        program_dir: where called subprograms ``O<n>.nc`` are looked for (a compact
            program's macro library); a subprogram found neither in the text nor there
            stops the run with alarm 76 naming it.  LinuxCNC: where ``o<name> call``
            finds ``<name>.ngc``.
        answers: a DMIS program's ``TEXT/QUERY`` answers by name (``--answers``).
    """
    if kind == "ngc" or control == "linuxcnc":
        return _run_ngc(text, vm, source=source, home=home, work_offset=work_offset,
                        feed_override=feed_override, program_dir=program_dir)
    if kind == "dmis":
        from probegen.sim.cmm.interpreter import run_dmis

        dres = run_dmis(text, CmmAdapter(vm), source=source, home=home, answers=answers)
        alarm = None if dres.alarm is None else _alarm_text(dres.alarm)
        report = tuple([f"skipped {s.line}: {s.text} ({s.reason})" for s in dres.skipped]
                       + [f"note {s.line}: {s.text} ({s.reason})" for s in dres.notes])
        return SimResult(dres.output, alarm, len(vm.touches), report=report)
    from probegen.sim.macrob.base import control_settings
    from probegen.sim.macrob.machine import run_program

    variables = {5221: work_offset[0], 5222: work_offset[1], 5223: work_offset[2],
                 11000 + tool: 0.0, 10000 + tool: 0.0}
    res = run_program(text, vm, source=source, variables=variables, program_dir=program_dir,
                      settings=control_settings(control, home=home,
                                                feed_override=feed_override,
                                                table_pivot=vm.pivot,
                                                tilt_axis=vm.tilt_axis,
                                                tilt_range=vm.tilt_range))
    alarm = None
    if res.alarm is not None:
        alarm = f"{res.alarm.number} {res.alarm.message} (line {res.alarm.line})"
    return SimResult(res.output, alarm, len(vm.touches), res.variables, res.rotation)


def _run_ngc(text: str, vm: VirtualMachine, *, source: str, home: Vec3, work_offset: Vec3,
             feed_override: float, program_dir: Path | None) -> SimResult:
    """Run rs274ngc text on the LinuxCNC control (``sim.ngc``); G54 holds ``work_offset``."""
    from probegen.sim.macrob.base import Settings
    from probegen.sim.ngc.interp import run_ngc

    res = run_ngc(text, vm, source=source, program_dir=program_dir,
                  parameters={5221: work_offset[0], 5222: work_offset[1],
                              5223: work_offset[2]},
                  settings=Settings(home=home, feed_override=feed_override))
    alarm = None if res.alarm is None else str(res.alarm)
    return SimResult(res.output, alarm, len(vm.touches), res.variables)


_TOOL_KINDS = ("H wear", "H geometry", "D wear", "D geometry")


def control_state(result: SimResult) -> list[str]:
    """What a Macro B run left in the control, one line each: work offsets that are not
    zero (``G54 X300.7958 Y199.6344 Z-99.7000``), tool offsets (``T12 D wear 0.0150``),
    the G68 rotation; for ``probegen sim`` (docs/actions.md)."""
    from probegen.sim.macrob.variables import EXTENDED, work_offset_slot

    sets: dict[int, dict[int, float]] = {}
    tools: list[str] = []
    for number, value in sorted(result.variables.items()):
        slot = work_offset_slot(number)
        if slot is not None and slot[1] < 3:
            sets.setdefault(slot[0], {})[slot[1]] = value
        elif 10001 <= number <= 13999:
            kind, tool = divmod(number - 10000, 1000)
            tools.append(f"T{tool} {_TOOL_KINDS[kind]} {value:.4f}")
    names = {0: "EXT", **{k: f"G{53 + k}" for k in range(1, 7)}}
    out = [" ".join([names.get(key, f"G54.1 P{key - EXTENDED + 1}"),
                     *(f"{'XYZ'[i]}{v:.4f}" for i, v in sorted(axes.items()))])
           for key, axes in sorted(sets.items())]
    out += tools
    if result.rotation is not None:
        cx, cy, r = result.rotation
        out.append(f"G68 X{cx:.4f} Y{cy:.4f} R{r:.6f}")
    return out


def _alarm_text(a: SimAlarm) -> str:
    line = f" (line {a.line})" if getattr(a, "line", None) else ""
    return f"{a.number} {a.message}{line}"


def program_kind(path: str | Path) -> str:
    """``"dmis"`` for .dmi/.dms/.dmis files, ``"ngc"`` for LinuxCNC's .ngc, else
    ``"macrob"``."""
    suffix = Path(path).suffix.lower()
    if suffix == ".ngc":
        return "ngc"
    return "dmis" if suffix in (".dmi", ".dms", ".dmis") else "macrob"


def program_control(path: str | Path) -> str:
    """The control a program file is for, by its name: ``"linuxcnc"`` for ``.ngc``,
    ``"haas"`` for the Haas dialect's ``.haas.nc``, else ``"fanuc"`` (``probegen sim
    --control`` overrides)."""
    name = Path(path).name.lower()
    if name.endswith(".ngc"):
        return "linuxcnc"
    return "haas" if name.endswith(".haas.nc") else "fanuc"
