"""Does this DPRNT log belong to this program?  The checks ``ingest`` makes first.

``docs/results.md`` ("Log identity") describes them for users.  In order:

1. **Which run.**  A log may hold several runs (a capture appended, LinuxCNC's
   ``LOGAPPEND``, a program started again).  A run is a ``PGSTART`` and what follows it;
   records before any ``PGSTART`` form a run of their own.  A run cut short (no
   ``PGEND``) and followed by another run is *resumed* by it: the runs of a chain
   ``cut short, cut short, ..., last`` are read together and a point printed again in a
   later run of the chain replaces the earlier one (the resumed-program rule of
   :mod:`probegen.evaluate.ingest`).  By default the chain ending at the last complete run is
   used; ``run=N`` (1-based, in log order) uses the chain ending at run ``N``.  A note
   says which run was used whenever there is more than one, and names a cut-short run
   after the one used.
2. **Identity.**  Every ``PGSTART`` of the chain must print the spec's program number
   and identity (:mod:`probegen.planning.identity`); a difference is refused naming both
   values, unless ``ignore_identity`` (then a note says so in every output).  A
   ``PGSTART`` without identity (a program compiled before identities) is accepted with
   the note "log carries no program identity".
3. **Point ids.**  A ``PT``/``LOC`` record whose feature is not in the plan, or whose
   index the plan does not have, is refused with file:line; so is a point printed twice
   within one run (a resumed program repeats points only after a new ``PGSTART``).
4. **Plausible values.**  The control reports the ball centre where the skip signal
   came, on the planned search line between its start and ``overtravel`` past the
   contact.  A touch farther than :data:`PLAUSIBLE_MARGIN` (plus the run-time location's
   uncertainty) from that segment cannot be that touch (a corrupt digit, a mixed-up
   line): it becomes a diagnostic naming file:line and the touch is treated as missing.
"""

from __future__ import annotations

import dataclasses
import re
from collections.abc import Sequence
from dataclasses import dataclass

from probegen.errors import Diagnostic, ProbegenError, ResultsParseError
from probegen.ir.identity import PlannedTouch
from probegen.results.dprnt import DprntLog, Run, Touch

PLAUSIBLE_MARGIN = 0.5
"""Largest distance (mm) of a reported ball centre from its planned search segment, on top
of the run-time location's uncertainty: the skip position lies on the commanded line up to
the machine's positioning error and the printed rounding, far below this."""


@dataclass(frozen=True, slots=True)
class CheckedLog:
    """A log after the checks of this module.

    Attributes:
        log: the chosen runs' records only, implausible touches removed, their
            diagnostics added (``runs`` holds the chosen chain).
        notes: what the checks found that a reader of the results must know.
        rejected: the implausible touches removed.
    """

    log: DprntLog
    notes: tuple[str, ...]
    rejected: tuple[Touch, ...] = ()


def check_log(log: DprntLog, *, program: int, identity: str,
              touches: Sequence[PlannedTouch], run: int | None = None,
              ignore_identity: bool = False, plausibility: bool = True,
              lines: Sequence[str] = ()) -> CheckedLog:
    """Apply the checks of the module docstring, in order.

    Args:
        log: the log as read.
        program: the spec's program number.
        identity: the spec's identity token (``H`` and 8 hex digits).
        touches: the planned probing moves (:func:`~probegen.planning.identity.planned_touches`).
        run: 1-based run to use (None: the last complete one).
        ignore_identity: accept a log of another program number or identity (a note).
        plausibility: check the touches against their planned moves (``post-ingest``
            checks them itself, on its stricter probing-line rule).
        lines: the log's lines (:func:`~probegen.results.dprnt.log_lines`), to quote an
            implausible touch and point at its worst coordinate.

    Raises:
        ProbegenError: ``run`` out of range, another program, an unknown or duplicate
            point id.
    """
    chosen, notes = select_runs(log, run)
    notes += _identity_notes(log.source, chosen.runs, program, identity, ignore_identity)
    check_point_ids(chosen, touches)
    kept, rejected, diags = (plausible(chosen, touches, lines) if plausibility
                             else (chosen.touches, (), ()))
    out = dataclasses.replace(chosen, touches=kept,
                              diagnostics=tuple(sorted((*chosen.diagnostics, *diags),
                                                       key=lambda d: d.line)))
    notes += [f"{log.source}:{t.line}: {t.kind} {t.feature} {t.index} cannot be that touch, "
              "treated as missing (see its diagnostic)" for t in rejected]
    return CheckedLog(out, tuple(notes), rejected)


def chain_of(runs: Sequence[Run], last: int) -> tuple[Run, ...]:
    """The runs read together with run ``last`` (0-based): it and the cut-short runs right
    before it that it resumes."""
    first = last
    while first > 0 and not runs[first - 1].complete:
        first -= 1
    return tuple(runs[first:last + 1])


def select_runs(log: DprntLog, run: int | None = None) -> tuple[DprntLog, list[str]]:
    """The log restricted to the chosen chain of runs, and the notes saying so.

    Raises:
        ProbegenError: ``run`` is not between 1 and the number of runs.
    """
    runs = log.runs or (Run(0, 0, int(log.complete), log.program, None),)
    n = len(runs)
    notes: list[str] = []
    if run is not None:
        if not 1 <= run <= n:
            raise ProbegenError(f"--run {run}: expected a run from 1 to {n}, "
                                f"{log.source} holds {n} run{'s' if n > 1 else ''}")
        last = run - 1
    else:
        complete = [r.number for r in runs if r.complete]
        last = complete[-1] if complete else n - 1
    chain = chain_of(runs, last)
    if n > 1:
        why = ("as asked (--run)" if run is not None else
               "the last complete one" if runs[last].complete else "no run is complete")
        starts = ", ".join(str(r.start) for r in runs if r.start)
        notes.append(f"the log holds {n} runs (PGSTART at lines {starts}); using run "
                     f"{last + 1} ({_span(runs[last])}), {why}; --run N chooses another")
        if len(chain) > 1:
            notes.append(f"run {last + 1} resumes run{'s' if len(chain) > 2 else ''} "
                         f"{', '.join(str(r.number + 1) for r in chain[:-1])} (cut short): "
                         "their points are read together, a point printed again counts "
                         "once, the last one read")
        cut = [r for r in runs[last + 1:] if not r.complete]
        if run is None and cut:
            notes.append(f"run {cut[-1].number + 1} after it ({_span(cut[-1])}) was cut "
                         f"short (no PGEND) and is not used; --run {cut[-1].number + 1} "
                         "uses it")
    numbers = {r.number for r in chain}
    chosen = dataclasses.replace(
        log,
        program=runs[last].program if runs[last].program is not None else log.program,
        touches=tuple(t for t in log.touches if t.run in numbers),
        centres=tuple(c for c in log.centres if c.run in numbers),
        errors=tuple(e for e in log.errors if e.run in numbers),
        results=tuple(r for r in log.results if r.run in numbers),
        serials=tuple(s for s in log.serials if s.run in numbers),
        complete=runs[last].complete, restarts=len(chain) - 1, runs=chain)
    return chosen, notes


def _span(r: Run) -> str:
    start = f"line {r.start}" if r.start else "the records before any PGSTART"
    return f"{start} to PGEND at line {r.end}" if r.end else f"from {start}, no PGEND"


def _identity_notes(source: str, runs: Sequence[Run], program: int, identity: str,
                    ignore: bool) -> list[str]:
    """Check each PGSTART of the chain against the spec (see the module docstring)."""
    notes: list[str] = []
    expected = f"O{program:04d} {identity}"
    for r in runs:
        if r.program is None:
            continue
        if r.program == program and r.identity in (None, identity):
            continue
        found = f"O{r.program:04d} {r.identity or '(no identity)'}"
        if not ignore:
            raise ResultsParseError(
                f"{source}:{r.start}: expected the program of the spec, {expected}, found "
                f"{found}: this log was printed by another program (or another version of "
                "it); --ignore-identity reads it anyway")
        notes.append(f"WARNING: identity not checked (--ignore-identity): the log's "
                     f"PGSTART at line {r.start} prints {found}, the spec's program is "
                     f"{expected}; these results may not belong to this spec")
    if any(r.identity is None and r.start for r in runs):
        notes.append("log carries no program identity (a PGSTART without the H token, "
                     "from a program compiled before identities): it was not checked "
                     "against the spec")
    elif not any(r.start for r in runs):
        notes.append("log carries no program identity (no PGSTART line: was the capture "
                     "started late?): it was not checked against the spec")
    return notes


def check_point_ids(log: DprntLog, touches: Sequence[PlannedTouch]) -> None:
    """Refuse a point the plan does not have, or one printed twice within one run.

    Raises:
        ResultsParseError: naming the log's file and line.
    """
    planned = {(p.kind, p.feature, p.index) for p in touches}
    features: dict[tuple[str, str], list[int]] = {}
    for p in touches:
        features.setdefault((p.kind, p.feature), []).append(p.index)
    seen: dict[tuple[int, str, str, int], int] = {}
    for t in log.touches:
        where = f"{log.source}:{t.line}: {t.kind} {t.feature} {t.index}"
        if (t.kind, t.feature, t.index) not in planned:
            indices = features.get((t.kind, t.feature))
            if indices is None:
                known = sorted({f for k, f in features if k == t.kind})
                raise ResultsParseError(
                    f"{where}: expected a {t.kind} point of a feature of the plan "
                    f"({', '.join(known) or 'none'}), found feature {t.feature}")
            raise ResultsParseError(f"{where}: expected a {t.kind} index the plan has for "
                                    f"{t.feature} ({ranges(sorted(indices))}), found "
                                    f"{t.index}")
        key = (t.run, t.kind, t.feature, t.index)
        if key in seen:
            raise ResultsParseError(
                f"{where}: printed twice in one run (first at line {seen[key]}); a resumed "
                "program prints a point again only after a new PGSTART")
        seen[key] = t.line


def plausible(log: DprntLog, touches: Sequence[PlannedTouch], lines: Sequence[str] = ()
              ) -> tuple[tuple[Touch, ...], tuple[Touch, ...], tuple[Diagnostic, ...]]:
    """Split the log's touches into those that can be their planned touch and those that
    cannot; one diagnostic per rejected touch (with ``lines``: quoting its line, the
    column at the coordinate farthest off)."""
    planned = {(p.kind, p.feature, p.index): p for p in touches}
    kept: list[Touch] = []
    rejected: list[Touch] = []
    diags: list[Diagnostic] = []
    for t in log.touches:
        plan = planned.get((t.kind, t.feature, t.index))
        limit = PLAUSIBLE_MARGIN + (plan.uncertainty if plan is not None else 0.0)
        d = plan.distance(t.xyz) if plan is not None else 0.0
        if d <= limit:
            kept.append(t)
            continue
        rejected.append(t)
        xyz = " ".join(f"{a}{v:.4f}" for a, v in zip("XYZ", t.xyz, strict=True))
        text = lines[t.line - 1] if 0 < t.line <= len(lines) else ""
        column = _axis_column(text, "XYZ"[plan.worst_axis(t.xyz)]) if plan else 0
        diags.append(Diagnostic(log.source, t.line, column, (
            f"{t.kind} {t.feature} {t.index} at {xyz} is {d:.4f} mm from its planned "
            f"search move (at most {limit:.4f} mm expected): a corrupt value, it cannot be "
            "that touch; treated as missing"), text if column else ""))
    return tuple(kept), tuple(rejected), tuple(diags)


_AXIS_AFTER_ID = re.compile(r"[ \t%]*(?:PT|LOC)[ \t]+\S+[ \t]+\S+[ \t]+", re.IGNORECASE)
"""The record word, feature id and index of a touch line: the axes follow."""


def _axis_column(text: str, axis: str) -> int:
    """1-based column of ``axis`` among the coordinates of touch line ``text`` (0: none)."""
    head = _AXIS_AFTER_ID.match(text)
    if head is None:
        return 0
    k = text.upper().find(axis, head.end())
    return k + 1 if k >= 0 else 0


def ranges(numbers: list[int]) -> str:
    """``1-25`` / ``1, 3-5``: a sorted list of integers as ranges."""
    out: list[list[int]] = []
    for n in numbers:
        if out and out[-1][1] == n - 1:
            out[-1][1] = n
        else:
            out.append([n, n])
    return ", ".join(str(a) if a == b else f"{a}-{b}" for a, b in out)
