"""Finding a sphere whose position is known only roughly (see ``sphere_test``).

Two forms of the same idea:

* ``locate_runtime``: for controllers with run-time arithmetic (Fanuc Macro B).  Six
  touches (top, +X, -X, +Y, -Y, top) store skip positions in variables; the centre is
  computed on the control and the measuring touches are relative to it.
* ``locate_frame``: for DMIS.  Five touches at nominal positions measure a sphere
  ``<id>L``; the frame is translated onto its centre, and the measuring touches are
  given relative to that centre.

With a probe calibration (the machine's ``calibration``) each stored skip position is
moved by ``−(r(n) − r)`` along its touch's normal before it is used
(``compensate.calibrated_centres``, ``r`` the nominal ball radius the sequence offsets
by): a constant in the run-time expressions, so the centre the control finds, and a
sphere test's ``set_work_offset`` from it, carry the calibrated radius in each of the
six directions.

Every move of the locating sequence keeps ``u + d`` between the ball and the nominal
surface (``u`` the uncertainty, ``d`` the approach distance), so it is clear wherever
within ``u`` the sphere really is.
"""

from __future__ import annotations

import math

import numpy as np

from probegen import ir
from probegen.machine.calibration import calibrated_centres, for_stylus
from probegen.machine.profile import MachineProfile
from probegen.planning.sphere_test import SphereTestPlan, measure_body

_SIDES: tuple[tuple[str, ir.Vec3], ...] = (
    ("X1", (1.0, 0.0, 0.0)), ("X2", (-1.0, 0.0, 0.0)),
    ("Y1", (0.0, 1.0, 0.0)), ("Y2", (0.0, -1.0, 0.0)),
)


def _var(fid: str, name: str, offset: float = 0.0) -> ir.Var:
    return ir.Var(f"{fid}_{name}", offset)


def calibration_shift(machine: MachineProfile, normal: ir.Vec3) -> float:
    """How far the calibration moves a ball centre's coordinate on the axis of
    ``normal`` (unit, along X, Y or Z here): ``−(r(n) − r)·n``, mm; 0 without a
    calibration."""
    cal = for_stylus(machine.calibration, machine.probe.ball_radius, machine.source)
    if cal is None:
        return 0.0
    n = np.asarray([normal], dtype=np.float64)
    moved = calibrated_centres(np.zeros_like(n), n, cal, machine.probe.ball_radius)[0]
    return float(moved[int(np.argmax(np.abs(n[0])))]) + 0.0


class _Locator:
    """Builds the run-time locating sequence for one sphere test."""

    def __init__(self, plan: SphereTestPlan, machine: MachineProfile) -> None:
        self.plan = plan
        self.fid = plan.feature.id
        self.c = plan.sphere.centre
        self.radius = plan.sphere.diameter / 2.0
        self.r_off = self.radius + machine.probe.ball_radius
        self.u = plan.feature.locate_uncertainty
        self.approach = self.u + max(plan.retract, machine.probe.approach)
        # A touch may meet the sphere up to u early or late, and up to
        # R' - sqrt(R'^2 - 2u^2) late off the pole/equator: reach past all of it.
        slack = self.r_off - math.sqrt(max(self.r_off**2 - 2.0 * self.u**2, 0.0))
        self.overtravel = self.u + slack + machine.probe.overtravel
        self.z_high = self.c[2] + self.r_off + self.approach
        self.nodes: list[ir.Node] = []
        self.index = 0
        self.machine = machine

    def at(self, name: str, normal: ir.Vec3, offset: float = 0.0) -> ir.Var:
        """The stored skip position ``name`` of a touch along ``normal``, calibrated."""
        return _var(self.fid, name, offset + calibration_shift(self.machine, normal))

    def touch(self, contact: ir.Point, normal: ir.Vec3,
              store: tuple[str | None, str | None, str | None]) -> None:
        """Probe from ``approach`` off ``contact`` along ``-normal``, then retract."""
        self.index += 1
        start = tuple(c + (self.r_off - self.radius + self.approach) * n
                      for c, n in zip(contact, normal, strict=True))
        last = self.nodes[-1] if self.nodes else None
        if not (isinstance(last, ir.Move) and last.target == start):
            self.nodes.append(ir.Move(start, ir.MoveMode.PROTECTED))  # type: ignore[arg-type]
        names = tuple(None if s is None else f"{self.fid}_{s}" for s in store)
        self.nodes.append(ir.Touch(self.fid, self.index, ir.TouchRole.LOCATE, contact, normal,
                                   self.approach, self.overtravel, names))  # type: ignore[arg-type]
        self.nodes.append(ir.Move(start, ir.MoveMode.RETRACT))  # type: ignore[arg-type]

    def up(self) -> None:
        """Rise to the height where every sideways move clears the sphere."""
        last = self.nodes[-1]
        assert isinstance(last, ir.Move)
        if last.target[2] != self.z_high:
            self.nodes.append(ir.Move((last.target[0], last.target[1], self.z_high),
                                      ir.MoveMode.PROTECTED))

    def side(self, name: str, normal: ir.Vec3, x: ir.Coord, y: ir.Coord) -> None:
        """Touch one side at the estimated centre height, through (x, y)."""
        ze = _var(self.fid, "ZE")
        k = self.r_off + self.approach
        out_x = x + k * normal[0] if normal[0] else x
        out_y = y + k * normal[1] if normal[1] else y
        self.nodes.append(ir.Move((out_x, out_y, self.z_high), ir.MoveMode.PROTECTED))
        contact = (x + self.radius * normal[0], y + self.radius * normal[1], ze)
        store = (name, None, None) if normal[0] else (None, name, None)
        self.touch(contact, normal, store)
        self.up()


def locate_runtime(plan: SphereTestPlan, machine: MachineProfile,
                   clearance: float) -> tuple[ir.Node, ...]:
    """Locate the sphere on the control, then measure around the found centre."""
    lo = _Locator(plan, machine)
    cx, cy, cz = lo.c
    fid = lo.fid
    lo.nodes.append(ir.Comment(f"LOCATE {fid}"))
    lo.nodes.append(ir.Move((cx, cy, clearance), ir.MoveMode.RAPID))
    lo.nodes.append(ir.Move((cx, cy, lo.z_high), ir.MoveMode.PROTECTED))
    lo.touch((cx, cy, cz + lo.radius), (0.0, 0.0, 1.0), (None, None, "Z1"))
    up = (0.0, 0.0, 1.0)
    lo.nodes.append(ir.Assign(f"{fid}_ZE", lo.at("Z1", up, -lo.r_off)))
    for name, normal in _SIDES[:2]:
        lo.side(name, normal, cx, cy)
    lo.nodes.append(ir.Assign(f"{fid}_CX", lo.at(*_SIDES[0]), lo.at(*_SIDES[1])))
    for name, normal in _SIDES[2:]:
        lo.side(name, normal, _var(fid, "CX"), cy)
    lo.nodes.append(ir.Assign(f"{fid}_CY", lo.at(*_SIDES[2]), lo.at(*_SIDES[3])))
    lo.nodes.append(ir.Move((_var(fid, "CX"), _var(fid, "CY"), lo.z_high),
                           ir.MoveMode.PROTECTED))
    lo.touch((_var(fid, "CX"), _var(fid, "CY"), cz + lo.radius), (0.0, 0.0, 1.0),
             (None, None, "Z2"))
    lo.nodes.append(ir.Assign(f"{fid}_CZ", lo.at("Z2", up, -lo.r_off)))
    centre = (_var(fid, "CX"), _var(fid, "CY"), _var(fid, "CZ"))
    lo.nodes.append(ir.ReportCentre(fid, centre))
    lo.nodes.append(ir.Comment(f"MEASURE {fid}"))
    body = measure_body(plan, centre, lo.z_high, machine, clearance)
    return (*lo.nodes, ir.FeatureBlock(_sphere_def(plan, plan.sphere.centre), body))


def locate_frame(plan: SphereTestPlan, machine: MachineProfile,
                 clearance: float) -> tuple[ir.Node, ...]:
    """Measure a 5-point sphere at nominal, move the frame onto it, then measure."""
    lo = _Locator(plan, machine)
    cx, cy, cz = lo.c
    lo.nodes.append(ir.Move((cx, cy, clearance), ir.MoveMode.RAPID))
    lo.nodes.append(ir.Move((cx, cy, lo.z_high), ir.MoveMode.PROTECTED))
    lo.touch((cx, cy, cz + lo.radius), (0.0, 0.0, 1.0), (None, None, None))
    for k, (_, normal) in enumerate(_SIDES):
        if k:
            lo.up()
        lo.nodes.append(ir.Move((cx + (lo.r_off + lo.approach) * normal[0],
                                 cy + (lo.r_off + lo.approach) * normal[1], lo.z_high),
                                ir.MoveMode.PROTECTED))
        lo.touch((cx + lo.radius * normal[0], cy + lo.radius * normal[1], cz), normal,
                 (None, None, None))
    lo.up()
    loc_def = ir.SphereDef(f"{lo.fid}L", lo.c, plan.sphere.diameter)
    frame = f"{lo.fid}C"
    z_local = lo.z_high - cz
    body = measure_body(plan, (0.0, 0.0, 0.0), z_local, machine, clearance - cz)
    return (
        ir.FeatureBlock(loc_def, tuple(lo.nodes)),
        ir.LocalFrame(frame, loc_def.id),
        ir.FeatureBlock(_sphere_def(plan, (0.0, 0.0, 0.0)), body),
        ir.RestoreFrame(frame),
    )


def measure_nominal(plan: SphereTestPlan, machine: MachineProfile,
                    clearance: float) -> tuple[ir.Node, ...]:
    """No locating: measure around the nominal centre."""
    c = plan.sphere.centre
    z_high = c[2] + plan.sphere.diameter / 2.0 + machine.probe.ball_radius + plan.retract
    body = measure_body(plan, c, z_high, machine, clearance)
    return (ir.Move((c[0], c[1], clearance), ir.MoveMode.RAPID),
            ir.FeatureBlock(_sphere_def(plan, c), body))


def _sphere_def(plan: SphereTestPlan, centre: ir.Vec3) -> ir.SphereDef:
    return ir.SphereDef(plan.feature.id, centre, plan.sphere.diameter)
