"""The dialect-neutral measuring program.

Frozen slotted dataclasses with tuple coordinates; never numpy arrays or OCP objects.
All lengths are millimetres in the work coordinate system; a dialect converts units.

A coordinate is either a number or a ``Var``: a value the controller computes at run time
(e.g. the centre of a sphere it has just located) plus a constant offset.  Dialects that
cannot compute at run time (DMIS) reject ``Var`` with ``UnsupportedError``.

Move modes:
    ``RAPID``: positioning at rapid rate; the planner only uses it at the clearance plane.
    ``PROTECTED``: positioning with the probe armed; an unexpected trigger stops the
        program with an alarm (Fanuc: a G31 move and a check of the skip position).
    ``RETRACT``: a plain feed move straight back from a touch, along the approach line.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum

from probegen.ir.actions import ActionNode
from probegen.ir.actions import Align as Align  # re-exported: ir.Align ...
from probegen.ir.actions import Check as Check
from probegen.ir.actions import SetWorkOffset as SetWorkOffset
from probegen.ir.actions import UpdateTool as UpdateTool


@dataclass(frozen=True, slots=True)
class Var:
    """A run-time value ``name`` plus a constant ``offset`` (mm)."""

    name: str
    offset: float = 0.0

    def __add__(self, other: float) -> Var:
        return Var(self.name, self.offset + other)


Coord = float | Var
Point = tuple[Coord, Coord, Coord]
Vec3 = tuple[float, float, float]


class MoveMode(Enum):
    """How a move is made; see the module docstring."""

    RAPID = "rapid"
    PROTECTED = "protected"
    RETRACT = "retract"


class TouchRole(Enum):
    """Why a touch is made: to find the part (``LOC``) or to measure it (``PT``)."""

    LOCATE = "LOC"
    MEASURE = "PT"


@dataclass(frozen=True, slots=True)
class Setup:
    """Everything the program must set before moving (it relies on no controller state).

    Attributes:
        program_number: O-number / program id.
        program_name: short upper-case name.
        units: ``mm`` or ``inch`` for the emitted program (IR values stay mm).
        work_offset: ``G54`` .. ``G59``.
        clearance_z: the clearance plane, work coordinates, mm.
        ball_diameter: stylus ball diameter, mm.
        shank_diameter: stylus shank diameter, mm.
        tool_number: the probe's tool and length-offset number.
        tool_change: whether to call the probe with a tool change.
        position_feed: protected positioning feed, mm/min.
        probe_feed: probing feed, mm/min.
        probe_on: blocks that switch the probe on.
        probe_off: blocks that switch it off.
        variable_base: first controller variable the program may use.
        reset_codes: modal codes set in the header (see ``MachineProfile``).
        probe_length: stylus length from the ball centre, mm.
        identity: the program identity printed on the ``PGSTART`` line (``H`` and 8 hex
            digits, :mod:`probegen.planning.identity`); empty for programs that print none
            (rotary, grating and posted programs).
        calibration: the probe calibration's header comment lines (upper case, no
            parentheses) when the program was compiled with one, else empty.
        calibration_id: its fingerprint (printed in the ``PGCAL`` line), or "".
        options: the controller options the machine declares (``[controller] options``),
            or None when not stated (posted and hand-made programs: every reset code is
            written, no override lock); the dialect writes the reset codes of optional
            modes and ``#3003``/``#3004`` around touches only when declared.
        line_length: the control's longest block, characters (0: the dialect's own).
        program_memory: the memory free for all the files of the program (a split
            program's driver and parts, the macro library), bytes (0: not checked).
        program_size: the largest single program the control takes, bytes (0: as
            ``program_memory``); a larger one is split (:mod:`probegen.dialects.split`).
        common_variables: the common variables the control has, ``(first, last)``
            ranges (empty: not checked).
        alarm_text_length: the longest macro alarm message, characters (0: the
            dialect's ``ALARM_TEXT_LENGTH``).
        limits_source: where the limits come from, for messages (the profile path).
        library_number: O number of the first subprogram of the macro library a compact
            Macro B program calls (``[controller] library_number``).
        stylus: the rack's label of the stylus the program starts with (the ``[probe]``
            stylus; a CMM's sensor label), or "" for a probe without a rack.
    """

    program_number: int
    program_name: str
    units: str
    work_offset: str
    clearance_z: float
    ball_diameter: float
    shank_diameter: float
    tool_number: int
    tool_change: bool
    position_feed: float
    probe_feed: float
    probe_on: tuple[str, ...]
    probe_off: tuple[str, ...]
    variable_base: int
    reset_codes: tuple[str, ...]
    probe_length: float
    identity: str = ""
    calibration: tuple[str, ...] = ()
    calibration_id: str = ""
    options: tuple[str, ...] | None = None
    line_length: int = 0
    program_memory: int = 0
    limits_source: str = ""
    library_number: int = 8000
    program_size: int = 0
    common_variables: tuple[tuple[int, int], ...] = ()
    alarm_text_length: int = 0
    stylus: str = ""


@dataclass(frozen=True, slots=True)
class Comment:
    """A comment line."""

    text: str


@dataclass(frozen=True, slots=True)
class Move:
    """A positioning move of the ball centre to ``target``."""

    target: Point
    mode: MoveMode


@dataclass(frozen=True, slots=True)
class Touch:
    """One probing move: from the ball-centre ``start`` along ``-normal`` until contact.

    Attributes:
        feature: feature id.
        index: 1-based touch index within the feature and role.
        role: locate or measure.
        contact: nominal contact point on the surface.
        normal: outward unit surface normal at ``contact`` (the approach is along -normal).
        approach: distance of the start point off the surface (ball surface to part), mm.
        overtravel: how far past the nominal contact the move may go, mm.
        store: run-time variable names that receive the skip position's X, Y, Z (or None).
        surface: the outward surface normal where the ball meets the part, when the
            touch does not run along it (M3 vertical probing of a slope; ``contact`` is
            then the point ``r`` below the theoretical ball centre along ``normal``);
            None when ``normal`` is the surface normal.  Only the collision check reads
            it: it stops the ball ``margin`` short of the surface, not of ``contact``.
    """

    feature: str
    index: int
    role: TouchRole
    contact: Point
    normal: Vec3
    approach: float
    overtravel: float
    store: tuple[str | None, str | None, str | None] = (None, None, None)
    surface: Vec3 | None = None


@dataclass(frozen=True, slots=True)
class Dwell:
    """Stand still for ``seconds`` (a sampling stop of a measuring instrument, e.g. a
    grating reading head; Fanuc and LinuxCNC ``G4``)."""

    seconds: float


@dataclass(frozen=True, slots=True)
class Assign:
    """``name = (a + b) / 2`` when ``b`` is given, else ``name = a + offset``."""

    name: str
    a: Coord
    b: Coord | None = None
    offset: float = 0.0


@dataclass(frozen=True, slots=True)
class ReportCentre:
    """Print a run-time centre (the DPRNT ``CTR`` line)."""

    feature: str
    centre: Point


@dataclass(frozen=True, slots=True)
class SphereDef:
    """A nominal sphere feature (DMIS ``FEAT/SPHERE``)."""

    id: str
    centre: Vec3
    diameter: float
    inner: bool = False


@dataclass(frozen=True, slots=True)
class CircleDef:
    """A nominal circle (DMIS ``FEAT/CIRCLE``): centre, axis (unit), diameter, mm."""

    id: str
    centre: Vec3
    axis: Vec3
    diameter: float
    inner: bool = False


@dataclass(frozen=True, slots=True)
class CylinderDef:
    """A nominal cylinder (DMIS ``FEAT/CYLNDR``): ``centre`` is the middle of the
    measured length on the axis; axis (unit), diameter and length, mm."""

    id: str
    centre: Vec3
    axis: Vec3
    diameter: float
    length: float
    inner: bool = False


@dataclass(frozen=True, slots=True)
class ConeDef:
    """A nominal cone (DMIS ``FEAT/CONE``): apex, axis (unit, towards the growing
    radius), half angle (rad)."""

    id: str
    apex: Vec3
    axis: Vec3
    half_angle: float
    inner: bool = False


@dataclass(frozen=True, slots=True)
class PlaneDef:
    """A nominal plane (DMIS ``FEAT/PLANE``): a point on it and its outward normal
    (``inner`` is always False: every feature definition has the attribute)."""

    id: str
    point: Vec3
    normal: Vec3
    inner: bool = False


@dataclass(frozen=True, slots=True)
class LineDef:
    """A nominal bounded line on a face (DMIS ``FEAT/LINE,BND``): from ``start`` to
    ``end`` (mm), ``normal`` the face's outward normal."""

    id: str
    start: Vec3
    end: Vec3
    normal: Vec3
    inner: bool = False


@dataclass(frozen=True, slots=True)
class FreeformDef:
    """A free-form face measured point by point (method M3).  DMIS measures each touch
    ``k`` as its own ``FEAT/POINT`` labelled ``<id>_<k>`` (nominal point and vector
    from the touch); controllers without features print a comment.

    Attributes:
        id: feature id.
        face: model face id.
        method: ``vector``, ``microplane``, ``vertical2d`` or ``vertical``.
        points: number of guide points.
    """

    id: str
    face: int
    method: str
    points: int
    inner: bool = False


@dataclass(frozen=True, slots=True)
class TorusDef:
    """A nominal torus (DMIS ``FEAT/TORUS``), mm.

    Attributes:
        centre: the centre of the tube's centre circle, on the axis.
        axis: unit vector.
        major_diameter: diameter of the tube's centre circle (``2R``).
        minor_diameter: diameter of the tube (``2r``).
        inner: the M2 sense, as for the other kinds: the outward normal of the measured
            faces leans towards the axis.
        tube_side: +1 when the faces lie on the outer half of the tube (farther from
            the axis than the centre circle), -1 on the inner half.
    """

    id: str
    centre: Vec3
    axis: Vec3
    major_diameter: float
    minor_diameter: float
    inner: bool = False
    tube_side: int = 1

    @property
    def concave(self) -> bool:
        """Whether the air lies inside the tube (a fillet; DMIS ``INNER``)."""
        return self.inner if self.tube_side == 1 else not self.inner


FeatureDef = (SphereDef | CircleDef | CylinderDef | ConeDef | TorusDef | PlaneDef | LineDef
              | FreeformDef)


@dataclass(frozen=True, slots=True)
class FeatureBlock:
    """The touches that measure one feature, with the moves between them."""

    feature: FeatureDef
    body: tuple[Node, ...]


@dataclass(frozen=True, slots=True)
class LocalFrame:
    """Work in a frame whose origin is the centre of the feature just measured.

    DMIS: ``D(name)=TRANS/XORIG,FA(f),YORIG,FA(f),ZORIG,FA(f)``.  Coordinates after it are
    relative to that centre until the matching ``RestoreFrame``.
    """

    name: str
    feature: str


@dataclass(frozen=True, slots=True)
class RestoreFrame:
    """Return to the frame in force before the last ``LocalFrame``."""

    name: str


@dataclass(frozen=True, slots=True)
class Rotary:
    """Turn the rotary axes of a five-axis machine, the linear axes standing still.

    Attributes:
        b: machine angle of the B axis (head tilt), deg, or None to leave it.
        c: machine angle of the C axis (table), deg, or None to leave it.
        head_shift: the nominal ball-centre shift of the head pose after the turn, mm:
            where the ball centre is less the commanded point (no tool-centre-point
            control; zero at ``B = 0``).  Points after this node stay ball centres;
            a dialect commands ``point − head_shift``.
    """

    b: float | None
    c: float | None
    head_shift: Vec3 = (0.0, 0.0, 0.0)


@dataclass(frozen=True, slots=True)
class Orient:
    """Turn the probe to a new orientation (issue 17): the coordinates of every node after
    it, up to the next ``Orient``, are in its *frame*.

    The frame: ``p_work = origin + R·p_frame`` with ``R = rotation`` (rows; its columns are
    the frame's X, Y and Z axes in work coordinates).  The probe hangs along the frame's
    -Z (frame +Z is the tool axis, from the part towards the head or spindle, as in
    Fanuc's feature coordinate system), so a feature is planned in its frame exactly as for
    a vertical probe.  The identity rotation is the vertical probe, the program's state at
    its start; a program that turned ends with an ``Orient`` back to it.  Helpers:
    :mod:`probegen.ir.frames`.

    The node stands between features, never inside a ``FeatureBlock``; the move before it
    ends at the previous frame's clearance level and the move after it starts at this
    frame's ``clearance_z``.

    Attributes:
        name: upper-case label, ``[A-Z0-9_]``, at most 16 characters: ``A90B-90`` becomes
            ``A90BM90`` (a CMM head's angles), ``TILT1`` (a tilted plane), the setup's name.
        rotation: the 3×3 rotation, rows, unit columns.
        origin: work coordinates of the frame origin, mm (the planner uses (0, 0, 0)).
        head: a CMM's indexable-head angles ``(A, B)``, deg, or None.
        rotary: the machine's rotary-axis angles the orientation needs, ``(("A", a),
            ("C", c))`` (informational: a Fanuc control finds them itself with G53.1),
            or ().
        clearance_z: this frame's clearance level (frame Z), mm.
    """

    name: str
    rotation: tuple[Vec3, Vec3, Vec3]
    origin: Vec3 = (0.0, 0.0, 0.0)
    head: tuple[float, float] | None = None
    rotary: tuple[tuple[str, float], ...] = ()
    clearance_z: float = 0.0


@dataclass(frozen=True, slots=True)
class SelectStylus:
    """Take another stylus of the rack (issue 17) before the next feature.

    A machine tool changes the probe tool (``T.. M6``, its length offset ``H``); a CMM
    selects the sensor (DMIS ``SNSLCT`` of the stylus label at the current orientation).
    Like ``Orient``, it stands between features, the probe at the clearance level.

    Attributes:
        label: the stylus's rack label, upper-case ``[A-Z0-9_]`` (DMIS sensor label).
        tool_number: its tool and length-offset number on a machine tool.
        ball_diameter: mm.
        shank_diameter: mm.
        length: ball centre to the probe body, mm.
    """

    label: str
    tool_number: int
    ball_diameter: float
    shank_diameter: float
    length: float


@dataclass(frozen=True, slots=True)
class WorkOffsetShift:
    """Add ``shift`` (mm, X Y Z) to the work offset ``work_offset`` (``G54`` .. ``G59``):
    a compensation the program applies, e.g. method M4's ``-δ`` along X."""

    work_offset: str
    shift: Vec3


Node = (Comment | Move | Touch | Dwell | Assign | ReportCentre | FeatureBlock | LocalFrame
        | RestoreFrame | Rotary | WorkOffsetShift | Orient | SelectStylus | ActionNode)


@dataclass(frozen=True, slots=True)
class Program:
    """A whole measuring program: the setup, then the body in order."""

    setup: Setup
    body: tuple[Node, ...]


def walk(nodes: tuple[Node, ...]) -> list[Node]:
    """Flatten ``FeatureBlock`` bodies into one list, blocks kept before their bodies."""
    out: list[Node] = []
    for node in nodes:
        out.append(node)
        if isinstance(node, FeatureBlock):
            out += walk(node.body)
    return out
