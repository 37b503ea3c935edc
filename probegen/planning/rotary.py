"""Method M4: programs that measure the rotary axes of a five-axis B/C machine.

Two tests on a reference sphere on the C table (``planning.rotary_spec``):

* ``m4`` (the seed's test): at ``B = 0`` the sphere's radius from touches on its
  equator (feature ``RAD``); then, at ``B = +90°``, touches along −X on its +X side
  (``BP90``) and at ``B = −90°`` along +X on its −X side (``BM90``).  The X positions
  give ``δ`` and ``ε`` (``calibrate.rotary``).
* ``pivot`` (the pivot calibration machine builders ship): the sphere, off the C axis,
  measured at several C positions with ``B = 0`` (features ``C1``, ``C2`` …) and at
  several B positions with ``C = 0`` (``B1``, ``B2`` …), each station a cap of touches
  around the stylus direction (the M1 layouts and order, ``geometry.sphere_layout``).

Frames: every point is a ball centre in work coordinates (the linear axes' frame,
which does not turn with C).  The nominal sphere centre at table angle ``c`` is
``Rz(−c)·S`` (the table turns by −c, ``machine.kinematics``); at head tilt ``b`` the
stylus points along ``s(b) = (sin b, 0, cos b)`` from the ball to the probe body and
the ball sits :func:`probegen.machine.kinematics.head_shift` away from the commanded point
(``ir.Rotary.head_shift``).

Paths: the rotary axes turn only with the commanded point at the clearance plane above
the sphere.  A station is entered straight down onto the pole point ``S + (R' + d)·s(b)``
(``R' = R + r``) and left the same way; touches run on the safe sphere ``R' + d`` with
``d`` from the chord condition of the largest step (M1).  Every move, the rotary
turns included, is checked against the sphere with the stylus in its pose
(:func:`check_rotary`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from probegen import ir
from probegen.errors import CollisionError
from probegen.geometry import sphere_layout as sl
from probegen.machine.kinematics import head_shift
from probegen.planning.collision import MIN_STEP, Stylus, _sweep, probe_stylus
from probegen.planning.rotary_spec import RotarySpec
from probegen.planning.setup import make_setup
from probegen.spec.model import Spec

Vec3 = tuple[float, float, float]


def stylus_direction(b_deg: float) -> np.ndarray:
    """Unit vector from the ball centre towards the probe body at head tilt ``b_deg``."""
    b = math.radians(b_deg)
    return np.array([math.sin(b), 0.0, math.cos(b)])


def table_point(p: Vec3 | np.ndarray, c_deg: float) -> np.ndarray:
    """Where a point of the table at ``p`` (work frame at C = 0) is at ``C = c_deg``."""
    c = math.radians(c_deg)
    x, y, z = (float(v) for v in p)
    return np.array([x * math.cos(c) + y * math.sin(c), -x * math.sin(c) + y * math.cos(c), z])


@dataclass(frozen=True, slots=True)
class Station:
    """One rotary pose and the touches made in it.

    Attributes:
        feature: the feature id the touches are printed under.
        b: head tilt, deg.
        c: table angle, deg.
        sphere: nominal sphere centre in this pose (work frame), mm.
        directions: unit surface normals of the touches, in measuring order.
        retract: distance of the approach points off the surface, mm.
    """

    feature: str
    b: float
    c: float
    sphere: Vec3
    directions: tuple[Vec3, ...]
    retract: float


@dataclass(frozen=True, slots=True)
class RotaryPlan:
    """A planned rotary test: its stations, the program and the smallest clearance."""

    spec: RotarySpec
    stations: tuple[Station, ...]
    program: ir.Program
    clearance: float


# ------------------------------------------------------------------------ stations


def _v(a: np.ndarray) -> Vec3:
    return (float(a[0]), float(a[1]), float(a[2]))


def _retract(spec: RotarySpec, alpha: float) -> float:
    """The M1 chord condition for steps up to ``alpha`` plus the margin, rounded up to 0.1."""
    r_off = spec.sphere_radius + spec.machine.probe.ball_radius
    safe = sl.safe_retract(r_off, alpha) + spec.machine.margin / math.cos(alpha / 2.0)
    return math.ceil(max(safe, spec.machine.probe.approach) * 10.0 - 1e-9) / 10.0


def _tilted(u: np.ndarray, b: float) -> np.ndarray:
    """Layout vectors (pole +Z) turned with the head: pole along ``s(b)``."""
    t = math.radians(b)
    rot = np.array([[math.cos(t), 0.0, math.sin(t)], [0.0, 1.0, 0.0],
                    [-math.sin(t), 0.0, math.cos(t)]])
    return np.asarray(u @ rot.T)


def cap_stations(spec: RotarySpec) -> tuple[Station, ...]:
    """The pivot calibration's stations: C positions at B = 0, then B positions at C = 0."""
    pts = sl.layout("cap", spec.points, spec.max_polar_angle)
    order = sl.zigzag_order(pts, band=2.0 * math.asin(sl.uniformity(pts).min_distance / 2.0))
    u = pts[order]
    back = math.acos(float(np.clip(u[-1, 2], -1.0, 1.0)))  # last point back to the pole
    retract = _retract(spec, max(sl.max_step_angle(pts, order), back))
    poses = [(f"C{k}", 0.0, c) for k, c in enumerate(spec.c_positions, start=1)]
    poses += [(f"B{k}", b, 0.0) for k, b in enumerate(spec.b_positions, start=1)]
    return tuple(
        Station(name, b, c, _v(table_point(spec.sphere_centre, c)),
                tuple(_v(n) for n in _tilted(u, b)), retract)
        for name, b, c in poses)


def m4_stations(spec: RotarySpec) -> tuple[Station, ...]:
    """The seed's test: the equator at B = 0, then one side at B = +90° and -90°."""
    phi = np.radians(np.arange(spec.radius_points) * 360.0 / spec.radius_points)
    equator = tuple((float(math.cos(p)), float(math.sin(p)), 0.0) for p in phi)
    s = spec.sphere_centre
    retract = _retract(spec, 0.0)
    return (Station("RAD", 0.0, 0.0, s, equator, retract),
            Station("BP90", 90.0, 0.0, s, ((1.0, 0.0, 0.0),) * spec.repeats, retract),
            Station("BM90", -90.0, 0.0, s, ((-1.0, 0.0, 0.0),) * spec.repeats, retract))


# ---------------------------------------------------------------------------- paths


class _Path:
    """Builds the IR of a rotary test, tracking the ball centre and the head pose."""

    def __init__(self, spec: RotarySpec) -> None:
        self.spec = spec
        self.r_off = spec.sphere_radius + spec.machine.probe.ball_radius
        self.nodes: list[ir.Node] = []
        self.b: float | None = None
        self.c: float | None = None
        self.ball: Vec3 | None = None

    def shift(self) -> Vec3:
        return head_shift(self.b or 0.0, self.spec.pivot_length)

    def move(self, p: Vec3, mode: ir.MoveMode, into: list[ir.Node]) -> None:
        if p != self.ball:
            into.append(ir.Move(p, mode))
        self.ball = p

    def turn(self, station: Station) -> None:
        """To the clearance plane above the station's sphere, then turn B and C there."""
        if (station.b, station.c) == (self.b, self.c):
            return
        x, y = station.sphere[0], station.sphere[1]
        old = self.shift()
        self.move((x + old[0], y + old[1], self.spec.clearance_z + old[2]),
                  ir.MoveMode.RAPID, self.nodes)
        b = None if station.b == self.b else station.b
        c = None if station.c == self.c else station.c
        self.b, self.c = station.b, station.c
        new = self.shift()
        self.nodes.append(ir.Rotary(b, c, new))
        self.ball = (x + new[0], y + new[1], self.spec.clearance_z + new[2])

    def touch(self, station: Station, k: int, n: Vec3, body: list[ir.Node]) -> None:
        """Approach point, touch ``k`` along ``-n``, retract to the approach point."""
        s, d = station.sphere, station.retract
        start = (s[0] + (self.r_off + d) * n[0], s[1] + (self.r_off + d) * n[1],
                 s[2] + (self.r_off + d) * n[2])
        self.move(start, ir.MoveMode.PROTECTED, body)
        contact = (s[0] + self.spec.sphere_radius * n[0], s[1] + self.spec.sphere_radius * n[1],
                   s[2] + self.spec.sphere_radius * n[2])
        body.append(ir.Touch(station.feature, k, ir.TouchRole.MEASURE, contact, n, d,
                             self.spec.machine.probe.overtravel))
        body.append(ir.Move(start, ir.MoveMode.RETRACT))

    def cap(self, station: Station) -> None:
        """Down onto the pole point, the touches, back to the pole point and up."""
        self.turn(station)
        assert self.ball is not None
        s, pole = station.sphere, stylus_direction(station.b)
        entry = _v(np.array(s) + (self.r_off + station.retract) * pole)
        top = self.ball[2]
        self.move((entry[0], entry[1], top), ir.MoveMode.RAPID, self.nodes)
        body: list[ir.Node] = []
        self.move(entry, ir.MoveMode.PROTECTED, body)
        for k, n in enumerate(station.directions, start=1):
            self.touch(station, k, n, body)
        self.move(entry, ir.MoveMode.PROTECTED, body)
        self.move((entry[0], entry[1], top), ir.MoveMode.PROTECTED, body)
        self.block(station, body)

    def equator(self, station: Station) -> None:
        """Touches on the equator at B = 0, each entered from above the sphere."""
        self.turn(station)
        assert self.ball is not None
        s, top = station.sphere, self.ball[2]
        reach = self.r_off + station.retract
        overs = [(s[0] + reach * n[0], s[1] + reach * n[1], s[2] + reach)
                 for n in station.directions]
        self.move((overs[0][0], overs[0][1], top), ir.MoveMode.RAPID, self.nodes)
        body: list[ir.Node] = []
        for k, (n, over) in enumerate(zip(station.directions, overs, strict=True), start=1):
            self.move(over, ir.MoveMode.PROTECTED, body)
            self.touch(station, k, n, body)
            self.move(over, ir.MoveMode.PROTECTED, body)
        self.move((overs[-1][0], overs[-1][1], top), ir.MoveMode.PROTECTED, body)
        self.block(station, body)

    def block(self, station: Station, body: list[ir.Node]) -> None:
        sphere = ir.SphereDef(station.feature, station.sphere, self.spec.sphere_diameter)
        self.nodes.append(ir.Comment(f"B{station.b:g} C{station.c:g}"))
        self.nodes.append(ir.FeatureBlock(sphere, tuple(body)))

    def home(self) -> None:
        """Back to B = 0, C = 0 at the clearance plane."""
        if (self.b, self.c) != (0.0, 0.0):
            s = self.spec.sphere_centre
            self.turn(Station("HOME", 0.0, 0.0, s, (), 0.0))


def plan_rotary(spec: RotarySpec) -> RotaryPlan:
    """Plan the spec's test and check every move (see the module docstring).

    Raises:
        CollisionError: a move would bring the stylus into the sphere.
    """
    path = _Path(spec)
    stations = m4_stations(spec) if spec.kind == "m4" else cap_stations(spec)
    path.nodes.append(ir.Comment("METHOD M4: B +-90 DEG TEST" if spec.kind == "m4"
                                 else "METHOD M4: PIVOT CALIBRATION"))
    for station in stations:
        if station.feature == "RAD":
            path.equator(station)
        else:
            path.cap(station)
    path.home()
    program = ir.Program(_setup(spec, spec.program_number, spec.program_name),
                         tuple(path.nodes))
    return RotaryPlan(spec, stations, program, check_rotary(program, spec))


def _setup(spec: RotarySpec, number: int, name: str) -> ir.Setup:
    """The program header of a rotary test (the machine profile's probe and controller)."""
    return make_setup(Spec(spec.source, None, spec.machine, "fanuc", spec.clearance_z,
                           number, name, ()))


def compensation_program(spec: RotarySpec, shift: Vec3) -> ir.Program:
    """A program that adds ``shift`` (mm) to the profile's work offset: M4's ``−δ``
    along X, or the pivot calibration's move onto the C axis.  Number: the test's + 1."""
    text = ", ".join(f"{a} {v:+.4f}" for a, v in zip("XYZ", shift, strict=True))
    body = (ir.Comment(f"METHOD M4 COMPENSATION: {spec.machine.work_offset} {text} MM"),
            ir.WorkOffsetShift(spec.machine.work_offset, shift))
    return ir.Program(_setup(spec, spec.program_number % 9999 + 1, "M4 COMPENSATION"), body)


# ------------------------------------------------------------------------ collisions


@dataclass(frozen=True)
class _PosedSphere:
    """The sphere in one rotary pose, with the stylus shank along ``axis`` (unit)."""

    centre: np.ndarray
    radius: float
    axis: np.ndarray

    def clearance(self, centre: np.ndarray, stylus: Stylus) -> tuple[float, float]:
        rel = self.centre - centre
        ball = float(np.linalg.norm(rel)) - self.radius - stylus.ball
        h = float(np.clip(rel @ self.axis, stylus.ball, stylus.length))
        shank = float(np.linalg.norm(rel - h * self.axis)) - self.radius - stylus.shank
        return ball, shank

    def name_at(self, point: np.ndarray) -> str:
        return "the reference sphere"


class _Checker:
    """Walks a rotary program as the control runs it and checks every move."""

    def __init__(self, spec: RotarySpec) -> None:
        probe = spec.machine.probe
        self.spec = spec
        self.stylus = probe_stylus(spec.machine, probe.ball_radius)
        self.clear = spec.machine.margin / 2.0
        self.b = self.c = 0.0
        self.least = math.inf

    def obstacle(self, b: float, c: float) -> _PosedSphere:
        return _PosedSphere(table_point(self.spec.sphere_centre, c), self.spec.sphere_radius,
                            stylus_direction(b))

    def segment(self, a: np.ndarray, z: np.ndarray, what: str) -> None:
        ball, shank, worst = _sweep(self.obstacle(self.b, self.c), a, z, 0.0, 0.0,
                                    self.stylus, self.clear)
        self.record(min(ball, shank), what, worst)

    def record(self, gap: float, what: str, where: np.ndarray) -> None:
        self.least = min(self.least, gap - self.clear)
        if gap < self.clear:
            raise CollisionError(
                f"rotary test {self.spec.source}: {what} near "
                f"({', '.join(f'{v:.3f}' for v in where)}): the stylus comes within "
                f"{gap:.3f} mm of the reference sphere; expected at least {self.clear:.3f} mm")

    def turn(self, command: np.ndarray, node: ir.Rotary) -> None:
        """Follow a rotary move by sphere tracing in the angle (see :func:`check_rotary`)."""
        b1 = self.b if node.b is None else node.b
        c1 = self.c if node.c is None else node.c
        c1 -= 360.0 * math.ceil((c1 - self.c - 180.0) / 360.0)  # C turns the shorter way
        lever = self.spec.pivot_length * (b1 != self.b) + (c1 != self.c) * (
            math.hypot(*self.spec.sphere_centre[:2]) + self.spec.sphere_radius)
        t, b0, c0 = 0.0, self.b, self.c
        span = max(abs(b1 - b0), abs(c1 - c0), 1e-12)
        while True:
            b, c = b0 + t * (b1 - b0), c0 + t * (c1 - c0)
            ball = command + np.array(head_shift(b, self.spec.pivot_length))
            gap = min(self.obstacle(b, c).clearance(ball, self.stylus))
            self.record(gap, f"the turn to B{b1:g} C{c1:g}", ball)
            if t >= 1.0:
                break
            step = max((gap - self.clear) / max(lever, 1e-9), MIN_STEP / max(lever, 1e-9))
            t = min(t + math.degrees(step) / span, 1.0)
        self.b, self.c = b1, c1 % 360.0


def check_rotary(program: ir.Program, spec: RotarySpec) -> float:
    """Check every move of a rotary test program against the sphere; the least spare
    clearance (beyond half the margin), mm.

    Linear moves and touches are swept as in ``planning.collision`` with the shank along
    the current stylus direction and the sphere where the table has turned it.  A
    rotary move is traced in its angle: every stylus point is at most ``L`` from the
    pivot (B) and every sphere point at most ``ρ + R`` from the C axis, so a clearance
    ``g`` above the requirement allows a further ``g / lever`` rad.

    Raises:
        CollisionError: the stylus would come closer than half the margin to the sphere.
    """
    check = _Checker(spec)
    r = spec.machine.probe.ball_radius
    pos: np.ndarray | None = None
    for node in ir.walk(program.body):
        if isinstance(node, ir.Move):
            target = np.array(node.target, dtype=np.float64)
            if pos is not None and node.mode is not ir.MoveMode.RETRACT:
                check.segment(pos, target, f"the {node.mode.value} move")
            pos = target
        elif isinstance(node, ir.Touch):
            n, contact = np.array(node.normal), np.array(node.contact, dtype=np.float64)
            stop = contact + (r + check.clear + MIN_STEP) * n
            check.segment(contact + (r + node.approach) * n, stop,
                          f"touch {node.feature} {node.index}")
        elif isinstance(node, ir.Rotary) and pos is not None:
            command = pos - np.array(head_shift(check.b, spec.pivot_length))
            check.turn(command, node)
    return check.least
