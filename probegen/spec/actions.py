"""In-process decisions of a spec feature, and the planar feature kinds ``line``/``plane``.

A feature may carry actions the control computes at run time (``docs/actions.md``)::

    on_out_of_tolerance = "alarm"          # alarm | stop | continue | flag
    flag = 510                             # with "flag": the variable set to 1 (else 0)
    set_work_offset = { offset = "G54", axes = "XY" }      # or "G54.1 P3"
    update_tool = { tool = 12, offset = "radius", dead_band = 0.005, max = 0.1,
                    feedback = 1.0 }
    align = { mode = "g68", variable = 520 }               # line features only

and the planar kinds, touched at given nominal contact points on one planar face::

    [[feature]]
    id = "EDGE"
    kind = "line"                          # or "plane"
    at = [50.0, 0.0, 25.0]                 # or face = N: a planar face of the model
    contacts = [[20.0, 0.0, 25.0], [80.0, 0.0, 25.0]]
    retract = 4.0
    tolerance = { position = [-0.1, 0.1], angle = 1.0, form = 0.02 }
    # position: mm along the normal; angle: degrees; form: flatness of a plane,
    # straightness of a line, mm (ISO 1101 minimum zone unless form_method =
    # "least_squares" here or in [evaluation])

Lengths are in ``[part] units`` and converted to mm (``k``); this module only reads
the tables, :mod:`probegen.planning.actions` checks them against the geometry.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

from probegen.errors import SpecError
from probegen.files import Table

Vec3 = tuple[float, float, float]

PLANAR_KINDS = ("line", "plane")
"""Feature kinds touched at given points of one planar face."""
FORM_MIN_POINTS = {"plane": 4, "line": 3}
"""Fewest touches the form of a plane or line is evaluated from: one more than its
fit's parameters (a ``form`` tolerance needs as many contacts)."""
FORM_METHODS = ("minimum_zone", "least_squares")
"""Values of ``form_method`` (``geometry.minimum_zone``)."""
ON_FAIL = ("alarm", "stop", "continue", "flag")
"""What the program does when a feature is out of tolerance."""
TOOL_OFFSETS = ("radius", "length")
"""Which wear offset ``update_tool`` corrects."""
ALIGN_MODES = ("g68", "variable")
"""``g68``: rotate the program's frame (and store the angle when ``variable`` is given);
``variable``: only store the angle for the part program's ``G68 ... R#n``."""
_OFFSET = re.compile(r"(G5[4-9])\Z|G54\.1 P([1-9][0-9]{0,2})\Z")
MAX_EXTENDED = 300
"""Highest G54.1 P number."""
FLAG_RANGE = (500, 999)
"""Variables a flag or a stored angle may use: the retained common variables."""


@dataclass(frozen=True, slots=True)
class WorkOffsetAction:
    """Set ``axes`` of work offset ``offset`` (``G54``-``G59``, ``G54.1 Pn``) so that
    the measured feature lies at its nominal position."""

    offset: str
    axes: str


@dataclass(frozen=True, slots=True)
class ToolAction:
    """Correct the wear of tool ``tool`` from the feature's size or position deviation.

    Attributes:
        tool: the offset number (H and D).
        offset: ``radius`` (D wear) or ``length`` (H wear).
        dead_band: a correction smaller than this (mm, absolute) is not made.
        max_correction: a correction larger than this (mm) is refused with an alarm.
        feedback: fraction of the correction applied (0 < f <= 1).
    """

    tool: int
    offset: str
    dead_band: float
    max_correction: float
    feedback: float


@dataclass(frozen=True, slots=True)
class AlignAction:
    """Rotate the frame by the measured angle of a line (``mode``: see ``ALIGN_MODES``);
    ``variable`` receives the angle in degrees, or None."""

    mode: str
    variable: int | None


@dataclass(frozen=True, slots=True)
class Actions:
    """Everything a feature decides at run time (all optional)."""

    work_offset: WorkOffsetAction | None = None
    tool: ToolAction | None = None
    align: AlignAction | None = None
    on_fail: str = "continue"
    flag: int | None = None
    checked: bool = False
    """Whether ``on_out_of_tolerance`` was given (even ``continue``: check and report)."""

    @property
    def any(self) -> bool:
        """Whether the feature asks for any run-time decision or check."""
        return (self.work_offset is not None or self.tool is not None
                or self.align is not None or self.checked)


@dataclass(frozen=True, slots=True)
class PlanarTolerance:
    """Limits of a line or plane: ``position`` the lowest and highest deviation along
    the face's outward normal (mm), ``angle`` the largest angle of a line from its
    nominal direction (degrees), ``form`` the largest flatness of a plane or
    straightness of a line (mm); None = not checked.  ``form_method``: how the form is
    evaluated, ``minimum_zone`` (ISO 1101) or ``least_squares`` (the range of the
    residuals about the least-squares fit).

    The form is evaluated offline only (``ingest``): the in-process check of a line or
    plane has no form value, so ``form`` never enters its run-time limits."""

    position: tuple[float, float] | None = None
    angle: float | None = None
    form: float | None = None
    form_method: str = "minimum_zone"


@dataclass(frozen=True, slots=True)
class PlanarSpec:
    """A line (angle and position) or plane (position) touched on one planar face.

    Attributes:
        id: feature id.
        where: ``file: feature[i]`` for error messages.
        kind: ``line`` or ``plane``.
        face: a model face id, or None.
        at: a point near the face, or None.
        contacts: nominal contact points on the face, in touch order (mm).
        retract: start distance of each touch off the surface (mm), or None for the
            probe's approach.
        tolerance: limits for pass/fail.
        actions: the run-time decisions.
        stylus: the label of the rack's stylus the spec forces (``stylus = "D2"``), or
            None: the planner picks.
    """

    id: str
    where: str
    kind: str
    face: int | None
    at: Vec3 | None
    contacts: tuple[Vec3, ...]
    retract: float | None
    tolerance: PlanarTolerance = PlanarTolerance()
    actions: Actions = Actions()
    stylus: str | None = None


def read_actions(t: Table, k: float, axes_allowed: str) -> Actions:
    """The action keys of feature table ``t`` (lengths scaled by ``k``)."""
    on_fail = t.get_str("on_out_of_tolerance", "continue", choices=ON_FAIL) or "continue"
    flag = t.get_int("flag", minimum=FLAG_RANGE[0], maximum=FLAG_RANGE[1])
    if (on_fail == "flag") != (flag is not None):
        raise SpecError(f"{t.where('flag')}: expected a flag variable exactly when "
                        f"on_out_of_tolerance = \"flag\", found on_out_of_tolerance = "
                        f"{on_fail!r} and flag = {flag!r}")
    return Actions(_work_offset(t, axes_allowed), _tool(t, k), _align(t), on_fail, flag,
                   t.has("on_out_of_tolerance"))


def _work_offset(t: Table, axes_allowed: str) -> WorkOffsetAction | None:
    if not t.has("set_work_offset"):
        return None
    w = t.table("set_work_offset")
    offset = w.get_str("offset", required=True) or ""
    m = _OFFSET.match(offset)
    if m is None or (m.group(2) and int(m.group(2)) > MAX_EXTENDED):
        raise w.fail("offset", "G54 to G59 or \"G54.1 Pn\" (n 1-300)")
    axes = w.get_str("axes", axes_allowed) or axes_allowed
    if not axes or any(a not in axes_allowed for a in axes) or len(set(axes)) != len(axes):
        raise w.fail("axes", f"one or more of {axes_allowed!r}, each once")
    w.done()
    return WorkOffsetAction(offset, "".join(sorted(axes)))


def _tool(t: Table, k: float) -> ToolAction | None:
    if not t.has("update_tool"):
        return None
    u = t.table("update_tool")
    tool = u.get_int("tool", required=True, minimum=1, maximum=999) or 1
    offset = u.get_str("offset", "radius", choices=TOOL_OFFSETS) or "radius"
    dead = u.get_float("dead_band", 0.0, minimum=0.0) or 0.0
    top = u.get_float("max", required=True, positive=True) or 0.0
    gain = u.get_float("feedback", 1.0, positive=True, maximum=1.0) or 1.0
    if dead >= top:
        raise u.fail("dead_band", f"a dead band below max ({top:g})")
    u.done()
    return ToolAction(tool, offset, dead * k, top * k, gain)


def _align(t: Table) -> AlignAction | None:
    if not t.has("align"):
        return None
    a = t.table("align")
    mode = a.get_str("mode", "g68", choices=ALIGN_MODES) or "g68"
    variable = a.get_int("variable", minimum=FLAG_RANGE[0], maximum=FLAG_RANGE[1])
    if mode == "variable" and variable is None:
        raise SpecError(f"{a.where('variable')}: required with mode = \"variable\", "
                        f"found none")
    a.done()
    return AlignAction(mode, variable)


def read_planar(t: Table, fid: str, kind: str, k: float,
                form_method: str = "minimum_zone") -> PlanarSpec:
    """A ``line`` or ``plane`` feature table (``form_method``: the ``[evaluation]``
    default, see ``PlanarTolerance``)."""
    face = t.get_int("face", minimum=1)
    at = t.get_vec("at")
    given = [key for key, v in (("face", face), ("at", at)) if v is not None]
    if len(given) != 1:
        raise SpecError(f"{t.where('face')}: expected exactly one of face, at, "
                        f"found {', '.join(given) or 'none'}")
    contacts = _contacts(t, k, 2 if kind == "line" else 1)
    retract = t.get_float("retract", positive=True)
    tolerance = _planar_tolerance(t.table("tolerance"), k, kind, form_method)
    if tolerance.form is not None and len(contacts) < FORM_MIN_POINTS[kind]:
        raise SpecError(f"{t.where('contacts')}: a form tolerance needs at least "
                        f"{FORM_MIN_POINTS[kind]} contacts on a {kind}, found "
                        f"{len(contacts)}")
    actions = read_actions(t, k, "XYZ")
    if actions.align is not None and kind != "line":
        raise SpecError(f"{t.where('align')}: align needs a line feature, found kind {kind}")
    return PlanarSpec(fid, f"{t.file}: {t.path}", kind, face,
                      None if at is None else (at[0] * k, at[1] * k, at[2] * k), contacts,
                      None if retract is None else retract * k, tolerance, actions)


def _contacts(t: Table, k: float, least: int) -> tuple[Vec3, ...]:
    value = t.get_any("contacts")
    ok = isinstance(value, list) and least <= len(value) <= 50 and all(
        isinstance(p, list) and len(p) == 3 and all(
            isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)
            for v in p) for p in value)
    if not ok:
        raise SpecError(f"{t.where('contacts')}: expected an array of {least}-50 points "
                        f"[x, y, z] on the face, found {value!r}")
    return tuple((float(p[0]) * k, float(p[1]) * k, float(p[2]) * k) for p in value)


def _planar_tolerance(t: Table, k: float, kind: str, form_method: str) -> PlanarTolerance:
    position = t.get_limits("position", k)
    angle = t.get_float("angle", positive=True, maximum=45.0) if kind == "line" else None
    form = t.get_float("form", positive=True)
    method = t.get_str("form_method", form_method, choices=FORM_METHODS) or form_method
    t.done()
    return PlanarTolerance(position, angle, None if form is None else form * k, method)
