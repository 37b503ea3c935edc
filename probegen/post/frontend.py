"""The post-processor's front end: a DMIS program → ``ir.Program`` for a machine tool.

The DMIS program runs once through the DMIS interpreter (:mod:`probegen.sim.cmm`)
against a *recording* machine that finds the part exactly where the nominals put it:
every probe returns the nominal ball centre.  So the interpreter resolves units, sensors,
``SNSET``, frames (``DATSET``, ``TRANS``, ``ROTATE``, ``RECALL``), ``CONST`` and
``GOTO/INCR`` with the very code the virtual CMM runs, and the front end translates the
moves it records, statement by statement, all in work coordinates (mm; the DMIS
program's MCS is the machine tool's work offset):

* ``GOTO`` → a protected move (``ir.MoveMode.PROTECTED``);
* ``PTMEAS`` → a protected move to the approach point (``APPRCH`` off the surface along
  the PTMEAS vector), an ``ir.Touch`` (overtravel ``SEARCH``), a retract back to the
  approach point and, if ``RETRCT`` is longer, a protected move on to the retract point;
* every other statement (``FEAT``, ``MEAS``, ``DATSET``, ``OUTPUT``, ``DISPLY``,
  ``PRCOMP``, ``FILNAM``, ``OPEN``, ...) and every ``$$`` comment → an ``ir.Comment``
  with its line number (the evaluation runs the DMIS program again, so nothing is lost);
* variables, expressions, ``IF``, ``DO``, ``SELECT``, ``JUMPTO``, macros, ``TEXT/QUERY``
  (:mod:`probegen.dmis.execute`) → evaluated now: each statement reached becomes its
  comment, loops are unrolled into straight moves; a branch or move on a value measured
  at run time (``OBTAIN`` of an actual) → ``UnsupportedError`` naming the statement;
* a statement the interpreter cannot execute, or a sensor whose ball differs from the
  machine's stylus → ``UnsupportedError`` naming ``source:line``; with
  ``skip_unsupported`` it is listed in :attr:`PostedProgram.skipped` and as a comment.

The program starts at the clearance plane (the dialect's header), reaches the first
position with a rapid over it and a protected move down, and ends straight up at it.
With an obstacle every segment is checked (``planning.collision.check_program``, the
machine profile's stylus); a colliding move raises ``CollisionError`` naming the DMIS
line, or with ``reroute`` a colliding positioning move is replaced by up to the
clearance plane, across, and down (checked again).  Touches are never rerouted.
Frames built on measured features are resolved on the nominals: the part must be set
up within the probing distances, as for a CMM's first run.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from probegen import ir
from probegen.dmis.execute import execute, is_control
from probegen.dmis.reader import DmisFile, Statement
from probegen.errors import CollisionError, UnsupportedError
from probegen.geometry.frames import FloatArray
from probegen.machine.profile import MachineProfile
from probegen.planning import setup_for
from probegen.planning.collision import Obstacle, SegmentClearance, check_program
from probegen.post.posted import PostedProgram, PostTouch
from probegen.sim.cmm.features import arr, vec3
from probegen.sim.cmm.interpreter import SkippedStatement, execute_statement, record_skipped
from probegen.sim.cmm.output import StateHost
from probegen.sim.cmm.state import NotExecutable, SkipWithNote, VmState

Vec3 = tuple[float, float, float]

SENSOR_MATCH = 1e-4
"""Largest difference (mm) between the program's sensor ball and the machine's stylus (an
inch program's diameter has 5 decimals); the evaluation compensates with the program's."""

COMMENT_WIDTH = 70
"""Longest comment text on one line (every dialect brackets it within its line limit)."""

_COMMENT_CHARS = re.compile(r"[^A-Z0-9 .,:=/+\-_']")
_ID_CHARS = re.compile(r"[^A-Z0-9]")
ID_LENGTH = 16
"""Longest feature id a DPRNT line carries."""
MIN_APPROACH = 0.1
"""Shortest APPRCH (mm) a touch may start from: a G31 must travel before it triggers."""
_MOTION = frozenset({"GOTO", "PTMEAS"})
_MEASURING = frozenset({"MEAS", "PTMEAS"})


class _Recorder:
    """A ``Cmm`` that records moves and finds every surface at its nominal place."""

    def __init__(self, radius: float) -> None:
        self.radius = radius
        self.approach = 0.0
        self.events: list[tuple[str, FloatArray, FloatArray]] = []

    @property
    def ball_radius(self) -> float:
        """The machine's stylus ball radius, mm."""
        return self.radius

    def move(self, start: Vec3, end: Vec3) -> None:
        """Record a positioning move (a NaN start: the first move of the program)."""
        if np.isnan(end).any():
            raise NotExecutable("an incremental move before any absolute position")
        self.events.append(("move", arr(start), arr(end)))

    def probe(self, start: Vec3, direction: Vec3, distance: float) -> Vec3:
        """Record a probing move; the ball stops ``APPRCH`` along it (the nominal)."""
        hit = arr(start) + self.approach * arr(direction)
        self.events.append(("probe", arr(start), hit))
        return vec3(hit)


@dataclass
class _Post:
    """The translation in progress."""

    machine: MachineProfile
    obstacle: Obstacle | None
    source: str
    skip: bool
    reroute: bool
    setup: ir.Setup
    body: list[ir.Node] = field(default_factory=list)
    position: FloatArray | None = None
    touches: list[PostTouch] = field(default_factory=list)
    ids: dict[str, str] = field(default_factory=dict)
    skipped: list[SkippedStatement] = field(default_factory=list)
    dropped: list[int] = field(default_factory=list)
    rerouted: list[int] = field(default_factory=list)
    segments: list[SegmentClearance] = field(default_factory=list)

    @property
    def radius(self) -> float:
        return self.machine.probe.ball_radius

    # ----------------------------------------------------------------- checking

    def check(self, start: FloatArray, nodes: list[ir.Node], st: Statement) -> None:
        """Collision-check ``nodes`` from ``start``; raise naming the DMIS line."""
        if self.obstacle is None:
            return
        program = ir.Program(self.setup, (ir.Move(vec3(start), ir.MoveMode.RAPID), *nodes))
        try:
            report = check_program(program, self.obstacle, (), self.machine)
        except CollisionError as exc:
            raise CollisionError(f"{self.source}:{st.line}: {st.text}: {exc}") from None
        self.segments += report.segments

    def emit(self, start: FloatArray, nodes: list[ir.Node], st: Statement) -> None:
        self.check(start, nodes, st)
        self.body += nodes

    # ------------------------------------------------------------------- motion

    def goto(self, target: FloatArray, st: Statement) -> None:
        """A positioning move to ``target`` (rerouted over the clearance plane if asked)."""
        if self.position is None:
            high = np.array([target[0], target[1], self.setup.clearance_z])
            self.body.append(ir.Move(vec3(high), ir.MoveMode.RAPID))
            self.emit(high, [ir.Move(vec3(target), ir.MoveMode.PROTECTED)], st)
        else:
            try:
                self.emit(self.position, [ir.Move(vec3(target), ir.MoveMode.PROTECTED)], st)
            except CollisionError as exc:
                if not self.reroute:
                    hint = ("the move ends too near the table or under it, whatever the route: "
                            "--raised says how far the part stands above it"
                            if "the table" in str(exc) else
                            "--reroute lifts a positioning move over the clearance plane")
                    raise CollisionError(f"{exc} ({hint})") from None
                self.lift(target, st)
        self.position = target

    def lift(self, target: FloatArray, st: Statement) -> None:
        """Up to the clearance plane, across, and down to ``target``."""
        assert self.position is not None
        h = max(self.setup.clearance_z, float(self.position[2]), float(target[2]))
        up = np.array([self.position[0], self.position[1], h])
        over = np.array([target[0], target[1], h])
        nodes: list[ir.Node] = [ir.Comment(f"L{st.line} REROUTED OVER THE CLEARANCE PLANE")]
        if not np.array_equal(up, self.position):
            nodes.append(ir.Move(vec3(up), ir.MoveMode.PROTECTED))
        nodes.append(ir.Move(vec3(over), ir.MoveMode.RAPID))
        nodes.append(ir.Move(vec3(target), ir.MoveMode.PROTECTED))
        try:
            self.emit(self.position, nodes, st)
        except CollisionError as exc:
            raise CollisionError(f"{exc} (also when lifted over the clearance plane)") from None
        self.rerouted.append(st.line)

    def touch(self, state: VmState, start: FloatArray, hit: FloatArray,
              retract_to: FloatArray | None, st: Statement) -> None:
        """A PTMEAS: approach, touch, retract (see the module docstring)."""
        if state.meas is None:  # the interpreter refuses PTMEAS outside MEAS
            raise state.error("PTMEAS outside a MEAS ... ENDMES block")
        if state.approach < MIN_APPROACH:
            raise NotExecutable(f"SNSET/APPRCH is {state.approach:g} mm: a machine tool's "
                                f"touch needs at least {MIN_APPROACH:g} mm to start from")
        self.goto(start, st)
        name = state.meas.name
        fid = self.feature_id(name)
        index = 1 + sum(1 for t in self.touches if t.feature == name)
        n = (start - hit) / float(np.linalg.norm(start - hit))
        touch = ir.Touch(fid, index, ir.TouchRole.MEASURE, vec3(hit - self.radius * n),
                         vec3(n), state.approach, state.search)
        self.emit(start, [touch, ir.Move(vec3(start), ir.MoveMode.RETRACT)], st)
        self.touches.append(PostTouch(name, fid, index, st.line, vec3(start), vec3(-n),
                                      state.approach + state.search))
        if retract_to is not None and state.retract > state.approach:
            self.goto(retract_to, st)

    def feature_id(self, name: str) -> str:
        """The DPRNT id of DMIS feature ``name``: ``[A-Z0-9]``, a letter first, unique."""
        if name not in self.ids:
            base = _ID_CHARS.sub("", name.upper())
            base = base if base[:1].isalpha() else "F" + base
            fid, k = base[:ID_LENGTH], 1
            while fid in self.ids.values():
                k += 1
                fid = base[: ID_LENGTH - len(str(k))] + str(k)
            self.ids[name] = fid
        return self.ids[name]

    def finish(self, st: Statement) -> None:
        """Straight up to the clearance plane at the end of the program."""
        if self.position is not None and self.position[2] < self.setup.clearance_z:
            up = np.array([self.position[0], self.position[1], self.setup.clearance_z])
            self.emit(self.position, [ir.Move(vec3(up), ir.MoveMode.PROTECTED)], st)

    # --------------------------------------------------------------- statements

    def translate(self, state: VmState, recorder: _Recorder, st: Statement) -> None:
        """Turn what one statement recorded into IR nodes."""
        events = recorder.events
        if st.major not in _MOTION:
            self.comment(st.line, st.text)
        k = 0
        while k < len(events):
            kind, start, end = events[k]
            if kind == "move" and k + 1 < len(events) and events[k + 1][0] == "probe":
                k += 1
                continue  # the approach move: part of the touch
            if kind == "move":
                self.goto(end, st)
            else:
                after = events[k + 1][2] if k + 1 < len(events) else None
                self.touch(state, start, end, after, st)
                k += 1 if after is not None else 0
            k += 1

    def comment(self, line: int, text: str) -> None:
        """``text`` as comment lines prefixed with the DMIS line number."""
        clean = " ".join(_COMMENT_CHARS.sub(" ", text.upper()).split())
        piece = COMMENT_WIDTH - len(f"L{line} ")  # a longer word is cut into pieces
        words = [w[k : k + piece] for w in clean.split(" ") for k in range(0, len(w), piece)]
        current = f"L{line}"
        for word in words:
            if len(current) + 1 + len(word) > COMMENT_WIDTH:
                self.body.append(ir.Comment(current))
                current = f"L{line}"
            current = f"{current} {word}"
        self.body.append(ir.Comment(current))

    def not_executed(self, state: VmState, st: Statement, reason: str) -> None:
        """Raise UnsupportedError, or list the statement as skipped.

        A measuring move (``MEAS``, ``PTMEAS``, anything that fails inside a ``MEAS``
        block) is refused even with ``skip``: leaving it out would change what the
        program measures."""
        measuring = st.major in _MEASURING or state.meas is not None
        if not self.skip or measuring:
            hint = " (a measuring move is never skipped, not even with " \
                   "--skip-unsupported)" if self.skip else ""
            raise UnsupportedError(f"{self.source}:{st.line}: cannot post-process "
                                   f"{st.major} for a machine tool: {reason}{hint}\n"
                                   f"    {st.text}")
        record_skipped(state, st, reason, self.skipped)
        self.comment(st.line, f"SKIPPED {st.text}: {reason}")

    def skip_with_note(self, state: VmState, st: Statement, reason: str) -> None:
        """List a statement left out by design (no flag needed) and comment it."""
        record_skipped(state, st, reason, self.skipped, effect=False)
        self.comment(st.line, f"SKIPPED {st.text}: {reason}")


def post_dmis(program: DmisFile, machine: MachineProfile, *,
              obstacle: Obstacle | None = None, skip_unsupported: bool = False,
              reroute: bool = False, number: int = 1001, name: str = "DMIS",
              answers: Mapping[str, str | int | float] | None = None) -> PostedProgram:
    """Translate a parsed DMIS program into a machine-tool program (module docstring).

    Args:
        program: the parsed DMIS program.
        machine: the machine profile (stylus, feeds, clearance plane, work offset).
        obstacle: the part as placed in work coordinates; None skips the collision check
            (for tests of the translation only: the CLI always passes the model).
        skip_unsupported: list statements that cannot be translated instead of raising.
        reroute: lift colliding positioning moves over the clearance plane.
        number: the program number.
        name: the program name.
        answers: answers to the program's ``TEXT/QUERY`` statements, by name.

    Raises:
        UnsupportedError: a statement that cannot be translated (``source:line``), or
            one whose flow or values depend on a value measured at run time (never
            skipped: the posted program would not be the CMM's).
        DmisProgramError: the DMIS program is wrong (undefined label, no ENDFIL ...).
        CollisionError: a move would bring the stylus into the part (``source:line``).
    """
    setup = setup_for(machine, number, name, machine.clearance_z)
    post = _Post(machine, obstacle, program.source, skip_unsupported, reroute, setup)
    recorder = _Recorder(machine.probe.ball_radius)
    state = VmState(recorder, program.source, "feature", np.full(3, np.nan))
    notes = sorted(program.comments)
    ended = False
    last: Statement | None = None
    steps = execute(program, StateHost(state), answers=answers, measured="refuse",
                    notes=state.notes)
    for st in steps:
        while notes and notes[0][0] <= st.line:
            post.comment(*notes.pop(0))
        if is_control(st):  # run by execute(): values known now, loops unrolled
            post.comment(st.line, st.text)
        else:
            _statement(post, state, recorder, st)
        last = st
        if st.major == "ENDFIL" and state.meas is None:
            ended = True
            break
    if not ended or last is None:
        raise state.error("the program ends without ENDFIL")
    post.finish(last)
    return PostedProgram(ir.Program(setup, tuple(post.body)), tuple(post.touches),
                         tuple(post.skipped), tuple(post.rerouted), tuple(post.segments),
                         tuple(post.dropped),
                         tuple(SkippedStatement(*note) for note in state.notes),
                         tuple(sorted((answers or {}).items())))


def _statement(post: _Post, state: VmState, recorder: _Recorder, st: Statement) -> None:
    """Run one statement on the recorder and translate what it did."""
    state.statement = st
    recorder.events.clear()
    recorder.approach = state.approach
    block = state.meas
    if block is not None and block.skipped_at is not None and st.major != "ENDMES":
        post.skipped.append(SkippedStatement(st.line, st.text, "in the MEAS block skipped "
                                             f"at line {block.skipped_at}"))
        post.comment(st.line, f"SKIPPED {st.text}")
        return
    radius = state.radius
    try:
        execute_statement(state, st)
        _check_sensor(post, state, radius)
        post.translate(state, recorder, st)
    except SkipWithNote as exc:
        post.skip_with_note(state, st, str(exc))
    except NotExecutable as exc:
        if st.major == "SNSLCT":
            state.radius = radius
            post.dropped.append(st.line)
        post.not_executed(state, st, str(exc))


def _check_sensor(post: _Post, state: VmState, before: float | None) -> None:
    """Refuse a selected sensor whose ball is not the machine's stylus."""
    if state.radius is None or state.radius == before:
        return
    if abs(state.radius - post.radius) > SENSOR_MATCH:
        raise NotExecutable(f"the sensor's ball is D{2 * state.radius:g} mm, the machine's "
                            f"stylus D{2 * post.radius:g} mm (give a machine profile with "
                            "this stylus, or skip the SNSLCT to compensate with the "
                            "machine's)")
