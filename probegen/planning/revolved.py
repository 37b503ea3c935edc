"""Method M2: revolved features measured in sections, with adaptive arc transitions.

A *section* is a circle of a surface of revolution square to its axis: centre ``O0``,
axis ``V``, radius ``R``, inner (bore) or outer (boss), and the azimuth intervals that
lie on the part (all of it, or arcs).  Per section (``docs/methods.md``, M2):

1. ``M1 = rotation_to_z(V)`` takes ``V`` onto +Z (identity for +Z, the half-turn about
   X for -Z); ``M2 = M1ᵀ`` takes section-plane coordinates back.  Azimuths ``φ`` are
   polar angles in that plane (the convention of :mod:`probegen.cad.revolved`).
2. ``n`` contact points ``p_i`` at equal arc length; on a partial arc they keep an end
   margin (arc length, default ``r + margin``) from its ends.
3. Retract vector ``N_i``: the unit outward normal, away from the axis for an outer
   feature and towards it for an inner one.  A section may carry a ``tilt`` (the angle
   of the normal out of the section plane, cones and off-equator sections of spheres
   and tori): ``N_i = cos τ·(±e_ρ) + sin τ·V``; ``tilt = 0`` is M2 exactly.
4. Ball-centre target ``P_ci = p_i + r·N_i``; safe point ``P_di = P_ci + d·N_i``.  The
   safe points lie on the *safe circle* of radius ``R_s = R ± (r + d)·cos τ``.
5. Outer feature: a chord of central angle ``α`` between safe points keeps the margin
   ``m`` from the offset surface iff ``R_s·cos(α/2) ≥ R_s − (d − m)/cos τ``, so
   ``α_max = 2·arccos((R + r + m)/(R + r + d))`` for ``τ = 0`` (``m = 0``: the
   methods.md formula).  Between consecutive safe points ``Δφ`` apart
   ``m = ceil(Δφ/α_max) − 1`` transitions are inserted, equally spaced on the safe
   circle.  Inner feature: chords inside a circle stay inside it, so a full circle
   needs none; it needs ``R_s > 0`` (else :class:`PlanningError`).  On a partial arc
   an inner step never exceeds :data:`INNER_MAX_STEP`, so that each chord stays in
   the sector between its ends and never crosses the missing arc.
6. Per section: safe → target → safe → transitions → next safe …; the path runs along
   each arc from one end to the other and never crosses a missing arc.  Between the
   arcs of one section, and between sections where the last azimuth is not
   accessible in the next one, the stylus leaves by the *clearance level* ``clear_z``
   (up along +Z, across, down).  Otherwise sections are linked along the axis at the
   safe radius, the next one traversed the other way (serpentine).

The clearance level is a world Z above the feature; entry and exit are straight above
the first and last safe points.  Tilted sections (cones, spheres and tori off their
equator) use the tangent cone of the surface for the chord condition: exact for cones,
conservative for convex profiles; the collision check is the final judge.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from enum import Enum
from itertools import pairwise
from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray

from probegen import ir
from probegen.errors import PlanningError
from probegen.geometry.frames import rotation_to_z
from probegen.machine.profile import MachineProfile

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


class PathKind(Enum):
    """What a point of a planned path is."""

    ENTRY = "entry"  # above the first safe point, at the clearance level
    SAFE = "safe"  # P_di, where a touch starts and ends
    TARGET = "target"  # P_ci, the ball centre at the nominal contact
    TRANSITION = "transition"  # on the safe circle, between safe points
    LINK = "link"  # on the next section's safe circle, straight along the axis
    CLEAR = "clear"  # at the clearance level, between arcs or sections
    LIFT = "lift"  # at a local safe height between two safe points (planning.reroute)
    EXIT = "exit"  # above the last safe point, at the clearance level


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
class PathPoint:
    """One point of a planned ball-centre path.

    Attributes:
        kind: see :class:`PathKind`.
        position: ball-centre position, work coordinates, mm.
        section: 0-based section index in the feature plan (-1 for entry/exit).
        azimuth: azimuth on the section's circle (safe, target, transition, link).
        index: 1-based touch index (safe and target points), else 0.
        contact: target only: the nominal contact point on the surface.
        normal: target only: the outward unit normal ``N_i``.
    """

    kind: PathKind
    position: Vec3
    section: int = -1
    azimuth: float | None = None
    index: int = 0
    contact: Vec3 | None = None
    normal: Vec3 | None = None


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


@dataclass(frozen=True, slots=True)
class FeaturePlan:
    """A planned feature: its sections and the whole path (entry to exit)."""

    feature: str
    sections: tuple[SectionPlan, ...]
    clear_z: float
    path: tuple[PathPoint, ...]


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

    ``2·arccos((R + r + m)/(R + r + d))`` for ``tilt = 0``; see the module docstring.

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
        PlanningError: no arc is longer than its two end margins.
    """
    if section.full:
        return (tuple(phase + TWO_PI * k / n for k in range(n)),)
    inset = end_margin / section.radius
    usable = [(a + inset, b - inset) for a, b in section.arcs]
    lengths = [b - a for a, b in usable]
    if not lengths or max(lengths) <= 0.0:
        raise PlanningError(
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


# ----------------------------------------------------------------------------- paths


class _PathBuilder:
    """Accumulates the path of a feature, section by section."""

    def __init__(self, clear_z: float) -> None:
        self.clear_z = clear_z
        self.points: list[PathPoint] = []
        self.index = 0

    def add(self, kind: PathKind, position: FloatArray, section: int = -1,
            azimuth: float | None = None) -> None:
        self.points.append(PathPoint(kind, _vec3(position), section, azimuth))

    def glide(self, circle: _Circle, k: int, a: float, b: float, step: float) -> None:
        """Transition points strictly between azimuths ``a`` and ``b`` on the safe circle."""
        m = transition_count(b - a, step)
        for j in range(1, m + 1):
            phi = a + (b - a) * j / (m + 1)
            self.add(PathKind.TRANSITION, circle.safe(phi), k, phi)

    def touch(self, circle: _Circle, k: int, phi: float, ball: float) -> None:
        """safe → target → safe at azimuth ``phi``."""
        self.index += 1
        safe, normal, contact = circle.safe(phi), circle.normal(phi), circle.contact(phi)
        here = PathPoint(PathKind.SAFE, _vec3(safe), k, phi, self.index)
        self.points += [here, PathPoint(PathKind.TARGET, _vec3(contact + ball * normal), k, phi,
                                        self.index, _vec3(contact), _vec3(normal)), here]

    def over(self, target: FloatArray) -> None:
        """Up from the current point to the clearance level, across above ``target``."""
        last = self.points[-1].position
        self.add(PathKind.CLEAR, np.array([last[0], last[1], self.clear_z]))
        self.add(PathKind.CLEAR, np.array([target[0], target[1], self.clear_z]))


def _arc_of(section: Section, phi: float) -> int | None:
    """Index of the arc holding azimuth ``phi``, or None."""
    for k, (a, b) in enumerate(section.arcs):
        if (phi - a) % TWO_PI <= b - a + 1e-12:
            return k
    return None


def _link_delta(section: Section, frm: float, to: float) -> float | None:
    """Signed azimuth travel from ``frm`` to ``to`` inside one arc, or None."""
    if section.full:
        return (to - frm + math.pi) % TWO_PI - math.pi
    k = _arc_of(section, frm)
    if k is None or _arc_of(section, to) != k:
        return None
    a = section.arcs[k][0]
    return (to - a) % TWO_PI - (frm - a) % TWO_PI


def plan_feature(sections: Sequence[Section], n: int, *, ball: float, retract: float,
                 margin: float, clear_z: float, end_margin: float | None = None,
                 phase: float = 0.0) -> FeaturePlan:
    """Plan the touches of every section of one feature and the path through them.

    Args:
        sections: the sections in measuring order (the same feature).
        n: touches per section.
        ball: stylus ball radius ``r``, mm.
        retract: ``d``, mm.
        margin: clearance every chord keeps from the offset surface, mm.
        clear_z: the clearance level above the feature (world Z), mm.
        end_margin: see :func:`plan_section`.
        phase: see :func:`plan_section`.

    Returns:
        The plan; its path runs entry → … → exit.

    Raises:
        PlanningError: see :func:`plan_section`; ``clear_z`` below a safe point.
    """
    if not sections:
        raise PlanningError("expected at least one section, found none")
    path = _PathBuilder(clear_z)
    plans: list[SectionPlan] = []
    for k, section in enumerate(sections):
        plan = plan_section(section, n, ball=ball, retract=retract, margin=margin,
                            end_margin=end_margin, phase=phase, reverse=k % 2 == 1)
        plans.append(plan)
        circle = _Circle(section, ball, retract)
        step = _step_limit(section, plan.alpha_max)
        _enter(path, circle, k, section, plan.passes[0][0], step)
        for j, azimuths in enumerate(plan.passes):
            if j:
                path.over(circle.safe(azimuths[0]))
            for i, phi in enumerate(azimuths):
                if i:
                    path.glide(circle, k, azimuths[i - 1], phi, step)
                path.touch(circle, k, phi, ball)
    last = path.points[-1].position
    path.add(PathKind.EXIT, np.array([last[0], last[1], clear_z]))
    _check_clear(path.points, clear_z, sections[0].feature)
    return FeaturePlan(sections[0].feature, tuple(plans), clear_z, tuple(path.points))


def _enter(path: _PathBuilder, circle: _Circle, k: int, section: Section, first: float,
           step: float) -> None:
    """Reach the first safe point of section ``k``: from above, or along the axis."""
    start = circle.safe(first)
    if not path.points:
        path.add(PathKind.ENTRY, np.array([start[0], start[1], path.clear_z]))
        return
    previous = path.points[-1].azimuth
    delta = None if previous is None else _link_delta(section, previous, first)
    if previous is None or delta is None:
        path.over(start)
        return
    if abs(delta) <= 1e-12:
        return  # the first safe point lies straight along the axis
    path.add(PathKind.LINK, circle.safe(previous), k, previous)
    path.glide(circle, k, previous, previous + delta, step)


def _check_clear(points: Sequence[PathPoint], clear_z: float, feature: str) -> None:
    """The clearance level must lie above every point of the path."""
    top = max(p.position[2] for p in points)
    if top > clear_z + 1e-9:
        raise PlanningError(f"feature {feature}: clearance level z = {clear_z:.3f}: expected "
                            f"it above every safe point, found one at z = {top:.3f}")


# ------------------------------------------------------------------------------- IR


def feature_nodes(plan: FeaturePlan, *, overtravel: float,
                  clearance_z: float | None = None) -> tuple[ir.Node, ...]:
    """The plan as IR nodes, in the style of :mod:`probegen.planning.sphere_test`.

    Moves along the path are ``PROTECTED``; a touch is an ``ir.Touch`` from its safe
    point (approach = the retract ``d``) followed by a ``RETRACT`` move back to it.
    With ``clearance_z`` (the program's clearance plane) the nodes start and end with a
    ``RAPID`` move there, straight above the entry and the exit (the entry itself when
    the plane is the plan's clearance level).
    """
    first, last = plan.path[0].position, plan.path[-1].position
    nodes: list[ir.Node] = [ir.Move(first, ir.MoveMode.PROTECTED)]
    if clearance_z is not None:
        high = ir.Move((first[0], first[1], clearance_z), ir.MoveMode.RAPID)
        nodes = [high] if clearance_z == plan.clear_z else [high, *nodes]
    for previous, p in pairwise(plan.path):
        if p.contact is not None and p.normal is not None:  # a target
            retract = plan.sections[p.section].retract
            nodes.append(ir.Touch(plan.feature, p.index, ir.TouchRole.MEASURE, p.contact,
                                  p.normal, retract, overtravel))
        elif previous.kind is PathKind.TARGET:
            nodes.append(ir.Move(p.position, ir.MoveMode.RETRACT))
        else:
            nodes.append(ir.Move(p.position, ir.MoveMode.PROTECTED))
    if clearance_z is not None and clearance_z != plan.clear_z:
        nodes.append(ir.Move((last[0], last[1], clearance_z), ir.MoveMode.RAPID))
    return tuple(nodes)


# --------------------------------------------------------------------------- metrics


@dataclass(frozen=True, slots=True)
class Segment:
    """One straight move of a path: ``rapid``, ``protected``, ``touch`` or ``retract``."""

    kind: str
    length: float


@dataclass(frozen=True, slots=True)
class Figures:
    """Path length (mm) and estimated time (s)."""

    length: float
    time: float


@dataclass(frozen=True, slots=True)
class Comparison:
    """The plan against the common baseline and the lower bound (see :func:`compare`)."""

    plan: Figures
    baseline: Figures
    lower_bound: Figures


def path_length(points: ArrayLike) -> float:
    """Length of the polyline through ``points : (k, 3) float``, mm."""
    p = np.asanyarray(points, dtype=np.float64).reshape(-1, 3)
    return float(np.linalg.norm(np.diff(p, axis=0), axis=1).sum())


def _dist(a: Sequence[float], b: Sequence[float]) -> float:
    return math.dist(a, b)


def plan_segments(plan: FeaturePlan) -> tuple[Segment, ...]:
    """The plan's moves: ``touch`` into a target, ``retract`` out, ``protected`` else."""
    return tuple(Segment(_kind(a, b), _dist(a.position, b.position))
                 for a, b in pairwise(plan.path))


def baseline_segments(plan: FeaturePlan) -> tuple[Segment, ...]:
    """The common baseline: the same touches, but after each one up to the clearance
    level (protected), across there (rapid) and down to the next safe point
    (protected)."""
    touches = [(a.position, b.position) for a, b in pairwise(plan.path)
               if b.kind is PathKind.TARGET]
    z = plan.clear_z
    out: list[Segment] = []
    previous = plan.path[0].position
    for k, (safe, target) in enumerate(touches):
        if k:
            out.append(Segment("rapid", math.hypot(safe[0] - previous[0],
                                                   safe[1] - previous[1])))
        out.append(Segment("protected", z - safe[2]))
        d = _dist(safe, target)
        out += [Segment("touch", d), Segment("retract", d), Segment("protected", z - safe[2])]
        previous = safe
    return tuple(out)


def _geodesic(plan: SectionPlan, delta: float, chord: float) -> float:
    """Shortest path between two safe-circle points ``delta`` apart that stays out of
    the offset surface (outer: wraps the offset circle where the chord cuts it)."""
    if plan.alpha_max is None:
        return chord
    c = math.cos(plan.section.tilt)
    rs = plan.safe_radius
    rho = rs - plan.retract / c
    free = 2.0 * math.acos(rho / rs)
    if abs(delta) <= free:
        return chord
    return 2.0 * math.sqrt(rs * rs - rho * rho) + rho * (abs(delta) - free)


def lower_bound_segments(plan: FeaturePlan) -> tuple[Segment, ...]:
    """The lower bound: the plan with every run of transitions between two points of a
    safe circle replaced by the shortest collision-free path between them (the chord,
    or for an outer section where the chord cuts the offset circle, the tangents and
    the arc of that circle).  No path through the same touches in the same order that
    avoids the part is shorter."""
    path = plan.path
    out: list[Segment] = []
    i = 0
    while i < len(path) - 1:
        j = i + 1
        while path[j].kind is PathKind.TRANSITION:
            j += 1
        a, b = path[i], path[j]
        if j > i + 1 and a.section == b.section:
            turn = sum(_wrap(path[k + 1].azimuth, path[k].azimuth) for k in range(i, j))
            chord = _dist(a.position, b.position)
            out.append(Segment("protected", _geodesic(plan.sections[a.section], turn, chord)))
        else:
            out += [Segment(_kind(path[k], path[k + 1]),
                            _dist(path[k].position, path[k + 1].position))
                    for k in range(i, j)]
        i = j
    return tuple(out)


def _kind(a: PathPoint, b: PathPoint) -> str:
    """The segment kind of the move ``a → b`` (see :class:`Segment`)."""
    if b.kind is PathKind.TARGET:
        return "touch"
    return "retract" if a.kind is PathKind.TARGET else "protected"


def _wrap(b: float | None, a: float | None) -> float:
    """Signed azimuth step from ``a`` to ``b`` in (-π, π]."""
    if a is None or b is None:
        return 0.0
    return (b - a + math.pi) % TWO_PI - math.pi


def cycle_time(segments: Sequence[Segment], *, rapid: float, position_feed: float,
               probe_feed: float, approach: float, overtravel: float = 0.0) -> float:
    """Estimated time of a path, s (feeds in mm/min).

    ``rapid`` moves at the rapid rate; ``protected`` and ``retract`` moves at the
    positioning feed; a ``touch`` covers its last ``approach`` mm (and ``overtravel``,
    0 for the nominal estimate, the probe's overtravel for the worst case) at the
    probing feed and the rest at the positioning feed.  Accelerations are ignored.
    """
    minutes = 0.0
    for s in segments:
        if s.kind == "rapid":
            minutes += s.length / rapid
        elif s.kind == "touch":
            slow = min(approach, s.length)
            minutes += (s.length - slow) / position_feed + (slow + overtravel) / probe_feed
        else:
            minutes += s.length / position_feed
    return 60.0 * minutes


def compare(plan: FeaturePlan, machine: MachineProfile) -> Comparison:
    """Length and nominal time of the plan, the baseline and the lower bound."""
    feeds = machine.feeds

    def figures(segments: Sequence[Segment]) -> Figures:
        time = cycle_time(segments, rapid=feeds.rapid, position_feed=feeds.position,
                          probe_feed=feeds.probe, approach=machine.probe.approach)
        return Figures(sum(s.length for s in segments), time)

    return Comparison(figures(plan_segments(plan)), figures(baseline_segments(plan)),
                      figures(lower_bound_segments(plan)))


def _vec3(v: Sequence[float] | FloatArray) -> Vec3:
    return (float(v[0]), float(v[1]), float(v[2]))


def _fmt(v: Sequence[float]) -> str:
    return "(" + ", ".join(f"{x:.3f}" for x in v) + ")"
