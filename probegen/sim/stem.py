"""The stylus's shank and the probe body on the virtual machine (issue 17): every move
the virtual machine makes is checked with the whole probe, not only its ball.

The planner clears its moves with its own collision check (``planning/collision.py``:
lower bounds from swept slabs, with the profile's margin).  The virtual machine checks
them again, independently and without a margin: a cylinder along the probe (the shank
from the ball's radius above its centre to the stylus's length, the body from there for
the body's length, as the profile states them) swept along a straight move is the
convex hull of the cylinder at the move's two ends; the hull of two inscribed
:data:`SIDES`-gon prisms (at most ``r·(1 − cos(π/SIDES))`` inside the true surface:
0.2 % of the radius, 0.04 mm of a 40 mm body) is tested against the part's mesh with
python-fcl (GJK on the convex hull, a bounding-volume tree on the mesh).  A move that
cuts into the part is a collision (alarm 9100 of the virtual machine), naming the
element (``SHANK``, ``BODY``) and the face.  A turn of a trunnion table is checked chord
by chord, the hull of the cylinder at both ends of each chord.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import fcl
import numpy as np
from scipy.spatial import ConvexHull

SIDES = 48
"""Sides of the polygon a cylinder's cross-section is taken as (inscribed)."""


@dataclass(frozen=True, slots=True)
class Cylinder:
    """A cylinder along the probe: ``radius``, from ``low`` to ``high`` mm above the ball's
    centre; ``name`` in the alarm text."""

    name: str
    radius: float
    low: float
    high: float


def probe_cylinders(ball_radius: float, shank_diameter: float, length: float,
                    body_diameter: float, body_length: float) -> tuple[Cylinder, ...]:
    """The shank (from the ball's radius above its centre to ``length``) and the body
    (from ``length`` for ``body_length``; none when either body figure is 0), mm."""
    out = [Cylinder("SHANK", shank_diameter / 2.0, ball_radius, length)]
    if body_diameter > 0.0 and body_length > 0.0:
        out.append(Cylinder("BODY", body_diameter / 2.0, length, length + body_length))
    return tuple(c for c in out if c.radius > 0.0 and c.high > c.low)


class Stem:
    """The test of a cylinder along the probe swept along a straight move against the
    part's mesh (part frame) as a bounding-volume tree."""

    def __init__(self, part: Any, face_ids: np.ndarray, low: np.ndarray,
                 high: np.ndarray) -> None:
        """``part``: the mesh's fcl collision object (the contact solver's own, built
        once per part); ``face_ids``: the 0-based face of each triangle; ``low``,
        ``high``: a box holding the mesh."""
        self._part, self._face_ids = part, face_ids
        self._low, self._high = low, high

    def cut(self, a: np.ndarray, b: np.ndarray, axis_a: np.ndarray, axis_b: np.ndarray,
            cylinders: tuple[Cylinder, ...]) -> tuple[str, int] | None:
        """The first of ``cylinders`` that meets the part when the ball's centre moves from
        ``a`` to ``b`` (part frame, mm) with the probe along ``axis_a`` then ``axis_b``
        (unit, from the ball towards the head), and the face it meets (1-based; 0: not
        known); None when all stay clear."""
        for c in cylinders:
            points = np.vstack([prism(a, axis_a, c), prism(b, axis_b, c)])
            face = self._meets(points)
            if face is not None:
                return c.name, face
        return None

    def _meets(self, points: np.ndarray) -> int | None:
        """The face (1-based) of a triangle the convex hull of ``points`` meets, or None."""
        low, high = points.min(axis=0), points.max(axis=0)
        if not (np.all(high >= self._low) and np.all(low <= self._high)):
            return None
        hull = ConvexHull(points, qhull_options="QJ")
        used = np.unique(hull.simplices)
        index = -np.ones(len(points), dtype=np.int64)
        index[used] = np.arange(len(used))
        faces = np.column_stack([np.full(len(hull.simplices), 3),
                                 index[hull.simplices]]).ravel()
        shape = fcl.Convex(points[used], len(hull.simplices), faces)
        request = fcl.CollisionRequest(num_max_contacts=1, enable_contact=True)
        result = fcl.CollisionResult()
        if fcl.collide(fcl.CollisionObject(shape, fcl.Transform()), self._part, request,
                       result) == 0:
            return None
        # the triangle's index is the contact's b1 or b2 (fcl orders mesh before shape)
        triangle = max(result.contacts[0].b1, result.contacts[0].b2) if result.contacts else -1
        return int(self._face_ids[triangle]) + 1 if 0 <= triangle < len(self._face_ids) else 0


_ANGLES = np.linspace(0.0, 2.0 * math.pi, SIDES, endpoint=False)
_RING = np.column_stack([np.cos(_ANGLES), np.sin(_ANGLES)])
"""The unit :data:`SIDES`-gon's corners (cos, sin)."""


def prism(centre: np.ndarray, axis: np.ndarray, c: Cylinder) -> np.ndarray:
    """The corners of the inscribed prism of ``c`` with the ball's centre at ``centre``
    and the probe along ``axis`` (unit)."""
    u = np.asarray(axis, dtype=np.float64)
    helper = np.array([1.0, 0.0, 0.0]) if abs(u[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    e1 = np.cross(u, helper)
    e1 /= float(np.linalg.norm(e1))
    e2 = np.cross(u, e1)
    ring = c.radius * (_RING[:, :1] * e1 + _RING[:, 1:] * e2)
    return np.vstack([centre + c.low * u + ring, centre + c.high * u + ring])
