"""The machine table under the part, as the collision check sees it.

The part stands on the table at its lowest point (work Z: the part as loaded, or as a
named setup turns it), or :attr:`probegen.cad.Part.raised` mm above it (a fixture,
parallels: ``[part] raised`` of the spec, ``--raised`` of ``plan --all-revolved``):
below that plane is steel, which a stylus path must clear as it clears the part.
Planning turns the part into frames (a CMM head index, a five-axis tilt:
:meth:`probegen.cad.Part.turned`); the table turns with it, so in a frame it is the
half-space ``n·x <= h`` with ``n`` the work +Z in frame coordinates (the frame
rotation's third row) and ``h`` the least ``n·v`` over the part's vertices.

Every element of the stylus is a ball or a cylinder along the frame's +Z (the probe's
axis), so its distance to the plane is exact and linear in the ball's centre: along a
straight move the least clearance is at one of the move's ends.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

NAME = "the table"
"""What messages call it."""


@dataclass(frozen=True, slots=True)
class Table:
    """The half-space ``normal·x <= height`` (frame coordinates, mm).

    Attributes:
        normal: the work +Z in the frame (a unit vector).
        height: the plane's offset along ``normal``: the part's lowest point.
    """

    normal: tuple[float, float, float]
    height: float

    @classmethod
    def under(cls, vertices: Any, rotation: Any | None, raised: float = 0.0) -> Table:
        """The table ``raised`` mm under a mesh's ``vertices`` (frame coordinates), the
        frame turned by ``rotation`` (rows; ``p_work = R·p_frame``; None: the work frame
        itself)."""
        n = np.array([0.0, 0.0, 1.0]) if rotation is None else np.asarray(
            rotation, dtype=np.float64)[2]
        height = float(np.min(np.asarray(vertices, dtype=np.float64) @ n)) - raised
        return cls((float(n[0]), float(n[1]), float(n[2])), height)

    def clearance(self, centre: np.ndarray, radius: float, low: float | None = None,
                  high: float | None = None) -> float:
        """The distance from a ball (``low``/``high`` None) or a cylinder along the
        frame's +Z from ``low`` to ``high`` above ``centre`` (``radius``) to the table;
        negative where it reaches below, mm."""
        nx, ny, nz = self.normal
        base = nx * float(centre[0]) + ny * float(centre[1]) + nz * float(centre[2]) \
            - self.height
        if low is None or high is None:
            return base - radius
        return base + min(low * nz, high * nz) - radius * math.hypot(nx, ny)

    def swept(self, a: np.ndarray, b: np.ndarray, radius: float, low: float | None = None,
              high: float | None = None) -> float:
        """The least :meth:`clearance` of the element moved from ``a`` to ``b`` (exact:
        the clearance is linear in the centre)."""
        return min(self.clearance(a, radius, low, high), self.clearance(b, radius, low, high))

    def depth(self, point: np.ndarray) -> float:
        """How far ``point`` lies below the table's plane (negative above), mm."""
        return -self.clearance(point, 0.0)
