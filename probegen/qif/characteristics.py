"""QIF characteristics: one checked quantity as definition, nominal, item and measurement.

QIF splits a characteristic in four linked records: the *definition* (the tolerance),
the *nominal* (the target value, linked to the feature nominal), the *item* (the
instance checked on the part, linked to the feature item and the measuring device) and,
in the results, the *measurement* (the value and its status, linked to the measured
feature).  :func:`add_characteristic` writes all four from one :class:`Check`.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from collections.abc import Sequence
from dataclasses import dataclass

from probegen.qif.document import QifBuilder, num, ref_list, sub, vec

SIZE_KINDS = frozenset({"Diameter", "SphericalDiameter", "Angle"})
"""Size characteristics: a target value and a bilateral tolerance on the deviation
(``Angle``: in the file's angular unit, degrees)."""

ZONE_KINDS = frozenset({"Flatness", "Straightness", "Cylindricity", "Circularity",
                        "Sphericity", "Position", "Conicity", "Toroidicity", "PointProfile",
                        "LineProfile", "SurfaceProfile"})
"""Geometric characteristics: a tolerance zone (QIF requires its value)."""

PROFILE_KINDS = frozenset({"PointProfile", "LineProfile", "SurfaceProfile"})
"""Zone kinds whose zone may be offset from the nominal (ISO 1101 ``UZ``)."""

ALGORITHMS = {"minimum zone": "MINMAX", "least squares": "LEASTSQUARES"}
"""A characteristic's ``method`` -> QIF ``SubstituteFeatureAlgorithmEnum``."""

ZONE_SHAPES = ("SphericalZone", "DiametricalZone")
"""Position zone shapes written (a sphere's centre: spherical; an axis: diametrical)."""


@dataclass(frozen=True, slots=True)
class Check:
    """One characteristic to write; lengths in mm.

    Attributes:
        kind: the QIF name stem, one of :data:`SIZE_KINDS` or :data:`ZONE_KINDS`.
        name: the characteristic item's name (``SPH1 D``, ``TOL4``).
        value: the measured value: the actual size, the form, or the position deviation
            as a zone diameter.
        status: ``PASS``, ``FAIL``, ``UNDEFINED`` (not toleranced) or ``NOT_ANALYZED``.
        target: the nominal size (size kinds).
        lower: lowest allowed deviation from ``target`` (size kinds), or None.
        upper: highest allowed deviation (size kinds), or None; both None: measured only.
        zone: the tolerance zone (zone kinds).
        zone_shape: the position zone, one of :data:`ZONE_SHAPES`.
        material: the position's material condition (QIF ``MaterialModifierEnum``).
        u: the value's combined standard uncertainty (QIF ``combinedUncertainty``, with
            ``meanError`` 0: the value is corrected for every known error), or None.
        offset: a profile zone's centre from the nominal, + outside the material (QIF
            ``UnequallyDisposedZone``, ISO 1101 ``UZ``), or None: centred.
        vector: a Straightness zone's width direction (``ZoneOrientationVector`` of its
            non-diametrical zone), a LineProfile's normal to the plane its line lies in
            (the nominal's ``Vector``, required there); unit, or None.
        method: how a form value was evaluated (``Characteristic.method``: "minimum
            zone", "least squares"; QIF ``SubstituteFeatureAlgorithm`` MINMAX,
            LEASTSQUARES on the item), or "".
    """

    kind: str
    name: str
    value: float
    status: str
    target: float | None = None
    lower: float | None = None
    upper: float | None = None
    zone: float | None = None
    zone_shape: str = "DiametricalZone"
    material: str = "NONE"
    u: float | None = None
    offset: float | None = None
    vector: tuple[float, float, float] | None = None
    method: str = ""


@dataclass(frozen=True, slots=True)
class Links:
    """The records a characteristic points at (None: not written)."""

    feature_nominal: int | None = None
    feature_item: int | None = None
    feature_measurement: int | None = None
    device: int | None = None


NOT_ANALYZED = "NOT_ANALYZED"
"""QIF ``CharacteristicStatusEnum`` of a toleranced characteristic NOT EVALUATED."""


def status(ok: bool | None, *, evaluated: bool = True) -> str:
    """QIF ``CharacteristicStatusEnum`` of a verdict: PASS, FAIL, or UNDEFINED (no
    limits); NOT_ANALYZED for a toleranced characteristic of a feature that was not
    evaluated completely (its value only informs)."""
    if ok is None:
        return "UNDEFINED"
    if not evaluated:
        return NOT_ANALYZED
    return "PASS" if ok else "FAIL"


def add_characteristic(b: QifBuilder, check: Check, links: Links = Links()) -> int:
    """Write ``check`` as definition, nominal, item and measurement; return the nominal's
    id (a part lists its characteristic nominals)."""
    definition = _definition(b, check)
    nominal = _nominal(b, check, definition, links)
    item = _item(b, check, nominal, links)
    _measurement(b, check, item, links)
    b.statuses.append(check.status)
    return nominal


def _definition(b: QifBuilder, check: Check) -> int:
    element, ident = b.add("CharacteristicDefinitions", f"{check.kind}CharacteristicDefinition")
    if check.kind in SIZE_KINDS:
        _size_tolerance(element, check)
        return ident
    if check.zone is None:
        raise ValueError(f"{check.kind} {check.name}: a zone characteristic needs its zone")
    sub(element, "ToleranceValue", num(check.zone))
    if check.kind in PROFILE_KINDS and check.offset:
        sub(element, "UnequallyDisposedZone", num(check.offset))
    if check.kind == "Position":
        sub(element, "MaterialCondition", check.material)
        sub(sub(element, "ZoneShape"), check.zone_shape)
    if check.kind == "Straightness":
        zone = sub(sub(element, "ZoneShape"), "NonDiametricalZone")
        if check.vector is not None:
            sub(zone, "ZoneOrientationVector", vec(check.vector))
    return ident


def _size_tolerance(element: ET.Element, check: Check) -> None:
    if check.lower is None and check.upper is None:
        sub(element, "NonTolerance", "MEASURED")
        return
    tolerance = sub(element, "Tolerance")
    if check.upper is not None:
        sub(tolerance, "MaxValue", num(check.upper))
    if check.lower is not None:
        sub(tolerance, "MinValue", num(check.lower))
    sub(tolerance, "DefinedAsLimit", "false")


def _nominal(b: QifBuilder, check: Check, definition: int, links: Links) -> int:
    element, ident = b.add("CharacteristicNominals", f"{check.kind}CharacteristicNominal")
    sub(element, "CharacteristicDefinitionId", str(definition))
    if links.feature_nominal is not None:
        ref_list(element, "FeatureNominalIds", [links.feature_nominal])
    if check.kind in SIZE_KINDS and check.target is not None:
        sub(element, "TargetValue", num(check.target))
    if check.kind == "LineProfile":
        sub(element, "Vector", vec(check.vector or (0.0, 0.0, 1.0)))
    return ident


def _item(b: QifBuilder, check: Check, nominal: int, links: Links) -> int:
    element, ident = b.add("CharacteristicItems", f"{check.kind}CharacteristicItem")
    sub(element, "Name", check.name)
    if links.feature_item is not None:
        ref_list(element, "FeatureItemIds", [links.feature_item])
    if check.method:
        sub(sub(element, "SubstituteFeatureAlgorithm"), "SubstituteFeatureAlgorithmEnum",
            ALGORITHMS[check.method])
    if links.device is not None:
        ref_list(element, "MeasurementDeviceIds", [links.device])
    sub(element, "CharacteristicNominalId", str(nominal))
    return ident


def _measurement(b: QifBuilder, check: Check, item: int, links: Links) -> None:
    tag = f"{check.kind}CharacteristicMeasurement"
    element, _ = b.add("CharacteristicMeasurements", tag)
    sub(sub(element, "Status"), "CharacteristicStatusEnum", check.status)
    sub(element, "CharacteristicItemId", str(item))
    if links.feature_measurement is not None:
        ref_list(element, "FeatureMeasurementIds", [links.feature_measurement])
    measured_value(element, "Value", check.value, check.u)


def measured_point(parent: ET.Element, tag: str, xyz: Sequence[float],
                   u: Sequence[float | None]) -> ET.Element:
    """A QIF measured point ``<tag>`` with ``x/y/zCombinedUncertainty`` where known."""
    attrs = {f"{axis}CombinedUncertainty": num(v)
             for axis, v in zip("xyz", u, strict=True) if v is not None}
    return sub(parent, tag, vec(xyz), **attrs)


def measured_value(parent: ET.Element, tag: str, value: float, u: float | None) -> ET.Element:
    """A QIF measured decimal ``<tag>``, with ``combinedUncertainty`` and ``meanError`` (0)
    when ``u`` is known (QIF wants both or neither)."""
    if u is None:
        return sub(parent, tag, num(value))
    return sub(parent, tag, num(value), combinedUncertainty=num(u), meanError=num(0.0))
