"""``results.json`` (as written by ``probegen ingest``) read into typed records.

The report reads only what it shows, so older or newer results files render as long as
the keys it needs are there.  A key that is present but malformed raises
``ProbegenError`` with its key path (``features[0].residuals[3]``), what was expected
and what was found.

Optional keys the report understands beyond ``ingest``'s output:

* ``calibration.probe``: the probe calibration, with the keys of the calibration file
  ``compensate.py`` documents (``ball_radius``, ``effective_radius``, ``directions``,
  ``radii``, ``source``);
* ``calibration.functions``: ``[{"name", "positions", "values", "unit"?}]``, identified
  error functions (rotary axis M4, 21 terms M5), drawn as line plots.

``decisions`` (``ingest``'s in-process decisions, ``docs/actions.md``) is optional too, and
so are ``uncertainty`` (the decision rule and its notes) and each characteristic's ``U``
and ``decision``; so is ``calibration.state``, which probe calibration the results were
compensated with (``ingest`` always writes it: "uncalibrated, nominal ball radius" or the
calibration's source, date and fingerprint).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, NoReturn

from probegen.errors import ProbegenError
from probegen.evaluate.characteristics import (
    NOT_EVALUATED,
    NOT_OK,
    OK,
    STATUSES,
    run_status,
    status_of,
)
from probegen.evaluate.run_identity import RunIdentity

Vec3 = tuple[float, float, float]

PATH_KINDS = ("rapid", "protected", "touch")
"""Segment groups the 3-D view colours; a segment's kind starts with one of these words
(``touch PT 5``); anything else is drawn as ``other``."""


@dataclass(frozen=True, slots=True)
class Characteristic:
    """One checked quantity of a feature (mm, or as the characteristic says); the values
    are None for a toleranced characteristic that was not evaluated; ``U`` its expanded
    uncertainty (k = 2) and ``decision`` the ISO 14253-1 decision, when the results carry
    them."""

    name: str
    measured: float | None
    nominal: float | None
    deviation: float | None
    lower: float | None
    upper: float | None
    ok: bool | None
    status: str = "-"
    U: float | None = None
    decision: str | None = None
    method: str = ""


@dataclass(frozen=True, slots=True)
class Feature:
    """One evaluated feature.

    Attributes:
        id: feature id from the spec.
        kind: feature kind (``sphere_test`` ...).
        ok: all toleranced characteristics within limits; None if none is toleranced or
            the feature was not evaluated.
        characteristics: the checked quantities, in results order.
        points: (n) compensated contact points, mm.
        directions: (n) nominal unit normals of the points.
        residuals: (n) signed radial residuals of the fit, mm (+ = outside).
        status: ``OK``, ``NOT OK``, ``NOT EVALUATED`` or ``-``.
        reason: why it was not evaluated.
    """

    id: str
    kind: str
    ok: bool | None
    characteristics: tuple[Characteristic, ...]
    points: tuple[Vec3, ...]
    directions: tuple[Vec3, ...]
    residuals: tuple[float, ...]
    status: str = "-"
    reason: str = ""

    def char(self, name: str) -> Characteristic | None:
        """The characteristic called ``name``, or None."""
        return next((c for c in self.characteristics if c.name == name), None)

    @property
    def nominal_centre(self) -> Vec3:
        """Nominal centre from the X, Y, Z characteristics (origin if absent)."""
        xyz = [self.char(axis) for axis in "XYZ"]
        x, y, z = (0.0 if c is None or c.nominal is None else c.nominal for c in xyz)
        return (x, y, z)

    @property
    def nominal_radius(self) -> float | None:
        """Half the nominal (calibrated) diameter ``D``, or None."""
        d = self.char("D")
        return None if d is None or d.nominal is None else d.nominal / 2.0


@dataclass(frozen=True, slots=True)
class Segment:
    """One straight move of the planned stylus path (ball centre, mm)."""

    feature: str
    kind: str
    start: Vec3
    end: Vec3

    @property
    def group(self) -> str:
        """``rapid``, ``protected``, ``touch`` or ``other``: what the view colours by."""
        word = self.kind.split(" ", 1)[0]
        return word if word in PATH_KINDS else "other"


@dataclass(frozen=True, slots=True)
class ProbeRadii:
    """Effective stylus radius by direction.

    Attributes:
        label: where the radii come from.
        ball_radius: nominal ball radius, mm.
        directions: (n) unit vectors, probe frame.
        radii: (n) effective radius in each direction, mm.
    """

    label: str
    ball_radius: float
    directions: tuple[Vec3, ...]
    radii: tuple[float, ...]


@dataclass(frozen=True, slots=True)
class Function:
    """An identified error function sampled along an axis (M4, M5)."""

    name: str
    positions: tuple[float, ...]
    values: tuple[float, ...]
    unit: str = ""


@dataclass(frozen=True, slots=True)
class Decision:
    """One value of an in-process decision (``probegen.evaluate.actions.Decision``).

    Attributes:
        feature: feature id.
        key: ``X Y D F P A E NG C`` (``probegen.ir.actions``; ``C`` the tool correction).
        offline: the value ``ingest`` computed from the log's points (mm, degrees; ``NG``
            1 or 0); None: too few points.
        machine: the value the machine printed in its ``RES`` line; None: not printed.
        agrees: within ``limit`` of each other; None when one is missing.
        limit: the largest difference that counts as agreeing (None in older results).
    """

    feature: str
    key: str
    offline: float | None
    machine: float | None
    agrees: bool | None
    limit: float | None


@dataclass(frozen=True, slots=True)
class Results:
    """What the report shows, read from ``results.json``."""

    source: str
    program: str
    complete: bool | None
    notes: tuple[str, ...]
    diagnostics: tuple[str, ...]
    features: tuple[Feature, ...]
    path: tuple[Segment, ...]
    probe: ProbeRadii | None
    functions: tuple[Function, ...]
    decisions: tuple[Decision, ...] = ()
    status: str = "-"
    decision_rule: str = ""
    uncertainty_notes: tuple[str, ...] = ()
    calibration: str = ""
    run: RunIdentity | None = None


RUN_FIELDS = (("time", "date"), ("part_number", "part number"), ("part_name", "part"),
              ("serial", "serial"), ("batch", "batch"), ("operator", "operator"),
              ("machine", "machine"), ("program", "program"))
"""The run's fields the report's header shows, in order, with their labels."""


def run_fields(run: RunIdentity | None) -> list[tuple[str, str]]:
    """(label, value) of each field of the run that is known, for the header."""
    if run is None:
        return []
    return [(label, str(getattr(run, key))) for key, label in RUN_FIELDS
            if getattr(run, key)]


def read_results(doc: Mapping[str, Any], source: str = "results.json") -> Results:
    """Read a parsed ``results.json`` document.

    Args:
        doc: the JSON object.
        source: file name for error messages.

    Raises:
        ProbegenError: a key the report needs is missing or malformed.
    """
    r = _Reader(source)
    root = r.mapping(doc, "")
    cal = r.mapping(root.get("calibration", {}), "calibration")
    unc = r.mapping(root.get("uncertainty", {}), "uncertainty")
    features = tuple(_feature(r, f, f"features[{i}]")
                     for i, f in enumerate(r.items(root.get("features"), "features")))
    complete = r.flag(root.get("complete"), "complete")
    return Results(
        source=r.text(root.get("source", ""), "source"),
        program="" if root.get("program") is None else str(root["program"]),
        complete=complete,
        notes=tuple(r.texts(root.get("notes", []), "notes")),
        diagnostics=tuple(r.texts(root.get("diagnostics", []), "diagnostics")),
        features=features,
        path=tuple(_segment(r, s, f"path[{i}]")
                   for i, s in enumerate(r.items(root.get("path", []), "path"))),
        probe=None if "probe" not in cal else _probe(r, cal["probe"], "calibration.probe"),
        functions=tuple(_function(r, f, f"calibration.functions[{i}]")
                        for i, f in enumerate(r.items(cal.get("functions", []),
                                                      "calibration.functions"))),
        decisions=tuple(_decision(r, d, f"decisions[{i}]")
                        for i, d in enumerate(r.items(root.get("decisions", []),
                                                      "decisions"))),
        status=r.status(root.get("status"), "status", _run_status(features, complete)),
        decision_rule=r.text(unc.get("decision_rule", ""), "uncertainty.decision_rule"),
        uncertainty_notes=tuple(r.texts(unc.get("notes", []), "uncertainty.notes")),
        calibration=r.text(cal.get("state", ""), "calibration.state"),
        run=None if root.get("run") is None else _run(r, root["run"]),
    )


def _run(r: _Reader, value: object) -> RunIdentity:
    """The ``run`` block (texts or null)."""
    block = r.mapping(value, "run")
    for key, item in block.items():
        if item is not None:
            r.text(item, f"run.{key}")
    return RunIdentity.from_json(dict(block))


def _run_status(features: Sequence[Feature], complete: bool | None) -> str:
    """The run's status for results without one: ``probegen.evaluate.characteristics.run_status`` of
    the features' statuses."""
    statuses = [f.status for f in features]
    return run_status(({OK: True, NOT_OK: False}.get(s) for s in statuses),
                      not_evaluated=NOT_EVALUATED in statuses, complete=complete is not False)


def _feature(r: _Reader, value: object, key: str) -> Feature:
    f = r.mapping(value, key)
    points = tuple(r.vec3(p, f"{key}.points[{i}]")
                   for i, p in enumerate(r.items(f.get("points", []), f"{key}.points")))
    directions = tuple(r.vec3(p, f"{key}.directions[{i}]") for i, p in
                       enumerate(r.items(f.get("directions", []), f"{key}.directions")))
    residuals = tuple(r.numbers(f.get("residuals", []), f"{key}.residuals"))
    for name, seq in (("directions", directions), ("residuals", residuals)):
        if seq and len(seq) != len(points):
            r.fail(f"{key}.{name}", f"{len(points)} entries (one per point)",
                   f"{len(seq)}")
    ok = r.flag(f.get("ok"), f"{key}.ok")
    return Feature(
        id=r.text(f.get("id"), f"{key}.id"), kind=r.text(f.get("kind", ""), f"{key}.kind"),
        ok=ok, status=r.status(f.get("status"), f"{key}.status", status_of(ok)),
        reason=r.text(f.get("reason", ""), f"{key}.reason"),
        characteristics=tuple(_characteristic(r, c, f"{key}.characteristics[{i}]")
                              for i, c in enumerate(r.items(f.get("characteristics", []),
                                                            f"{key}.characteristics"))),
        points=points, directions=directions, residuals=residuals)


def _characteristic(r: _Reader, value: object, key: str) -> Characteristic:
    c = r.mapping(value, key)
    ok = r.flag(c.get("ok"), f"{key}.ok")
    status = r.status(c.get("status"), f"{key}.status", status_of(ok))
    # only a characteristic NOT EVALUATED may lack its values
    number = r.optional_number if status == NOT_EVALUATED else r.number
    return Characteristic(
        name=r.text(c.get("name"), f"{key}.name"),
        measured=number(c.get("measured"), f"{key}.measured"),
        nominal=number(c.get("nominal"), f"{key}.nominal"),
        deviation=number(c.get("deviation"), f"{key}.deviation"),
        lower=r.optional_number(c.get("lower"), f"{key}.lower"),
        upper=r.optional_number(c.get("upper"), f"{key}.upper"),
        ok=ok, status=status,
        U=r.optional_number(c.get("U"), f"{key}.U"),
        decision=None if c.get("decision") is None
        else r.text(c.get("decision"), f"{key}.decision"),
        method=r.text(c.get("method", ""), f"{key}.method"))


def _segment(r: _Reader, value: object, key: str) -> Segment:
    s = r.mapping(value, key)
    return Segment(feature=r.text(s.get("feature", ""), f"{key}.feature"),
                   kind=r.text(s.get("kind"), f"{key}.kind"),
                   start=r.vec3(s.get("start"), f"{key}.start"),
                   end=r.vec3(s.get("end"), f"{key}.end"))


def _decision(r: _Reader, value: object, key: str) -> Decision:
    d = r.mapping(value, key)
    return Decision(feature=r.text(d.get("feature"), f"{key}.feature"),
                    key=r.text(d.get("key"), f"{key}.key"),
                    offline=r.optional_number(d.get("offline"), f"{key}.offline"),
                    machine=r.optional_number(d.get("machine"), f"{key}.machine"),
                    agrees=r.flag(d.get("agrees"), f"{key}.agrees"),
                    limit=r.optional_number(d.get("limit"), f"{key}.limit"))


def _probe(r: _Reader, value: object, key: str) -> ProbeRadii:
    p = r.mapping(value, key)
    directions = tuple(r.vec3(d, f"{key}.directions[{i}]") for i, d in
                       enumerate(r.items(p.get("directions"), f"{key}.directions")))
    radii = tuple(r.numbers(p.get("radii"), f"{key}.radii"))
    if len(radii) != len(directions):
        r.fail(f"{key}.radii", f"{len(directions)} radii (one per direction)",
               f"{len(radii)}")
    source = r.text(p.get("source", ""), f"{key}.source")
    return ProbeRadii(label=f"probe calibration{f' from {source}' if source else ''}",
                      ball_radius=r.number(p.get("ball_radius"), f"{key}.ball_radius"),
                      directions=directions, radii=radii)


def _function(r: _Reader, value: object, key: str) -> Function:
    f = r.mapping(value, key)
    positions = tuple(r.numbers(f.get("positions"), f"{key}.positions"))
    values = tuple(r.numbers(f.get("values"), f"{key}.values"))
    if len(values) != len(positions) or len(values) < 2:
        r.fail(f"{key}.values", f"as many values as positions ({len(positions)}), "
               "at least 2", f"{len(values)}")
    return Function(name=r.text(f.get("name"), f"{key}.name"), positions=positions,
                    values=values, unit=r.text(f.get("unit", ""), f"{key}.unit"))


def sphere_test_radii(feature: Feature) -> ProbeRadii | None:
    """Effective radius in each measured direction, from a sphere test's results.

    ``r_i = R_EFF + ε_i``: the ball radius the points were compensated with, plus the
    fitted radius' error, plus the point's radial residual (``evaluate.py``'s
    ``radii``).  None when the feature is not a sphere test or lacks the data.
    """
    r_eff = feature.char("R_EFF")
    if feature.kind != "sphere_test" or r_eff is None or not feature.residuals \
            or not feature.directions or feature.status == NOT_EVALUATED \
            or r_eff.nominal is None or r_eff.measured is None:
        return None
    return ProbeRadii(label=f"sphere test {feature.id} (r_i = R_EFF + \u03b5_i)",
                      ball_radius=r_eff.nominal, directions=feature.directions,
                      radii=tuple(r_eff.measured + e for e in feature.residuals))


class _Reader:
    """Type checks with key paths in the messages."""

    def __init__(self, source: str) -> None:
        self.source = source

    def fail(self, key: str, expected: str, found: str) -> NoReturn:
        where = f"{self.source}: {key}" if key else self.source
        raise ProbegenError(f"{where}: expected {expected}, found {found}")

    def mapping(self, value: object, key: str) -> Mapping[str, Any]:
        if not isinstance(value, Mapping):
            self.fail(key, "an object", _short(value))
        return value

    def items(self, value: object, key: str) -> Sequence[Any]:
        if not isinstance(value, list):
            self.fail(key, "a list", _short(value))
        return value

    def number(self, value: object, key: str) -> float:
        if isinstance(value, bool) or not isinstance(value, int | float):
            self.fail(key, "a number", _short(value))
        return float(value)

    def optional_number(self, value: object, key: str) -> float | None:
        return None if value is None else self.number(value, key)

    def numbers(self, value: object, key: str) -> list[float]:
        return [self.number(v, f"{key}[{i}]") for i, v in enumerate(self.items(value, key))]

    def vec3(self, value: object, key: str) -> Vec3:
        x = self.numbers(value, key)
        if len(x) != 3:
            self.fail(key, "3 numbers", _short(value))
        return (x[0], x[1], x[2])

    def text(self, value: object, key: str) -> str:
        if not isinstance(value, str):
            self.fail(key, "a string", _short(value))
        return value

    def texts(self, value: object, key: str) -> list[str]:
        return [self.text(v, f"{key}[{i}]") for i, v in enumerate(self.items(value, key))]

    def status(self, value: object, key: str, default: str) -> str:
        """A status string (``default`` when absent)."""
        if value is None:
            return default
        if value not in STATUSES:
            self.fail(key, "one of " + ", ".join(repr(s) for s in STATUSES), _short(value))
        return str(value)

    def flag(self, value: object, key: str) -> bool | None:
        if value is not None and not isinstance(value, bool):
            self.fail(key, "true, false or null", _short(value))
        return value if isinstance(value, bool) else None


def _short(value: object) -> str:
    text = "nothing" if value is None else repr(value)
    return text if len(text) <= 40 else text[:37] + "..."
