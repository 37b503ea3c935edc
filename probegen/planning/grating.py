"""Method M5's measuring plan: five paths in each of the XY, XZ and YZ planes (seed 003).

A planar grating lies in one plane of the machine; its reading head is the "tool" (tool
length offset ``head_length``: the read point is that far below the spindle gauge point,
on the spindle axis).  In each plane, with ``u``, ``v`` the plane's axes and the corners
``A(u0, v0)``, ``B(u1, v0)``, ``C(u1, v1)``, ``D(u0, v1)``, the head runs (seed naming
for plane I = XY; XZ is ``L2k``, YZ ``L3k``)::

    L10 A→B   L11 B→D (diagonal)   L12 D→C   L13 C→B   L11 B→D again   L14 D→A

with a sampling stop (G1 to the point, G4 dwell) at ``points`` evenly spaced positions on
each line, ends included.  A corner ends one line and starts the next: it is one stop,
listed under both lines.  The second pass of L11 continues L11's indices.

Setups: one program per setup, a setup being the plane, its out-of-plane coordinate
``w`` (work coordinates of the read point: z for XY, y for XZ, x for YZ) and the head
length.  A ``riser`` moves the grating along the plane's outward normal (towards the
head: +Z for XY, −Y for XZ, −X for YZ) and gives the plane's second setup.

Program layout (Fanuc Macro B): the dialect's header (units, G90, reset codes, work
offset, ``G43 H<tool>`` to the clearance height), a comment naming the setup, ``G0`` to
above A at the clearance height, ``G1`` down to A (the plate lies beyond the read point
along the normal, so this move runs beside or above it), then ``G1`` + ``G4 P<ms>`` at
every stop, ``G0`` back up to the clearance height, the dialect's footer.  The collision
check: every end point (and so every straight segment: the head side of the plate is a
half-space) stays on the head's side of the plate surface.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from probegen import ir
from probegen.errors import CollisionError, SpecError
from probegen.files import Table, load_toml
from probegen.machine.kinematics import PLANE_OUTWARD as OUTWARD
from probegen.machine.kinematics import PLANES
from probegen.machine.profile import DEFAULT_RESET, MachineProfile

SEED_NUMBER = {"XY": 1, "XZ": 2, "YZ": 3}
"""The seed's plane numbers (lines L10-L14, L20-L24, L30-L34)."""
AXIS_NAMES = "XYZ"


@dataclass(frozen=True)
class PlaneSpec:
    """One grating plane: its axis ranges (mm, work), offset ``w`` and optional riser."""

    name: str
    u: tuple[float, float]
    v: tuple[float, float]
    w: float
    riser: float | None = None


def _default_planes() -> tuple[PlaneSpec, ...]:
    return (PlaneSpec("XY", (-100.0, 100.0), (-100.0, 100.0), -200.0, 50.0),
            PlaneSpec("XZ", (-100.0, 100.0), (-300.0, -100.0), 50.0, 50.0),
            PlaneSpec("YZ", (-100.0, 100.0), (-300.0, -100.0), 50.0, 50.0))


@dataclass(frozen=True)
class GratingSpec:
    """The whole M5 plan (see ``samples/grating/grating.toml``).

    Attributes:
        planes: the three planes.
        points: stops per line, ends included.
        feed: feed between stops, mm/min.
        dwell: sampling stop, s.
        head_length: read point below the spindle gauge point (tool length), mm.
        clearance: approach height above the plates' top, mm.
        plate_margin: how far the plate reaches beyond the measured square, mm.
        tool: tool (and length offset) number of the reading head.
        program_number: number of the first program (one per setup, counting up).
        second_head: the length of a second, longer head extension, mm (optional): its
            setups separate the Z axis' pitch and yaw from its straightness.
    """

    planes: tuple[PlaneSpec, ...] = field(default_factory=_default_planes)
    points: int = 11
    feed: float = 1000.0
    dwell: float = 0.5
    head_length: float = 100.0
    clearance: float = 30.0
    plate_margin: float = 20.0
    tool: int = 30
    program_number: int = 7100
    second_head: float | None = 200.0


@dataclass(frozen=True)
class GratingSetup:
    """One mounting of the grating: plane, out-of-plane coordinate (riser applied), head."""

    plane: str
    w: float
    riser: float
    head_length: float

    head_index: int = 0

    @property
    def label(self) -> str:
        """E.g. ``XY``, ``XY+40`` (a riser of 40 mm), ``XY/h200`` (the second head)."""
        riser = "" if self.riser == 0.0 else f"+{self.riser:g}"
        return f"{self.plane}{riser}{f'/h{self.head_length:g}' if self.head_index else ''}"


@dataclass(frozen=True)
class SetupPlan:
    """The stops of one setup.

    Attributes:
        setup: the mounting.
        stops: (k, 3) float, the nominal read points in program order, work mm.
        lines: (line name, stop indices) in order; corners appear in two lines.
        base: (k, 3) float, the stops without the riser (what the readings CSV lists).
    """

    setup: GratingSetup
    stops: np.ndarray
    lines: tuple[tuple[str, tuple[int, ...]], ...]
    base: np.ndarray


def load_grating_spec(path: str) -> GratingSpec:
    """Read a ``[grating]`` TOML table (keys as :class:`GratingSpec`, planes under
    ``[grating.XY]`` etc. with ``u``, ``v`` = [lo, hi], ``w`` and optional ``riser``).

    Raises:
        SpecError: a missing or malformed key, or axis ranges that disagree between planes.
    """
    root = Table(load_toml(path), path, "")
    g = root.table("grating", required=True)
    base = GratingSpec()
    planes = tuple(_plane(g.table(name, required=True), name) for name in PLANES)
    spec = GratingSpec(
        planes=planes,
        points=g.get_int("points", base.points, minimum=4, maximum=201) or base.points,
        feed=g.get_float("feed", base.feed, positive=True) or base.feed,
        dwell=g.get_float("dwell", base.dwell, positive=True) or base.dwell,
        head_length=g.get_float("head_length", base.head_length) or 0.0,
        clearance=g.get_float("clearance", base.clearance, positive=True) or base.clearance,
        plate_margin=g.get_float("plate_margin", base.plate_margin) or 0.0,
        tool=g.get_int("tool", base.tool, minimum=1, maximum=9999) or base.tool,
        program_number=g.get_int("program_number", base.program_number, minimum=1,
                                 maximum=9990) or base.program_number,
        second_head=g.get_float("second_head", None, positive=True)
        if g.has("second_head") else None)
    g.done()
    root.done()
    check_spec(spec, path)
    return spec


def _plane(t: Table, name: str) -> PlaneSpec:
    ranges = []
    for key in ("u", "v"):
        value = t.get_vec(key, 2)
        if value is None or not value[0] < value[1]:
            raise t.fail(key, "[lo, hi] with lo < hi, mm")
        ranges.append((value[0], value[1]))
    w = t.get_float("w", required=True) or 0.0
    riser = t.get_float("riser", None, positive=True) if t.has("riser") else None
    t.done()
    return PlaneSpec(name, ranges[0], ranges[1], w, riser)


def check_spec(spec: GratingSpec, where: str = "grating spec") -> None:
    """Each axis must have one range in both planes that move it; enough points a line."""
    if spec.points < 4:
        raise SpecError(f"{where}: grating.points: expected at least 4, found {spec.points}")
    seen: dict[int, tuple[float, float]] = {}
    for p in spec.planes:
        u, v, _ = PLANES[p.name]
        for axis, rng in ((u, p.u), (v, p.v)):
            if seen.setdefault(axis, rng) != rng:
                raise SpecError(f"{where}: grating.{p.name}: expected the {AXIS_NAMES[axis]} "
                                f"range {list(seen[axis])} of the other plane, found {list(rng)}"
                                " (one range per axis: the identified functions live on it)")


def setups(spec: GratingSpec, *, second_offset: bool = False,
           second_head: bool = False) -> list[GratingSetup]:
    """The seed's three setups, plus each plane's riser setup when ``second_offset``, plus
    each plane with the second head when ``second_head``."""
    out = [GratingSetup(p.name, p.w, 0.0, spec.head_length) for p in spec.planes]
    if second_offset:
        for p in spec.planes:
            if p.riser is None:
                raise SpecError(f"grating.{p.name}.riser: a second offset needs a riser height")
            out.append(GratingSetup(p.name, p.w + OUTWARD[p.name] * p.riser, p.riser,
                                    spec.head_length))
    if second_head:
        if spec.second_head is None:
            raise SpecError("grating.second_head: a second head needs its length")
        out += [GratingSetup(p.name, p.w, 0.0, spec.second_head, 1) for p in spec.planes]
    return out


def plan_setup(spec: GratingSpec, setup: GratingSetup) -> SetupPlan:
    """The stops of one setup, in program order (see the module docstring)."""
    plane = next(p for p in spec.planes if p.name == setup.plane)
    u_axis, v_axis, n_axis = PLANES[setup.plane]
    corners = {"A": (plane.u[0], plane.v[0]), "B": (plane.u[1], plane.v[0]),
               "C": (plane.u[1], plane.v[1]), "D": (plane.u[0], plane.v[1])}
    k = SEED_NUMBER[setup.plane]
    path = [(f"L{k}0", "A", "B"), (f"L{k}1", "B", "D"), (f"L{k}2", "D", "C"),
            (f"L{k}3", "C", "B"), (f"L{k}1", "B", "D"), (f"L{k}4", "D", "A")]
    t = np.linspace(0.0, 1.0, spec.points)
    stops: list[tuple[float, float]] = [corners["A"]]
    lines: dict[str, list[int]] = {}
    for name, a, b in path:
        pa, pb = np.array(corners[a]), np.array(corners[b])
        indices = lines.setdefault(name, [])
        indices.append(len(stops) - 1)
        for s in t[1:]:
            p = pa + s * (pb - pa)
            stops.append((float(p[0]), float(p[1])))
            indices.append(len(stops) - 1)
    uv = np.array(stops)
    pts = np.zeros((len(uv), 3))
    pts[:, u_axis], pts[:, v_axis], pts[:, n_axis] = uv[:, 0], uv[:, 1], setup.w
    base = pts.copy()
    base[:, n_axis] = plane.w
    return SetupPlan(setup, pts, tuple((n, tuple(i)) for n, i in lines.items()), base)


def clearance_height(spec: GratingSpec, setup: GratingSetup) -> float:
    """Approach height (work z of the read point): above the read points and the plate."""
    plane = next(p for p in spec.planes if p.name == setup.plane)
    if setup.plane == "XY":
        return setup.w + spec.clearance
    return plane.v[1] + spec.plate_margin + spec.clearance


def build_program(spec: GratingSpec, plan: SetupPlan, number: int,
                  profile: MachineProfile | None = None) -> ir.Program:
    """The IR of one setup's program (layout in the module docstring), collision-checked."""
    s = plan.setup
    z_safe = clearance_height(spec, s)
    a = plan.stops[0]
    body: list[ir.Node] = [
        ir.Comment(f"GRATING {s.label.replace('/', ' ')} {AXIS_NAMES[PLANES[s.plane][2]]}{s.w:.4f} "
                   f"HEAD {s.head_length:.4f} STOPS {len(plan.stops)}"),
        ir.Move((float(a[0]), float(a[1]), z_safe), ir.MoveMode.RAPID)]
    for p in plan.stops:
        body.append(ir.Move((float(p[0]), float(p[1]), float(p[2])), ir.MoveMode.RETRACT))
        body.append(ir.Dwell(spec.dwell))
    last = plan.stops[-1]
    body.append(ir.Move((float(last[0]), float(last[1]), z_safe), ir.MoveMode.RAPID))
    check_clear(plan, body)
    c = profile.controller if profile is not None else None
    setup = ir.Setup(
        program_number=number, program_name=f"GRATING {s.label.replace('/', ' ')}"[:16],
        units=profile.units if profile else "mm",
        work_offset=profile.work_offset if profile else "G54", clearance_z=z_safe,
        ball_diameter=0.0, shank_diameter=0.0, tool_number=spec.tool,
        tool_change=c.tool_change if c else True, position_feed=spec.feed,
        probe_feed=spec.feed, probe_on=(), probe_off=(),
        variable_base=c.variable_base if c else 100,
        reset_codes=c.reset_codes if c else DEFAULT_RESET, probe_length=s.head_length,
        options=c.options if c else None, line_length=c.line_length if c else 0,
        program_memory=c.program_memory if c else 0,
        limits_source=profile.source if profile else "")
    return ir.Program(setup, tuple(body))


def check_clear(plan: SetupPlan, body: list[ir.Node]) -> None:
    """Every move end point lies on the head's side of the plate surface.

    Raises:
        CollisionError: a move would run into the plate.
    """
    s = plan.setup
    n_axis = PLANES[s.plane][2]
    sign = OUTWARD[s.plane]
    for node in body:
        if isinstance(node, ir.Move):
            depth = sign * (s.w - float(node.target[n_axis]))  # type: ignore[arg-type]
            if depth > 1e-9:
                raise CollisionError(f"grating {s.label}: move to {node.target} runs "
                                     f"{depth:.4f} mm into the grating plate")
