"""Method M2, the geometry of one section: figures, rotations, touch azimuths.

Owns the :class:`Section` input (and :func:`section_of`, which builds it from a
recognised feature through a ``Protocol``, never importing ``cad``), the rotations
``M1``/``M2``, the outer chord limit ``α_max``, transition counts, the touch azimuths on
full circles and partial arcs, the world geometry of a section (contact points, normals,
safe circle) and :func:`plan_section` (steps 1-5 of :mod:`probegen.planning.revolved`).
The path through the sections is built by :mod:`probegen.planning.revolved_path`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from itertools import pairwise
from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray

from probegen.errors import PlanningError
from probegen.geometry.frames import rotation_to_z

FloatArray = NDArray[np.float64]
Vec3 = tuple[float, float, float]
Arc = tuple[float, float]
"""An azimuth interval ``(start, end)``, rad, ``start < end <= start + 2π``."""

TWO_PI = 2.0 * math.pi
FULL_CIRCLE: tuple[Arc, ...] = ((0.0, TWO_PI),)
INNER_MAX_STEP = 0.5 * math.pi
"""Largest step (rad) between safe points of an inner section on a partial arc: a chord
shorter than a half-turn stays in the sector between its ends; a quarter-turn also keeps
it well clear of the axis region."""
STEP_SLACK = 1e-9
"""Relative slack in ``ceil(Δφ/α_max)`` so that an exact multiple needs no extra point."""


class ArcTooShortError(PlanningError):
    """No arc of a section is longer than its two end margins (:func:`point_azimuths`)."""


@dataclass(frozen=True, slots=True)
class Section:
    """One target section (the M2 input).

    Attributes:
        feature: feature id, for messages and touches.
        centre: ``O0``, the circle's centre, mm.
        axis: ``V``, unit vector (normalised on use).
        radius: ``R``, mm.
        inner: True for a bore (normals towards the axis), False for a boss.
        arcs: accessible azimuth intervals in the frame of ``rotation_to_z(axis)``.
        tilt: angle of the outward normal out of the section plane, towards ``+axis``.
    """

    feature: str
    centre: Vec3
    axis: Vec3
    radius: float
    inner: bool
    arcs: tuple[Arc, ...] = FULL_CIRCLE
    tilt: float = 0.0

    @property
    def full(self) -> bool:
        """Whether the whole circle is accessible."""
        return any(b - a >= TWO_PI - 1e-12 for a, b in self.arcs)


class FeatureLike(Protocol):
    """What :func:`section_of` reads of a recognised feature (``cad.revolved``)."""

    @property
    def axis(self) -> Vec3: ...

    @property
    def inner(self) -> bool: ...


class SectionLike(Protocol):
    """What :func:`section_of` reads of a recognised section (``cad.revolved``)."""

    @property
    def centre(self) -> Vec3: ...

    @property
    def radius(self) -> float: ...

    @property
    def tilt(self) -> float: ...

    @property
    def arcs(self) -> tuple[Arc, ...]: ...


def section_of(feature_id: str, feature: FeatureLike, section: SectionLike) -> Section:
    """The M2 :class:`Section` of a recognised feature's section (no cad import here)."""
    return Section(feature_id, section.centre, feature.axis, section.radius, feature.inner,
                   section.arcs, section.tilt)


@dataclass(frozen=True, slots=True)
class SectionPlan:
    """The M2 figures of one section.

    Attributes:
        section: the input.
        ball: stylus ball radius ``r``, mm.
        retract: ``d``, mm.
        margin: clearance kept by every chord, mm.
        safe_radius: ``R_s``, mm.
        alpha_max: the largest chord step (outer), rad; None for inner sections.
        passes: the touch azimuths (rad) per arc, in measuring order.
        transitions: transition count between consecutive touches of one arc.
    """

    section: Section
    ball: float
    retract: float
    margin: float
    safe_radius: float
    alpha_max: float | None
    passes: tuple[tuple[float, ...], ...]
    transitions: tuple[int, ...]

    @property
    def azimuths(self) -> tuple[float, ...]:
        """The touch azimuths in measuring order, rad."""
        return tuple(phi for p in self.passes for phi in p)


# ------------------------------------------------------------------------- figures


def m1_rotation(axis: ArrayLike) -> FloatArray:
    """``M1``: (3, 3) float rotation taking ``axis`` onto +Z (rows ``e1, e2, axis``)."""
    return rotation_to_z(axis)


def m2_rotation(axis: ArrayLike) -> FloatArray:
    """``M2 = M1ᵀ``: (3, 3) float, takes section-plane coordinates back."""
    return np.asarray(rotation_to_z(axis).T)


def alpha_max(radius: float, ball: float, retract: float, *, margin: float = 0.0,
              tilt: float = 0.0) -> float:
    """Largest central angle between safe points of an outer section, rad.

    ``2·arccos((R + r + m)/(R + r + d))`` for ``tilt = 0``; see
    :mod:`probegen.planning.revolved`, step 5.

    Raises:
        PlanningError: ``retract <= margin`` (no chord keeps the margin).
    """
    if retract <= margin:
        raise PlanningError(f"retract {retract:g} mm: expected more than the margin "
                            f"{margin:g} mm, else no move between safe points is clear")
    c = math.cos(tilt)
    safe = radius + (ball + retract) * c
    limit = safe - (retract - margin) / c  # ≤ 0: the offset surface misses the safe plane
    return 2.0 * math.acos(min(max(limit / safe, 0.0), 1.0))


def transition_count(delta: float, step: float) -> int:
    """``m = ceil(Δφ/step) − 1`` (at least 0) transition points for a step of ``delta``."""
    return max(math.ceil(abs(delta) / step * (1.0 - STEP_SLACK)) - 1, 0)


def _allocate(n: int, lengths: Sequence[float]) -> list[int]:
    """Split ``n`` points over arcs in proportion to ``lengths`` (largest remainder)."""
    total = sum(max(x, 0.0) for x in lengths)
    shares = [n * max(x, 0.0) / total for x in lengths]
    counts = [math.floor(s) for s in shares]
    by_remainder = sorted(range(len(shares)), key=lambda k: (counts[k] - shares[k], k))
    for k in by_remainder[: n - sum(counts)]:
        counts[k] += 1
    return counts


def point_azimuths(section: Section, n: int, *, end_margin: float,
                   phase: float = 0.0) -> tuple[tuple[float, ...], ...]:
    """Azimuths of ``n`` contact points, one increasing tuple per arc that gets points.

    Full circle: ``phase + 2πk/n``.  Partial arcs: the points are shared out in
    proportion to the arcs' usable lengths (each arc less ``end_margin`` of arc length
    at both ends), spread evenly over each (one point: the middle).

    Raises:
        ArcTooShortError: no arc is longer than its two end margins.
    """
    if section.full:
        return (tuple(phase + TWO_PI * k / n for k in range(n)),)
    inset = end_margin / section.radius
    usable = [(a + inset, b - inset) for a, b in section.arcs]
    lengths = [b - a for a, b in usable]
    if not lengths or max(lengths) <= 0.0:
        raise ArcTooShortError(
            f"feature {section.feature}: section at {_fmt(section.centre)}: expected an "
            f"accessible arc longer than twice the end margin {end_margin:.3f} mm, found "
            f"arcs of {', '.join(f'{(b - a) * section.radius:.3f}' for a, b in section.arcs)}"
            " mm")
    out = []
    for (a, b), k in zip(usable, _allocate(n, lengths), strict=True):
        if k:
            out.append(tuple(np.linspace(a, b, k).tolist()) if k > 1 else (0.5 * (a + b),))
    return tuple(out)


# ------------------------------------------------------------------------- geometry


class _Circle:
    """World geometry of one section: contact points, normals, safe circle."""

    def __init__(self, section: Section, ball: float, retract: float) -> None:
        self.m2 = m2_rotation(section.axis)
        self.o = np.asarray(section.centre, dtype=np.float64)
        self.sigma = -1.0 if section.inner else 1.0
        self.radius = section.radius
        self.cos, self.sin = math.cos(section.tilt), math.sin(section.tilt)
        self.reach = ball + retract
        self.safe_radius = section.radius + self.sigma * self.reach * self.cos

    def normal(self, phi: float) -> FloatArray:
        """``N`` at azimuth ``phi``: (3,) float unit vector."""
        c = self.sigma * self.cos
        return self.m2 @ np.array([c * math.cos(phi), c * math.sin(phi), self.sin])

    def contact(self, phi: float) -> FloatArray:
        """``p`` at azimuth ``phi``: (3,) float."""
        return self.o + self.m2 @ np.array([self.radius * math.cos(phi),
                                            self.radius * math.sin(phi), 0.0])

    def safe(self, phi: float) -> FloatArray:
        """``P_d`` (or a transition point) at azimuth ``phi``: (3,) float."""
        return self.contact(phi) + self.reach * self.normal(phi)


def _check_section(section: Section, ball: float, retract: float, margin: float,
                   safe_radius: float) -> None:
    """Refuse a section no safe path can serve."""
    where = f"feature {section.feature}: section at {_fmt(section.centre)}"
    if section.radius <= 0.0 or not section.arcs:
        raise PlanningError(f"{where}: expected a radius > 0 and an accessible arc, found "
                            f"radius {section.radius:g} and {len(section.arcs)} arcs")
    if retract <= margin:
        raise PlanningError(f"{where}: expected a retract above the margin {margin:g} mm, "
                            f"found {retract:g}")
    if section.inner and safe_radius <= 0.0:
        raise PlanningError(
            f"{where}: inner radius {section.radius:.3f} mm: the safe circle R - r - d = "
            f"{safe_radius:.3f} mm: expected R > r + d = {ball + retract:.3f} mm (a "
            "smaller ball or retract)")


def plan_section(section: Section, n: int, *, ball: float, retract: float, margin: float,
                 end_margin: float | None = None, phase: float = 0.0,
                 reverse: bool = False) -> SectionPlan:
    """Plan the touches of one section (method M2, steps 1-5).

    Args:
        section: the section.
        n: number of touches, at least 1.
        ball: stylus ball radius ``r``, mm.
        retract: ``d``, mm.
        margin: clearance every chord keeps from the offset surface, mm.
        end_margin: arc length kept free at the ends of a partial arc, mm (default
            ``ball + margin``).
        phase: azimuth of the first point of a full circle, rad.
        reverse: traverse in decreasing azimuth (arcs and points).

    Returns:
        The section's figures and its touch azimuths.

    Raises:
        PlanningError: a bad ``n``, an inner circle too small for the ball and the
            retract, a retract not above the margin, or no usable arc.
    """
    if n < 1:
        raise PlanningError(f"feature {section.feature}: expected at least 1 point, found {n}")
    circle = _Circle(section, ball, retract)
    _check_section(section, ball, retract, margin, circle.safe_radius)
    ends = ball + margin if end_margin is None else end_margin
    passes = point_azimuths(section, n, end_margin=ends, phase=phase)
    if reverse:
        passes = tuple(tuple(reversed(p)) for p in reversed(passes))
    alpha = None if section.inner else alpha_max(section.radius, ball, retract,
                                                 margin=margin, tilt=section.tilt)
    step = _step_limit(section, alpha)
    counts = tuple(transition_count(b - a, step) for p in passes for a, b in pairwise(p))
    return SectionPlan(section, ball, retract, margin, circle.safe_radius, alpha, passes,
                       counts)


def _step_limit(section: Section, alpha: float | None) -> float:
    """The largest azimuth step between consecutive safe-circle points."""
    if alpha is not None:
        return alpha
    return math.inf if section.full else INNER_MAX_STEP


def _vec3(v: Sequence[float] | FloatArray) -> Vec3:
    return (float(v[0]), float(v[1]), float(v[2]))


def _fmt(v: Sequence[float]) -> str:
    return "(" + ", ".join(f"{x:.3f}" for x in v) + ")"

