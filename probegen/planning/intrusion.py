"""How far the stylus cuts into the part where the collision check refuses a move.

The sweep of :mod:`probegen.planning.collision` stops at the first point whose clearance
falls below the requirement: its figure there is a bound (the mesh tolerance and half a
step: "0.015 mm"), not how deep the stylus goes.  Here the depth is measured, for the
message only, on the element that meets the part (the ball, the shank or the probe body):

- *from the side*: how far the part reaches in from the element's surface towards its
  axis (a cylinder) or centre (the ball): the element's radius less the largest radius of
  the same element at the same place that clears the part (a ball whose centre lies in
  the material: its radius and the centre's depth below the surface);
- *from below* (a cylinder): how far the part reaches up from the element's lower end
  along the probe: the least the lower end must rise (the cylinder shortened from below)
  for the rest to clear.

The depth is the smaller of the two (a cylinder), the side figure (the ball): the part's
reach into the element from its nearest surface.  Each is found by bisection to
:data:`DEPTH_TOLERANCE` on the overlap test the obstacle gives (the part's mesh: a contact
with its triangles, or the element wholly inside the material), so each is exact up to
the mesh's chordal deviation.  Along a move the depth is taken at points from where the
sweep first found the stylus too close to the move's end (every :data:`SPACING` mm, at
most :data:`SAMPLES`), then refined about the deepest (:data:`REFINE` halvings of the
spacing): each figure changes no faster than the stylus moves, so the figure found is a
lower bound of the greatest along the move, within half the last spacing of the greatest
near the deepest point sampled (the deepest of all where the depth rises and falls once
along the move, as through one wall).  The search looks for the ball wholly inside the
material at every sample but where the sweep stopped (it came there from outside), for
the shank or the body so only when no element meets the part's surface at any sample.

Conventions: the ball's centre is the stylus position, the probe along +Z of the frame
the move is in, heights along the probe from the ball's centre, mm.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace

import numpy as np

DEPTH_TOLERANCE = 1e-3
"""The depth's resolution, mm (the bisection stops at it; the least radius or length of
an element tried)."""
SAMPLES = 9
"""The most points of a move at which the depth is taken (both ends included)."""
SPACING = 5.0
"""The depth is taken at least this often along a move, mm (up to :data:`SAMPLES`
points)."""
REFINE = 4
"""Halvings of the sample spacing about the deepest point."""
SCAN_TOLERANCE = 0.1
"""The resolution of the side figure by which the deepest point is sought, mm (the final
figures are taken there to :data:`DEPTH_TOLERANCE`)."""


@dataclass(frozen=True, slots=True)
class Element:
    """One part of the stylus: the ball (``low`` None: a sphere of ``radius`` about the
    ball's centre) or a cylinder along the probe (``radius``, from ``low`` to ``high``
    above the ball's centre), mm; ``name`` as messages give it."""

    name: str
    radius: float
    low: float | None = None
    high: float | None = None


@dataclass(frozen=True, slots=True)
class Intrusion:
    """How far the part reaches into one element of the stylus, mm.

    Attributes:
        element: ``ball``, ``shank`` or ``probe body``.
        depth: the smaller of ``side`` and ``up`` (the ball: ``side``).
        side: from the element's surface towards its axis (its centre); the element's
            radius when the part reaches the axis.
        up: from the element's lower end along the probe (None for the ball); the
            element's length when the part reaches its top.
        at: the ball's centre where the depth is greatest.
    """

    element: str
    depth: float
    side: float
    up: float | None
    at: np.ndarray


Overlaps = Callable[[np.ndarray, Element, bool], bool]
"""Whether ``element`` with the ball's centre at the point overlaps the part; with the
flag false, only whether it meets the part's surface (not whether it lies wholly inside
the material: the cheaper test the search for the deepest point makes)."""


Beneath = Callable[[np.ndarray], float]
"""How deep a point that lies in the material is below the part's surface, mm."""


def elements(ball: float, cylinders: Sequence[tuple[float, float, float]]) -> tuple[Element, ...]:
    """The ball (radius ``ball``) and the cylinders of a stylus (``(radius, low, high)``,
    :meth:`probegen.planning.collision.Stylus.cylinders`: the shank, then the probe
    body)."""
    names = ("shank", "probe body")
    return (Element("ball", ball),
            *(Element(names[min(k, 1)], r, low, high)
              for k, (r, low, high) in enumerate(cylinders)))


def depth_at(overlaps: Overlaps, centre: np.ndarray, e: Element,
             tolerance: float = DEPTH_TOLERANCE, *, side_only: bool = False,
             solid: bool = True, beneath: Beneath | None = None
             ) -> tuple[float, float | None]:
    """``(side, up)`` of element ``e`` with the ball's centre at ``centre`` (mm; both 0
    when it clears the part; ``up`` None for the ball, or with ``side_only``), to
    ``tolerance``; ``solid``: see :data:`Overlaps`.  A ball whose centre lies in the
    material: its radius and how deep its centre lies (with ``beneath``)."""
    if not overlaps(centre, e, solid):
        return 0.0, None if e.low is None or side_only else 0.0
    clear = _largest(lambda r: not overlaps(centre, replace(e, radius=r), solid),
                     e.radius, tolerance)
    side = e.radius - clear
    if e.low is None or e.high is None:
        if clear == 0.0 and beneath is not None:
            side += beneath(centre)
        return side, None
    if side_only:
        return side, None
    low, length = e.low, e.high - e.low
    up = _least(lambda h: not overlaps(centre, replace(e, low=low + h), solid), length,
                tolerance)
    return side, up


def _largest(clears: Callable[[float], bool], top: float, tolerance: float) -> float:
    """The largest ``x`` in ``[0, top]`` (to ``tolerance``) with ``clears(x)``, given
    ``clears(top)`` is false and clearing is kept as ``x`` falls; 0 when even
    ``tolerance`` does not clear."""
    if not clears(tolerance):
        return 0.0
    lo, hi = tolerance, top
    while hi - lo > tolerance:
        mid = (lo + hi) / 2.0
        lo, hi = (mid, hi) if clears(mid) else (lo, mid)
    return lo


def _least(clears: Callable[[float], bool], top: float, tolerance: float) -> float:
    """The least ``x`` in ``[0, top]`` (to ``tolerance``, rounded up) with ``clears(x)``,
    given ``clears(0)`` is false and clearing is kept as ``x`` grows; ``top`` when
    ``top - tolerance`` does not clear."""
    if not clears(top - tolerance):
        return top
    lo, hi = 0.0, top - tolerance
    while hi - lo > tolerance:
        mid = (lo + hi) / 2.0
        lo, hi = (lo, mid) if clears(mid) else (mid, hi)
    return hi


def _depth(side: float, up: float | None) -> float:
    return side if up is None else min(side, up)


def deepest(overlaps: Overlaps, parts: Sequence[Element], a: np.ndarray,
            b: np.ndarray, beneath: Beneath | None = None) -> Intrusion | None:
    """The deepest intrusion of any of ``parts`` along the move ``a → b`` (ball centres,
    mm; ``a`` where the sweep found the stylus too close), or None when none of them
    overlaps the part at any point tried (the sweep's figure was within the mesh's
    tolerance of touching).  The points tried: one every :data:`SPACING` mm or closer
    (at least both ends, at most :data:`SAMPLES`), then :data:`REFINE` halvings of the
    spacing about the deepest."""
    length = float(np.linalg.norm(b - a))

    solid = False

    def score(t: float) -> tuple[float, int]:
        # the ball whole (its centre inside: one query), but where the sweep found the
        # stylus too close (t = 0): it came there from outside
        found = [depth_at(overlaps, a + t * (b - a), e, SCAN_TOLERANCE, side_only=True,
                          solid=solid or (e.low is None and t > 0.0), beneath=beneath)[0]
                 for e in parts]
        k = max(range(len(found)), key=lambda i: found[i])
        return found[k], k

    n = 1 if length < DEPTH_TOLERANCE else min(SAMPLES, 2 + int(length / SPACING))
    ts = [float(t) for t in np.linspace(0.0, 1.0, n)]
    scores = {t: score(t) for t in ts}
    if max(v[0] for v in scores.values()) <= 0.0:
        solid = True  # nothing meets the surface: is an element wholly inside?
        scores = {t: score(t) for t in ts}
    step = 1.0 / (n - 1) if n > 1 else 0.0
    best = max(scores, key=lambda t: (scores[t][0], -t))
    for _ in range(REFINE if n > 2 else 0):
        step /= 2.0
        for t in (best - step, best + step):
            if 0.0 <= t <= 1.0 and t not in scores:
                scores[t] = score(t)
        best = max(scores, key=lambda t: (scores[t][0], -t))
    if scores[best][0] <= 0.0:
        return None
    e, at = parts[scores[best][1]], a + best * (b - a)
    side, up = depth_at(overlaps, at, e, solid=True, beneath=beneath)
    return Intrusion(e.name, _depth(side, up), side, up, at)


def words(hit: Intrusion, radius: float) -> str:
    """How far the part reaches into the element (of ``radius``, mm), for a message:
    ``0.250 mm`` (the ball), ``0.250 mm (0.250 mm in from its side, 7.000 mm up from its
    lower end)``, ``0.700 mm (across its axis, 12.000 mm up from its lower end)``."""
    if hit.up is None:
        return f"{hit.depth:.3f} mm"
    side = "across its axis" if hit.side >= radius - DEPTH_TOLERANCE else \
        f"{hit.side:.3f} mm in from its side"
    return f"{hit.depth:.3f} mm ({side}, {hit.up:.3f} mm up from its lower end)"
