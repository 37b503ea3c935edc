"""From what the machine returned to evaluated features: ``probegen ingest``.

Reads a DPRNT log (as captured: the raw bytes on disk are never rewritten), matches each
measuring touch to its planned point by feature id and point index, compensates the ball
centres along the planned normals, fits and evaluates each feature, and writes
``results.json`` and ``results.csv``.

Matching: the spec is planned again (points and order only, no program), so touch ``k``
of feature ``F`` is the plan's ``k``-th point of ``F``; a resumed program's repeated
touches count once, the last one read.
"""

from __future__ import annotations

import csv
import io
import json
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from probegen.compensate import ProbeCalibration, compensate
from probegen.errors import ProbegenError
from probegen.evaluate import SphereTestResult, evaluate_sphere_test
from probegen.evaluate_freeform import (
    FreeformResult,
    NominalPoint,
    Touches,
    complete_guides,
    evaluate_freeform,
)
from probegen.evaluate_revolved import (
    MIN_SECTIONS,
    Nominal,
    RevolvedResult,
    evaluate_revolved,
)
from probegen.geometry.fits_solver import vec3
from probegen.ingest_actions import Decision, decisions
from probegen.results import DmisOutput, DprntLog, read_dmis_output, read_dprnt
from probegen.spec import FREEFORM_STRIDE, FreeformSpec, RevolvedSpec, Spec
from probegen.spec_actions import PlanarSpec

Vec3 = tuple[float, float, float]

MIN_POINTS = 5
"""Fewest touches a sphere test is evaluated from (4 determine a sphere; one more checks)."""
REVOLVED_MIN_POINTS = {"circle": 4, "cylinder": 6, "cone": 7, "sphere": 5, "torus": 8}
"""Fewest touches each revolved kind is evaluated from: one more than its fit's
parameters (circle 3 in its plane, cylinder 5, cone 6, sphere 4, torus 7), so at least
one touch checks the form."""


@dataclass(frozen=True, slots=True)
class Ingested:
    """Everything ``ingest`` found.

    Attributes:
        source: the log file.
        log: the parsed log (with its diagnostics).
        results: one evaluated result per spec feature that has touches.
        notes: problems found while matching (missing touches, alarms in the log).
        path: the planned stylus path at nominal, as (feature, kind, start, end) segments
            (kind: rapid, protected, or touch ...), for the report.
        revolved: one evaluated result per revolved feature (method M2) with touches.
        decisions: the in-process decisions' values, offline and as the machine
            printed them (``ingest_actions``).
        freeform: one evaluated result per free-form feature with touches.
    """

    source: str
    log: DprntLog
    results: tuple[SphereTestResult, ...]
    notes: tuple[str, ...]
    path: tuple[tuple[str, str, Vec3, Vec3], ...] = ()
    revolved: tuple[RevolvedResult, ...] = ()
    decisions: tuple[Decision, ...] = ()
    freeform: tuple[FreeformResult, ...] = ()


def ingest(log_path: str | Path, spec: Spec, *,
           calibration: ProbeCalibration | None = None, with_path: bool = False) -> Ingested:
    """Read a DPRNT log and evaluate every feature of ``spec`` it has touches for.

    ``with_path`` also plans the whole program again (with its collision check) to
    record the nominal stylus path for the report.
    """
    from probegen.planning.sphere_test import plan_points, resolve_sphere

    log = read_dprnt(log_path)
    notes = [f"the program stopped: ERR {e.code} {e.feature} {e.index} (line {e.line})"
             for e in log.errors]
    if not log.complete:
        notes.append("the log has no PGEND line: the program did not finish")
    touches = {(t.feature, t.index): t.xyz for t in log.latest_touches() if t.kind == "PT"}
    results = []
    revolved: list[RevolvedResult] = []
    freeform: list[FreeformResult] = []
    for feature in spec.features:
        if isinstance(feature, RevolvedSpec):
            found_r = _revolved(feature, spec, touches, notes)
            if found_r is not None:
                revolved.append(found_r)
            continue
        if isinstance(feature, FreeformSpec):
            found_f = ingest_freeform(feature, spec, touches, notes, calibration)
            if found_f is not None:
                freeform.append(found_f)
            continue
        if isinstance(feature, PlanarSpec):  # lines and planes: decisions only
            continue
        sphere = resolve_sphere(feature, spec.model)
        plan = plan_points(feature, sphere, spec.machine)
        found = [k for k in range(1, len(plan.directions) + 1) if (feature.id, k) in touches]
        missing = sorted(set(range(1, len(plan.directions) + 1)) - set(found))
        if missing:
            notes.append(f"feature {feature.id}: no touch for points {_ranges(missing)}")
        if len(found) < MIN_POINTS:
            notes.append(f"feature {feature.id}: not evaluated, {len(found)} touches "
                         f"(at least {MIN_POINTS} needed)")
            continue
        centres = np.array([touches[(feature.id, k)] for k in found])
        normals = np.array([plan.directions[k - 1] for k in found])
        r = spec.machine.probe.ball_radius if calibration is None else calibration
        points = compensate(centres, normals, r)
        tol = feature.tolerance
        results.append(evaluate_sphere_test(
            feature.id, points, normals, nominal_centre=sphere.centre,
            calibrated_diameter=sphere.diameter,
            ball_radius=r if isinstance(r, float) else r.effective_radius,
            form=tol.form, size=tol.size, position=tol.position))
    if not results and not revolved and not freeform:
        raise ProbegenError(f"{log_path}: expected measuring touches (PT lines) of the "
                            f"spec's features, found none usable; " + "; ".join(notes))
    path: tuple[tuple[str, str, Vec3, Vec3], ...] = ()
    if with_path:
        from probegen.planning import plan_program

        segments = plan_program(spec, runtime_variables=True).clearance.segments
        path = tuple((s.feature, s.kind, s.start, s.end) for s in segments)
    return Ingested(str(log_path), log, tuple(results), tuple(notes), path, tuple(revolved),
                    decisions(spec, log), tuple(freeform))


def ingest_freeform(feature: FreeformSpec, spec: Spec, touches: Touches, notes: list[str],
                    calibration: ProbeCalibration | None = None) -> FreeformResult | None:
    """Evaluate one free-form feature from ball centres by (feature, touch index).

    The feature is planned again (with its collision checks) for the theoretical contact
    points and normals; guide points missing a touch are left out with a note.
    """
    from probegen.planning import make_setup
    from probegen.planning.freeform_spec import plan_freeform

    plan = plan_freeform(feature, spec.model, spec.machine, make_setup(spec))
    nominal = [NominalPoint(t.guide, t.contact, t.normal) for t in plan.touches
               if t.role == 0]
    full, missing = complete_guides(feature.id, feature.method, nominal, touches)
    if missing:
        notes.append(f"feature {feature.id}: guide points {_ranges(missing)} lack touches, "
                     "not evaluated")
    if not full:
        notes.append(f"feature {feature.id}: not evaluated, no guide point has all its "
                     "touches")
        return None
    r = spec.machine.probe.ball_radius if calibration is None else calibration
    return evaluate_freeform(feature.id, feature.method, full, touches,
                             direction=feature.direction, radius=r,
                             deviation=feature.deviation)


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


def ingest_dmis(path: str | Path, spec: Spec) -> Ingested:
    """``probegen ingest`` of a DMIS output file: the free-form features of ``spec``
    (the CMM reports the other kinds itself; ``probegen qif`` exports them).

    ``log`` is an empty DPRNT log that carries the file's diagnostics; ``complete`` is
    whether the output holds at least one feature actual.

    Raises:
        ProbegenError: the file cannot be read, or holds no free-form touches of the spec.
    """
    output = read_dmis_output(path)
    results, notes = ingest_dmis_freeform(output, spec)
    if not results:
        raise ProbegenError(f"{path}: expected point actuals FA(<id>_<k>) of the spec's "
                            "free-form features, found none usable; " + "; ".join(notes))
    log = DprntLog(str(path), None, (), (), (), bool(output.features), 0, output.diagnostics)
    return Ingested(str(path), log, (), notes, freeform=results)


def ingest_dmis_freeform(output: DmisOutput, spec: Spec) -> tuple[tuple[FreeformResult, ...],
                                                                   tuple[str, ...]]:
    """Evaluate the free-form features of ``spec`` from a DMIS output file (the CMM
    evaluates the other kinds itself); returns the results and the notes."""
    touches = dmis_touches(output, spec)
    notes: list[str] = []
    found = [ingest_freeform(f, spec, touches, notes) for f in spec.features
             if isinstance(f, FreeformSpec)]
    return tuple(r for r in found if r is not None), tuple(notes)


def _revolved(feature: RevolvedSpec, spec: Spec, touches: dict[tuple[str, int], Vec3],
              notes: list[str]) -> RevolvedResult | None:
    """Evaluate a revolved feature from its touches (too few, or a failed fit: a note)."""
    from probegen.planning.revolved_spec import plan_revolved

    plan = plan_revolved(feature, spec.model, spec.machine, spec.clearance_z)
    indices = sorted(plan.normals)
    found = [k for k in indices if (feature.id, k) in touches]
    missing = sorted(set(indices) - set(found))
    if missing:
        notes.append(f"feature {feature.id}: no touch for points {_ranges(missing)}")
    least, sections = REVOLVED_MIN_POINTS[feature.kind], MIN_SECTIONS[feature.kind]
    which = [plan.section_of_touch[k] for k in found]
    if len(found) < least or len(set(which)) < sections:
        notes.append(f"feature {feature.id}: not evaluated, {len(found)} touches in "
                     f"{len(set(which))} sections (at least {least} needed"
                     f"{f', in {sections} sections' if sections > 1 else ''})")
        return None
    try:
        return evaluate_revolved(
            feature.id, nominal_of(plan), [touches[(feature.id, k)] for k in found], which,
            ball_radius=spec.machine.probe.ball_radius, limits=feature.tolerance)
    except ProbegenError as exc:
        notes.append(f"feature {feature.id}: not evaluated: {exc}")
        return None


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


def _ranges(numbers: list[int]) -> str:
    out: list[str] = []
    for n in numbers:
        if out and out[-1].split("-")[-1] == str(n - 1):
            out[-1] = out[-1].split("-")[0] + f"-{n}"
        else:
            out.append(str(n))
    return ", ".join(out)


def _f(x: float) -> float:
    return float(f"{x:.7f}") + 0.0


def to_json(ing: Ingested) -> str:
    """``results.json``: repeatable text (fixed rounding to 1e-7 mm)."""
    doc: dict[str, Any] = {
        "source": ing.source,
        "program": ing.log.program,
        "complete": ing.log.complete,
        "notes": list(ing.notes),
        "diagnostics": [str(d) for d in ing.log.diagnostics],
        "features": [_feature_json(r) for r in ing.results]
        + [_revolved_json(r) for r in ing.revolved]
        + [freeform_json(r) for r in ing.freeform],
        "path": [{"feature": f, "kind": k, "start": [_f(v) for v in a],
                  "end": [_f(v) for v in b]} for f, k, a, b in ing.path],
    }
    if ing.decisions:  # features with in-process decisions (docs/actions.md)
        doc["decisions"] = [{"feature": d.feature, "key": d.key, "agrees": d.agrees,
                             "offline": None if d.offline is None else _f(d.offline),
                             "machine": None if d.machine is None else _f(d.machine),
                             "limit": _f(d.limit)}
                            for d in ing.decisions]
    return json.dumps(doc, indent=2) + "\n"


def _measured_json(characteristics: Any, points: Any, directions: Any,
                   residuals: Any) -> dict[str, Any]:
    """The part of a feature's JSON every kind shares: checks, points, normals, residuals."""
    return {
        "characteristics": [
            {"name": c.name, "measured": _f(c.measured), "nominal": _f(c.nominal),
             "deviation": _f(c.deviation),
             "lower": None if c.lower is None else _f(c.lower),
             "upper": None if c.upper is None else _f(c.upper), "ok": c.ok}
            for c in characteristics
        ],
        "points": [[_f(v) for v in p] for p in points],
        "directions": [[_f(v) for v in d] for d in directions],
        "residuals": [_f(v) for v in residuals],
    }


def _feature_json(r: SphereTestResult) -> dict[str, Any]:
    return {
        "id": r.feature,
        "kind": "sphere_test",
        "ok": r.ok,
        "n": len(r.points),
        "centre": [_f(v) for v in r.fit.centre],
        "diameter": _f(2.0 * r.fit.radius),
        "p_ftu": _f(r.p_ftu),
        "p_stu": _f(r.p_stu),
        "effective_radius": _f(r.effective_radius),
        **_measured_json(r.characteristics, r.points, r.directions, r.fit.residuals),
    }


def _revolved_json(r: RevolvedResult) -> dict[str, Any]:
    return {
        "id": r.feature,
        "kind": r.kind,
        "ok": r.ok,
        "n": len(r.points),
        "centre": [_f(v) for v in r.centre],
        "axis": [_f(v) for v in r.axis],
        "diameter": _f(r.diameter),
        "form": _f(r.form),
        **({} if r.half_angle is None else {"half_angle_deg": _f(math.degrees(r.half_angle))}),
        **({} if r.apex is None else {"apex": [_f(v) for v in r.apex]}),
        **({} if r.major_diameter is None else {"major_diameter": _f(r.major_diameter)}),
        **_measured_json(r.characteristics, r.points, r.directions, r.residuals),
    }


def freeform_json(r: FreeformResult) -> dict[str, Any]:
    """A free-form feature in ``results.json``: ``points`` are the compensated contact
    points, ``directions`` the nominal normals, ``residuals`` the deviations along them
    (the deviation map), ``nominal`` the theoretical contact points."""
    s = r.summary
    return {
        "id": r.feature,
        "kind": "freeform",
        "method": r.method,
        "ok": r.ok,
        "n": len(r.points),
        "guides": list(r.guides),
        "touch_stride": FREEFORM_STRIDE,
        "deviation": {"min": _f(s.min), "max": _f(s.max), "mean": _f(s.mean),
                      "rms": _f(s.rms)},
        "nominal": [[_f(v) for v in p] for p in r.nominal],
        "normals_used": [[_f(v) for v in n] for n in r.normals_used],
        **_measured_json(r.characteristics, r.points, r.directions, r.residuals),
    }


def _status(ok: bool | None) -> str:
    return "-" if ok is None else ("OK" if ok else "NOT OK")


def _tol(lo: float | None, hi: float | None) -> str:
    if lo is None and hi is None:
        return "-"
    if lo is None:
        return f"<= {hi:.4f}"
    return f"{lo:+.4f}/{hi:+.4f}"


def to_csv(ing: Ingested) -> str:
    """``results.csv``: one row per characteristic."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["feature", "characteristic", "measured", "nominal", "deviation", "lower",
                "upper", "status"])
    rs: list[SphereTestResult | RevolvedResult | FreeformResult] = [
        *ing.results, *ing.revolved, *ing.freeform]
    for r in rs:
        for c in r.characteristics:
            w.writerow([r.feature, c.name, f"{c.measured:.4f}", f"{c.nominal:.4f}",
                        f"{c.deviation:.4f}", "" if c.lower is None else f"{c.lower:.4f}",
                        "" if c.upper is None else f"{c.upper:.4f}", _status(c.ok)])
    return buf.getvalue()


def to_table(ing: Ingested) -> str:
    """The table ``probegen ingest`` prints."""
    rows = [("feature", "char", "measured", "nominal", "deviation", "tolerance", "status")]
    rs: list[SphereTestResult | RevolvedResult | FreeformResult] = [
        *ing.results, *ing.revolved, *ing.freeform]
    for r in rs:
        for c in r.characteristics:
            rows.append((r.feature, c.name, f"{c.measured:.4f}", f"{c.nominal:.4f}",
                         f"{c.deviation:+.4f}", _tol(c.lower, c.upper), _status(c.ok)))
    text = _columns(rows)
    if ing.decisions:
        text += "\n" + _columns([("feature", "value", "offline", "machine", "agrees")] + [
            (d.feature, d.key, _opt(d.offline), _opt(d.machine),
             {None: "-", True: "yes", False: "NO"}[d.agrees]) for d in ing.decisions])
    return text


def _opt(x: float | None) -> str:
    return "-" if x is None else f"{x:.6f}"


def _columns(rows: Sequence[tuple[str, ...]]) -> str:
    """Rows as aligned columns (the first two left-aligned)."""
    widths = [max(len(row[i]) for row in rows) for i in range(len(rows[0]))]
    lines = ["  ".join(cell.ljust(w) if i < 2 else cell.rjust(w)
                       for i, (cell, w) in enumerate(zip(row, widths, strict=True))).rstrip()
             for row in rows]
    return "\n".join(lines) + "\n"


def write_outputs(ing: Ingested, out_dir: Path) -> tuple[Path, Path]:
    """Write ``results.json`` and ``results.csv`` into ``out_dir``."""
    from probegen.outputs import output_folder, write_file

    output_folder(out_dir, "results.json and results.csv")
    js = write_file(out_dir / "results.json", to_json(ing), "the results")
    cs = write_file(out_dir / "results.csv", to_csv(ing), "the results table")
    return js, cs
