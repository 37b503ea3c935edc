"""Method M3: touches at the guide points of a free-form face, and their IR.

Given guide points ``G`` (on the face, with outward normals), a ``ParamSurface`` of the
face and the guide direction ``d`` (unit, out of the material; the probe comes down
along ``-d``), every guide point becomes a *group* of touches:

* ``vertical`` (the seed's naive method): one touch along ``-d`` on the guide line
  through ``G``;
* ``vertical2d``: that touch and two more on the guide lines through ``G ∓ s·t``, with
  ``t`` the unit vector square to ``d`` along the surface's slope at ``G`` (the
  profile plane of the seed's 2-D method);
* ``microplane``: that touch and three more on the guide lines through three points
  120° apart on the circle of radius ``s`` about ``G`` square to ``d``;
* ``vector``: one touch along the nominal normal ``n`` at the theoretical contact
  point ``P_t``, starting at ``O_t + approach·n``.

Each guide line meets the surface offset by the ball radius ``r`` at the theoretical
ball centre ``O_t`` (:func:`probegen.geometry.offset_surface.ball_centres`, Newton to
1e-10 mm), and ``P_t = O_t − r·n(P_t)``.  A vertical touch is written as an
``ir.Touch`` whose ``contact`` is ``O_t − r·d`` with ``normal = d`` (so its ball-centre
end point is ``O_t``) and whose ``surface`` is ``n(P_t)`` for the collision check.

Touch indices: touch ``j`` (0 = the guide line's own, 1-3 the extra ones) of guide
point ``g`` has index ``10·g + j``, so a log line names its guide point and role
without the plan.  numpy only; no OCP.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from probegen import ir
from probegen.geometry.frames import FloatArray
from probegen.geometry.freeform_offsets import micro_plane_offsets, two_d_offsets
from probegen.geometry.offset_surface import ParamSurface, ball_centres
from probegen.spec.model import FREEFORM_EXTRA as EXTRA_TOUCHES
from probegen.spec.model import FREEFORM_STRIDE as INDEX_STRIDE

Vec3 = tuple[float, float, float]



@dataclass(frozen=True, slots=True)
class PlannedTouch:
    """One planned touch of a free-form feature (mm, work coordinates).

    Attributes:
        index: the touch index (``10·guide + role``).
        guide: the guide point (1-based).
        role: 0 for the guide line's own touch, 1-3 for the extra touches.
        centre: theoretical ball centre ``O_t`` at contact.
        contact: theoretical contact point ``P_t``.
        normal: outward unit surface normal at ``P_t``.
        direction: unit vector the ball moves against while probing (``d`` for the
            vertical methods, ``n`` for vector probing).
        uv: surface parameters of ``P_t``.
    """

    index: int
    guide: int
    role: int
    centre: Vec3
    contact: Vec3
    normal: Vec3
    direction: Vec3
    uv: tuple[float, float]

    def start(self, approach: float) -> FloatArray:
        """The ball centre where the touch starts, ``approach`` mm before contact."""
        return np.add(self.centre, approach * np.asarray(self.direction))

    def node(self, feature: str, r: float, approach: float, overtravel: float) -> ir.Touch:
        """The ``ir.Touch`` (see the module docstring for vertical touches)."""
        vertical = self.direction != self.normal
        contact = (_v(np.subtract(self.centre, r * np.asarray(self.direction))) if vertical
                   else self.contact)
        return ir.Touch(feature, self.index, ir.TouchRole.MEASURE, contact, self.direction,
                        approach, overtravel, surface=self.normal if vertical else None)


@dataclass(frozen=True, slots=True)
class Failed:
    """A guide point without touches: which (1-based), where (mm) and why."""

    guide: int
    point: Vec3
    reason: str


def guide_lines(points: FloatArray, normals: FloatArray, d: FloatArray, method: str,
                spacing: float) -> tuple[FloatArray, np.ndarray, np.ndarray]:
    """Origins of every guide line: (m, 3), with the guide row (m,) and role (m,) of each.

    The extra lines sit where :mod:`probegen.evaluate.compensate_freeform` expects them
    (:mod:`probegen.geometry.freeform_offsets`), so plan and compensation agree.

    Args:
        points: (n, 3) guide points.
        normals: (n, 3) outward normals at the guide points.
        d: (3,) unit guide direction (out of the material).
        method: one of :data:`EXTRA_TOUCHES`.
        spacing: distance of the extra lines from the guide point, mm.
    """
    count = 1 + EXTRA_TOUCHES[method]
    rows = np.repeat(np.arange(len(points)), count)
    roles = np.tile(np.arange(count), len(points))
    offsets = np.zeros((len(points), count, 3))
    if method == "vertical2d" and len(points):
        offsets[:, 1:] = two_d_offsets(normals, spacing=spacing, probe_direction=-d)
    elif method == "microplane":
        offsets[:, 1:] = micro_plane_offsets(radius=spacing, probe_direction=-d)
    origins = (points[:, None, :] + offsets).reshape(-1, 3)
    return origins, rows, roles


def plan_touches(surface: ParamSurface, normal_sign: float, guides: FloatArray,
                 normals: FloatArray, seeds: FloatArray, *, d: Vec3, method: str,
                 spacing: float, r: float, first_index: tuple[int, ...] | None = None,
                 ) -> tuple[list[list[PlannedTouch]], list[Failed]]:
    """Theoretical ball centres and contacts of every touch, grouped by guide point.

    Args:
        surface: the face's surface.
        normal_sign: +1 when ``Su × Sv`` points out of the material.
        guides: (n, 3) guide points; normals: (n, 3); seeds: (n, 2) their ``(u, v)``.
        d: unit guide direction.
        method: the M3 method.
        spacing: extra-touch distance, mm.
        r: ball radius, mm.
        first_index: the 1-based number of each guide point (default 1..n).

    Returns:
        One list of touches per guide point that solved, and the guide points that
        did not (the solver's reason).
    """
    dv = np.asarray(d, dtype=np.float64)
    numbers = first_index or tuple(range(1, len(guides) + 1))
    origins, rows, roles = guide_lines(guides, normals, dv, method, spacing)
    found = ball_centres(surface, origins, -dv, r, seeds[rows], normal_sign=normal_sign)
    groups: list[list[PlannedTouch]] = [[] for _ in guides]
    failed: dict[int, str] = {}
    for k in range(len(origins)):
        row = int(rows[k])
        if not found.ok[k]:
            failed.setdefault(row, found.message(k).split(" iterations, ", 1)[-1])
            continue
        normal = _v(found.normal[k])
        direction = normal if method == "vector" else _v(dv)
        g = numbers[row]
        groups[row].append(PlannedTouch(INDEX_STRIDE * g + int(roles[k]), g, int(roles[k]),
                                        _v(found.centre[k]), _v(found.contact[k]), normal,
                                        direction, (float(found.uv[k, 0]),
                                                    float(found.uv[k, 1]))))
    kept = [grp for row, grp in enumerate(groups) if row not in failed]
    lost = [Failed(numbers[row], _v(guides[row]), why) for row, why in sorted(failed.items())]
    return kept, lost


def group_nodes(feature: str, touches: list[PlannedTouch], *, r: float, approach: float,
                overtravel: float, safe_z: float) -> tuple[ir.Node, ...]:
    """One guide point's moves and touches: down from ``safe_z`` above the first start,
    each touch and its retract, straight on to the next start, up to ``safe_z``."""
    starts = [t.start(approach) for t in touches]
    first, last = starts[0], starts[-1]
    nodes: list[ir.Node] = [ir.Move((float(first[0]), float(first[1]), safe_z),
                                    ir.MoveMode.PROTECTED)]
    for t, s in zip(touches, starts, strict=True):
        nodes.append(ir.Move(_v(s), ir.MoveMode.PROTECTED))
        nodes.append(t.node(feature, r, approach, overtravel))
        nodes.append(ir.Move(_v(s), ir.MoveMode.RETRACT))
    nodes.append(ir.Move((float(last[0]), float(last[1]), safe_z), ir.MoveMode.PROTECTED))
    return tuple(nodes)


def _v(p: FloatArray | tuple[float, ...]) -> Vec3:
    return (float(p[0]), float(p[1]), float(p[2]))
