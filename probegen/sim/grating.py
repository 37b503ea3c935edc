"""The virtual planar grating: readings of a grating program run on the virtual machine.

The grating program's text runs through the Macro B interpreter (as a control would run
it) against :class:`VirtualGrating`, a ``Machine`` with the kinematic chain and its
errors and a grating plate mounted in one plane.  The reading head is the tool: the
control's length offset ``H`` holds the head length, so the positions the interpreter
passes are the spindle gauge point's, i.e. the axis positions ``q``; the read point
really is at ``actual_tool_point(q, (0, 0, −head))``.

Sampling: the machine does not see a ``G4`` dwell, so the grating samples at the end of
every ``G1`` move that ends on the plate's plane (the program's sampling stops, each
followed by its dwell; the approach from above ends on the first stop).  Each stop's
reading is ``actual − nominal`` of the read point in the plate's two axes, µm, plus the
optional seeded Gaussian noise.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from probegen.errors import ProbegenError
from probegen.machine.kinematics import PLANES, Machine
from probegen.sim.macrob.machine import Point, Settings, run_program

ON_PLANE = 1e-6
"""How close (mm) a move's end must be to the plate's plane to be a sampling stop."""


@dataclass(frozen=True)
class GratingStop:
    """One sampling stop: the commanded read point (work = machine mm) and the reading
    ``du``, ``dv`` (µm) along the plane's first and second axis."""

    point: tuple[float, float, float]
    du: float
    dv: float


@dataclass
class VirtualGrating:
    """A machine with a grating plate in ``plane`` at read-point coordinate ``w``.

    Attributes:
        kinematics: the kinematic chain with its errors.
        plane: ``XY``, ``XZ`` or ``YZ``.
        w: the read points' coordinate along the plane's normal, mm.
        head: reading-head length below the gauge point (the H offset), mm.
        noise: standard deviation of each reading, µm.
        seed: noise seed.
        stops: the stops so far.
    """

    kinematics: Machine
    plane: str
    w: float
    head: float
    noise: float = 0.0
    seed: int = 0
    stops: list[GratingStop] = field(default_factory=list)

    def __post_init__(self) -> None:
        self._rng = np.random.default_rng(self.seed)

    def rapid(self, start: Point, end: Point) -> None:
        """G0: no sample."""

    def skip(self, start: Point, end: Point, feed_mm_min: float) -> Point | None:
        """G31: a grating program has none; nothing triggers."""
        return None

    def feed(self, start: Point, end: Point, feed_mm_min: float) -> None:
        """G1: a stop on the plate's plane is sampled."""
        u, v, n = PLANES[self.plane]
        t = np.array([0.0, 0.0, -self.head])
        q = np.asarray(end, dtype=np.float64)
        nominal = q + t
        if abs(nominal[n] - self.w) > ON_PLANE:
            return
        actual = self.kinematics.actual_tool_point(q, t)
        e = (actual - nominal) * 1e3
        if self.noise > 0.0:
            e = e + self._rng.normal(0.0, self.noise, 3)
        self.stops.append(GratingStop((float(nominal[0]), float(nominal[1]),
                                       float(nominal[2])), float(e[u]), float(e[v])))


def run_grating(text: str, grating: VirtualGrating, *, tool: int,
                source: str = "<program>") -> list[GratingStop]:
    """Run grating program text on ``grating``; the head's length offset is set to
    ``grating.head`` (tool ``tool``), G54 is zero.

    Raises:
        ProbegenError: the run ended on an alarm.
    """
    variables = {11000 + tool: grating.head, 10000 + tool: 0.0}
    res = run_program(text, grating, source=source, variables=variables,
                      settings=Settings(home=(0.0, 0.0, 0.0)))
    if res.alarm is not None:
        raise ProbegenError(f"grating program stopped on an alarm: {res.alarm}")
    return list(grating.stops)
