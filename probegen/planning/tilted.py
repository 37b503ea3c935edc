"""A revolved feature probed with a CMM's head turned well off the feature's axis (issue
17): a boss under an overhang (a ball on a neck), the blend in a pocket's corner under a
roof, the edge round of a plate, measured as a CMM programmer measures them in a
first-article inspection: the head at an index that leans the stylus away from what is
in the way, the touches still square to the feature.

The feature is planned in its own frame ``E`` (:func:`probegen.ir.frames.frame_for` of
its axis out of an open end: touches along its normals, method M2) on the part turned
into ``E``; every point of that plan is then expressed in the index's frame ``I`` (a
:class:`View`: ``p_I = Iᵀ·E·p_E``, :func:`express`) and made safe there by the reroute
(:func:`probegen.planning.reroute.reroute`) against the part turned into ``I``, with the
stylus along ``I``'s Z: a touch the leaning stylus cannot reach is dropped, the others
are joined by moves the collision check clears, entered and left along the stylus from
``I``'s clearance level; the well-posed rule
(:func:`probegen.planning.well_posed.unevaluable`) decides whether what is left measures
the feature.  Which index: :func:`screen` ranks the head's indices by the touches whose
stylus (shank and probe body along the index's direction from the ball at the touch)
clears the part, in work coordinates on the part as loaded (one collision test per touch
and index, no turned part), and only the best few are planned.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any

import numpy as np

from probegen import ir
from probegen.geometry.determined import incomplete, undetermined
from probegen.geometry.frames import rotation_to_z
from probegen.ir import frames
from probegen.machine.profile import Head
from probegen.planning.collision import Stylus
from probegen.planning.revolved import FeaturePlan, PathKind, PathPoint

if TYPE_CHECKING:
    from probegen.cad import Part

LEVEL_KINDS = (PathKind.ENTRY, PathKind.EXIT, PathKind.CLEAR)
"""The path points at the clearance level: put at ``I``'s level over their place."""
TRIED = 2
"""Indices planned per stylus and approach, the best of :func:`screen` first."""
MOST_PLANS = 6
"""Indices planned per feature at most (every approach and stylus together): a feature
none of them measures is left out (planning one is the reroute of every touch)."""
PRUNED = True
""":func:`screen` with ``best`` stops testing where the first ``best`` cannot change
(False: every index and touch tested, the benchmark's baseline)."""
MOST_TILT = 97.5
"""The stylus stands at most this far (deg) off the feature's axis (approach out of the
open end): beyond, it would reach back under the feature's own end."""


@dataclass(frozen=True, slots=True)
class View:
    """Where a plan made in the feature's frame ``E`` is probed: the head's index frame
    ``I``.

    Attributes:
        turn: ``E`` in ``I``'s coordinates (an ``ir.Orient`` whose rotation is ``Iᵀ·E``:
            :func:`probegen.ir.frames.to_work` of it takes ``E`` points to ``I``).
        part: the part turned into ``I`` (``part.turned(I)``).
        clearance_z: ``I``'s clearance level (frame Z), mm.
    """

    turn: ir.Orient
    part: Part
    clearance_z: float


def view_of(index: frames.Rotation, exact: frames.Rotation, part: Part,
            clearance_z: float) -> View:
    """The view of a plan made in frame ``exact`` probed at frame ``index`` on the part
    turned into it (``part``) with its clearance level ``clearance_z``."""
    return View(ir.Orient("EXACT", frames.product_t(index, exact)), part, clearance_z)


def express(plan: FeaturePlan, view: View) -> FeaturePlan:
    """``plan`` (frame ``E``) in ``I``'s coordinates: every point, contact and normal
    turned; the points at the clearance level (:data:`LEVEL_KINDS`) put at ``I``'s level
    straight over where they land (the reroute enters and leaves along the stylus)."""
    turn = view.turn

    def moved(p: PathPoint) -> PathPoint:
        q = frames.to_work(turn, p.position)
        if p.kind in LEVEL_KINDS:
            q = (q[0], q[1], view.clearance_z)
        return replace(p, position=q,
                       contact=None if p.contact is None else frames.to_work(turn, p.contact),
                       normal=None if p.normal is None else frames.direction_to_work(
                           turn, p.normal))

    return replace(plan, path=tuple(moved(p) for p in plan.path), clear_z=view.clearance_z)


def feature_in(turn: ir.Orient, feature: Any) -> Any:
    """A recognised feature (``cad.revolved.RevolvedFeature``) with its origin, axis and
    sections' centres turned by ``turn``."""
    return replace(feature, origin=frames.to_work(turn, feature.origin),
                   axis=frames.direction_to_work(turn, feature.axis),
                   sections=sections_in(turn, feature.sections))


def sections_in(turn: ir.Orient, sections: Sequence[Any]) -> tuple[Any, ...]:
    """Recognised sections (``cad.revolved.FeatureSection``) with their centres turned."""
    return tuple(replace(s, centre=frames.to_work(turn, s.centre)) for s in sections)


@dataclass(frozen=True, slots=True)
class Touch:
    """One planned touch in work coordinates: the ball's centre at the contact, the
    contact, and its 0-based section."""

    centre: np.ndarray
    contact: np.ndarray
    section: int


def touches_in_work(plan: FeaturePlan, exact: frames.Rotation) -> list[Touch]:
    """The touches of a plan made in frame ``exact`` (rotation of ``E``), in work
    coordinates."""
    turn = ir.Orient("E", exact)
    out = []
    for p in plan.path:
        if p.kind is PathKind.TARGET and p.contact is not None:
            out.append(Touch(np.asarray(frames.to_work(turn, p.position)),
                             np.asarray(frames.to_work(turn, p.contact)), p.section))
    return out


def head_indices(head: Head) -> list[tuple[float, float]]:
    """Every index ``(A, B)`` of the head's grid within its ranges (A0 once), deg."""
    out: list[tuple[float, float]] = []
    count_a = int(math.floor((head.a[1] - head.a[0]) / head.step + 1e-9))
    first_a = math.ceil(head.a[0] / head.step - 1e-9)
    first_b = math.ceil(head.b[0] / head.step - 1e-9)
    count_b = int(math.floor((head.b[1] - head.b[0]) / head.step + 1e-9))
    seen: set[tuple[float, float]] = set()
    for ka in range(first_a, first_a + count_a + 1):
        a = ka * head.step + 0.0
        for kb in ([0] if a == 0.0 else range(first_b, first_b + count_b + 1)):
            b = kb * head.step + 0.0
            key = (a, round(b % 360.0, 9) % 360.0)
            if key in seen or not head.a[0] <= a <= head.a[1]:
                continue
            seen.add(key)
            out.append((a, b))
    return out


def _angle(u: np.ndarray, v: np.ndarray) -> float:
    """The angle between unit vectors ``u`` and ``v``, deg."""
    return math.degrees(math.atan2(float(np.linalg.norm(np.cross(u, v))), float(u @ v)))


def screen(touches: Sequence[Touch], kind: str, axis: ir.Vec3, obstacle: Any,
           stylus: Stylus, required: float, head: Head, least_tilt: float,
           free: bool, best: int | None = None) -> list[tuple[float, float]]:
    """The head's indices worth planning a feature at, best first (with ``best``, only
    the first ``best`` of them).

    An index is kept when the stylus along its direction (shank and probe body, the
    collision check's :class:`~probegen.planning.collision.Stylus`) stands clear of the
    part by ``required`` mm at enough touches (``touches``, work coordinates, on the
    part as loaded: ``obstacle`` a :class:`~probegen.planning.collision.MeshObstacle`
    of it) for the evaluation (:func:`~probegen.geometry.determined.incomplete` of
    ``kind``; with ``free``, a free fit's
    :func:`~probegen.geometry.determined.undetermined` about ``axis``, the feature's
    axis out of the end it is approached from, work coordinates); its tilt off
    ``axis`` more than ``least_tilt`` and at most :data:`MOST_TILT` deg.  Best first:
    the most clear touches, then the least tilt, then the order of
    :func:`head_indices`.

    With ``best`` (and :data:`PRUNED`) the indices are tested least tilt first and the
    tests stop where they cannot change the first ``best``: an index is left as soon
    as the touches still untested could not bring it above the ``best``-th kept one (a
    later index ties it only with more tilt), and the screen ends when the ``best``-th
    kept one has every touch clear.  The same first ``best`` as the full ranking."""
    fcl = obstacle.fcl
    part = obstacle.part
    u = np.asarray(axis, dtype=np.float64)
    objects = [(fcl.Cylinder(radius + required, high - low), 0.5 * (low + high))
               for radius, low, high in stylus.cylinders()]
    bound = best if PRUNED else None
    indices: list[tuple[float, int, tuple[float, float], np.ndarray]] = []
    for k, (a_deg, b_deg) in enumerate(head_indices(head)):
        a = np.asarray(frames.head_approach(a_deg, b_deg))
        tilt = _angle(a, u)
        if least_tilt < tilt <= MOST_TILT:
            indices.append((tilt, k, (a_deg, b_deg), a))
    if bound is not None:
        indices.sort(key=lambda i: (i[0], i[1]))
    ranked: list[tuple[int, float, int, tuple[float, float]]] = []
    for tilt, k, angles, a in indices:
        # the clear touches the index must beat: the best-th kept so far
        beat = -ranked[bound - 1][0] if bound is not None and len(ranked) >= bound else -1
        if beat == len(touches):
            break  # the best kept have every touch clear: no later index is better
        rot = np.asarray(rotation_to_z(a)).T  # takes +Z onto a
        clear: list[Touch] = []
        for n, t in enumerate(touches):
            if not any(fcl.collide(fcl.CollisionObject(shape, fcl.Transform(
                    rot, t.centre + mid * a)), part, fcl.CollisionRequest(),
                    fcl.CollisionResult()) for shape, mid in objects):
                clear.append(t)
            elif len(clear) + len(touches) - n - 1 <= beat:
                break  # cannot beat the best-th kept
        else:
            if not clear or incomplete(kind, [t.section for t in clear]):
                continue
            if free and undetermined(kind, np.array([t.contact for t in clear]), axis):
                continue
            ranked.append((-len(clear), tilt, k, angles))
            if bound is not None:
                ranked = sorted(ranked)[:bound]
    ranked.sort()
    return [r[3] for r in ranked]
