"""The virtual CMM: a DMIS interpreter that runs a program against a CMM model.

:func:`run_dmis` executes a DMIS program statement by statement, as a CMM controller
would, against any object following the :class:`Cmm` protocol (moves and probing of the
stylus ball centre in machine coordinates), and returns the DMIS output file the CMM
would write, the actual features and tolerances, and the alarm that stopped it, if any.

Conventions (details in the modules named):

* Units: ``UNITS/MM|INCH,ANGDEC|ANGRAD``; everything is millimetres and machine
  coordinates inside, program units and the active PCS in statements and output.
* Frames: :mod:`probegen.sim.cmm.frames` and :mod:`probegen.sim.cmm.datums`.
* Stylus: the CMM model's ``ball_radius`` is the physical ball, touched and compensated
  with.  ``SNSLCT/S(x)`` of a ``SNSDEF/PROBE`` sensor (ball diameter: the last
  parameter) must agree with it within :data:`SENSOR_MATCH`; a different ball is not
  executed (compensating with one ball while touching with another would make every
  size wrong by the difference).  Sensors that stand for "the machine's stylus" map to
  ``cmm.ball_radius`` with a note (:attr:`DmisRunResult.notes`), without any flag:
  ``SNSLCT/SA(x)`` and ``RECALL/SA(x)`` (a sensor calibrated on the CMM) and a
  ``SNSDEF`` whose ball diameter is 0.
* PTMEAS ``x,y,z,i,j,k`` (nominal point, unit vector out of the material): the ball
  centre's target is ``p + r n``; the CMM moves straight to ``p + (r + APPRCH) n``,
  probes along ``-n`` at most ``APPRCH + SEARCH``, records the ball centre where it
  touched and retracts ``RETRCT`` along ``+n``.  Compensation of the recorded centres:
  :mod:`probegen.sim.cmm.features` (``compensation="feature"`` or ``"vector"``).
  ``SNSET/DEPTH`` is accepted and has no effect on ``PTMEAS``.  Before the program
  sets them, APPRCH, RETRCT and SEARCH are 5 mm.
* Motion: ``GOTO/x,y,z`` (or ``GOTO/INCR,d,i,j,k``) is one straight ``cmm.move``.
  With ``home=None`` the ball is taken to start where the first motion begins (that
  first positioning is not simulated).
* Alarms: a :class:`SimAlarm` from the CMM (unexpected contact) stops the run; so does
  a PTMEAS that touches nothing: alarm :data:`ALARM_NO_CONTACT`.  The result keeps
  the output written until then (without ``ENDFIL``) and the alarm with its line.
* Tolerances: :mod:`probegen.sim.cmm.tolerances`; output format:
  :mod:`probegen.sim.cmm.output`.
* Variables, expressions, IF, DO, SELECT, JUMPTO, macros and TEXT/QUERY:
  :mod:`probegen.dmis.execute` (values measured here are read by ``OBTAIN``).
* Accepted and ignored: :data:`NO_OPS`.  Skipped with their reason, always, no flag
  needed (nothing a touch depends on): :data:`NOTED` (TECOMP, FLY, MODE, WKPLAN, CRMODE,
  CZSLCT, VFORM ..., :mod:`probegen.sim.cmm.sensors`), listed in
  :attr:`DmisRunResult.skipped`.  Anything else the VM cannot execute raises
  ``UnsupportedError`` (with source and line) unless ``skip_unsupported=True``; then
  each such statement is listed in :attr:`DmisRunResult.skipped`, a MEAS block with a
  skipped statement is not fitted, and statements using labels it defined are skipped
  too.  Wrong programs raise :class:`DmisProgramError`.
"""

from __future__ import annotations

import textwrap
from collections.abc import Callable, Mapping
from dataclasses import dataclass

import numpy as np

from probegen.dmis.execute import execute, is_control
from probegen.dmis.reader import DmisFile, Label, Statement, Text, parse_dmis_all
from probegen.errors import ProbegenError, UnsupportedError
from probegen.geometry.frames import FloatArray, unit
from probegen.sim.alarms import SimAlarm
from probegen.sim.cmm.datums import (
    do_const,
    do_datdef,
    do_datset,
    do_recall,
    do_rotate,
    do_save,
    do_trans,
)
from probegen.sim.cmm.features import (
    MINIMUM_POINTS,
    Compensation,
    DmisFeature,
    Vec3,
    arr,
    fit_feature,
    undetermined,
    vec3,
)
from probegen.sim.cmm.measure import do_feat, do_meas, do_tol
from probegen.sim.cmm.output import StateHost, echo, feature_text, tolerance_text
from probegen.sim.cmm.sensors import NOTED, SENSOR_MATCH, do_noted, do_snsdef, do_snset, do_snslct
from probegen.sim.cmm.state import (
    Cmm,
    DmisProgramError,
    MeasBlock,
    NotExecutable,
    SkipWithNote,
    VmState,
)
from probegen.sim.cmm.tolerances import ToleranceResult, evaluate

__all__ = [
    "ALARM_NO_CONTACT",
    "NO_OPS",
    "NOTED",
    "SENSOR_MATCH",
    "Cmm",
    "DmisFeature",
    "DmisProgramError",
    "DmisRunResult",
    "NotExecutable",
    "VmState",
    "SimAlarm",
    "SkippedStatement",
    "ToleranceResult",
    "execute_statement",
    "record_skipped",
    "run_dmis",
]

ALARM_NO_CONTACT = 4101
"""Alarm number: a PTMEAS touched nothing within ``APPRCH + SEARCH`` of its start."""

NO_OPS = frozenset({
    "ACLRAT", "CLOSE", "DECL", "DEVICE", "DISPLY", "FEDRAT", "FINPOS", "OPEN",
    "PRCOMP", "SNSMNT", "TEXT",
})
"""Statements accepted and ignored (``TEXT/OUTFIL`` is copied to the output file)."""

_IN_MEAS = frozenset({"GOTO", "PTMEAS", "ENDMES", "SNSET", "SNSLCT"}) | NO_OPS | set(NOTED)
"""Statements allowed between MEAS and ENDMES (vendors repeat SNSET and SNSLCT before
each PTMEAS)."""


@dataclass(frozen=True, slots=True)
class SkippedStatement:
    """A statement not executed under ``skip_unsupported=True``.

    Attributes:
        line: its 1-based line.
        text: the statement as written.
        reason: what the virtual CMM does not execute.
    """

    line: int
    text: str
    reason: str


@dataclass(frozen=True, slots=True)
class DmisRunResult:
    """What running a DMIS program produced.

    Attributes:
        output: the DMIS output file text (``FILNAM`` first, ``ENDFIL`` last unless an
            alarm stopped the run), ``\\n`` line ends.
        features: actual features by name (measured and constructed), MCS millimetres.
        nominals: nominal features by name, MCS millimetres (each read in the PCS
            active where it was defined).
        tolerances: evaluated tolerances by name.
        alarm: the alarm that stopped the run, with its line, or None.
        skipped: statements not executed (only with ``skip_unsupported=True``).
        notes: statements executed with a note (line, text, the note): a sensor
            mapped to the machine's calibrated stylus.
    """

    output: str
    features: dict[str, DmisFeature]
    nominals: dict[str, DmisFeature]
    tolerances: dict[str, ToleranceResult]
    alarm: SimAlarm | None
    skipped: tuple[SkippedStatement, ...]
    notes: tuple[SkippedStatement, ...] = ()


def run_dmis(program: DmisFile | str, cmm: Cmm, *, source: str | None = None,
             skip_unsupported: bool = False, compensation: Compensation = "feature",
             home: Vec3 | None = None, answers: Mapping[str, object] | None = None
             ) -> DmisRunResult:
    """Run a DMIS program on ``cmm`` and return the output file and the actuals.

    Args:
        program: a parsed program or its text.
        cmm: the machine (see :class:`Cmm`).
        source: the file name for messages (default: the parsed file's, or ``<string>``).
        skip_unsupported: list statements the VM cannot execute instead of raising.
        compensation: ``"feature"`` or ``"vector"`` stylus compensation.
        home: the ball centre's machine position at the start, if known.
        answers: answers to ``TEXT/QUERY`` by name (:mod:`probegen.dmis.execute`).

    Returns:
        The run result; a machine alarm is reported in it, not raised.

    Raises:
        ProgramParseError: ``program`` text does not parse (every bad statement listed).
        UnsupportedError: a statement the VM cannot execute (``source:line`` named).
        DmisProgramError: the program is wrong (undefined label, too few points ...).
    """
    parsed = parse_dmis_all(program, source=source or "<string>") \
        if isinstance(program, str) else program
    start = arr(home) if home is not None else None
    state = VmState(cmm, source or parsed.source, compensation, start)
    skipped: list[SkippedStatement] = []
    alarm, ended = None, False
    for statement in execute(parsed, StateHost(state), answers=answers, notes=state.notes):
        state.statement = statement
        if is_control(statement):  # variables and control flow: run by execute()
            continue
        try:
            ended = execute_statement(state, statement)
        except SkipWithNote as exc:
            record_skipped(state, statement, str(exc), skipped, effect=False)
        except NotExecutable as exc:
            _not_executed(state, statement, str(exc), skip_unsupported, skipped)
        except SimAlarm as exc:
            alarm = exc.at_line(statement.line)
            break
        if ended:
            break
    state.statement = None
    if alarm is None and not ended:
        raise state.error("the program ends without ENDFIL")
    return DmisRunResult(_output_text(state), dict(state.actuals), dict(state.nominals),
                         dict(state.results), alarm, tuple(skipped),
                         tuple(SkippedStatement(*note) for note in state.notes))


def _output_text(state: VmState) -> str:
    header = state.header or f"FILNAM/{Text(state.name or state.source)}"
    return "\n".join([header, *state.lines]) + "\n"


def execute_statement(state: VmState, st: Statement) -> bool:
    """Execute one statement; return True at ENDFIL.

    Raises:
        NotExecutable: the statement (or a part of it) is not executed.
        DmisProgramError: the program is wrong.
    """
    if state.meas is not None and state.meas.skipped_at is not None and st.major != "ENDMES":
        return False
    if st.major == "ENDFIL":
        if state.meas is not None:
            raise state.error(f"ENDFIL inside the MEAS block of line {state.meas.line}")
        state.emit("ENDFIL")
        return True
    if state.meas is not None and st.major not in _IN_MEAS:
        where = f"{st.major} inside the MEAS block of line {state.meas.line}"
        if st.major in _HANDLERS:  # FEAT, MEAS, DATSET ... never belong there
            raise state.error(where)
        raise NotExecutable(f"{where} (scanning and vendor settings there are not executed)")
    handler = _HANDLERS.get(st.major)
    if handler is not None:
        handler(state, st)
    elif st.major not in NO_OPS:
        raise NotExecutable(f"{st.major} is not a statement the virtual CMM executes")
    return False


def _not_executed(state: VmState, st: Statement, reason: str, skip: bool,
                  skipped: list[SkippedStatement]) -> None:
    """Raise UnsupportedError, or record the skipped statement and what it defined."""
    if not skip:
        raise UnsupportedError(f"{state.source}:{st.line}: the virtual CMM cannot execute "
                               f"{st.major}: {reason}\n    {st.text}")
    record_skipped(state, st, reason, skipped)


def record_skipped(state: VmState, st: Statement, reason: str,
                   skipped: list[SkippedStatement], *, effect: bool = True) -> None:
    """List ``st`` as skipped; unless it has no ``effect`` on the measurement
    (:class:`SkipWithNote`), labels it defines (``CONST`` included) and a MEAS block it
    is in become unusable."""
    skipped.append(SkippedStatement(st.line, st.text, reason))
    if not effect:
        return
    defined = st.label if st.label is not None else (
        st.params[1] if st.major in ("CONST", "DATDEF") and len(st.params) > 1 else None)
    if isinstance(defined, Label):
        state.skipped_labels[f"{defined.kind}({defined.name})"] = st.line
    if st.major == "MEAS":
        target = st.params[1] if len(st.params) > 1 else None
        name = target.name if isinstance(target, Label) else "?"
        state.meas = MeasBlock(None, name, 0, st.line, skipped_at=st.line)
    elif state.meas is not None:
        state.meas.skipped_at = st.line


# ------------------------------------------------------------------- program frame


def do_dmismn(state: VmState, st: Statement) -> None:
    """``DMISMN/'name'[,version]``: the name is the default output FILNAM."""
    if st.params and isinstance(st.params[0], Text):
        state.name = st.params[0].value


def do_filnam(state: VmState, st: Statement) -> None:
    """``FILNAM/'name'[,version]``: the first line of the output file."""
    state.header = echo(st)


def do_units(state: VmState, st: Statement) -> None:
    """``UNITS/MM|INCH,ANGDEC|ANGRAD``: echoed to the output."""
    state.set_units(st.params)
    state.emit(echo(st))


def do_text(state: VmState, st: Statement) -> None:
    """``TEXT/OUTFIL,'...'`` is copied to the output file; other TEXT is ignored."""
    if st.params and st.params[0] == "OUTFIL":
        state.emit(echo(st))


# ------------------------------------------------------------------------ sensors


def _ball_radius(state: VmState) -> float:
    return state.radius if state.radius is not None else float(state.cmm.ball_radius)


# ------------------------------------------------------------------------- motion


def _move(state: VmState, target: FloatArray) -> None:
    """Move the ball centre to ``target`` (MCS) in a straight line."""
    if state.position is not None and not np.array_equal(state.position, target):
        state.cmm.move(vec3(state.position), vec3(target))
    state.position = target


def do_goto(state: VmState, st: Statement) -> None:
    """``GOTO/[CART,]x,y,z`` in the active PCS, or ``GOTO/INCR,distance,i,j,k``."""
    params = list(st.params)
    if params and params[0] == "INCR":
        if state.position is None:
            raise state.error("GOTO/INCR before the machine position is known")
        values = state.numbers(params[1:], "GOTO/INCR")
        if len(values) != 4:
            raise state.error("GOTO/INCR expects distance,i,j,k")
        step = unit(state.frame.vector_to_mcs(arr((values[1], values[2], values[3]))))
        _move(state, state.position + values[0] * state.scale * step)
        return
    if params and params[0] == "CART":
        params = params[1:]
    if len(params) != 3:
        raise NotExecutable("GOTO: only x,y,z (CART) and INCR positions are executed")
    xyz = np.array(state.numbers(params, "GOTO coordinate")) * state.scale
    _move(state, state.frame.to_mcs(xyz))


def do_ptmeas(state: VmState, st: Statement) -> None:
    """``PTMEAS/CART,x,y,z,i,j,k``: touch one point (see the module docstring)."""
    block = state.meas
    if block is None:
        raise state.error("PTMEAS outside a MEAS ... ENDMES block")
    params = list(st.params)
    if not params or params[0] != "CART" or len(params) != 7:
        raise NotExecutable("PTMEAS: only CART,x,y,z,i,j,k (with the vector) is executed")
    values = state.numbers(params[1:], "PTMEAS value")
    point = state.frame.to_mcs(np.array(values[:3]) * state.scale)
    try:
        vector = unit(state.frame.vector_to_mcs(np.array(values[3:])), what="PTMEAS vector")
    except ProbegenError as exc:
        raise state.error(str(exc)) from None
    block.centres.append(_touch(state, point, vector))
    block.vectors.append(vector)


def _touch(state: VmState, point: FloatArray, vector: FloatArray) -> FloatArray:
    """Approach, probe and retract for one point; return the ball centre at contact."""
    target = point + _ball_radius(state) * vector
    start = target + state.approach * vector
    _move(state, start)
    reach = state.approach + state.search
    hit = state.cmm.probe(vec3(start), vec3(-vector), reach)
    if hit is None:
        where = ", ".join(f"{v / state.scale:.5f}" for v in state.frame.to_pcs(point))
        raise SimAlarm(ALARM_NO_CONTACT, f"PTMEAS {where}: no contact within "
                       f"APPRCH + SEARCH = {reach / state.scale:g}")
    centre = arr(hit)
    state.position = centre
    if state.retract > 0.0:
        _move(state, centre + state.retract * vector)
    return centre


def do_endmes(state: VmState, st: Statement) -> None:
    """``ENDMES``: fit the measured feature and store it as ``FA(x)``."""
    block = state.meas
    if block is None:
        raise state.error("ENDMES without MEAS")
    state.meas = None
    if block.skipped_at is not None or block.nominal is None:
        state.skipped_labels[f"F({block.name})"] = block.skipped_at or block.line
        return
    nominal, found = block.nominal, len(block.centres)
    if found != block.count:
        raise state.error(f"MEAS/{nominal.kind} F({nominal.name}) at line {block.line} "
                          f"announced {block.count} points, the block measured {found}")
    if found < MINIMUM_POINTS[nominal.kind]:
        raise state.error(f"MEAS/{nominal.kind} needs at least "
                          f"{MINIMUM_POINTS[nominal.kind]} points, found {found}")
    why = undetermined(nominal, np.array(block.centres))
    if why:
        raise state.error(f"MEAS/{nominal.kind} F({nominal.name}): {why}; not reported as "
                          "a measurement")
    try:
        actual = fit_feature(nominal, np.array(block.centres), np.array(block.vectors),
                             _ball_radius(state), state.compensation)
    except ProbegenError as exc:
        raise state.error(f"MEAS/{nominal.kind} F({nominal.name}): {exc}") from None
    state.actuals[nominal.name] = actual


# ---------------------------------------------------------------------- results


def do_eval(state: VmState, st: Statement) -> None:
    """``EVAL/FA(f),T(t)``: evaluate a tolerance (reported by a later ``OUTPUT/TA(t)``)."""
    if len(st.params) != 2:
        raise state.error("EVAL expects FA(feature),T(tolerance)")
    feature = state.actual(state.label(st.params[0], ("FA",), "EVAL").name)
    _evaluate(state, state.label(st.params[1], ("T",), "EVAL").name, feature)


def _evaluate(state: VmState, name: str, feature: DmisFeature) -> ToleranceResult:
    if name not in state.tolerances:
        state.check_skipped("T", name)
        raise state.error(f"T({name}) is not defined")
    nominal = state.nominal(feature.name)
    try:
        result = evaluate(state.tolerances[name], feature, nominal,
                          vec3(state.frame.rotation[2]))
    except ValueError as exc:
        raise state.error(str(exc)) from None
    state.results[name] = result
    return result


def do_output(state: VmState, st: Statement) -> None:
    """``OUTPUT/FA(x)[,TA(t)...]``: echo, then the actuals in the active PCS.

    ``TA(t)`` is evaluated on the last feature before it in the statement, or, without
    one, taken from an earlier ``EVAL``; ``F(x)`` writes the nominal.
    """
    texts: list[str] = []
    last: DmisFeature | None = None
    for param in st.params:
        if isinstance(param, Label) and param.kind not in ("FA", "F", "TA", "T"):
            raise NotExecutable(f"OUTPUT/{param}: only FA, F, TA and T are reported")
        ref = state.label(param, ("FA", "F", "TA", "T"), "OUTPUT")
        if ref.kind == "FA":
            last = state.actual(ref.name)
            texts.append(feature_text("FA", last, state.frame, state.scale))
            texts.extend(_comment(f"FA({last.name}) warning: {note}") for note in last.notes)
        elif ref.kind == "F":
            texts.append(feature_text("F", state.nominal(ref.name), state.frame,
                                      state.scale))
        else:
            texts.append(tolerance_text(_tolerance_for(state, ref.name, last), state.scale))
    state.emit(echo(st))
    for text in texts:
        state.emit(text)


def _comment(text: str) -> str:
    """``text`` as DMIS comment lines (``$$ ...``) of at most 80 characters."""
    return "\n".join(f"$$ {line}" for line in textwrap.wrap(text, width=77))


def _tolerance_for(state: VmState, name: str, feature: DmisFeature | None
                   ) -> ToleranceResult:
    if feature is not None:
        return _evaluate(state, name, feature)
    if name in state.results:
        return state.results[name]
    state.check_skipped("T", name)
    raise state.error(f"TA({name}): no feature to evaluate it on (OUTPUT/FA(x),TA({name}) "
                      "or EVAL first)")


_HANDLERS: dict[str, Callable[[VmState, Statement], None]] = {
    "DMISMN": do_dmismn, "FILNAM": do_filnam, "UNITS": do_units, "TEXT": do_text,
    "SNSDEF": do_snsdef, "SNSLCT": do_snslct, "SNSET": do_snset, "GOTO": do_goto,
    "FEAT": do_feat, "TOL": do_tol, "MEAS": do_meas, "PTMEAS": do_ptmeas,
    "ENDMES": do_endmes, "DATSET": do_datset, "TRANS": do_trans, "ROTATE": do_rotate,
    "DATDEF": do_datdef, "SAVE": do_save, "RECALL": do_recall, "CONST": do_const,
    "EVAL": do_eval, "OUTPUT": do_output,
}
_HANDLERS.update({major: do_noted for major in NOTED})
"""Major word -> handler; majors in :data:`NO_OPS` need none."""
