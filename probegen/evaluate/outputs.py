"""What ``probegen ingest`` writes: ``results.json``, ``results.csv`` and the table it prints.

The records come from :mod:`probegen.evaluate.ingest` (an :class:`Ingested`: the evaluated
features, the NOT EVALUATED ones, the calibration and the uncertainty budget used); this
module only turns them into repeatable text (fixed rounding, a fixed key order).
"""

from __future__ import annotations

import csv
import io
import json
import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from probegen.evaluate.characteristics import (
    NOT_EVALUATED,
    Evaluated,
    NotEvaluated,
    accepted,
    status_of,
)
from probegen.evaluate.freeform import FreeformResult
from probegen.evaluate.ingest import Ingested
from probegen.evaluate.planar import PlanarResult
from probegen.evaluate.revolved import RevolvedResult
from probegen.evaluate.sphere_test import SphereTestResult
from probegen.geometry.uncertainty import COVERAGE_FACTOR, Budget
from probegen.machine.calibration import calibration_state
from probegen.spec.model import FREEFORM_STRIDE


def _f(x: float) -> float:
    return float(f"{x:.7f}") + 0.0


def to_json(ing: Ingested) -> str:
    """``results.json``: repeatable text (fixed rounding to 1e-7 mm).

    ``status`` (run, feature, characteristic) is one of ``OK``, ``NOT OK``, ``NOT
    EVALUATED``, ``-`` (:mod:`probegen.evaluate.characteristics`); ``ok`` is kept beside
    it (None for what is not toleranced or not evaluated).  The completely evaluated features come
    first, then the NOT EVALUATED ones with their ``reason``."""
    doc: dict[str, Any] = {"source": ing.source}
    if ing.run is not None:  # who, what, when (docs/results.md, "The run")
        doc["run"] = ing.run.to_json()
    doc |= {
        "program": ing.log.program,
        "complete": ing.log.complete,
        "status": ing.status,
        "calibration": calibration_state(ing.calibration),
        "notes": list(ing.notes),
        "uncertainty": uncertainty_json(ing.budget, ing.rule, ing.uncertainty_notes),
        "diagnostics": [str(d) for d in ing.log.diagnostics],
        "features": [_evaluated_json(r, ing.rule) for r in ing.evaluated]
        + [_not_evaluated_json(n, ing.rule) for n in ing.not_evaluated],
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


def _evaluated_json(r: Evaluated, rule: str) -> dict[str, Any]:
    """One evaluated feature of any kind, with its ``status`` under ``rule``."""
    if isinstance(r, SphereTestResult):
        doc = _feature_json(r, rule)
    elif isinstance(r, RevolvedResult):
        doc = _revolved_json(r, rule)
    elif isinstance(r, FreeformResult):
        doc = freeform_json(r, rule)
    else:
        assert isinstance(r, PlanarResult)
        doc = _planar_json(r, rule)
    return _after_ok(doc, status=status_of(accepted(r.characteristics, rule)))


def _after_ok(doc: dict[str, Any], **keys: Any) -> dict[str, Any]:
    """``doc`` with ``keys`` set right after its ``ok`` key (replaced where present)."""
    out: dict[str, Any] = {}
    for k, v in doc.items():
        if k not in keys:
            out[k] = v
        if k == "ok":
            out.update(keys)
    return out


def _not_evaluated_json(n: NotEvaluated, rule: str) -> dict[str, Any]:
    """A NOT EVALUATED feature: the partial fit's keys when there is one (for
    information), every characteristic's ``ok`` None and its status NOT EVALUATED
    (``-`` where not toleranced)."""
    doc: dict[str, Any] = {"id": n.feature, "kind": n.kind, "ok": None, "n": 0,
                           "characteristics": [], "points": [], "directions": [],
                           "residuals": []}
    if n.partial is not None:
        doc = _evaluated_json(n.partial, rule)
    doc["characteristics"] = [
        {"name": name, "measured": _opt_f(measured), "nominal": _opt_f(nominal),
         "deviation": _opt_f(deviation), "lower": _opt_f(lower), "upper": _opt_f(upper),
         "ok": None, "status": status, "u": _opt_f(u), "U": _opt_f(big_u), "decision": None}
        for name, measured, nominal, deviation, lower, upper, status, u, big_u, _, _
        in _rows_of(n, rule)]
    return _after_ok({**doc, "ok": None}, status=NOT_EVALUATED, reason=n.reason)


def uncertainty_json(budget: Budget, rule: str, notes: Sequence[str]) -> dict[str, Any]:
    """The ``uncertainty`` object of ``results.json``: coverage factor, decision rule and
    the stated contributions (None: not stated), with what they leave out."""
    return {"k": COVERAGE_FACTOR, "decision_rule": rule, "u_radius": _f(budget.radius),
            "machine": None if budget.machine is None else _f(budget.machine),
            "probe": None if budget.probe is None else _f(budget.probe),
            "notes": list(notes)}


def _opt_f(x: float | None) -> float | None:
    return None if x is None else _f(x)


Row = tuple[str, float | None, float | None, float | None, float | None, float | None, str,
            float | None, float | None, str | None, str]
"""A characteristic as the outputs list it: name, measured, nominal, deviation, lower,
upper, status, u, U, decision (ISO 14253-1), method (of a form value, else "")."""


def _rows_of(r: Evaluated | NotEvaluated, rule: str) -> list[Row]:
    """The characteristic rows of one feature (statuses under ``rule``); a NOT EVALUATED
    feature: its partial fit's (toleranced ones NOT EVALUATED), then its other
    toleranced characteristics without values."""
    if not isinstance(r, NotEvaluated):
        return [(c.name, c.measured, c.nominal, c.deviation, c.lower, c.upper,
                 status_of(c.accepted(rule)), c.u, c.U, c.decision, c.method)
                for c in r.characteristics]
    chars = () if r.partial is None else r.partial.characteristics
    rows: list[Row] = [(c.name, c.measured, c.nominal, c.deviation, c.lower, c.upper,
                        "-" if c.ok is None else NOT_EVALUATED, c.u, c.U, None, c.method)
                       for c in chars]
    shown = {c.name for c in chars}
    rows += [(name, None, None, None, lo, hi, NOT_EVALUATED, None, None, None, "")
             for name, (lo, hi) in zip(r.characteristics, r.limits, strict=True)
             if name not in shown]
    return rows


def _head(r: Evaluated, kind: str, rule: str) -> dict[str, Any]:
    """The keys every feature's JSON starts with: id, kind, the verdict, the touches."""
    return {"id": r.feature, "kind": kind, "ok": accepted(r.characteristics, rule),
            "n": len(r.points)}


def _planar_json(r: PlanarResult, rule: str) -> dict[str, Any]:
    return {
        **_head(r, r.kind, rule),
        **_measured_json(r.characteristics, r.points, r.directions, r.residuals, rule),
    }


def _measured_json(characteristics: Any, points: Any, directions: Any,
                   residuals: Any, rule: str) -> dict[str, Any]:
    """The part of a feature's JSON every kind shares: checks (``ok`` and ``status``
    are the verdict under ``rule``), points, normals, residuals."""
    return {
        "characteristics": [
            {"name": c.name, "measured": _f(c.measured), "nominal": _f(c.nominal),
             "deviation": _f(c.deviation), "lower": _opt_f(c.lower),
             "upper": _opt_f(c.upper), "ok": c.accepted(rule),
             "status": status_of(c.accepted(rule)), "u": _opt_f(c.u), "U": _opt_f(c.U),
             "decision": c.decision, **({"method": c.method} if c.method else {})}
            for c in characteristics
        ],
        "points": [[_f(v) for v in p] for p in points],
        "directions": [[_f(v) for v in d] for d in directions],
        "residuals": [_f(v) for v in residuals],
    }


def _feature_json(r: SphereTestResult, rule: str) -> dict[str, Any]:
    return {
        **_head(r, "sphere_test", rule),
        "centre": [_f(v) for v in r.fit.centre],
        "diameter": _f(2.0 * r.fit.radius),
        "p_ftu": _f(r.p_ftu),
        "p_stu": _f(r.p_stu),
        "effective_radius": _f(r.effective_radius),
        **_measured_json(r.characteristics, r.points, r.directions, r.fit.residuals, rule),
    }


def _revolved_json(r: RevolvedResult, rule: str) -> dict[str, Any]:
    return {
        **_head(r, r.kind, rule),
        "centre": [_f(v) for v in r.centre],
        "axis": [_f(v) for v in r.axis],
        "diameter": _f(r.diameter),
        "form": _f(r.form),
        **({} if r.half_angle is None else {"half_angle_deg": _f(math.degrees(r.half_angle))}),
        **({} if r.apex is None else {"apex": [_f(v) for v in r.apex]}),
        **({} if r.major_diameter is None else {"major_diameter": _f(r.major_diameter)}),
        # how well the touches determine the fit (geometry.fits_conditioning), 4 digits
        **({} if r.condition is None or not math.isfinite(r.condition)
           else {"condition": float(f"{r.condition:.4g}")}),
        **_measured_json(r.characteristics, r.points, r.directions, r.residuals, rule),
    }


def freeform_json(r: FreeformResult, rule: str = "simple") -> dict[str, Any]:
    """A free-form feature in ``results.json``: ``points`` are the compensated contact
    points, ``directions`` the nominal normals, ``residuals`` the deviations along them
    (the deviation map), ``nominal`` the theoretical contact points."""
    s = r.summary
    return {
        "id": r.feature,
        "kind": "freeform",
        "method": r.method,
        "ok": accepted(r.characteristics, rule),
        "n": len(r.points),
        "guides": list(r.guides),
        "touch_stride": FREEFORM_STRIDE,
        "deviation": {"min": _f(s.min), "max": _f(s.max), "mean": _f(s.mean),
                      "rms": _f(s.rms)},
        "nominal": [[_f(v) for v in p] for p in r.nominal],
        "normals_used": [[_f(v) for v in n] for n in r.normals_used],
        **_measured_json(r.characteristics, r.points, r.directions, r.residuals, rule),
    }


def _tol(lo: float | None, hi: float | None) -> str:
    if lo is None and hi is None:
        return "-"
    if lo is None:
        return f"<= {hi:.4f}"
    if hi is None:
        return f">= {lo:.4f}"
    return f"{lo:+.4f}/{hi:+.4f}"


def _all_rows(ing: Ingested) -> list[tuple[str, Row]]:
    """Every characteristic row of every feature; a NOT EVALUATED feature without any
    is one row named ``-``."""
    out: list[tuple[str, Row]] = []
    features: list[Evaluated | NotEvaluated] = [*ing.evaluated, *ing.not_evaluated]
    for r in features:
        rows = _rows_of(r, ing.rule) or [
            ("-", None, None, None, None, None, NOT_EVALUATED, None, None, None, "")]
        out += [(r.feature, row) for row in rows]
    return out


def _num(x: float | None, fmt: str) -> str:
    return "" if x is None else format(x, fmt)


def to_csv(ing: Ingested) -> str:
    """``results.csv``: one row per characteristic (``status``: see :func:`to_json`)."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["feature", "characteristic", "measured", "nominal", "deviation", "lower",
                "upper", "status", "u", "U", "decision", "calibration", "method"])
    for feature, (name, measured, nominal, deviation, lo, hi, status, u, big_u,
                  decision, method) in _all_rows(ing):
        w.writerow([feature, name, _num(measured, ".4f"), _num(nominal, ".4f"),
                    _num(deviation, ".4f"), _num(lo, ".4f"), _num(hi, ".4f"), status,
                    _num(u, ".5f"), _num(big_u, ".4f"), decision or "",
                    ing.calibration_text, method])
    return buf.getvalue()


def to_table(ing: Ingested) -> str:
    """The table ``probegen ingest`` prints, each NOT EVALUATED feature's reason and
    the run's status."""
    rows = [("feature", "char", "measured", "nominal", "deviation", "tolerance", "status",
             "U", "decision", "method")]
    for feature, (name, measured, nominal, deviation, lo, hi, status, _, big_u,
                  decision, method) in _all_rows(ing):
        rows.append((feature, name, _num(measured, ".4f") or "-", _num(nominal, ".4f") or "-",
                     _num(deviation, "+.4f") or "-", _tol(lo, hi), status,
                     _num(big_u, ".4f") or "-", decision or "-", method))
    text = f"probe: {ing.calibration_text}\n" + _columns(rows)
    text += (f"U: expanded uncertainty (k = {COVERAGE_FACTOR:g}); decision rule "
             f"{ing.rule} (ISO 14253-1)\n")
    text += "".join(f"{note}\n" for note in ing.uncertainty_notes)
    for n in ing.not_evaluated:
        text += f"{n.feature}: NOT EVALUATED: {n.reason}\n"
    if ing.decisions:
        text += "\n" + _columns([("feature", "value", "offline", "machine", "agrees")] + [
            (d.feature, d.key, _opt(d.offline), _opt(d.machine),
             {None: "-", True: "yes", False: "NO"}[d.agrees]) for d in ing.decisions])
    finished = "" if ing.log.complete else " (the run did not finish)"
    return text + f"status: {ing.status}{finished}\n"


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
    from probegen.files import output_folder, write_file

    output_folder(out_dir, "results.json and results.csv")
    js = write_file(out_dir / "results.json", to_json(ing), "the results")
    cs = write_file(out_dir / "results.csv", to_csv(ing), "the results table")
    return js, cs
