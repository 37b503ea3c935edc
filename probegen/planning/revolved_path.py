"""Method M2, the path: sections joined into one ball-centre path, and its IR nodes.

Owns the path records (:class:`PathKind`, :class:`PathPoint`, :class:`FeaturePlan`),
:func:`plan_feature` (step 6 of :mod:`probegen.planning.revolved`: touches, transitions
on the safe circle, links along the axis, moves over the clearance level, entry and
exit) and :func:`feature_nodes` (the plan as IR).  The figures of each section come
from :mod:`probegen.planning.revolved_geometry`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from enum import Enum
from itertools import pairwise

import numpy as np

from probegen import ir
from probegen.errors import PlanningError
from probegen.planning.revolved_geometry import (
    TWO_PI,
    FloatArray,
    Section,
    SectionPlan,
    Vec3,
    _Circle,
    _step_limit,
    _vec3,
    plan_section,
    transition_count,
)


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
class FeaturePlan:
    """A planned feature: its sections and the whole path (entry to exit)."""

    feature: str
    sections: tuple[SectionPlan, ...]
    clear_z: float
    path: tuple[PathPoint, ...]


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
