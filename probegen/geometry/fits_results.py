"""Result records of the least-squares fits: frozen, slotted, plain Python floats.

Shared conventions (every record):

* ``residuals`` are orthogonal distances, one per input point, in input order, ``+``
  outside the shape: away from the centre (circle, sphere), away from the axis
  (cylinder, cone), away from the tube's centre circle (torus), along the normal
  (plane, 2-D line).  3-D line residuals are unsigned distances.
* ``rms`` is ``sqrt(mean(residuals**2))``; ``form`` is ``max - min`` of the residuals
  (for the 3-D line, whose residuals are unsigned, ``2 * max``: the diameter of the
  cylinder about the fitted line that holds every point); ``n`` the number of points.
* Directions are unit vectors.  Unless a record says otherwise the sign of a direction
  is normalised so that its component of largest absolute value is positive (the first
  such component on an exact tie).  The cone's axis instead points to increasing radius.
* ``condition`` is the condition number of the fit's Jacobian at the solution on
  normalised data (``probegen.geometry.fits_conditioning`` explains it and the limits
  beyond which a fit is refused instead).
* A point on an axis is the orthogonal projection of the data centroid onto the axis
  (the NIST Algorithm Testing System convention); for lines and planes it is the data
  centroid itself, which lies on the least-squares line or plane.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

Vec2 = tuple[float, float]
Vec3 = tuple[float, float, float]


@dataclass(frozen=True, slots=True)
class Line2dFit:
    """A least-squares line in the plane.

    Attributes:
        point: the data centroid ``(x, y)``, a point on the line.
        direction: unit direction ``(dx, dy)``, largest absolute component positive.
        normal: unit normal ``(-dy, dx)``: the direction turned +90 degrees.
        residuals: signed distance of each point along ``normal``.
        rms: root mean square residual.
        form: straightness, ``max - min`` residual.
        n: number of points.
        condition: how well the points determine the fit: the condition number of
            its Jacobian on normalised data (``fits_conditioning``); 1 is ideal.
    """

    point: Vec2
    direction: Vec2
    normal: Vec2
    residuals: tuple[float, ...]
    rms: float
    form: float
    n: int
    condition: float


@dataclass(frozen=True, slots=True)
class Line3dFit:
    """A least-squares line in space.

    Attributes:
        point: the data centroid, a point on the line.
        direction: unit direction, largest absolute component positive.
        residuals: unsigned distance of each point from the line.
        rms: root mean square residual.
        form: straightness, ``2 * max`` residual.
        n: number of points.
        condition: how well the points determine the fit: the condition number of
            its Jacobian on normalised data (``fits_conditioning``); 1 is ideal.
    """

    point: Vec3
    direction: Vec3
    residuals: tuple[float, ...]
    rms: float
    form: float
    n: int
    condition: float


@dataclass(frozen=True, slots=True)
class PlaneFit:
    """A least-squares plane.

    Attributes:
        point: the data centroid, a point on the plane.
        normal: unit normal, largest absolute component positive.
        residuals: signed distance of each point along ``normal``.
        rms: root mean square residual.
        form: flatness, ``max - min`` residual.
        n: number of points.
        condition: how well the points determine the fit: the condition number of
            its Jacobian on normalised data (``fits_conditioning``); 1 is ideal.
    """

    point: Vec3
    normal: Vec3
    residuals: tuple[float, ...]
    rms: float
    form: float
    n: int
    condition: float


@dataclass(frozen=True, slots=True)
class Circle2dFit:
    """A least-squares circle in the plane.

    Attributes:
        centre: ``(x, y)``.
        radius: radius.
        residuals: distance from the centre minus ``radius`` (``+`` outside).
        rms: root mean square residual.
        form: roundness, ``max - min`` residual.
        n: number of points.
        condition: how well the points determine the fit: the condition number of
            its Jacobian on normalised data (``fits_conditioning``); 1 is ideal.
    """

    centre: Vec2
    radius: float
    residuals: tuple[float, ...]
    rms: float
    form: float
    n: int
    condition: float

    @property
    def diameter(self) -> float:
        """Twice the radius."""
        return 2.0 * self.radius


@dataclass(frozen=True, slots=True)
class Circle3dFit:
    """A least-squares circle in space (NIST: least-squares plane, project, 2-D circle).

    Attributes:
        centre: centre, in the least-squares plane of the points.
        normal: unit normal of that plane, largest absolute component positive.
        radius: radius.
        residuals: in-plane radial deviation of each projected point (``+`` outside).
        rms: root mean square residual.
        form: roundness, ``max - min`` residual.
        n: number of points.
        condition: how well the points determine the fit: the condition number of
            its Jacobian on normalised data (``fits_conditioning``); 1 is ideal.
    """

    centre: Vec3
    normal: Vec3
    radius: float
    residuals: tuple[float, ...]
    rms: float
    form: float
    n: int
    condition: float

    @property
    def diameter(self) -> float:
        """Twice the radius."""
        return 2.0 * self.radius


@dataclass(frozen=True, slots=True)
class SphereFit:
    """A least-squares sphere.

    Attributes:
        centre: centre.
        radius: radius.
        residuals: distance from the centre minus ``radius`` (``+`` outside).
        rms: root mean square residual.
        form: sphericity, ``max - min`` residual.
        n: number of points.
        condition: how well the points determine the fit: the condition number of
            its Jacobian on normalised data (``fits_conditioning``); 1 is ideal.
    """

    centre: Vec3
    radius: float
    residuals: tuple[float, ...]
    rms: float
    form: float
    n: int
    condition: float

    @property
    def diameter(self) -> float:
        """Twice the radius."""
        return 2.0 * self.radius


@dataclass(frozen=True, slots=True)
class CylinderFit:
    """A least-squares cylinder.

    Attributes:
        point: projection of the data centroid onto the axis.
        axis: unit axis direction, largest absolute component positive.
        radius: radius.
        residuals: distance from the axis minus ``radius`` (``+`` outside).
        rms: root mean square residual.
        form: cylindricity, ``max - min`` residual.
        n: number of points.
        condition: how well the points determine the fit: the condition number of
            its Jacobian on normalised data (``fits_conditioning``); 1 is ideal.
    """

    point: Vec3
    axis: Vec3
    radius: float
    residuals: tuple[float, ...]
    rms: float
    form: float
    n: int
    condition: float

    @property
    def diameter(self) -> float:
        """Twice the radius."""
        return 2.0 * self.radius


@dataclass(frozen=True, slots=True)
class ConeFit:
    """A least-squares cone (one nappe).

    Attributes:
        point: projection of the data centroid onto the axis.
        axis: unit axis direction, pointing to increasing radius.
        half_angle: angle between axis and surface lines, radians, in ``[0, pi/2)``.
        radius: radius of the cone's section through ``point`` (negative if ``point``
            lies beyond the apex).
        residuals: orthogonal distance to the cone surface (``+`` away from the axis).
        rms: root mean square residual.
        form: conicity, ``max - min`` residual.
        n: number of points.
        condition: how well the points determine the fit: the condition number of
            its Jacobian on normalised data (``fits_conditioning``); 1 is ideal.
    """

    point: Vec3
    axis: Vec3
    half_angle: float
    radius: float
    residuals: tuple[float, ...]
    rms: float
    form: float
    n: int
    condition: float

    @property
    def apex_angle(self) -> float:
        """The full (included) angle at the apex, radians."""
        return 2.0 * self.half_angle

    @property
    def distance(self) -> float:
        """Orthogonal distance from ``point`` to the surface (NIST's fourth parameter)."""
        return self.radius * math.cos(self.half_angle)

    @property
    def apex(self) -> Vec3:
        """The apex; not finite (``inf``) when ``half_angle`` is zero."""
        if self.half_angle == 0.0:
            return (math.inf, math.inf, math.inf)
        t = self.radius / math.tan(self.half_angle)
        p, a = self.point, self.axis
        return (p[0] - t * a[0], p[1] - t * a[1], p[2] - t * a[2])


@dataclass(frozen=True, slots=True)
class TorusFit:
    """A least-squares torus.

    Attributes:
        centre: centre (on the axis, in the plane of the tube's centre circle).
        axis: unit axis direction, largest absolute component positive.
        major_radius: radius of the tube's centre circle.
        minor_radius: radius of the tube.
        residuals: distance from the tube's centre circle minus ``minor_radius``
            (``+`` outside the tube).
        rms: root mean square residual.
        form: ``max - min`` residual.
        n: number of points.
        condition: how well the points determine the fit: the condition number of
            its Jacobian on normalised data (``fits_conditioning``); 1 is ideal.
    """

    centre: Vec3
    axis: Vec3
    major_radius: float
    minor_radius: float
    residuals: tuple[float, ...]
    rms: float
    form: float
    n: int
    condition: float
