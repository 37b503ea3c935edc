"""Several logs of one part, one per named setup: ``probegen ingest LOG1 LOG2 ...``
(issue 17, item 2).

A spec whose machine profile has ``[[setup]]`` tables is measured by one program per
setup that has features (:mod:`probegen.planning.setups`): the part as loaded (the spec's
program number), then each setup turned (the spec's number plus the setup's place in the
profile).  Each log is paired with its program by the program number its ``PGSTART``
prints (the identity token is then checked by :func:`probegen.evaluate.ingest.ingest` as
for any log); it is ingested against that setup's spec and part, its touches turned back
to part coordinates (``p_part = Rᵀ·p_table``, after the frame of a tilted feature), and
the outcomes of all logs are one result set in the spec's order.  A feature whose setup's
log is not given is NOT EVALUATED ("not measured: no log of setup ..."), never OK.

A profile without setups: one log, exactly :func:`probegen.evaluate.ingest.ingest`.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypeVar

from probegen.errors import ProbegenError
from probegen.evaluate.characteristics import NotEvaluated
from probegen.evaluate.ingest import Ingested, _revolved_names, ingest, nominal_of
from probegen.machine.calibration import ProbeCalibration
from probegen.results.dprnt import parse_dprnt, read_raw
from probegen.spec.model import RevolvedSpec, Spec

if TYPE_CHECKING:
    from probegen.cad import Part
    from probegen.planning.setups import SetupProgram


def log_program(path: str | Path) -> int | None:
    """The program number a DPRNT log's last run prints (``PGSTART``), or None."""
    log = parse_dprnt(read_raw(path), source=str(path))
    for r in reversed(log.runs):
        if r.program is not None:
            return int(r.program)
    return log.program


T = TypeVar("T")


def pair_each(paths: Sequence[str | Path], items: Sequence[T],
              programs: Sequence[SetupProgram], identify: Callable[[str | Path, T], int],
              what: str, name: Callable[[SetupProgram], str]) -> dict[int, tuple[str | Path, T]]:
    """Each returned file (``paths[i]``, read as ``items[i]``) paired with its program, by
    its index in ``programs`` as ``identify`` finds it (which raises for a file of none of
    them); ``what`` names the files ("log", "DMIS output") and ``name`` a program in the
    message.

    Raises:
        ProbegenError: as ``identify``; two files of one program.
    """
    out: dict[int, tuple[str | Path, T]] = {}
    for path, item in zip(paths, items, strict=True):
        k = identify(path, item)
        if k in out:
            raise ProbegenError(f"{path}: expected one {what} per setup program, found a "
                                f"second {what} of {name(programs[k])} (setup "
                                f"{programs[k].name}; the first: {out[k][0]})")
        out[k] = (path, item)
    return out


def pair_logs(logs: Sequence[str | Path], programs: Sequence[SetupProgram]
              ) -> dict[int, str | Path]:
    """Each log's program (by its index in ``programs``), by the number its ``PGSTART``
    prints; a single log of a single program is that program's whatever it prints (its
    identity is checked when it is ingested).

    Raises:
        ProbegenError: a log of none of the programs, or two logs of one program.
    """
    if len(logs) == 1 and len(programs) == 1:
        return {0: logs[0]}
    numbers = {sp.spec.program_number: k for k, sp in enumerate(programs)}
    known = ", ".join(f"O{sp.spec.program_number:04d} (setup {sp.name})" for sp in programs)

    def identify(log: str | Path, number: int | None) -> int:
        k = numbers.get(number) if number is not None else None
        if k is None:
            found = "no PGSTART line" if number is None else f"O{number:04d}"
            raise ProbegenError(f"{log}: expected the log of one of the spec's setup "
                                f"programs {known}, found {found}")
        return k

    paired = pair_each(logs, [log_program(log) for log in logs], programs, identify, "log",
                       lambda sp: f"O{sp.spec.program_number:04d}")
    return {k: path for k, (path, _) in paired.items()}


def ingest_setups(logs: Sequence[str | Path], spec: Spec, *,
                  calibration: ProbeCalibration | None = None, with_path: bool = False,
                  decision_rule: str | None = None, run: int | None = None,
                  ignore_identity: bool = False, part: Part | None = None) -> Ingested:
    """Evaluate every feature of ``spec`` from the logs of its setup programs (see the
    module docstring); the options are :func:`probegen.evaluate.ingest.ingest`'s
    (``run`` only with one log).

    Raises:
        ProbegenError: as :func:`pair_logs` and :func:`probegen.evaluate.ingest.ingest`;
            ``run`` with several logs.
    """
    from probegen.planning import part_of
    from probegen.planning.setups import split_setups

    if part is None:
        part = part_of(spec)
    programs = split_setups(spec, part)
    if run is not None and len(logs) > 1:
        raise ProbegenError(f"ingest --run {run}: expected one log, found {len(logs)} (the "
                            "run of a log of several is chosen per log: ingest it alone)")
    paired = pair_logs(logs, programs)
    if len(programs) == 1 and programs[0].setup is None:
        return ingest(paired[0], spec, calibration=calibration, with_path=with_path,
                      decision_rule=decision_rule, run=run, ignore_identity=ignore_identity,
                      part=part)
    done: list[tuple[SetupProgram, Ingested]] = []
    missing: list[NotEvaluated] = []
    for k, sp in enumerate(programs):
        if k not in paired:
            missing += _not_measured(sp)
            continue
        got = ingest(paired[k], sp.spec, calibration=calibration,
                     with_path=with_path and sp.setup is None, decision_rule=decision_rule,
                     run=run, ignore_identity=ignore_identity, part=sp.part,
                     turn=None if sp.setup is None else sp.rotation)
        done.append((sp, got))
    return _merged(spec, done, missing)


def _not_measured(sp: SetupProgram, what: str = "log") -> list[NotEvaluated]:
    """The features of a setup program whose log (``what``: or DMIS output) is not given:
    NOT EVALUATED, with the characteristics the spec asks for (the program planned again
    for the sections)."""
    from probegen.planning import plan_program

    planned = plan_program(sp.spec, runtime_variables=True, check_collisions=False,
                           part=sp.part)
    sections = {o.plan.spec.id: len(nominal_of(o.plan).sections) for o in planned.oriented}
    why = (f"not measured: no {what} of setup {sp.name} (program "
           f"O{sp.spec.program_number:04d}) was given")
    out = []
    for f in sp.spec.features:
        names = _revolved_names(f, sections.get(f.id, 0)) if isinstance(f, RevolvedSpec) \
            else []
        kind = getattr(f, "kind", "sphere_test")
        out.append(NotEvaluated(f.id, kind, why, tuple(n for n, _, _ in names),
                                tuple((lo, hi) for _, lo, hi in names)))
    return out


def _merged(spec: Spec, done: Sequence[tuple[SetupProgram, Ingested]],
            missing: Sequence[NotEvaluated]) -> Ingested:
    """One result set from the setups' ingests: the outcomes in spec order, each note
    prefixed with its setup, the log and source of the first ingested program (its file's
    time is the run's; complete only when every log is), the diagnostics of all."""
    order = {f.id: k for k, f in enumerate(spec.features)}

    def ordered(items: Sequence[Any]) -> tuple[Any, ...]:
        return tuple(sorted(items, key=lambda r: order[r.feature]))

    first = done[0][1]
    notes: list[str] = [n.reason for n in missing[:1]]
    for sp, ing in done:
        notes += [f"setup {sp.name} (O{sp.spec.program_number:04d}, {ing.source}): {n}"
                  for n in ing.notes]
    log = dataclasses.replace(
        first.log, complete=all(ing.log.complete for _, ing in done),
        diagnostics=tuple(d for _, ing in done for d in ing.log.diagnostics))
    return dataclasses.replace(
        first, log=log, notes=tuple(notes),
        results=ordered([r for _, ing in done for r in ing.results]),
        revolved=ordered([r for _, ing in done for r in ing.revolved]),
        freeform=ordered([r for _, ing in done for r in ing.freeform]),
        planar=ordered([r for _, ing in done for r in ing.planar]),
        not_evaluated=ordered([*(r for _, ing in done for r in ing.not_evaluated), *missing]),
        decisions=tuple(d for _, ing in done for d in ing.decisions),
        path=tuple(s for _, ing in done for s in ing.path))
