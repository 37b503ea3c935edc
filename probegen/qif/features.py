"""Revolved, planar and free-form results of ``probegen ingest`` in a QIF 3 document.

Each revolved feature (method M2) becomes a ``MeasuredPointSet`` of its contact points
(with their fitted outward normals, ``Compensated`` true) and a feature measurement:

=========  ============================  ===============================================
kind       QIF                           written
=========  ============================  ===============================================
circle     CircleFeatureMeasurement      Location, Normal, Diameter, Form (roundness)
cylinder   CylinderFeatureMeasurement    Axis (the centre, direction), Diameter, Form
cone       ConeFeatureMeasurement        Axis (apex, direction), HalfAngle (deg), Form
sphere     SphereFeatureMeasurement      Location, Diameter, Form
torus      TorusFeatureMeasurement       Location, AxisVector, MinorDiameter (tube),
                                         MajorDiameter, Form
=========  ============================  ===============================================

and its characteristics: ``D`` (Diameter; SphericalDiameter on a sphere) always, ``ANGLE``
(Angle) always on a cone, the section diameters ``D_Sk`` (Diameter) when the diameter is
toleranced (always on a cone: they are its sizes), and when toleranced ``POS``
(Position: a diametrical zone, a spherical one on a sphere), ``FORM`` (Circularity,
Cylindricity, Conicity, Sphericity, Toroidicity) and ``RON_Sk`` (Circularity).  A
toleranced ``TAPER`` has no QIF counterpart here and is named in the notes.

A line or plane (``evaluate_planar``): its contact points as a ``MeasuredPointSet``
(with the nominal outward normal) and a ``LineFeatureMeasurement`` (Location: the
first touch projected on the measured line, Direction, Length: from the first touch
to the last, Normal: the face's nominal normal, Form) or ``PlaneFeatureMeasurement``
(Location: the contact points' centroid, Normal: the least-squares normal from 3
touches, else the nominal one, Form).  Its characteristics: ``ANGLE`` (Angle, the
line's direction in XY against the nominal) always on a line, and when toleranced
``DIST`` (LineProfile, SurfaceProfile: the zone ``upper − lower`` about the nominal
face, offset by ``(upper + lower)/2`` as ``UnequallyDisposedZone`` when not centred;
the value ``2·|DIST − offset|``, the zone so placed the face's mean position needs,
so the status is ``lower <= DIST <= upper``; the form is the separate ``FORM``) and
``FORM`` (Straightness, Flatness).

Every form characteristic names its method on its item (``SubstituteFeatureAlgorithm``
MINMAX for the ISO 1101 minimum zone, LEASTSQUARES for least squares).

A free-form feature (method M3): its contact points as a ``MeasuredPointSet``, a
``PointFeatureMeasurement`` per guide point (``<id> E<g>``: the contact point and the
nominal normal) and, when toleranced, a ``PointProfile`` characteristic per guide point
(the zone ``upper − lower``; the value ``2·|e|``, the zone a symmetric profile needs).

Every measured value carries its standard uncertainty as ``combinedUncertainty`` (with
``meanError`` 0), every location ``x/y/zCombinedUncertainty``.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from probegen.errors import ProbegenError
from probegen.geometry.fits import fit_plane
from probegen.qif.characteristics import (
    Check,
    Links,
    add_characteristic,
    measured_point,
    measured_value,
    status,
)
from probegen.qif.document import QifBuilder, point_lines, sub, vec

if TYPE_CHECKING:
    from probegen.evaluate.characteristics import Characteristic
    from probegen.evaluate.freeform import FreeformResult
    from probegen.evaluate.planar import PlanarResult
    from probegen.evaluate.revolved import RevolvedResult

FEATURE_TAGS = {"circle": "Circle", "cylinder": "Cylinder", "cone": "Cone",
                "sphere": "Sphere", "torus": "Torus"}
"""Revolved kind -> QIF feature stem (``<stem>FeatureMeasurement``)."""
FORM_KINDS = {"circle": "Circularity", "cylinder": "Cylindricity", "cone": "Conicity",
              "sphere": "Sphericity", "torus": "Toroidicity"}
"""Revolved kind -> the QIF form characteristic of its ``FORM``."""
_POINTS_DEPTH = 6


def point_set(b: QifBuilder, points: Sequence[Sequence[float]],
              normals: Sequence[Sequence[float]], device: int, sensor: int) -> int:
    """Write a compensated ``MeasuredPointSet``; return its id."""
    element, ident = b.add("MeasuredPointSets", "MeasuredPointSet")
    element.attrib["count"] = str(len(points))
    sub(element, "Points", point_lines(points, _POINTS_DEPTH))
    sub(element, "Normals", point_lines(normals, _POINTS_DEPTH))
    sub(element, "Compensated", "true")
    sub(element, "MeasurementDeviceId", str(device))
    sub(element, "SensorId", str(sensor))
    return ident


def revolved_qif(b: QifBuilder, r: RevolvedResult, device: int, sensor: int,
                 rule: str) -> list[int]:
    """Write one revolved feature; return its characteristic nominal ids."""
    points = point_set(b, r.points, r.directions, device, sensor)
    element, measurement = b.add("MeasuredFeatures",
                                 f"{FEATURE_TAGS[r.kind]}FeatureMeasurement")
    sub(element, "FeatureName", r.feature)
    sub(sub(element, "PointList", n="1"), "WholePointSetId", str(points))
    chars = {c.name: c for c in r.characteristics}
    _geometry(element, r, chars)
    links = Links(feature_measurement=measurement, device=device)
    out = []
    for check in _checks(r, chars, rule, b.notes):
        out.append(add_characteristic(b, check, links))
    return out


def _u(chars: dict[str, Characteristic], name: str) -> float | None:
    c = chars.get(name)
    return None if c is None else c.u


def _geometry(element: ET.Element, r: RevolvedResult, chars: dict[str, Characteristic]) -> None:
    """The kind's children of the feature measurement, in schema order."""
    centre_u = (_u(chars, "X"), _u(chars, "Y"), _u(chars, "Z"))
    if r.kind == "cylinder":
        axis = sub(element, "Axis")
        measured_point(axis, "AxisPoint", r.centre, centre_u)
        sub(axis, "Direction", vec(r.axis))
    elif r.kind == "cone":
        axis = sub(element, "Axis")
        sub(axis, "AxisPoint", vec(r.apex or r.centre))
        sub(axis, "Direction", vec(r.axis))
    else:
        measured_point(element, "Location", r.centre, centre_u)
    if r.kind == "circle":
        sub(element, "Normal", vec(r.axis))
    if r.kind == "torus":
        sub(element, "AxisVector", vec(r.axis))
        measured_value(element, "MinorDiameter", r.diameter, _u(chars, "D"))
        measured_value(element, "MajorDiameter", r.major_diameter or 0.0, _u(chars, "DMAJ"))
    elif r.kind == "cone":
        measured_value(element, "HalfAngle", math.degrees(r.half_angle or 0.0),
                       _u(chars, "ANGLE"))
    else:
        measured_value(element, "Diameter", r.diameter, _u(chars, "D"))
    measured_value(element, "Form", r.form, _u(chars, "FORM"))


def _toleranced(c: Characteristic) -> bool:
    return c.lower is not None or c.upper is not None


def _checks(r: RevolvedResult, chars: dict[str, Characteristic], rule: str,
            notes: list[str]) -> list[Check]:
    """The characteristics written for one revolved feature (see the module doc)."""
    out: list[Check] = []
    for c in r.characteristics:
        name, verdict = f"{r.feature} {c.name}", status(c.accepted(rule))
        size = (c.name == "D" or c.name == "ANGLE"
                or (c.name.startswith("D_S") and (_toleranced(c) or r.kind == "cone")))
        if size:
            kind = ("Angle" if c.name == "ANGLE" else
                    "SphericalDiameter" if r.kind == "sphere" and c.name == "D" else "Diameter")
            out.append(Check(kind, name, c.measured, verdict, target=c.nominal,
                             lower=c.lower, upper=c.upper, u=c.u))
        elif c.upper is None:
            continue
        elif c.name == "POS":
            shape = "SphericalZone" if r.kind == "sphere" else "DiametricalZone"
            out.append(Check("Position", name, c.measured, verdict, zone=c.upper,
                             zone_shape=shape, u=c.u))
        elif c.name == "FORM" or c.name.startswith("RON_S"):
            kind = FORM_KINDS[r.kind] if c.name == "FORM" else "Circularity"
            out.append(Check(kind, name, c.measured, verdict, zone=c.upper, u=c.u,
                             method=c.method))
        else:
            notes.append(f"{name}: no QIF characteristic for {c.name}; its value "
                         f"{c.measured:.4f} ({verdict}) is in results.json")
    return out


def freeform_qif(b: QifBuilder, r: FreeformResult, device: int, sensor: int,
                 rule: str) -> list[int]:
    """Write one free-form feature; return its characteristic nominal ids."""
    point_set(b, r.points, r.directions, device, sensor)
    out = []
    for c, point, normal in zip(r.characteristics, r.points, r.directions, strict=True):
        element, measurement = b.add("MeasuredFeatures", "PointFeatureMeasurement")
        sub(element, "FeatureName", f"{r.feature} {c.name}")
        measured_point(element, "Location", point, (c.u, c.u, c.u))
        sub(element, "Normal", vec(normal))
        if c.lower is None or c.upper is None:
            continue
        check = Check("PointProfile", f"{r.feature} {c.name}", 2.0 * abs(c.deviation),
                      status(c.accepted(rule)), zone=c.upper - c.lower,
                      u=None if c.u is None else 2.0 * c.u)
        out.append(add_characteristic(b, check, Links(feature_measurement=measurement,
                                                      device=device)))
    return out



PLANAR_TAGS = {"line": ("Line", "LineProfile", "Straightness"),
               "plane": ("Plane", "SurfaceProfile", "Flatness")}
"""Planar kind -> QIF feature stem, the characteristic of ``DIST``, of ``FORM``."""


def planar_qif(b: QifBuilder, r: PlanarResult, device: int, sensor: int,
               rule: str) -> list[int]:
    """Write one line or plane (see the module doc); return its characteristic nominal
    ids."""
    stem, profile, form_kind = PLANAR_TAGS[r.kind]
    points = point_set(b, r.points, r.directions, device, sensor)
    element, measurement = b.add("MeasuredFeatures", f"{stem}FeatureMeasurement")
    sub(element, "FeatureName", r.feature)
    sub(sub(element, "PointList", n="1"), "WholePointSetId", str(points))
    chars = {c.name: c for c in r.characteristics}
    if r.kind == "line":
        _line_geometry(element, r, chars)
    else:
        _plane_geometry(element, r, chars)
    links = Links(feature_measurement=measurement, device=device)
    normal = r.directions[0]
    # a line's straightness is in XY: its zone is across the face, in the plane z = const
    plane = (0.0, 0.0, 1.0) if r.kind == "line" else None
    out = []
    for c in r.characteristics:
        name, verdict = f"{r.feature} {c.name}", status(c.accepted(rule))
        if c.name == "ANGLE":
            check = Check("Angle", name, c.measured, verdict, target=c.nominal,
                          lower=c.lower, upper=c.upper, u=c.u)
        elif c.lower is not None and c.upper is not None and c.name == "DIST":
            offset = 0.5 * (c.upper + c.lower)
            check = Check(profile, name, 2.0 * abs(c.measured - offset), verdict,
                          zone=c.upper - c.lower, offset=offset, vector=plane,
                          u=None if c.u is None else 2.0 * c.u)
        elif c.upper is not None and c.name == "FORM":
            check = Check(form_kind, name, c.measured, verdict, zone=c.upper, u=c.u,
                          vector=normal if r.kind == "line" else None, method=c.method)
        else:
            continue
        out.append(add_characteristic(b, check, links))
    return out


def _line_geometry(element: ET.Element, r: PlanarResult,
                   chars: dict[str, Characteristic]) -> None:
    """Location (the first touch on the measured line), Direction, Length, Normal, Form."""
    p = np.asarray(r.points, dtype=np.float64)
    theta = math.radians(chars["ANGLE"].measured)
    d = np.array([math.cos(theta), math.sin(theta), 0.0])
    centre = p.mean(axis=0)
    start = centre + d * float((p[0] - centre) @ d)
    u = _u(chars, "DIST")
    measured_point(element, "Location", [float(v) for v in start], (u, u, u))
    sub(element, "Direction", vec([float(v) for v in d]))
    measured_value(element, "Length", float((p[-1] - p[0]) @ d), u)
    sub(element, "Normal", vec(r.directions[0]))
    if "FORM" in chars:
        measured_value(element, "Form", chars["FORM"].measured, _u(chars, "FORM"))


def _plane_geometry(element: ET.Element, r: PlanarResult,
                    chars: dict[str, Characteristic]) -> None:
    """Location (the centroid), Normal (least squares from 3 touches), Form."""
    p = np.asarray(r.points, dtype=np.float64)
    u = _u(chars, "DIST")
    measured_point(element, "Location", [float(v) for v in p.mean(axis=0)], (u, u, u))
    nominal = np.asarray(r.directions[0], dtype=np.float64)
    normal = nominal
    if len(p) >= 3:
        try:
            fitted = np.asarray(fit_plane(p).normal, dtype=np.float64)
            normal = fitted if fitted @ nominal >= 0.0 else -fitted
        except ProbegenError:  # collinear touches: the nominal normal
            pass
    sub(element, "Normal", vec([float(v) for v in normal]))
    if "FORM" in chars:
        measured_value(element, "Form", chars["FORM"].measured, _u(chars, "FORM"))
