"""Tolerances of the virtual CMM: ``T(x)=TOL/...`` definitions and their actuals ``TA(x)``.

Supported kinds and the actual value each reports (millimetres inside; the output
writes program units):

* ``TOL/DIAM,lo,hi``: actual diameter minus nominal; in tolerance if ``lo <= d <= hi``.
  Not on a cone (an angle) nor a torus (it has two diameters, major and tube).
* ``TOL/POS,2D|3D,zone[,...]``: the position deviation as a *diameter*, like the zone
  it is compared with: twice the distance of the actual from the nominal.  ``3D``: the
  distance of the actual location from the nominal location (for a plane, along its
  normal; for a cylinder or line, from the nominal location to the actual axis).
  ``2D``: the same measured square to the nominal axis or normal only (for an axis:
  where the actual axis crosses the plane through the nominal location square to the
  nominal axis; a torus's centre is a point: its offset square to the nominal axis);
  for a sphere or point without a vector, square to the active Z axis.
  Datum references after the zone (``RFS,DAT(A)...``) are accepted and not used: the
  deviation is taken in the active frame, which the program aligns to those datums.
* ``TOL/FLAT,t`` (plane), ``TOL/CIRLTY,t`` (circle), ``TOL/CYLCTY,t`` (cylinder),
  ``TOL/STRGHT,t`` (line): the form of the least-squares fit (``max - min`` residual).

A deviation is in tolerance within ``tol.zero`` of a limit, so a perfect feature passes
a zero tolerance (``TOL/POS,2D,0.000``) despite floating-point noise.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from probegen.constants import tol
from probegen.sim.cmm.features import DmisFeature, arr

FORM_KINDS = {"FLAT": "PLANE", "CIRLTY": "CIRCLE", "CYLCTY": "CYLNDR", "STRGHT": "LINE"}
"""Form tolerance -> the feature type it applies to."""

TOLERANCE_KINDS = ("DIAM", "POS", *FORM_KINDS)
"""Tolerance kinds the virtual CMM evaluates."""


@dataclass(frozen=True, slots=True)
class Tolerance:
    """A tolerance definition, limits in millimetres.

    Attributes:
        name: the label name (``T1`` for ``T(T1)``).
        kind: one of :data:`TOLERANCE_KINDS`.
        lower: lowest allowed deviation (``DIAM``); 0 for zones.
        upper: highest allowed deviation (``DIAM``) or the zone size.
        mode: ``2D`` or ``3D`` for ``POS``, None otherwise.
    """

    name: str
    kind: str
    lower: float
    upper: float
    mode: str | None = None


@dataclass(frozen=True, slots=True)
class ToleranceResult:
    """An evaluated tolerance ``TA(x)``.

    Attributes:
        tolerance: the definition.
        feature: name of the actual feature it was evaluated on.
        deviation: the actual value (mm), as described in the module docstring.
        in_tolerance: True for INTOL, False for OUTOL.
    """

    tolerance: Tolerance
    feature: str
    deviation: float
    in_tolerance: bool


def parse_tolerance(name: str, params: list[object], scale: float) -> Tolerance:
    """Build a tolerance from ``TOL/`` parameters.

    Args:
        name: label name.
        params: the statement's parameters (first the kind word).
        scale: millimetres per program unit.

    Raises:
        NotImplementedError: a kind the virtual CMM does not evaluate.
        ValueError: the parameters do not fit the kind.
    """
    kind = params[0] if params else None
    if kind not in TOLERANCE_KINDS:
        raise NotImplementedError(f"TOL/{kind} (supported: {', '.join(TOLERANCE_KINDS)})")
    if kind == "DIAM":
        lower, upper = _numbers(params[1:3], 2, "TOL/DIAM,lower,upper")
        return Tolerance(name, kind, lower * scale, upper * scale)
    if kind == "POS":
        mode = params[1] if len(params) > 1 else None
        if mode not in ("2D", "3D"):
            raise ValueError(f"TOL/POS: expected 2D or 3D, found {mode!r}")
        (zone,) = _numbers(params[2:3], 1, "TOL/POS,2D|3D,zone")
        return Tolerance(name, kind, 0.0, zone * scale, str(mode))
    (zone,) = _numbers(params[1:2], 1, f"TOL/{kind},zone")
    return Tolerance(name, str(kind), 0.0, zone * scale)


def _numbers(values: list[object], count: int, shape: str) -> list[float]:
    if len(values) != count or not all(isinstance(v, int | float) for v in values):
        raise ValueError(f"expected {shape}, found {values!r}")
    return [float(v) for v in values if isinstance(v, int | float)]


def evaluate(tolerance: Tolerance, actual: DmisFeature, nominal: DmisFeature,
             workplane_normal: tuple[float, float, float]) -> ToleranceResult:
    """Evaluate ``tolerance`` on a measured or constructed feature.

    Args:
        tolerance: the definition.
        actual: the actual feature (MCS).
        nominal: its nominal (MCS).
        workplane_normal: unit MCS direction used by a 2D position of a feature
            without a vector (the active Z axis).

    Raises:
        ValueError: the tolerance does not apply to the feature.
    """
    deviation = _deviation(tolerance, actual, nominal, workplane_normal)
    slack = tol.zero
    ok = tolerance.lower - slack <= deviation <= tolerance.upper + slack
    return ToleranceResult(tolerance, actual.name, deviation, ok)


def _deviation(tolerance: Tolerance, actual: DmisFeature, nominal: DmisFeature,
               workplane_normal: tuple[float, float, float]) -> float:
    if tolerance.kind == "DIAM":
        if actual.size is None or nominal.size is None or actual.kind in ("CONE", "TORUS"):
            raise ValueError(f"TOL/DIAM does not apply to the {actual.kind} {actual.name}")
        return actual.size - nominal.size
    if tolerance.kind == "POS":
        return 2.0 * _position_distance(tolerance.mode == "2D", actual, nominal,
                                        workplane_normal)
    wanted = FORM_KINDS[tolerance.kind]
    if actual.kind != wanted or actual.form is None:
        raise ValueError(f"TOL/{tolerance.kind} applies to a measured {wanted}, "
                         f"not to the {actual.kind} {actual.name}")
    return actual.form


def _position_distance(planar: bool, actual: DmisFeature, nominal: DmisFeature,
                       workplane_normal: tuple[float, float, float]) -> float:
    """Distance of the actual from the nominal location (see the module docstring)."""
    target = arr(nominal.location)
    if actual.kind == "PLANE":
        return abs(float((target - arr(actual.location)) @ arr(actual.vector or (0, 0, 1))))
    point = arr(actual.location)
    axial = actual.kind in ("CIRCLE", "CYLNDR", "CONE", "LINE")
    if axial and actual.vector is not None:
        axis = arr(actual.vector)
        point = point + float((target - point) @ axis) * axis  # nearest point of the axis
    if not planar:
        return float(np.linalg.norm(point - target))
    normal = arr(nominal.vector or workplane_normal)
    if axial and actual.vector is not None:
        axis = arr(actual.vector)
        along = float(axis @ normal)
        if abs(along) > 1e-12:
            point = point + (float((target - point) @ normal) / along) * axis
    offset = point - target
    return float(np.linalg.norm(offset - float(offset @ normal) * normal))
