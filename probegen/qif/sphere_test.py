"""The sphere test's results (``probegen ingest``) as a QIF 3 document.

Per evaluated sphere: a ``SphereFeatureDefinition`` (the certified diameter), a
``SphereFeatureNominal`` (the nominal or located centre), a ``SphereFeatureItem``; in the
results a ``MeasuredPointSet`` of the compensated contact points (with their approach
normals, ``Compensated`` true and the ``ProbeRadius`` they were compensated with) and a
``SphereFeatureMeasurement`` (fitted centre, diameter, form = ``P_FTU``; ``P_FTU``,
``P_STU`` and ``R_EFF`` also as attributes).  Characteristics: the spherical diameter
always (measured only when the spec gives no ``size`` limit), the sphericity when
``form`` is toleranced and the position when ``position`` is (a zone diameter, as QIF
and probegen's ``POS`` both state it, see ``docs/qif.md``).
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass
from datetime import datetime
from pathlib import Path
from typing import TYPE_CHECKING

from probegen.qif.characteristics import (
    NOT_ANALYZED,
    Check,
    Links,
    add_characteristic,
    measured_point,
    measured_value,
    status,
)
from probegen.qif.document import (
    QifBuilder,
    attributes,
    begin_document,
    num,
    point_lines,
    ref_list,
    sub,
    vec,
)

if TYPE_CHECKING:
    from probegen.evaluate.characteristics import Characteristic
    from probegen.evaluate.ingest import Ingested
    from probegen.evaluate.run_identity import RunIdentity
    from probegen.evaluate.sphere_test import SphereTestResult
    from probegen.spec.model import Spec

STANDARD = ("ISO", "ISO 10360-5", "Acceptance and reverification tests for coordinate "
            "measuring systems - Part 5: Coordinate measuring machines using single and "
            "multiple stylus contacting probing systems")
"""The formal standard of the sphere test's characteristics."""
GPS_STANDARD = ("ISO", "ISO 1101", "Geometrical product specifications (GPS) - Geometrical "
                "tolerancing - Tolerances of form, orientation, location and run-out")
"""The formal standard of a document without a sphere test."""

_POINTS_DEPTH = 6
"""Depth of ``Points`` below the root (Results/Set/MeasurementResults/PointSets/Set)."""


@dataclass(frozen=True, slots=True)
class _Resources:
    """Ids of the measuring device and the probe (sensor)."""

    device: int
    sensor: int


def sphere_results_qif(ing: Ingested, *, spec: Spec | None, application: str, version: str,
                       created: datetime | None, qpid: str | None) -> str:
    """Build the QIF text of an ingest (see :func:`probegen.qif.export.ingested_to_qif`): the
    sphere tests here, the other kinds by :mod:`probegen.qif.features`."""
    from probegen.qif.features import freeform_qif, planar_qif, revolved_qif

    b = QifBuilder(application, version, created, qpid)
    begin_document(b, standard=STANDARD if ing.results else GPS_STANDARD, source=ing.source,
                   source_kind="DPRNT log")
    b.notes += [*ing.notes, *ing.uncertainty_notes,
                f"uncertainty: combinedUncertainty is the standard uncertainty u; the "
                f"expanded U = 2u; decision rule {ing.rule} (ISO 14253-1)"]
    b.identify(ing.run)
    resources = _resources(b, ing, spec)
    part = _part(b, spec, ing.run)
    nominals: list[int] = []
    characteristic_nominals: list[int] = []
    for result, evaluated in _spheres(ing):
        nominal, chars = _sphere(b, result, resources, ing.rule, evaluated)
        nominals.append(nominal)
        characteristic_nominals += chars
    for revolved in ing.revolved:
        characteristic_nominals += revolved_qif(b, revolved, resources.device,
                                                resources.sensor, ing.rule)
    for freeform in ing.freeform:
        characteristic_nominals += freeform_qif(b, freeform, resources.device,
                                                resources.sensor, ing.rule)
    for planar in ing.planar:
        characteristic_nominals += planar_qif(b, planar, resources.device,
                                              resources.sensor, ing.rule)
    for n in ing.not_evaluated:  # none of them may let the inspection PASS
        b.statuses.append(NOT_ANALYZED)
        b.notes.append(f"feature {n.feature}: NOT EVALUATED: {n.reason}")
    if not ing.log.complete:
        b.statuses.append(NOT_ANALYZED)
    if nominals:
        ref_list(part, "FeatureNominalIds", nominals)
    if characteristic_nominals:
        ref_list(part, "CharacteristicNominalIds", characteristic_nominals)
    return b.to_text()


def _spheres(ing: Ingested) -> list[tuple[SphereTestResult, bool]]:
    """The sphere tests to write, each with whether it was evaluated completely (a NOT
    EVALUATED one is written when its touches sufficed for a fit, its toleranced
    characteristics NOT_ANALYZED)."""
    from probegen.evaluate.sphere_test import SphereTestResult

    partial = [n.partial for n in ing.not_evaluated if isinstance(n.partial, SphereTestResult)]
    return [(r, True) for r in ing.results] + [(r, False) for r in partial]


def _resources(b: QifBuilder, ing: Ingested, spec: Spec | None) -> _Resources:
    """``MeasurementResources``: the machine and its probe (ball diameter, shank)."""
    section = ET.Element("MeasurementResources")
    devices = sub(section, "MeasurementDevices", n="1")
    device_id = b.new_id()
    name = spec.machine.name if spec else "machine tool with a touch-trigger probe"
    sub(sub(devices, "MeasurementDevice", id=str(device_id)), "Name", name)
    sensors = sub(section, "DetachableSensors", n="1")
    sensor_id = b.new_id()
    probe = sub(sensors, "SimpleTactileProbeSensor", id=str(sensor_id))
    if spec is not None:
        p = spec.machine.probe
        sub(probe, "Name", f"touch-trigger probe T{p.tool_number}")
        sub(probe, "Length", num(p.length))
        _tip(probe, p.ball_diameter, p.shank_diameter)
    else:
        sub(probe, "Name", "touch-trigger probe")
        spheres = _spheres(ing)
        if spheres:
            _tip(probe, 2.0 * spheres[0][0].ball_radius, None)
    b.single("MeasurementResources", section)
    return _Resources(device_id, sensor_id)


def _tip(probe: ET.Element, ball: float, shank: float | None) -> None:
    sub(sub(probe, "TipEndGeometry"), "TipEndGeometryEnum", "SPHERE")
    sub(probe, "TipEndDiameter", num(ball))
    if shank is not None:
        sub(probe, "StemDiameter", num(shank))


def _part(b: QifBuilder, spec: Spec | None, run: RunIdentity | None) -> ET.Element:
    """``Product/PartSet`` with the one part: its name (``Header/Name``), and as
    ``ModelNumber`` its part
    number (``[part] number``, ``--part-number``), else the spec's model file."""
    product = ET.Element("Product")
    part_set = sub(product, "PartSet", n="1")
    part = sub(part_set, "Part", id=str(b.new_id()))
    if run is not None and run.part_name:
        sub(sub(part, "Header"), "Name", run.part_name)
    if run is not None and run.part_number:
        sub(part, "ModelNumber", run.part_number)
    elif spec is not None and spec.model is not None:
        sub(part, "ModelNumber", Path(spec.model).name)
    b.single("Product", product)
    return part


def _sphere(b: QifBuilder, r: SphereTestResult, res: _Resources,
            rule: str, evaluated: bool) -> tuple[int, list[int]]:
    """Write one sphere; return its feature nominal id and characteristic nominal ids."""
    definition, def_id = b.add("FeatureDefinitions", "SphereFeatureDefinition")
    sub(definition, "InternalExternal", "EXTERNAL")
    sub(definition, "Diameter", num(r.calibrated_diameter))
    nominal, nominal_id = b.add("FeatureNominals", "SphereFeatureNominal")
    sub(nominal, "FeatureDefinitionId", str(def_id))
    sub(nominal, "Location", vec(r.nominal_centre))
    item, item_id = b.add("FeatureItems", "SphereFeatureItem")
    sub(item, "FeatureNominalId", str(nominal_id))
    sub(item, "FeatureName", r.feature)
    sub(sub(sub(sub(item, "DeterminationMode"), "Checked"), "CheckDetails"), "Measured")
    points_id = _point_set(b, r, res)
    measured_id = _measurement(b, r, item_id, points_id)
    links = Links(nominal_id, item_id, measured_id, res.device)
    return nominal_id, [add_characteristic(b, check, links)
                        for check in _checks(r, rule, evaluated)]


def _point_set(b: QifBuilder, r: SphereTestResult, res: _Resources) -> int:
    element, ident = b.add("MeasuredPointSets", "MeasuredPointSet")
    element.attrib["count"] = str(len(r.points))
    sub(element, "Points", point_lines(r.points, _POINTS_DEPTH))
    sub(element, "Normals", point_lines(r.directions, _POINTS_DEPTH))
    sub(element, "Compensated", "true")
    sub(element, "ProbeRadius", num(r.ball_radius))
    sub(element, "MeasurementDeviceId", str(res.device))
    sub(element, "SensorId", str(res.sensor))
    return ident


def _measurement(b: QifBuilder, r: SphereTestResult, item_id: int, points_id: int) -> int:
    element, ident = b.add("MeasuredFeatures", "SphereFeatureMeasurement")
    attributes(element, [("P_FTU", r.p_ftu), ("P_STU", r.p_stu),
                         ("R_EFF", r.effective_radius)])
    sub(element, "FeatureItemId", str(item_id))
    sub(element, "FeatureName", r.feature)
    sub(sub(element, "PointList", n="1"), "WholePointSetId", str(points_id))
    u = {c.name: c.u for c in r.characteristics}
    measured_point(element, "Location", r.fit.centre, (u["X"], u["Y"], u["Z"]))
    measured_value(element, "Diameter", 2.0 * r.fit.radius, u["D"])
    measured_value(element, "Form", r.p_ftu, u["P_FTU"])
    return ident


def _checks(r: SphereTestResult, rule: str, evaluated: bool = True) -> list[Check]:
    """The characteristics of one sphere: diameter always, form and position if
    toleranced (verdicts under ``rule``; NOT_ANALYZED when the sphere was not evaluated
    completely)."""
    by_name = {c.name: c for c in r.characteristics}
    d = by_name["D"]
    checks = [Check("SphericalDiameter", f"{r.feature} D", d.measured,
                    status(d.accepted(rule), evaluated=evaluated), target=d.nominal,
                    lower=d.lower, upper=d.upper, u=d.u)]
    form = by_name["P_FTU"]
    if form.upper is not None:
        checks.append(Check("Sphericity", f"{r.feature} P_FTU", form.measured,
                            status(form.accepted(rule), evaluated=evaluated),
                            zone=form.upper, u=form.u))
    checks += _position(r.feature, by_name["POS"], rule, evaluated)
    return checks


def _position(feature: str, pos: Characteristic, rule: str, evaluated: bool) -> list[Check]:
    """The position check: ``POS`` and its limit are already spherical zone diameters
    (twice the centre distance)."""
    if pos.upper is None:
        return []
    return [Check("Position", f"{feature} POS", pos.measured,
                  status(pos.accepted(rule), evaluated=evaluated), zone=pos.upper,
                  zone_shape="SphericalZone", material="NONE", u=pos.u)]
