"""What the post's front end produces: the posted program and its touches.

``post/frontend.py`` builds a :class:`PostedProgram` from a DMIS program; the feature
map (``post/featuremap.py``) records its :class:`PostTouch` list for ``probegen
post-ingest``.  Lengths in mm, work coordinates.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from probegen import ir

if TYPE_CHECKING:  # annotations only: reading a feature map loads no planning
    from probegen.planning.collision import SegmentClearance
    from probegen.sim.cmm.interpreter import SkippedStatement

Vec3 = tuple[float, float, float]


@dataclass(frozen=True, slots=True)
class PostTouch:
    """One posted touch, as the feature map records it.

    Attributes:
        feature: the DMIS feature name (``A_CIRCLE``).
        id: the id printed in the log (``ACIRCLE``).
        index: 1-based touch index within the feature.
        line: the PTMEAS line.
        start: approach point (ball centre), work coordinates, mm.
        direction: unit probing direction (into the material).
        reach: longest probing travel (APPRCH + SEARCH), mm.
    """

    feature: str
    id: str
    index: int
    line: int
    start: Vec3
    direction: Vec3
    reach: float



@dataclass(frozen=True, slots=True)
class PostedProgram:
    """The front end's result.

    Attributes:
        program: the IR, ready for a dialect.
        touches: every touch in program order.
        skipped: statements left out (``skip_unsupported``), in line order.
        rerouted: lines of positioning moves lifted over the clearance plane.
        segments: the collision check's figures (empty without an obstacle).
        dropped_lines: lines of skipped statements the interpreter would execute (a
            sensor the machine does not have): the evaluation runs without them.
        notes: statements executed with a note (a sensor that stands for the machine's
            stylus: ``SNSLCT/SA``, ``RECALL/SA``, a zero-diameter ``SNSDEF``) or an
            answered ``TEXT/QUERY``.
        answers: the answers given to ``TEXT/QUERY`` statements (name, value), sorted.
    """

    program: ir.Program
    touches: tuple[PostTouch, ...]
    skipped: tuple[SkippedStatement, ...]
    rerouted: tuple[int, ...]
    segments: tuple[SegmentClearance, ...]
    dropped_lines: tuple[int, ...]
    notes: tuple[SkippedStatement, ...] = ()
    answers: tuple[tuple[str, str | int | float], ...] = ()

    @property
    def move_clearance(self) -> float:
        """The smallest clearance above the margin (mm) of a positioning move (touches
        reach the margin by design), infinite when nothing was checked."""
        return min((min(s.ball, s.shank) for s in self.segments
                    if not s.kind.startswith("touch")), default=float("inf"))
