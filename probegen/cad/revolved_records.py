"""The records of revolved-feature recognition: features, sections and their figures.

Owns :class:`RevolvedFeature` and :class:`FeatureSection` (with the radius, tilt and
centre of a section at any axial position), the azimuth-interval type :data:`Arc` and
the tolerance :data:`SAME_LENGTH` that recognition and section analysis share.  The
conventions (axis sense, origin, azimuth frame, ``inner``) are those of
:mod:`probegen.cad.revolved`, which recognises the features;
:mod:`probegen.cad.revolved_sections` finds the accessible arcs of their sections.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from probegen.cad import Vec3
from probegen.geometry.frames import rotation_to_z

FloatArray = NDArray[np.float64]
Arc = tuple[float, float]
"""An azimuth interval ``(start, end)``, rad: ``0 <= start < 2π``, ``start < end <= start + 2π``."""

TWO_PI = 2.0 * math.pi
FULL_CIRCLE: tuple[Arc, ...] = ((0.0, TWO_PI),)

SAME_LENGTH = 1e-4
"""Axes, centres and radii that agree to this (mm) belong to one surface: STEP writers
round at 1e-7 to 1e-6 mm, and no two machined surfaces are meant to be this close."""


@dataclass(frozen=True, slots=True)
class FeatureSection:
    """One section of a revolved feature: a circle square to its axis.

    Attributes:
        axial: position along the axis from the feature's origin, mm.
        centre: the circle's centre on the axis, mm.
        radius: the circle's radius on the surface, mm.
        tilt: angle of the outward normal out of the section plane, rad, positive
            towards ``+axis``.
        arcs: azimuth intervals of the circle that lie on the feature's faces, sorted
            by start; :data:`FULL_CIRCLE` when the whole circle does.
        reachable: whether a vertical probe can reach the section.
        reason: why not (empty when reachable).
    """

    axial: float
    centre: Vec3
    radius: float
    tilt: float
    arcs: tuple[Arc, ...]
    reachable: bool
    reason: str

    @property
    def full(self) -> bool:
        """Whether the whole circle lies on the feature."""
        return self.arcs == FULL_CIRCLE


@dataclass(frozen=True, slots=True)
class RevolvedFeature:
    """One surface of revolution of a model, possibly made of several faces.

    Attributes:
        id: 1-based index in the order of :func:`revolved_features`.
        type: ``cylinder``, ``cone``, ``sphere`` or ``torus``.
        faces: the model face ids, ascending.
        origin: the point of the axis where axial positions start (see
            :mod:`probegen.cad.revolved`).
        axis: unit vector (see :mod:`probegen.cad.revolved` for its sense).
        inner: M2 sense: True when the outward normal leans towards the axis.
        radius: cylinder, sphere: the radius; cone: the radius at ``origin``; torus:
            the major radius.
        minor_radius: torus tube radius, else None.
        half_angle: cone half angle (positive), else None.
        tube_side: torus: +1 when the faces lie on the outer half of the tube (farther
            from the axis than the centre circle), -1 on the inner half; else 0.
        extent: lowest and highest axial position of the faces, mm.
        sections: the default sections (see :func:`default_axials`).
        accessible: whether a vertical probe can measure at least one section.
        reason: why not (empty when accessible).
    """

    id: int
    type: str
    faces: tuple[int, ...]
    origin: Vec3
    axis: Vec3
    inner: bool
    radius: float
    minor_radius: float | None
    half_angle: float | None
    tube_side: int
    extent: tuple[float, float]
    sections: tuple[FeatureSection, ...]
    accessible: bool
    reason: str

    @property
    def length(self) -> float:
        """Length of the extent along the axis, mm."""
        return self.extent[1] - self.extent[0]

    def radius_at(self, axial: float) -> float:
        """Radius of the section circle at ``axial`` (0 where the surface has none)."""
        return _radius_at(self.type, self.radius, self.minor_radius, self.half_angle,
                          self.tube_side, axial)

    def tilt_at(self, axial: float) -> float:
        """Angle of the outward normal out of the section plane at ``axial``, rad."""
        sigma = -1.0 if self.inner else 1.0
        if self.type == "cone":
            return -sigma * (self.half_angle or 0.0)
        if self.type == "cylinder":
            return 0.0
        size = self.minor_radius if self.type == "torus" else self.radius
        sense = sigma * (self.tube_side if self.type == "torus" else 1)
        return math.asin(min(max(sense * axial / (size or 1.0), -1.0), 1.0))

    def centre_at(self, axial: float) -> Vec3:
        """The point of the axis at ``axial``, mm."""
        return _vec3(np.add(self.origin, axial * np.asarray(self.axis)))

    def frame(self) -> FloatArray:
        """The azimuth frame: (3, 3) float, rows ``e1, e2, axis``."""
        return rotation_to_z(self.axis)


def _radius_at(kind: str, radius: float, minor: float | None, half: float | None,
               side: int, axial: float) -> float:
    """The section radius of a surface of revolution at ``axial`` (see the feature)."""
    if kind == "cylinder":
        return radius
    if kind == "cone":
        return max(radius + axial * math.tan(half or 0.0), 0.0)
    if kind == "sphere":
        return math.sqrt(max(radius * radius - axial * axial, 0.0))
    tube = minor or 0.0
    return max(radius + side * math.sqrt(max(tube * tube - axial * axial, 0.0)), 0.0)


def _vec3(values: Sequence[float] | FloatArray) -> Vec3:
    """A 3-tuple of plain floats."""
    return (float(values[0]), float(values[1]), float(values[2]))


def _ids(faces: Sequence[int]) -> str:
    """Face ids as ``78,79``."""
    return ",".join(str(f) for f in faces)

