"""The stylus rack and the ways a machine turns its probe (issue 17): the records of
``[[probe.stylus]]``, ``[head]``, ``[tilt]`` and ``[[setup]]`` in a machine profile, and
their reading and checks (``load_profile`` calls them; ``docs/spec.md``, "Styli,
orientations and setups").

Lengths are read in the profile's units and kept in mm (the caller passes the factor);
angles are degrees.  Every problem is a ``SpecError`` naming the file and key path.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable
from dataclasses import dataclass

from probegen.errors import SpecError
from probegen.files import Table
from probegen.ir import frames

LABEL = re.compile(r"[A-Z0-9_]{1,8}\Z")
"""A stylus label: the DMIS sensor label ``S(label)`` and the name in a spec's
``stylus =`` key."""
SETUP_NAME = re.compile(r"[A-Z0-9_]{1,16}\Z")
"""A setup's name (it names the setup's program and its ``ir.Orient``)."""
MACHINE_TOOLS = ("fanuc", "haas", "linuxcnc")
"""Dialects of a machine tool: a stylus there is a tool (``T.. M6``) with a number."""
TILT_COMMANDS = {"fanuc": "G68.2", "haas": "G268"}
"""The tilted-work-plane command of each dialect that has one."""
ROTATION_TOLERANCE = 1e-6
"""How far a setup's rotation may be from orthonormal with determinant +1."""
NOTE_LENGTH = 80
"""Longest fixture note of a setup (one line of the program header)."""
@dataclass(frozen=True, slots=True)
class Stylus:
    """One stylus of the rack (issue 17): ``[[probe.stylus]]`` in the profile.

    Attributes:
        label: upper-case ``[A-Z0-9_]`` name, the DMIS sensor label (``S(label)``).
        ball_diameter: mm.
        shank_diameter: mm.
        length: ball centre to the probe body, mm.
        tool_number: tool and length-offset number on a machine tool.
        offset: a star stylus's tip offset from the probe axis, mm (frame of the vertical
            probe), (0, 0, 0) for a straight stylus.
    """

    label: str
    ball_diameter: float
    shank_diameter: float
    length: float
    tool_number: int
    offset: tuple[float, float, float] = (0.0, 0.0, 0.0)

    @property
    def ball_radius(self) -> float:
        """Half the ball diameter, mm."""
        return self.ball_diameter / 2.0


@dataclass(frozen=True, slots=True)
class Head:
    """A CMM's indexable probe head (``[head]``, like a Renishaw PH10): ``A`` tilts the
    stylus from straight down (0) towards the horizontal (90) and beyond, ``B`` turns it
    about the vertical; both in ``step`` increments.

    Attributes:
        a: the A range, deg.
        b: the B range, deg.
        step: the index step, deg.
        body_diameter: the probe body and head's diameter for the collision check, mm.
        body_length: from the stylus's end to the head's turning centre, mm.
    """

    a: tuple[float, float] = (0.0, 105.0)
    b: tuple[float, float] = (-180.0, 180.0)
    step: float = 7.5
    body_diameter: float = 25.0
    body_length: float = 60.0


@dataclass(frozen=True, slots=True)
class Tilt:
    """A five-axis machine's 3+2 positioning with a tilted work plane (``[tilt]``).

    Attributes:
        command: ``G68.2`` (Fanuc, with ``G53.1``), ``G268`` (Haas NGC, with ``G253``).
        tilt_axis: the axis that tilts (``A`` or ``B``).
        rotary_axis: the rotary table's axis (``C``).
        tilt_range: the tilt axis's travel, deg.
        rotary_range: the rotary axis's travel, deg (a continuous table: -360, 360).
    """

    command: str = "G68.2"
    tilt_axis: str = "A"
    rotary_axis: str = "C"
    tilt_range: tuple[float, float] = (-110.0, 110.0)
    rotary_range: tuple[float, float] = (-360.0, 360.0)


@dataclass(frozen=True, slots=True)
class NamedSetup:
    """A named setup (``[[setup]]``): the part turned on the table, one program each.

    Attributes:
        name: upper-case ``[A-Z0-9_]`` name.
        rotation: the part's turn, rows (part coordinates → table frame: ``p_table =
            R·p_part + origin``).
        origin: mm.
        note: the fixture note printed in the program header.
    """

    name: str
    rotation: tuple[tuple[float, float, float], tuple[float, float, float],
                    tuple[float, float, float]]
    origin: tuple[float, float, float] = (0.0, 0.0, 0.0)
    note: str = ""


def probe_stylus(rack: tuple[Stylus, ...], tool_number: int, ball_diameter: float,
                 shank_diameter: float, length: float) -> Stylus:
    """The ``[probe]`` stylus: the rack's straight stylus of the same ball, shank and length
    and the same tool number (or none, on a CMM), else one labelled ``PRB<tool number>``."""
    for s in rack:
        if ((s.ball_diameter, s.shank_diameter, s.length) == (ball_diameter, shank_diameter,
                                                                length)
                and s.tool_number in (tool_number, 0) and s.offset == (0.0, 0.0, 0.0)):
            return s
    return Stylus(f"PRB{tool_number}", ball_diameter, shank_diameter, length, tool_number)


def read_rack(probe: Table, k: float, dialect: str, first: tuple[int, float, float, float],
              tool_change: bool) -> tuple[Stylus, ...]:
    """``[[probe.stylus]]`` of the ``[probe]`` table ``probe``, lengths times ``k``.

    Args:
        first: the ``[probe]`` stylus's tool number, ball, shank and length (mm): the
            rack is checked together with it (labels and tool numbers unique).
        tool_change: ``[controller] tool_change``: a machine tool takes another stylus
            only by a tool change.

    Raises:
        SpecError: a bad entry, a label or tool number twice, a tool number missing on a
            machine tool, or a rack of several styli on a machine tool without tool
            changes.
    """
    tables = probe.tables("stylus")
    rack = tuple(_stylus(t, k, dialect) for t in tables)
    start = probe_stylus(rack, *first)
    labels = {start.label: "probe"}
    tools = {start.tool_number: f"the [probe] stylus {start.label}"}
    for t, s in zip(tables, rack, strict=True):
        if s == start:
            continue
        if s.label in labels:
            raise t.fail("label", f"a label no other stylus has (the labels so far: "
                                  f"{', '.join(labels)})")
        labels[s.label] = t.path
        if s.tool_number and s.tool_number in tools:
            hint = ("; an entry with the [probe] stylus's tool number must have its ball, "
                    "shank and length" if s.tool_number == first[0] else "")
            raise t.fail("tool_number", f"a tool number no other stylus has, not "
                                        f"{s.tool_number} of {tools[s.tool_number]}{hint}")
        if s.tool_number:
            tools[s.tool_number] = t.path
    if len(labels) > 1 and dialect in MACHINE_TOOLS and not tool_change:
        raise SpecError(f"{probe.where('stylus')}: a rack of {len(labels)} styli needs tool "
                        "changes (T.. M6) to take them, found [controller] tool_change = "
                        "false; set it to true or keep only the [probe] stylus")
    return rack


def dialect_problem(rack: tuple[Stylus, ...], head: Head | None, tilt: Tilt | None,
                    dialect: str) -> str:
    """Why a profile with this rack, head and tilt cannot drive ``dialect`` (a spec's
    ``[machine] dialect`` other than the profile's), or ``""``."""
    if head is not None and dialect != "dmis":
        return "its [head] is a CMM's (dialect dmis)"
    if tilt is not None and TILT_COMMANDS.get(dialect) != tilt.command:
        return f"its [tilt] command {tilt.command} is not a {dialect} command"
    if dialect in MACHINE_TOOLS and any(s.tool_number == 0 for s in rack):
        return ("its [[probe.stylus]] entries have no tool_number (a machine tool takes a "
                "stylus with T.. M6)")
    return ""


def _stylus(t: Table, k: float, dialect: str) -> Stylus:
    label = t.get_str("label", required=True) or ""
    if not LABEL.match(label):
        raise t.fail("label", "1-8 of A-Z 0-9 _ (the DMIS sensor label)")
    ball = t.get_float("ball_diameter", required=True, positive=True) or 0.0
    shank = t.get_float("shank_diameter", required=True, positive=True) or 0.0
    length = t.get_float("length", required=True, positive=True) or 0.0
    if shank >= ball:
        raise t.fail("shank_diameter", f"less than ball_diameter ({ball:g}): a stylus's "
                                       "shank is thinner than its ball, or the shank touches "
                                       "a wall with the ball")
    if length <= ball / 2.0:
        raise t.fail("length", f"more than the ball's radius ({ball / 2.0:g}): the length "
                               "runs from the ball's centre to the probe body")
    needed = dialect in MACHINE_TOOLS
    tool = t.get_int("tool_number", required=needed, minimum=1, maximum=9999) or 0
    offset = t.get_vec("offset") or (0.0, 0.0, 0.0)
    t.done()
    return Stylus(label, k * ball, k * shank, k * length, tool,
                  (k * offset[0], k * offset[1], k * offset[2]))


def _angles(t: Table, key: str, default: tuple[float, float], bound: float
            ) -> tuple[float, float]:
    """``key = [low, high]`` degrees: ordered, within ``±bound`` and holding 0 (the
    vertical probe, where every program starts and ends)."""
    low, high = t.get_vec(key, 2) or default
    if not (-bound <= low <= 0.0 <= high <= bound and low < high):
        raise t.fail(key, f"[low, high] degrees with -{bound:g} <= low <= 0 <= high <= "
                          f"{bound:g} and low < high (0: the probe vertical, where every "
                          "program starts and ends)")
    return (low, high)


def read_head(root: Table, k: float, dialect: str) -> Head | None:
    """``[head]``: a CMM's indexable head, or None when the profile has none.

    Raises:
        SpecError: not a DMIS profile, a range out of order or off the step, a step that
            is not positive, a body size that is not positive.
    """
    if not root.has("head"):
        return None
    t = root.table("head")
    if dialect != "dmis":
        raise SpecError(f"{root.where('head')}: an indexable head is a CMM's (dialect dmis), "
                        f"found dialect {dialect!r}; a machine tool turns its probe with "
                        "[tilt] (fanuc, haas) or the part with [[setup]]")
    default = Head()
    step = t.get_float("step", default.step, positive=True, maximum=90.0) or default.step
    a = _angles(t, "a", default.a, 180.0)
    b = _angles(t, "b", default.b, 360.0)
    for key, (low, high) in (("a", a), ("b", b)):
        if not all(_multiple(v, step) for v in (low, high)):
            raise t.fail(key, f"[low, high] on the head's {step:g} deg steps (multiples of "
                              "step)")
    body_d = t.get_float("body_diameter", default.body_diameter, positive=True)
    body_l = t.get_float("body_length", default.body_length, positive=True)
    t.done()
    return Head(a, b, step, k * (body_d or default.body_diameter),
                k * (body_l or default.body_length))


def _multiple(value: float, step: float) -> bool:
    n = value / step
    return abs(n - round(n)) <= 1e-9 * max(1.0, abs(n))


def read_tilt(root: Table, dialect: str) -> Tilt | None:
    """``[tilt]``: a five-axis machine's tilted work plane, or None.

    Raises:
        SpecError: not a Fanuc or Haas profile, another dialect's command, an axis out
            of the choices or the same twice, a range out of order or not holding 0.
    """
    if not root.has("tilt"):
        return None
    t = root.table("tilt")
    command = TILT_COMMANDS.get(dialect)
    if command is None:
        why = (" (LinuxCNC tilts through its own kinematics, which probegen does not "
               "drive: turn the part with [[setup]])" if dialect == "linuxcnc" else
               " (a CMM turns its probe with [head])" if dialect == "dmis" else "")
        raise SpecError(f"{root.where('tilt')}: a tilted work plane needs dialect fanuc "
                        f"(G68.2) or haas (G268), found dialect {dialect!r}{why}")
    given = t.get_str("command", command, choices=tuple(TILT_COMMANDS.values())) or command
    if given != command:
        raise t.fail("command", f"{command!r}, the {dialect} tilted-plane command")
    default = Tilt()
    tilt_axis = t.get_str("tilt_axis", default.tilt_axis, choices=("A", "B")) or "A"
    rotary_axis = t.get_str("rotary_axis", default.rotary_axis,
                            choices=("A", "B", "C")) or "C"
    if rotary_axis == tilt_axis:
        raise t.fail("rotary_axis", f"another axis than tilt_axis ({tilt_axis})")
    tilt = Tilt(command, tilt_axis, rotary_axis,
                _angles(t, "tilt_range", default.tilt_range, 180.0),
                _angles(t, "rotary_range", default.rotary_range, 360.0))
    t.done()
    return tilt


def read_setups(root: Table, k: float) -> tuple[NamedSetup, ...]:
    """``[[setup]]``: the named setups, origins times ``k``.

    Raises:
        SpecError: a bad or repeated name, not exactly one of ``rotation`` and
            ``euler_zxz``, a rotation that is not proper, a bad origin or note.
    """
    out: list[NamedSetup] = []
    for t in root.tables("setup"):
        name = t.get_str("name", required=True) or ""
        if not SETUP_NAME.match(name):
            raise t.fail("name", "1-16 of A-Z 0-9 _")
        if name in (s.name for s in out):
            raise t.fail("name", "a name no other setup has")
        rotation = _rotation(t)
        origin = t.get_vec("origin") or (0.0, 0.0, 0.0)
        note = t.get_str("note", "") or ""
        if len(note) > NOTE_LENGTH or not note.isprintable():
            raise t.fail("note", f"one line of at most {NOTE_LENGTH} printable characters "
                                 "(the fixture note in the program header)")
        t.done()
        out.append(NamedSetup(name, rotation, (k * origin[0], k * origin[1], k * origin[2]),
                              note))
    return tuple(out)


def _rotation(t: Table) -> frames.Rotation:
    """``rotation = [[...], [...], [...]]`` (rows) or ``euler_zxz = [i, j, k]`` (deg, the
    G68.2 convention of :func:`probegen.ir.frames.from_euler_zxz`), exactly one."""
    given = [key for key in ("rotation", "euler_zxz") if t.has(key)]
    if len(given) != 1:
        raise SpecError(f"{t.where('rotation')}: expected exactly one of rotation, "
                        f"euler_zxz, found {', '.join(given) or 'none'}")
    if given[0] == "euler_zxz":
        i, j, kk = t.get_vec("euler_zxz") or (0.0, 0.0, 0.0)
        turn = frames.from_euler_zxz(i, j, kk)
        return tuple(tuple(_snap(v) for v in row) for row in turn)  # type: ignore[return-value]
    value = t.get_any("rotation")
    rows = _rows(value)
    if rows is None:
        raise t.fail("rotation", "3 rows of 3 numbers")
    problem = rotation_problem(rows)
    if problem:
        raise t.fail("rotation", f"a proper rotation (rows orthonormal and determinant "
                                 f"+1, within {ROTATION_TOLERANCE:g}; {problem})")
    return rows


def _snap(x: float) -> float:
    """``x`` with values within 1e-15 of 0 or ±1 snapped (no ``6e-17`` from a right
    angle's cosine, no ``-0``)."""
    for v in (0.0, 1.0, -1.0):
        if abs(x - v) < 1e-15:
            return v + 0.0
    return x


def _rows(value: object) -> frames.Rotation | None:
    ok = isinstance(value, list) and len(value) == 3 and all(
        isinstance(r, list) and len(r) == 3 and all(
            isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)
            for v in r) for r in value)
    if not ok:
        return None
    assert isinstance(value, list)
    return tuple(tuple(float(v) for v in r) for r in value)  # type: ignore[return-value]


def rotation_problem(r: frames.Rotation) -> str:
    """What keeps ``r`` from being a proper rotation (``""`` when nothing does): the
    largest error of ``R Rᵀ = I`` (the rows' dot products) or a determinant other than
    +1 (-1: a mirror image)."""
    worst = max(abs(sum(r[i][m] * r[j][m] for m in range(3)) - (1.0 if i == j else 0.0))
                for i in range(3) for j in range(3))
    if worst > ROTATION_TOLERANCE:
        return f"the rows' dot products are off by up to {worst:.3g}"
    det = (r[0][0] * (r[1][1] * r[2][2] - r[1][2] * r[2][1])
           - r[0][1] * (r[1][0] * r[2][2] - r[1][2] * r[2][0])
           + r[0][2] * (r[1][0] * r[2][1] - r[1][1] * r[2][0]))
    if abs(det - 1.0) > ROTATION_TOLERANCE:
        return f"determinant {det:.6g}" + (": a mirror image" if det < 0 else "")
    return ""


STAR_REFUSAL = ("has a tip offset off the probe axis (a star stylus): probegen plans "
                "and collision-checks only styli along the probe axis (the ball on the "
                "axis, the shank and body above it), so it never takes this one")
"""Why a star stylus is never planned: a collision check of the wrong geometry would
clear moves that crash the star's other arms or its offset tip."""


def is_star(s: Stylus) -> bool:
    """Whether ``s`` has a tip offset off the probe axis."""
    return any(c != 0.0 for c in s.offset)


def star_refusal(styli: Iterable[Stylus], label: str, source: object) -> str | None:
    """Why the stylus ``label`` of ``styli`` (a profile's, read from ``source``) is not
    taken when it is a star stylus (:data:`STAR_REFUSAL`), else None."""
    if any(s.label == label and is_star(s) for s in styli):
        return f"stylus {label} ({source}: [[probe.stylus]]) {STAR_REFUSAL}"
    return None
