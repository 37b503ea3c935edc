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

from probegen.qif_chars import Check, Links, add_characteristic, status
from probegen.qif_xml import (
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
    from probegen.evaluate import Characteristic, SphereTestResult
    from probegen.ingest import Ingested
    from probegen.spec import Spec

STANDARD = ("ISO", "ISO 10360-5", "Acceptance and reverification tests for coordinate "
            "measuring systems - Part 5: Coordinate measuring machines using single and "
            "multiple stylus contacting probing systems")
"""The formal standard of the sphere test's characteristics."""

_POINTS_DEPTH = 6
"""Depth of ``Points`` below the root (Results/Set/MeasurementResults/PointSets/Set)."""


@dataclass(frozen=True, slots=True)
class _Resources:
    """Ids of the measuring device and the probe (sensor)."""

    device: int
    sensor: int


def sphere_results_qif(ing: Ingested, *, spec: Spec | None, application: str, version: str,
                       created: datetime | None, qpid: str | None) -> str:
    """Build the QIF text of an ingest (see :func:`probegen.qif.ingested_to_qif`)."""
    b = QifBuilder(application, version, created, qpid)
    begin_document(b, standard=STANDARD, source=ing.source, source_kind="DPRNT log")
    b.notes += list(ing.notes)
    resources = _resources(b, ing, spec)
    part = _part(b, spec)
    nominals: list[int] = []
    characteristic_nominals: list[int] = []
    for result in ing.results:
        nominal, chars = _sphere(b, result, resources)
        nominals.append(nominal)
        characteristic_nominals += chars
    ref_list(part, "FeatureNominalIds", nominals)
    if characteristic_nominals:
        ref_list(part, "CharacteristicNominalIds", characteristic_nominals)
    return b.to_text()


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
        _tip(probe, 2.0 * ing.results[0].ball_radius, None)
    b.single("MeasurementResources", section)
    return _Resources(device_id, sensor_id)


def _tip(probe: ET.Element, ball: float, shank: float | None) -> None:
    sub(sub(probe, "TipEndGeometry"), "TipEndGeometryEnum", "SPHERE")
    sub(probe, "TipEndDiameter", num(ball))
    if shank is not None:
        sub(probe, "StemDiameter", num(shank))


def _part(b: QifBuilder, spec: Spec | None) -> ET.Element:
    """``Product/PartSet`` with the one part (named after the spec's model file)."""
    product = ET.Element("Product")
    part_set = sub(product, "PartSet", n="1")
    part = sub(part_set, "Part", id=str(b.new_id()))
    if spec is not None and spec.model is not None:
        sub(part, "ModelNumber", Path(spec.model).name)
    b.single("Product", product)
    return part


def _sphere(b: QifBuilder, r: SphereTestResult, res: _Resources) -> tuple[int, list[int]]:
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
    return nominal_id, [add_characteristic(b, check, links) for check in _checks(r)]


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
    sub(element, "Location", vec(r.fit.centre))
    sub(element, "Diameter", num(2.0 * r.fit.radius))
    sub(element, "Form", num(r.p_ftu))
    return ident


def _checks(r: SphereTestResult) -> list[Check]:
    """The characteristics of one sphere: diameter always, form and position if toleranced."""
    by_name = {c.name: c for c in r.characteristics}
    d = by_name["D"]
    checks = [Check("SphericalDiameter", f"{r.feature} D", d.measured, status(d.ok),
                    target=d.nominal, lower=d.lower, upper=d.upper)]
    form = by_name["P_FTU"]
    if form.upper is not None:
        checks.append(Check("Sphericity", f"{r.feature} P_FTU", form.measured,
                            status(form.ok), zone=form.upper))
    checks += _position(r.feature, by_name["POS"])
    return checks


def _position(feature: str, pos: Characteristic) -> list[Check]:
    """The position check: ``POS`` and its limit are already spherical zone diameters
    (twice the centre distance)."""
    if pos.upper is None:
        return []
    return [Check("Position", f"{feature} POS", pos.measured, status(pos.ok),
                  zone=pos.upper, zone_shape="SphericalZone", material="NONE")]
