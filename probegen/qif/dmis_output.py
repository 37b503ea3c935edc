"""A DMIS output file (``FA``/``TA`` actuals) as a QIF 3 results document.

Feature actuals become QIF feature measurements, named after the DMIS label (a DMIS
output has no nominals, so no feature definitions, nominals or items are written):

=========  ================================  =========================================
DMIS       QIF                               written
=========  ================================  =========================================
POINT      PointFeatureMeasurement           Location, Normal (when given)
PLANE      PlaneFeatureMeasurement           Location, Normal
LINE       LineFeatureMeasurement            Location, Direction, Length (bounded), Normal
CIRCLE     CircleFeatureMeasurement          Location, Normal, Diameter
SPHERE     SphereFeatureMeasurement          Location, Diameter
CYLNDR     CylinderFeatureMeasurement        Axis (point, direction), Diameter, Length
CONE       ConeFeatureMeasurement            Axis (apex, direction), FullAngle (degrees)
TORUS      TorusFeatureMeasurement           Location, AxisVector, MinorDiameter,
                                             MajorDiameter
=========  ================================  =========================================

The ``PTMEAS`` points echoed inside a ``MEAS`` block become the feature's
``MeasuredPointSet`` (``Compensated`` true: DMIS reports surface points).

Tolerance actuals become characteristics: ``DIAM`` (Diameter; SphericalDiameter on a
sphere), ``FLAT`` (Flatness), ``CIRLTY`` (Circularity), ``CYLCTY`` (Cylindricity),
``POS`` (Position: ``2D`` a diametrical zone, ``3D`` a spherical one), ``INTOL``/``OUTOL``
as PASS/FAIL.  A ``TA`` belongs to the nearest ``FA`` before it in the file (``OUTPUT/
FA(x),TA(y)`` writes them in that order).  QIF needs every characteristic's tolerance,
which a DMIS output does not repeat: the limits come from the ``T(name)=TOL/...``
definitions (:func:`read_dmis_tolerances` on the program, or on an output that echoes
them).  Whatever cannot be written is listed in :attr:`QifExport.notes`.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from collections.abc import Mapping
from dataclasses import dataclass
from datetime import datetime
from typing import TYPE_CHECKING

from probegen.qif.characteristics import Check, Links, add_characteristic
from probegen.qif.document import QifBuilder, begin_document, num, point_lines, sub, vec

if TYPE_CHECKING:
    from probegen.dmis.reader import Param
    from probegen.results.dmis_output import (
        DmisOutput,
        FeatureActual,
        MeasuredPoint,
        ToleranceActual,
    )

STANDARD = ("ANSI", "ANSI/DMIS 105.2", "Dimensional Measuring Interface Standard")
"""The formal standard of characteristics read from DMIS tolerances."""

FEATURE_TAGS = {"POINT": "Point", "PLANE": "Plane", "LINE": "Line", "CIRCLE": "Circle",
                "SPHERE": "Sphere", "CYLNDR": "Cylinder", "CONE": "Cone",
                "TORUS": "Torus"}
"""DMIS feature type -> QIF feature stem (``<stem>FeatureMeasurement``)."""

FORM_TOLERANCES = {"FLAT": ("Flatness", "PLANE"), "CIRLTY": ("Circularity", "CIRCLE"),
                   "CYLCTY": ("Cylindricity", "CYLNDR")}
"""DMIS form tolerance -> (QIF characteristic stem, the DMIS feature type it applies to)."""

TOLERANCE_KINDS = ("DIAM", "POS", *FORM_TOLERANCES)
"""The DMIS tolerance kinds converted."""

MATERIAL = {"RFS": "REGARDLESS", "MMC": "MAXIMUM", "LMC": "LEAST"}
"""DMIS material condition -> QIF ``MaterialModifierEnum`` (none written: ``NONE``)."""

_POINTS_DEPTH = 6


@dataclass(frozen=True, slots=True)
class DmisTolerance:
    """A tolerance definition ``T(name)=TOL/<kind>,...``; lengths mm.

    Attributes:
        name: the label name, upper case.
        kind: ``DIAM``, ``POS``, ``FLAT``, ``CIRLTY`` or ``CYLCTY`` (other kinds are
            not read: they have no QIF counterpart here).
        lower: lowest allowed deviation (``DIAM``), else None.
        upper: highest allowed deviation (``DIAM``), else None.
        zone: the tolerance zone (form and position), else None.
        mode: ``2D`` or ``3D`` (``POS``), else None.
        material: ``RFS``, ``MMC`` or ``LMC`` when written, else None.
        line: 1-based line of the definition.
    """

    name: str
    kind: str
    lower: float | None = None
    upper: float | None = None
    zone: float | None = None
    mode: str | None = None
    material: str | None = None
    line: int = 0


@dataclass(frozen=True, slots=True)
class QifExport:
    """A converted document and what could not be converted.

    Attributes:
        text: the QIF document.
        notes: one line per item left out or only partly written, naming it.
    """

    text: str
    notes: tuple[str, ...]


def read_dmis_tolerances(text: str, *, source: str = "<string>") -> dict[str, DmisTolerance]:
    """Read the ``T(name)=TOL/...`` definitions of a DMIS program (or output), in mm.

    Statements that do not parse, and definitions whose numbers do not fit their kind,
    are skipped: :func:`probegen.qif.export.dmis_output_to_qif` then reports the tolerance
    actuals that need them as left out.
    """
    from probegen.dmis.reader import parse_dmis_recovering
    from probegen.results.dmis_output import MM_PER_UNIT

    dmis, _ = parse_dmis_recovering(text, source=source)
    scale, found = 1.0, {}
    for stmt in dmis.statements:
        if stmt.major == "UNITS" and stmt.params and stmt.params[0] in MM_PER_UNIT:
            scale = MM_PER_UNIT[str(stmt.params[0])]
        elif stmt.label is not None and stmt.label.kind == "T" and stmt.major == "TOL":
            tolerance = _tolerance(stmt.label.name, stmt.params, scale, stmt.line)
            if tolerance is not None:
                found[tolerance.name] = tolerance
    return found


def _tolerance(name: str, params: tuple[Param, ...], scale: float,
               line: int) -> DmisTolerance | None:
    """Decode one ``TOL/`` definition (None when its numbers do not fit its kind)."""
    kind = params[0] if params and isinstance(params[0], str) else ""
    numbers = [float(p) * scale for p in params[1:] if isinstance(p, int | float)]
    words = [p for p in params[1:] if isinstance(p, str)]
    material = next((w for w in words if w in MATERIAL), None)
    if kind == "DIAM" and len(numbers) >= 2:
        return DmisTolerance(name, kind, lower=numbers[0], upper=numbers[1], line=line)
    if kind == "POS" and numbers:
        mode = next((w for w in words if w in ("2D", "3D")), None)
        return DmisTolerance(name, kind, zone=numbers[0], mode=mode, material=material,
                             line=line)
    if kind in FORM_TOLERANCES and numbers:
        return DmisTolerance(name, kind, zone=numbers[0], material=material, line=line)
    return None


def dmis_output_qif(out: DmisOutput, *, tolerances: Mapping[str, DmisTolerance] | None,
                    application: str, version: str, created: datetime | None,
                    qpid: str | None) -> QifExport:
    """Build the QIF of a DMIS output (see :func:`probegen.qif.export.dmis_output_to_qif`)."""
    b = QifBuilder(application, version, created, qpid)
    begin_document(b, standard=STANDARD, source=out.source, source_kind="DMIS output")
    _product(b)
    notes = [f"{out.source}: {len(out.diagnostics)} statement(s) could not be read "
             f"and are left out"] if out.diagnostics else []
    measured: dict[int, tuple[FeatureActual, int]] = {}
    previous: dict[str, int] = {}
    for feature in out.features:
        points = [p for p in out.points if p.feature == feature.name and p.via == "PTMEAS"
                  and previous.get(feature.name, 0) < p.line < feature.line]
        measured[feature.line] = (feature, _feature(b, feature, points))
        previous[feature.name] = feature.line
    for ta in out.tolerances:
        owner = _owner(measured, ta)
        note = _characteristic(b, ta, owner, (tolerances or {}).get(ta.name))
        notes += [note] if note else []
    b.statuses = ["PASS" if ta.intol else "FAIL" for ta in out.tolerances]
    b.notes += notes
    return QifExport(b.to_text(), tuple(notes))


def _product(b: QifBuilder) -> None:
    product = ET.Element("Product")
    sub(sub(product, "PartSet", n="1"), "Part", id=str(b.new_id()))
    b.single("Product", product)


def _owner(measured: dict[int, tuple[FeatureActual, int]],
           ta: ToleranceActual) -> tuple[FeatureActual, int] | None:
    """The feature actual written last before ``ta`` (and its measurement id)."""
    before = [line for line in measured if line < ta.line]
    return measured[max(before)] if before else None


def _feature(b: QifBuilder, f: FeatureActual, points: list[MeasuredPoint]) -> int:
    """Write one feature actual and its measured points; return its id."""
    points_id = _point_set(b, points) if points else None
    element, ident = b.add("MeasuredFeatures", f"{FEATURE_TAGS[f.type]}FeatureMeasurement")
    sub(element, "FeatureName", f.name)
    if points_id is not None:
        sub(sub(element, "PointList", n="1"), "WholePointSetId", str(points_id))
    _geometry(element, f)
    return ident


def _point_set(b: QifBuilder, points: list[MeasuredPoint]) -> int:
    element, ident = b.add("MeasuredPointSets", "MeasuredPointSet")
    element.attrib["count"] = str(len(points))
    sub(element, "Points", point_lines([p.xyz for p in points], _POINTS_DEPTH))
    normals = [p.normal for p in points if p.normal is not None]
    if len(normals) == len(points):
        sub(element, "Normals", point_lines(normals, _POINTS_DEPTH))
    sub(element, "Compensated", "true")
    return ident


def _geometry(element: ET.Element, f: FeatureActual) -> None:
    """The type-specific children of a feature measurement, in schema order."""
    if f.type == "TORUS":
        sub(element, "Location", vec(f.position))
        sub(element, "AxisVector", vec(f.direction or (0.0, 0.0, 1.0)))
        _optional(element, "MinorDiameter", f.minor_diameter)
        _optional(element, "MajorDiameter", f.diameter)
        return
    if f.type in ("CYLNDR", "CONE"):
        axis = sub(element, "Axis")
        sub(axis, "AxisPoint", vec(f.position))
        sub(axis, "Direction", vec(f.direction or (0.0, 0.0, 1.0)))
    else:
        sub(element, "Location", vec(f.position))
    if f.type == "LINE":
        sub(element, "Direction", vec(f.direction or (0.0, 0.0, 1.0)))
        _optional(element, "Length", f.length)
        if f.normal is not None:
            sub(element, "Normal", vec(f.normal))
    elif f.type in ("POINT", "PLANE", "CIRCLE") and f.direction is not None:
        sub(element, "Normal", vec(f.direction))
    _optional(element, "Diameter", f.diameter)
    if f.type == "CYLNDR":
        _optional(element, "Length", f.length)
    if f.type == "CONE" and f.angle is not None:
        sub(element, "FullAngle", num(f.angle))


def _optional(element: ET.Element, tag: str, value: float | None) -> None:
    if value is not None and math.isfinite(value):
        sub(element, tag, num(value))


def _characteristic(b: QifBuilder, ta: ToleranceActual,
                    owner: tuple[FeatureActual, int] | None,
                    limits: DmisTolerance | None) -> str | None:
    """Write one tolerance actual; return a note when it cannot be (else None)."""
    label = f"TA({ta.name})=TOL/{ta.kind} (line {ta.line})"
    if ta.kind not in TOLERANCE_KINDS:
        return f"{label}: no QIF characteristic for DMIS {ta.kind}; left out"
    if limits is None:
        return (f"{label}: the limits of T({ta.name}) are unknown (a DMIS output does not "
                f"repeat them; pass the program's TOL definitions); left out")
    if limits.kind != ta.kind:
        return (f"{label}: T({ta.name}) (line {limits.line}) defines a {limits.kind} "
                f"tolerance, not {ta.kind}; left out")
    feature, measurement = owner if owner else (None, None)
    try:
        check = _check(ta, feature, limits)
    except _Unmapped as exc:
        return f"{label}: {exc}; left out"
    add_characteristic(b, check, Links(feature_measurement=measurement))
    return None


class _Unmapped(Exception):
    """A tolerance actual that cannot become a characteristic (the message says why)."""


def _check(ta: ToleranceActual, feature: FeatureActual | None,
           limits: DmisTolerance) -> Check:
    """The characteristic of a tolerance actual and its definition."""
    verdict = "PASS" if ta.intol else "FAIL"
    if ta.kind == "DIAM":
        if feature is None or feature.diameter is None or feature.type == "TORUS":
            raise _Unmapped("DIAM needs the actual diameter of a CIRCLE, SPHERE or CYLNDR "
                            "written before it")
        kind = "SphericalDiameter" if feature.type == "SPHERE" else "Diameter"
        return Check(kind, ta.name, feature.diameter, verdict,
                     target=feature.diameter - ta.value, lower=limits.lower,
                     upper=limits.upper)
    if ta.kind == "POS":
        shape = "SphericalZone" if "3D" in (*ta.qualifiers, limits.mode) else "DiametricalZone"
        return Check("Position", ta.name, ta.value, verdict, zone=limits.zone,
                     zone_shape=shape, material=MATERIAL.get(limits.material or "", "NONE"))
    stem, applies_to = FORM_TOLERANCES[ta.kind]
    if feature is not None and feature.type != applies_to:
        raise _Unmapped(f"{ta.kind} applies to a {applies_to}, the feature before it is "
                        f"the {feature.type} {feature.name}")
    return Check(stem, ta.name, ta.value, verdict, zone=limits.zone)
