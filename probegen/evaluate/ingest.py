"""From what the machine returned to evaluated features: ``probegen ingest``.

Reads a DPRNT log (as captured: the raw bytes on disk are never rewritten), matches each
measuring touch to its planned point by feature id and point index, compensates the ball
centres along the planned normals, fits and evaluates each feature into an
:class:`Ingested` (written as ``results.json`` and ``results.csv`` by
:mod:`probegen.evaluate.outputs`).

Matching: the spec is planned again (its program without the collision check), so
touch ``k`` of feature ``F`` is the plan's ``k``-th point of ``F``.  Before matching, the
log is checked against that plan (:mod:`probegen.results.logcheck`): the run used (the last
complete one unless ``run`` says otherwise), the program number and identity its
``PGSTART`` prints, unknown and duplicate point ids, and touches that cannot be their
planned move (treated as missing).  A resumed program (a run cut short, then a new
``PGSTART``) re-prints some points: the runs are read together and a repeated point counts
once, the last one read; the same point twice within one run is refused.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypeVar

import numpy as np

from probegen.errors import ProbegenError
from probegen.evaluate.actions import Decision, decisions
from probegen.evaluate.characteristics import (
    Evaluated,
    NotEvaluated,
    accepted,
    run_status,
)
from probegen.evaluate.freeform import (
    FreeformResult,
    NominalPoint,
    Touches,
    complete_guides,
    evaluate_freeform,
)
from probegen.evaluate.planar import PlanarResult, evaluate_planar
from probegen.evaluate.revolved import Nominal, RevolvedResult, evaluate_revolved
from probegen.evaluate.run_identity import (
    IdentityOptions,
    RunIdentity,
    program_label,
    run_identity,
)
from probegen.evaluate.sphere_test import SphereTestResult, evaluate_sphere_test
from probegen.geometry.determined import incomplete
from probegen.geometry.fits_solver import vec3
from probegen.geometry.uncertainty import Budget, few_dof_note
from probegen.ir import frames
from probegen.machine.calibration import (
    ProbeCalibration,
    calibration_state,
    compensate,
    for_stylus,
    stylus_calibration,
)
from probegen.results import DmisOutput, DprntLog, read_dmis_output
from probegen.results.dprnt import log_lines, parse_dprnt, read_raw
from probegen.results.logcheck import check_log, ranges
from probegen.spec.actions import PlanarSpec
from probegen.spec.model import FreeformSpec, RevolvedSpec, Spec, SphereTest

if TYPE_CHECKING:
    from probegen.cad import Part

Vec3 = tuple[float, float, float]

MIN_POINTS = 5
"""Fewest touches a sphere test is evaluated from (4 determine a sphere; one more checks)."""


@dataclass(frozen=True, slots=True)
class Ingested:
    """Everything ``ingest`` found.

    Attributes:
        source: the log file.
        log: the parsed log (with its diagnostics).
        results: one evaluated result per sphere test with all its touches.
        notes: problems found while matching (missing touches, alarms in the log).
        path: the planned stylus path at nominal, as (feature, kind, start, end) segments
            (kind: rapid, protected, or touch ...), for the report.
        revolved: one evaluated result per revolved feature (method M2) with all its
            touches.
        decisions: the in-process decisions' values, offline and as the machine
            printed them (``ingest_actions``).
        freeform: one evaluated result per free-form feature with all its touches.
        planar: one evaluated result per line and plane with all its touches.
        not_evaluated: every other spec feature: too few or no-contact touches, a
            failed fit, a run cut short before it, touches removed as implausible
            (``NOT EVALUATED``).
        rule: the ISO 14253-1 decision rule of the verdicts (``simple``, ``guard_band``).
        budget: the stated uncertainty contributions the characteristics' ``u`` used.
        calibration: the probe calibration the results were compensated with, or None
            (the nominal ball radius).
        run: the run's identity (part number, serial, time ...; :func:`identified`),
            None until it is gathered.
    """

    source: str
    log: DprntLog
    results: tuple[SphereTestResult, ...]
    notes: tuple[str, ...]
    path: tuple[tuple[str, str, Vec3, Vec3], ...] = ()
    revolved: tuple[RevolvedResult, ...] = ()
    decisions: tuple[Decision, ...] = ()
    freeform: tuple[FreeformResult, ...] = ()
    planar: tuple[PlanarResult, ...] = ()
    not_evaluated: tuple[NotEvaluated, ...] = ()
    rule: str = "simple"
    budget: Budget = Budget()
    calibration: ProbeCalibration | None = None
    run: RunIdentity | None = None

    @property
    def evaluated(self) -> tuple[Evaluated, ...]:
        """Every completely evaluated feature, by kind (sphere tests, revolved,
        free-form, planar), each in spec order."""
        return (*self.results, *self.revolved, *self.freeform, *self.planar)

    @property
    def status(self) -> str:
        """The run's status (:func:`probegen.evaluate.characteristics.run_status`)."""
        return run_status((accepted(r.characteristics, self.rule) for r in self.evaluated),
                          not_evaluated=bool(self.not_evaluated), complete=self.log.complete)

    @property
    def incomplete(self) -> tuple[str, ...]:
        """Ids of the features NOT EVALUATED (missing, no-contact or implausible touches,
        a run cut short, a failed fit): a calibration is never written from such a
        sphere test."""
        return tuple(n.feature for n in self.not_evaluated)

    @property
    def uncertainty_notes(self) -> tuple[str, ...]:
        """What the uncertainties leave out: unstated contributions, fits with few
        degrees of freedom (a revolved result without points is a CMM's feature actual,
        not a fit of ours: ``evaluate/setups_dmis.py``)."""
        fits = [(r.feature, "sphere_test", len(r.points)) for r in self.results]
        fits += [(r.feature, r.kind, len(r.points)) for r in self.revolved if r.points]
        few = [few_dof_note(f, k, n, self.budget) for f, k, n in fits]
        return (*self.budget.notes(), *(n for n in few if n is not None))

    @property
    def ok(self) -> bool:
        """No evaluated feature fails its verdict under ``rule``."""
        return not any(accepted(r.characteristics, self.rule) is False
                       for r in self.evaluated)

    @property
    def calibration_text(self) -> str:
        """What every output says about the calibration used."""
        return str(calibration_state(self.calibration)["state"])


def identified(ing: Ingested, spec: Spec,
               options: IdentityOptions | None = None) -> Ingested:
    """``ing`` with its run identity (:mod:`probegen.evaluate.run_identity`): the
    options, the log's ``PGSERIAL`` and ``PGSTART`` (program number and identity token of
    the run read), the spec's ``[part]``, the profile's name, the log file's time.

    Raises:
        ProbegenError: a bad option (``--time`` not ISO 8601 with an offset ...).
    """
    last = ing.log.runs[-1] if ing.log.runs else None
    number = last.program if last is not None and last.program is not None else (
        ing.log.program or spec.program_number)
    identity = run_identity(
        source=ing.source, options=options or IdentityOptions(),
        part_number=spec.part_number, part_name=spec.part_name, machine=spec.machine.name,
        program=program_label(number, None if last is None else last.identity),
        log_serial=ing.log.serial,
        calibration=None if ing.calibration is None else ing.calibration.fingerprint)
    return dataclasses.replace(ing, run=identity)


def calibration_notes(log: DprntLog, calibration: ProbeCalibration | None) -> list[str]:
    """Warnings when the log's ``PGCAL`` (the calibration its program was compiled with)
    is not the calibration the results use."""
    marks = sorted({m.fingerprint for m in log.calibrations})
    if not marks:
        if calibration is None:
            return []
        return [f"the program was compiled without a probe calibration (no PGCAL line): "
                f"the values it computed on the control used the nominal ball radius, "
                f"the results use calibration {calibration.fingerprint}"]
    if calibration is None:
        return [f"the program was compiled with probe calibration {', '.join(marks)} "
                f"(PGCAL) but none was given (--calibration): the results use the "
                f"nominal ball radius"]
    other = [m for m in marks if m != calibration.fingerprint]
    if other:
        return [f"the program was compiled with probe calibration {', '.join(other)} "
                f"(PGCAL), the results use {calibration.fingerprint} "
                f"({calibration.source or 'unknown source'})"]
    return []


def budget_of(spec: Spec, calibration: ProbeCalibration | None) -> Budget:
    """The stated uncertainty contributions: the profile's and the calibration's."""
    stated = spec.machine.uncertainty
    return Budget(0.0 if calibration is None else calibration.u_radius, stated.machine,
                  stated.probe)


Outcome = Evaluated | NotEvaluated


class _Gaps:
    """Which planned touches of a feature are missing or reported no contact.

    A no-contact touch is an ``ERR NOTOUCH`` record not followed by a touch of the
    same point (a resumed program that measured it again)."""

    def __init__(self, log: DprntLog, touches: Touches) -> None:
        self.touches = touches
        self.notouch = log.no_contact()

    def reason(self, feature: str, indices: Sequence[int], *, missing_too: bool = True
               ) -> str:
        """Why the feature is incomplete ("" when every touch is there); only the
        no-contact touches unless ``missing_too``."""
        blind = [k for k in indices if (feature, k) in self.notouch]
        missing = [k for k in indices if (feature, k) not in self.touches and k not in blind]
        why = [f"no contact at point {k} (ERR NOTOUCH, line {self.notouch[(feature, k)]})"
               for k in blind]
        if missing and missing_too:
            why.append(f"no touch for point{'s' if len(missing) > 1 else ''} "
                       f"{ranges(missing)}")
        return "; ".join(why)


def ingest(log_path: str | Path, spec: Spec, *,
           calibration: ProbeCalibration | None = None, with_path: bool = False,
           decision_rule: str | None = None, run: int | None = None,
           ignore_identity: bool = False, part: Part | None = None,
           turn: frames.Rotation | None = None) -> Ingested:
    """Read a DPRNT log and evaluate every feature of ``spec``: completely, or as
    ``NOT EVALUATED`` with the reason.

    The log is first checked against the program (:func:`probegen.results.logcheck.check_log`:
    program number and identity, which run, unknown and duplicate point ids, touches
    too far from their planned move); ``run`` (1-based) and ``ignore_identity`` are
    passed to it.  ``with_path`` also runs the collision check of the whole program
    again to record the nominal stylus path for the report.  ``decision_rule``
    overrides the spec's ``[evaluation] decision_rule``.  ``calibration`` defaults to
    the spec's ``[machine] calibration``.  ``part`` is the spec's model, loaded
    (:func:`probegen.planning.part_of`); loaded here when not given.  ``turn``: a named
    setup's program (``spec`` and ``part`` the setup's, in the table frame,
    :mod:`probegen.evaluate.setups`): the setup's rotation ``R`` (``p_table =
    R·p_part``); the revolved features' touches and nominals are turned back to part
    coordinates before the fits.

    Raises:
        ProbegenError: the log cannot be read, belongs to another program, names points
            the plan does not have, or holds no touch of any feature of the spec and no
            alarm of one (a run stopped at its first touch is NOT EVALUATED).
    """
    from probegen.planning import part_of, plan_program
    from probegen.planning.identity import planned_touches
    from probegen.planning.well_posed import for_log

    spec = for_log(spec)  # a DPRNT log: planned as its Macro B program was

    calibration = for_stylus(calibration or spec.machine.calibration,
                             spec.machine.probe.ball_radius, f"{spec.source}: [machine]")
    if part is None:
        part = part_of(spec)
    planned = plan_program(spec, runtime_variables=True, check_collisions=with_path,
                           part=part)
    data = read_raw(log_path)  # once: parsed here, quoted in diagnostics by check_log
    checked = check_log(parse_dprnt(data, source=str(log_path)), program=spec.program_number,
                        identity=planned.program.setup.identity,
                        touches=planned_touches(planned.program, planned.sphere_tests),
                        run=run, ignore_identity=ignore_identity,
                        lines=log_lines(data))
    log = checked.log
    notes = list(checked.notes) + calibration_notes(log, calibration)
    notes += [f"the program stopped: ERR {e.code} {e.feature} {e.index} (line {e.line})"
              for e in log.errors]
    if not log.complete:
        notes.append("the log has no PGEND line: the program did not finish")
    touches = {(t.feature, t.index): t.xyz for t in log.latest_touches() if t.kind == "PT"}
    ids = {f.id for f in spec.features}
    if not any(f in ids for f, _ in touches) and not any(e.feature in ids
                                                          for e in log.errors):
        raise ProbegenError(f"{log_path}: expected measuring touches (PT lines) of the "
                            f"spec's features, found none usable; " + "; ".join(notes))
    gaps = _Gaps(log, touches)
    budget = budget_of(spec, calibration)
    outcomes: list[Outcome] = []
    oriented = {o.plan.spec.id: o for o in planned.oriented}
    for feature in spec.features:
        if isinstance(feature, RevolvedSpec):
            outcomes.append(_revolved(feature, spec, oriented[feature.id], touches, notes,
                                      gaps, budget, calibration, turn))
        elif isinstance(feature, FreeformSpec):
            outcomes.append(ingest_freeform(feature, spec, part, touches, notes, calibration,
                                            gaps))
        elif isinstance(feature, PlanarSpec):
            outcomes.append(_planar(feature, spec, part, touches, gaps, calibration))
        else:
            outcomes.append(_sphere_test(feature, spec, part, touches, notes, gaps,
                                         calibration, budget))
    path = tuple((s.feature, s.kind, s.start, s.end)
                 for s in planned.clearance.segments) if with_path else ()
    return Ingested(str(log_path), log, _only(outcomes, SphereTestResult), tuple(notes),
                    path, _only(outcomes, RevolvedResult), decisions(spec, log, calibration, part),
                    _only(outcomes, FreeformResult), _only(outcomes, PlanarResult),
                    _only(outcomes, NotEvaluated), decision_rule or spec.decision_rule, budget,
                    calibration)


T = TypeVar("T")


def _only(outcomes: Sequence[object], kind: type[T]) -> tuple[T, ...]:
    return tuple(o for o in outcomes if isinstance(o, kind))


def _judge(feature: str, kind: str, reason: str,
           names: Sequence[tuple[str, float | None, float | None]],
           evaluate: Callable[[], Evaluated] | None) -> Outcome:
    """The outcome of one feature: ``evaluate()`` when nothing is missing, else NOT
    EVALUATED for ``reason`` (with the fit of the touches there are, when ``evaluate``
    is given and succeeds, for information).  A failed fit is NOT EVALUATED too."""
    def not_evaluated(why: str, partial: Evaluated | None) -> NotEvaluated:
        return NotEvaluated(feature, kind, why, tuple(n for n, _, _ in names),
                            tuple((lo, hi) for _, lo, hi in names), partial)

    if evaluate is None:
        return not_evaluated(reason, None)
    try:
        result = evaluate()
    except ProbegenError as exc:
        return not_evaluated("; ".join(w for w in (reason, f"the fit failed: {exc}") if w),
                             None)
    return not_evaluated(reason, result) if reason else result


def _limits(*pairs: tuple[str, tuple[float | None, float | None] | None]
            ) -> list[tuple[str, float | None, float | None]]:
    """The toleranced characteristics among ``(name, limits or None)``."""
    return [(n, lim[0], lim[1]) for n, lim in pairs if lim is not None]


def _sym(limit: float | None) -> tuple[float | None, float | None] | None:
    return None if limit is None else (-limit, limit)


def _upper(limit: float | None) -> tuple[float | None, float | None] | None:
    return None if limit is None else (None, limit)


def _sphere_test(feature: SphereTest, spec: Spec, part: Part | None, touches: Touches,
                 notes: list[str], gaps: _Gaps, calibration: ProbeCalibration | None,
                 budget: Budget) -> Outcome:
    """Evaluate a sphere test (method M1) from its touches, with the stylus it names
    (its ball; its entry of ``calibration``)."""
    from probegen.planning.sphere_test import plan_points, resolve_sphere, sphere_test_profile

    machine = sphere_test_profile(feature, spec.machine)
    stylus = machine.stylus.label if machine.rack else ""
    if machine is not spec.machine and calibration is not None:
        calibration = stylus_calibration(calibration, stylus, machine.probe.ball_radius, "",
                                         feature.where)
    sphere = resolve_sphere(feature, part)
    plan = plan_points(feature, sphere, machine)
    planned = range(1, len(plan.directions) + 1)
    found = [k for k in planned if (feature.id, k) in touches]
    missing = sorted(set(planned) - set(found))
    if missing:
        notes.append(f"feature {feature.id}: no touch for points {ranges(missing)}")
    tol = feature.tolerance
    names = _limits(("POS", _upper(tol.position)), ("D", _sym(tol.size)),
                    ("P_FTU", _upper(tol.form)), ("P_STU", _sym(tol.size)))
    reason = gaps.reason(feature.id, planned)

    def evaluate() -> SphereTestResult:
        centres = np.array([touches[(feature.id, k)] for k in found])
        normals = np.array([plan.directions[k - 1] for k in found])
        # One radius, not the map: the sphere test measures the map (P_FTU, the radii
        # by direction); compensating it with the map would hide what it measures.
        r = machine.probe.ball_radius if calibration is None else \
            calibration.effective_radius
        result = evaluate_sphere_test(
            feature.id, compensate(centres, normals, r), normals,
            nominal_centre=sphere.centre, calibrated_diameter=sphere.diameter,
            ball_radius=r, nominal_radius=machine.probe.ball_radius,
            form=tol.form, size=tol.size, position=tol.position, budget=budget)
        return replace(result, stylus=stylus)

    if len(found) < MIN_POINTS:
        notes.append(f"feature {feature.id}: not evaluated, {len(found)} touches "
                     f"(at least {MIN_POINTS} needed)")
        return _judge(feature.id, "sphere_test", reason, names, None)
    return _judge(feature.id, "sphere_test", reason, names, evaluate)


def _planar(feature: PlanarSpec, spec: Spec, part: Part | None, touches: Touches,
            gaps: _Gaps, calibration: ProbeCalibration | None) -> Outcome:
    """Evaluate a line or plane from its touches (``evaluate_planar``)."""
    from probegen.planning.actions import planar_fit
    from probegen.planning.planar import plan_planar

    machine = dataclasses.replace(spec.machine, calibration=calibration)
    check = planar_fit(plan_planar(feature, part, machine), machine)
    tol = feature.tolerance
    names = _limits(("DIST", tol.position), ("ANGLE", _sym(tol.angle)),
                    ("FORM", _upper(tol.form)))
    planned = range(1, len(feature.contacts) + 1)
    reason = gaps.reason(feature.id, planned)
    balls = {k: touches[(feature.id, k)] for k in planned if (feature.id, k) in touches}
    return _judge(feature.id, feature.kind, reason, names, None if reason else (
        lambda: evaluate_planar(check, balls, radius=calibration, tolerance=tol)))


def ingest_freeform(feature: FreeformSpec, spec: Spec, part: Part | None, touches: Touches,
                    notes: list[str], calibration: ProbeCalibration | None = None,
                    gaps: _Gaps | None = None) -> Outcome:
    """Evaluate one free-form feature from ball centres by (feature, touch index).

    The feature is planned again (with its collision checks) for the theoretical contact
    points and normals; a guide point missing a touch (or, with ``gaps``, one with a
    no-contact touch) makes the feature NOT EVALUATED, with the other guide points'
    deviations for information.
    """
    from probegen.planning import make_setup
    from probegen.planning.freeform_spec import plan_freeform

    plan = plan_freeform(feature, part, spec.machine, make_setup(spec))
    nominal = [NominalPoint(t.guide, t.contact, t.normal) for t in plan.touches
               if t.role == 0]
    full, missing = complete_guides(feature.id, feature.method, nominal, touches)
    lim = feature.deviation
    names = [] if lim is None else [(f"E{p.guide}", lim[0], lim[1]) for p in nominal]
    reason = "" if gaps is None else gaps.reason(
        feature.id, [t.index for t in plan.touches], missing_too=False)
    if missing:
        notes.append(f"feature {feature.id}: guide points {ranges(missing)} lack touches, "
                     "not evaluated")
        reason = "; ".join(w for w in (reason, f"guide points {ranges(missing)} lack "
                                               "touches") if w)
    if not full:
        notes.append(f"feature {feature.id}: not evaluated, no guide point has all its "
                     "touches")
        return _judge(feature.id, "freeform", reason, names, None)
    r = spec.machine.probe.ball_radius if calibration is None else calibration
    return _judge(feature.id, "freeform", reason, names, lambda: evaluate_freeform(
        feature.id, feature.method, full, touches, direction=feature.direction, radius=r,
        deviation=feature.deviation, budget=budget_of(spec, calibration)))


def dmis_touches(output: DmisOutput, spec: Spec) -> dict[tuple[str, int], Vec3]:
    """Ball centres of the free-form touches in a DMIS output file, by (feature, index).

    Touch ``k`` of feature ``F`` is the point actual ``FA(F_k)``; the CMM reports the
    contact compensated along the PTMEAS vector, so the ball centre is the point plus
    the ball radius along that vector.
    """
    ids = {f.id for f in spec.features if isinstance(f, FreeformSpec)}
    r = spec.machine.probe.ball_radius
    out: dict[tuple[str, int], Vec3] = {}
    for fa in output.features:
        name, _, index = fa.name.rpartition("_")
        if fa.type == "POINT" and name in ids and index.isdigit() and fa.direction:
            p, n = np.array(fa.position), np.array(fa.direction)
            x, y, z = (p + r * n).tolist()
            out[(name, int(index))] = (x, y, z)
    return out


def ingest_dmis(path: str | Path, spec: Spec, *, decision_rule: str | None = None,
                part: Part | None = None) -> Ingested:
    """``probegen ingest`` of a DMIS output file: the free-form features of ``spec``
    (the CMM reports the other kinds itself; ``probegen qif`` exports them).

    ``log`` is an empty DPRNT log that carries the file's diagnostics; ``complete`` is
    whether the output holds at least one feature actual.

    ``part`` is the spec's model, loaded; loaded here when not given.

    Raises:
        ProbegenError: the file cannot be read, or holds no free-form touches of the spec.
    """
    output = read_dmis_output(path)
    outcomes, notes = ingest_dmis_freeform(output, spec, part)
    if not any(isinstance(o, FreeformResult) or (
            isinstance(o, NotEvaluated) and o.partial is not None) for o in outcomes):
        raise ProbegenError(f"{path}: expected point actuals FA(<id>_<k>) of the spec's "
                            "free-form features, found none usable; " + "; ".join(notes))
    log = DprntLog(str(path), None, (), (), (), bool(output.features), 0, output.diagnostics)
    return Ingested(str(path), log, (), notes, freeform=_only(outcomes, FreeformResult),
                    not_evaluated=_only(outcomes, NotEvaluated),
                    rule=decision_rule or spec.decision_rule, budget=budget_of(spec, None))


def ingest_dmis_freeform(output: DmisOutput, spec: Spec, part: Part | None = None
                         ) -> tuple[tuple[Outcome, ...], tuple[str, ...]]:
    """Evaluate the free-form features of ``spec`` from a DMIS output file (the CMM
    evaluates the other kinds itself); returns the outcomes and the notes.  ``part`` is
    the spec's model, loaded; loaded here when not given (and the spec has free-form
    features)."""
    from probegen.planning import part_of

    touches = dmis_touches(output, spec)
    notes: list[str] = []
    wanted = [f for f in spec.features if isinstance(f, FreeformSpec)]
    if part is None and wanted:
        part = part_of(spec)
    found = [ingest_freeform(f, spec, part, touches, notes) for f in wanted]
    return tuple(found), tuple(notes)


def _revolved(feature: RevolvedSpec, spec: Spec, oriented: Any, touches: Touches,
              notes: list[str], gaps: _Gaps, budget: Budget,
              calibration: ProbeCalibration | None = None,
              turn: frames.Rotation | None = None) -> Outcome:
    """Evaluate a revolved feature from its touches (NOT EVALUATED: a touch missing or
    without contact, too few to fit, or a failed fit).

    ``oriented`` is the feature's plan in the re-planned program
    (``planning.oriented.OrientedPlan``): a feature measured in a turned frame has its
    plan there and the control printed its touches there (#5061-#5063 under G68.2), so
    the nominal and the touches are turned back to work coordinates with the frame's
    rotation (:mod:`probegen.ir.frames`); the ball is that of the feature's stylus (the
    calibration's radius only for the ``[probe]`` stylus).  ``turn``: a named setup's
    rotation ``R``; the frame's rotation is then ``Rᵀ·O`` (frame → table → part).
    """
    plan, rotation = oriented.plan, oriented.orientation.rotation
    if turn is not None:
        rotation = frames.product_t(turn, rotation)  # Rᵀ·O
    if oriented.stylus != spec.machine.stylus:
        calibration = None
    ball = oriented.stylus.ball_radius if calibration is None else calibration
    indices = sorted(plan.normals)
    found = [k for k in indices if (feature.id, k) in touches]
    missing = sorted(set(indices) - set(found))
    if missing:
        notes.append(f"feature {feature.id}: no touch for points {ranges(missing)}")
    nominal = nominal_in_work(nominal_of(plan), rotation)
    names = _revolved_names(feature, len(nominal.sections))
    reason = gaps.reason(feature.id, indices)
    which = [plan.section_of_touch[k] for k in found]
    few = incomplete(feature.kind, which)  # the planner's rule too (well_posed)
    if few:
        notes.append(f"feature {feature.id}: not evaluated, {few}")
        return _judge(feature.id, feature.kind, reason or f"too few touches: {few}", names,
                      None)
    outcome = _judge(feature.id, feature.kind, reason, names, lambda: evaluate_revolved(
        feature.id, nominal, [frames.apply(rotation, touches[(feature.id, k)])
                              for k in found], which,
        ball_radius=ball, limits=feature.tolerance, budget=budget))
    if isinstance(outcome, NotEvaluated) and outcome.partial is None:
        notes.append(f"feature {feature.id}: not evaluated: {outcome.reason}")
    found_fit = outcome.partial if isinstance(outcome, NotEvaluated) else outcome
    if isinstance(found_fit, RevolvedResult):
        notes.extend(found_fit.notes)  # other solutions the touches admit
    return outcome


def _revolved_names(feature: RevolvedSpec, sections: int
                    ) -> list[tuple[str, float | None, float | None]]:
    """The toleranced characteristics of a revolved feature, in the order
    ``evaluate_revolved`` gives them."""
    t, kind = feature.tolerance, feature.kind
    per_section: list[tuple[str, tuple[float | None, float | None] | None]] = []
    if kind in ("cylinder", "cone"):
        for j in range(1, sections + 1):
            per_section += [(f"D_S{j}", t.diameter), (f"RON_S{j}", _upper(t.roundness))]
    return _limits(("POS", _upper(t.position)),
                   ("D", None if kind == "cone" else t.diameter),
                   ("ANGLE", t.angle if kind == "cone" else None), *per_section,
                   ("TAPER", _sym(t.taper) if kind == "cylinder" else None),
                   ("FORM", _upper(t.form)))


def nominal_in_work(nominal: Nominal, rotation: frames.Rotation) -> Nominal:
    """A nominal planned in the frame of ``rotation`` (``p_work = R·p_frame``) in work
    coordinates; unchanged for the identity."""
    if frames.is_identity(rotation):
        return nominal
    sections = tuple((frames.apply(rotation, c), d) for c, d in nominal.sections)
    return replace(nominal, centre=frames.apply(rotation, nominal.centre),
                   axis=frames.apply(rotation, nominal.axis), sections=sections)


def nominal_of(plan: Any) -> Nominal:
    """The nominal feature of a ``planning.revolved_spec.RevolvedPlan`` for
    ``evaluate_revolved``."""
    d, kind = plan.definition, plan.spec.kind
    sections = tuple((vec3(np.asarray(s.centre, dtype=np.float64)), 2.0 * float(s.radius))
                     for s in plan.resolved.sections)
    axis = vec3(np.asarray(getattr(d, "axis", plan.resolved.feature.axis), dtype=np.float64))
    inside = bool(getattr(d, "concave", d.inner))
    if kind == "cone":
        return Nominal(kind, d.apex, axis, 0.0, inside, sections, half_angle=d.half_angle)
    if kind == "torus":
        return Nominal(kind, d.centre, axis, d.minor_diameter, inside, sections,
                       major_diameter=d.major_diameter)
    return Nominal(kind, d.centre, axis, d.diameter, inside, sections)
