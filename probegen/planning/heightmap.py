"""A fast, conservative collision check for many short paths (M3 guide points, links).

:func:`clear_paths` answers, for each path of IR nodes, "cleared" or "unsure"; an unsure
path goes to the exact check (:func:`probegen.planning.collision.check_program`), so the
fast check only ever saves time.  It is conservative: every distance it proves is a
lower bound of the true distance between the stylus and the part mesh, so a move it
clears has at every point the exact check samples a clearance at least the required one.
The segments are exactly those the exact check sweeps (touch stops from
:func:`probegen.planning.collision.touch_check_stop`).

Per segment, in order of cost:

1. **Height map** (:class:`HeightMap`): an upper bound of the mesh's height in every cell
   of an XY grid (per triangle and cell, the smaller of its highest vertex and the
   highest corner of its plane over the cell; cells overlapping the triangle's XY box),
   dilated by a disc footprint of cells (cell-to-cell distance, one cell of slack for
   rounding).  Along a segment sampled at most one cell apart (the disc grown by half a
   cell), the highest mesh point within ``R`` of the stylus axis bounds what the
   stylus can meet.  With ``q`` the required distance and ``R = max(r, shank) + q``, all
   mesh points within ``R`` lying ``q`` below the ball's lowest point clears ball and
   shank; for the shank alone ``shank + q`` and ``q`` below its bottom (``r`` above
   the centre); for the probe body ``body + q`` and ``q`` below its bottom (the
   stylus's ``length`` above the centre).
2. **Swept volumes** (python-fcl collision tests, ten times cheaper than distances):
   the ball swept along a segment is a capsule, so a capsule of radius ``r + q`` that
   meets no triangle proves the ball ``q`` clear over the whole segment (sphere tracing
   only samples it).  The shank swept vertically is a longer cylinder; swept along a
   slanted segment it lies inside a vertical cylinder around the segment's midpoint,
   ``|Δxy|/2`` wider; grown by ``q`` in radius and at both ends; the body likewise.
3. A segment start not known to be outside the part (an end of a cleared segment, or
   above every triangle of its cell) makes the path unsure; so does a segment whose
   ball, shank or body comes within ``q`` of the table under the part
   (:mod:`probegen.planning.table`, exact).

A cleared segment goes into the obstacle's sweep cache (the exact check's key, with the
proven lower bounds ``clear + FCL_SLACK`` as its clearances), so the check of the whole
program (``plan_program``) does not sweep it again; its report then gives, for such
segments, that lower bound rather than the sampled minimum.

``q = clear + MESH_TOLERANCE + MIN_STEP/2 + FCL_SLACK``: the exact check accepts a
sample whose fcl distance is at least ``clear + MESH_TOLERANCE + MIN_STEP/2``, and
``FCL_SLACK`` covers fcl's own GJK tolerance.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from scipy.ndimage import maximum_filter1d

from probegen import ir
from probegen.machine.profile import MachineProfile
from probegen.planning.collision import (
    MESH_TOLERANCE,
    MIN_STEP,
    MeshObstacle,
    Obstacle,
    Stylus,
    probe_stylus,
    touch_check_stop,
)

FCL_SLACK = 1e-3
"""Added to every required distance, mm: fcl's distances are exact to about 1e-6 mm."""
MAX_CELLS = 4_000_000
"""Largest height-map grid; the cell grows for larger parts (at least ``CELL``)."""
CELL = 0.1
"""Height-map cell, mm."""
CHUNK = 4_000_000
"""Triangle-cell pairs rasterised at once."""
BIG = 256
"""Triangles whose XY box covers more cells are rasterised one by one."""

Segment = tuple[np.ndarray, np.ndarray]


class HeightMap:
    """Upper bounds of a mesh's height (z, mm) per XY cell, and their dilations."""

    def __init__(self, vertices: np.ndarray, faces: np.ndarray) -> None:
        lo, hi = vertices[:, :2].min(axis=0), vertices[:, :2].max(axis=0)
        self.cell = max(CELL, float(np.sqrt(np.prod(hi - lo + 1.0) / MAX_CELLS)))
        self.origin = lo - self.cell
        self.shape = tuple(int(v) for v in np.floor((hi - self.origin) / self.cell) + 2)
        self.height = self._rasterise(vertices[faces])
        self._dilated: dict[float, tuple[np.ndarray, int]] = {}

    def _rasterise(self, tri: np.ndarray) -> np.ndarray:
        """Per cell the largest bound over the triangles whose XY box overlaps it: small
        triangles all at once (in chunks of ``CHUNK`` triangle-cell pairs), large ones
        one by one over their box."""
        out = np.full(self.shape, -np.inf)
        lo, hi = self._cells(tri)
        counts = (hi - lo + 1).prod(axis=1)
        big = np.flatnonzero(counts > BIG)
        if len(big):
            top, flat, grad = _planes(tri[big])
            rising = grad > 0
            h, o = self.cell, self.origin
            for m, t in enumerate(big):  # the sums of _bound, on scalars of this triangle
                i = np.arange(lo[t, 0], hi[t, 0] + 1)
                j = np.arange(lo[t, 1], hi[t, 1] + 1)
                x0, y0, z0 = tri[t, 0]
                if flat[m]:
                    cx = o[0] + h * (i + rising[m, 0])
                    cy = o[1] + h * (j + rising[m, 1])
                    plane = (z0 + grad[m, 0] * (cx - x0))[:, None] + grad[m, 1] * (cy - y0)
                    block = np.minimum(plane, top[m]) + FCL_SLACK
                else:
                    block = top[m] + FCL_SLACK
                view = out[i[0]:i[-1] + 1, j[0]:j[-1] + 1]
                np.maximum(view, block, out=view)
        small = tri[counts <= BIG]
        for first in range(0, len(small), CHUNK // BIG):
            part = small[first:first + CHUNK // BIG]
            lo, hi = self._cells(part)
            n = (hi - lo + 1).prod(axis=1)
            k = np.repeat(np.arange(len(part)), n)
            local = np.arange(len(k)) - np.repeat(np.cumsum(n) - n, n)
            width = (hi - lo + 1)[k, 1]
            i, j = lo[k, 0] + local // width, lo[k, 1] + local % width
            np.maximum.at(out, (i, j), self._bound(part[k], i, j))
        return out

    def _cells(self, tri: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The first and last cell (i, j) of each triangle's XY box."""
        lo = np.floor((tri[:, :, :2].min(axis=1) - self.origin) / self.cell)
        hi = np.floor((tri[:, :, :2].max(axis=1) - self.origin) / self.cell)
        return lo.astype(np.int64), hi.astype(np.int64)

    def _bound(self, tri: np.ndarray, i: np.ndarray, j: np.ndarray) -> np.ndarray:
        """Upper bound of the height of triangles ``tri`` (m, 3, 3) over cells ``(i, j)``
        (arrays broadcasting with (m,)): the smaller of the highest vertex and the
        plane's highest corner of the cell (the upper corner along a rising gradient;
        the highest vertex alone for a vertical triangle)."""
        h, o = self.cell, self.origin
        top, flat, grad = _planes(tri)
        v0 = tri[:, 0].T
        cx = o[0] + h * (i + (grad[..., 0] > 0))
        cy = o[1] + h * (j + (grad[..., 1] > 0))
        plane = v0[2] + grad[..., 0] * (cx - v0[0]) + grad[..., 1] * (cy - v0[1])
        return np.where(flat, np.minimum(plane, top), top) + FCL_SLACK

    def dilated(self, radius: float) -> tuple[np.ndarray, int]:
        """The height map dilated to every cell within ``radius`` mm of a point of the
        cell (plus one cell for rounding), padded by ``k`` cells on every side (returned
        with it) beyond which no cell is within ``radius`` of the mesh; in single
        precision, each height rounded up (:data:`SINGLE`)."""
        hit = self._dilated.get(radius)
        if hit is not None:
            return hit
        k = int(np.ceil(radius / self.cell)) + 2
        pad = np.pad(rounded_up(self.height) if SINGLE else self.height, k,
                     constant_values=-np.inf)
        out = np.full_like(pad, -np.inf)
        run, width = pad, -1
        for a in range(k + 1):
            # cells (a, b) apart hold points at least h·(|a| - 1) apart along x (and y):
            # one more cell of slack on each axis for rounding
            da = max(a - 2, 0) * self.cell
            if da > radius:
                break
            w = int(np.floor(np.sqrt(radius**2 - da**2) / self.cell)) + 2
            if w != width:  # w falls with |a|: one run of the filter in memory at a time
                run, width = maximum_filter1d(pad, 2 * w + 1, axis=1, mode="constant",
                                              cval=-np.inf), w
            shift_max(out, run, a)
        self._dilated[radius] = (out, k)
        return out, k

    def highest_along(self, a: np.ndarray, b: np.ndarray, radius: float) -> np.ndarray:
        """Upper bounds (mm) of the mesh's height within ``radius`` (XY) of each segment
        ``a[i] → b[i]`` ((n, 2) or (n, 3); only x and y are used)."""
        grid, pad = self.dilated(radius + self.cell / 2.0)
        length = np.hypot(*(b[:, :2] - a[:, :2]).T)
        counts = np.ceil(length / self.cell).astype(np.int64) + 1
        seg = np.repeat(np.arange(len(a)), counts)
        start = np.repeat(np.cumsum(counts) - counts, counts)
        t = (np.arange(len(seg)) - start) / np.maximum(counts[seg] - 1, 1)
        p = a[seg, :2] + t[:, None] * (b[seg, :2] - a[seg, :2])
        idx = np.floor((p - self.origin) / self.cell).astype(np.int64) + pad
        ok = np.all((idx >= 0) & (idx < np.array(grid.shape)), axis=1)
        value = np.full(len(seg), -np.inf)
        value[ok] = grid[idx[ok, 0], idx[ok, 1]]
        out = np.full(len(a), -np.inf)
        np.maximum.at(out, seg, value)
        return out


def _planes(tri: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per triangle of ``tri`` (m, 3, 3): its highest vertex's z, whether it is not
    vertical, and its plane's gradient (dz/dx, dz/dy; zero for a vertical one)."""
    top = tri[:, :, 2].max(axis=1)
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    flat = np.abs(n[:, 2]) > 1e-9 * np.linalg.norm(n, axis=1)
    grad = np.zeros((len(tri), 2))
    grad[flat] = -n[flat, :2] / n[flat, 2:3]
    return top, flat, grad


SINGLE = True
"""Whether :meth:`HeightMap.dilated` works in single precision on the heights rounded up
(:func:`rounded_up`: still upper bounds, at most 6e-5 mm higher where a height is under
1 m in size, against :data:`FCL_SLACK`'s 1e-3 mm): half the memory and less time than
double precision (``benchmarks/bench_dilation_single.py``)."""


def rounded_up(height: np.ndarray) -> np.ndarray:
    """``height`` in single precision, each value the least float32 at or above it
    (-inf stays -inf)."""
    out = height.astype(np.float32)
    low = out.astype(np.float64) < height
    out[low] = np.nextafter(out[low], np.float32(np.inf))
    return out


def shift_max(out: np.ndarray, run: np.ndarray, a: int) -> None:
    """``out = max(out, run shifted by a rows)`` and by ``-a`` rows, in place: what
    ``np.maximum(out, np.roll(run, ±a, axis=0))`` gives where the rows rolled round are
    -inf (the height map's padding, at least ``a`` rows), without a copy of ``run``."""
    if a == 0:
        np.maximum(out, run, out=out)
        return
    np.maximum(out[a:], run[:-a], out=out[a:])
    np.maximum(out[:-a], run[a:], out=out[:-a])


def height_map(obstacle: MeshObstacle) -> HeightMap:
    """The obstacle's height map: built on first use, kept among the part's most
    recently used ones (:attr:`MeshObstacle.recent`; up to 300 MB with its dilations)."""
    mesh = obstacle.mesh
    return obstacle.recent("height map").get(obstacle, lambda: HeightMap(
        np.asarray(mesh.vertices, dtype=np.float64), np.asarray(mesh.faces, dtype=np.int64)))


def path_segments(nodes: Sequence[ir.Node], r: float, clear: float) -> list[Segment] | None:
    """The segments :func:`check_program` sweeps for ``nodes`` (plain coordinates, no
    frames), or None for anything else or anything it would refuse."""
    pos: np.ndarray | None = None
    touch_start: np.ndarray | None = None
    out: list[Segment] = []
    for node in nodes:
        if isinstance(node, ir.Move):
            if any(isinstance(c, ir.Var) for c in node.target):
                return None
            target = np.array(node.target, dtype=np.float64)
            if node.mode is ir.MoveMode.RETRACT:
                if touch_start is None or not _same(target, touch_start):
                    return None
            elif pos is not None:
                out.append((pos, target))
            pos, touch_start = target, None
        elif isinstance(node, ir.Touch):
            if any(isinstance(c, ir.Var) for c in node.contact):
                return None
            contact = np.array(node.contact, dtype=np.float64)
            n = np.array(node.normal)
            start = contact + (r + node.approach) * n
            if pos is None or not _same(pos, start):
                return None
            out.append((start, touch_check_stop(node, contact, r, clear, 0.0)))
            touch_start = start
        else:
            return None
    return out


def _same(p: np.ndarray, q: np.ndarray) -> bool:
    """``np.allclose(p, q, atol=1e-9)`` as the exact check tests it, for 3-vectors."""
    return bool(np.all(np.abs(p - q) <= 1e-9 + 1e-5 * np.abs(q)))


class _Swept:
    """Whether swept stylus parts stay ``q`` clear of the mesh: python-fcl collision
    tests of the swept volumes grown by ``q`` (a capsule grown by ``q`` is exactly the
    set within ``q`` of the swept ball; a cylinder grown by ``q`` in radius and at both
    ends contains the set within ``q`` of it)."""

    def __init__(self, obstacle: MeshObstacle, stylus: Stylus, q: float) -> None:
        self.obstacle, self.stylus, self.q = obstacle, stylus, q
        self.cache: dict[tuple[Any, ...], bool] = {}
        self.request = obstacle.fcl.CollisionRequest()

    def _free(self, shape: Any, centre: np.ndarray, axis: np.ndarray) -> bool:
        fcl = self.obstacle.fcl
        z = axis / np.linalg.norm(axis)
        # any unit x square to z (z × e_x, or z × e_y near the x axis), y = z × x
        x = (np.array([0.0, z[2], -z[1]]) if abs(z[0]) < 0.9
             else np.array([-z[2], 0.0, z[0]]))
        x /= np.linalg.norm(x)
        y = np.array([z[1] * x[2] - z[2] * x[1], z[2] * x[0] - z[0] * x[2],
                      z[0] * x[1] - z[1] * x[0]])
        rot = np.column_stack([x, y, z])
        obj = fcl.CollisionObject(shape, fcl.Transform(rot, centre))
        return not fcl.collide(obj, self.obstacle.part, self.request, fcl.CollisionResult())

    def ball(self, a: np.ndarray, b: np.ndarray) -> bool:
        """The ball swept from ``a`` to ``b`` (a capsule) stays ``q`` clear."""
        key = ("ball", *sorted((tuple(a), tuple(b))))
        if key not in self.cache:
            fcl, axis = self.obstacle.fcl, b - a
            length = float(np.linalg.norm(axis))
            radius = self.stylus.ball + self.q
            shape = fcl.Capsule(radius, length) if length > 0.0 else fcl.Sphere(radius)
            self.cache[key] = self._free(shape, (a + b) / 2.0,
                                         axis if length > 0.0 else np.array([0, 0, 1.0]))
        return self.cache[key]

    def shank(self, a: np.ndarray, b: np.ndarray) -> bool:
        """The shank swept from ``a`` to ``b`` stays ``q`` clear: exact for a vertical
        segment, else tested as a vertical cylinder containing the sweep."""
        return self.cylinder(a, b, 0)

    def body(self, a: np.ndarray, b: np.ndarray) -> bool:
        """The probe body swept from ``a`` to ``b`` stays ``q`` clear (as the shank)."""
        return all(self.cylinder(a, b, k) for k in range(1, len(self.stylus.cylinders())))

    def cylinder(self, a: np.ndarray, b: np.ndarray, k: int) -> bool:
        """Cylinder ``k`` of the stylus (:meth:`Stylus.cylinders`: 0 the shank, 1 the
        body) swept from ``a`` to ``b`` stays ``q`` clear."""
        key = (f"cylinder{k}", *sorted((tuple(a), tuple(b))))
        if key not in self.cache:
            radius, low, high = self.stylus.cylinders()[k]
            q = self.q
            bottom = min(a[2], b[2]) + low - q
            top = max(a[2], b[2]) + high + q
            widen = float(np.hypot(*(b[:2] - a[:2]))) / 2.0
            mid = (a + b) / 2.0
            centre = np.array([mid[0], mid[1], (bottom + top) / 2.0])
            shape = self.obstacle.fcl.Cylinder(radius + widen + q, top - bottom)
            self.cache[key] = self._free(shape, centre, np.array([0.0, 0.0, 1.0]))
        return self.cache[key]


def clear_paths(paths: Sequence[Sequence[ir.Node]], obstacle: Obstacle, setup: ir.Setup,
                machine: MachineProfile) -> np.ndarray:
    """For each path: True when the fast check clears every move of it (the exact check
    would too); False when unsure (check it exactly).  Paths are checked on their own,
    as :func:`check_program` checks ``ir.Program(setup, path)`` with no located features.
    """
    r = setup.ball_diameter / 2.0
    clear = machine.margin / 2.0
    stylus = probe_stylus(machine, r)
    return clear_segments([path_segments(p, r, clear) for p in paths], obstacle, stylus,
                          clear)


def clear_segments(segments: Sequence[Sequence[Segment] | None], obstacle: Obstacle,
                   stylus: Stylus, clear: float) -> np.ndarray:
    """For each path given by its segments (None: unsure): True when the fast check
    clears every segment with the required clearance ``clear`` (mm), the first one
    starting outside the part; False when unsure.  Cleared segments go into the
    obstacle's sweep cache."""
    result = np.zeros(len(segments), dtype=bool)
    if not isinstance(obstacle, MeshObstacle) or not segments:
        return result
    r = stylus.ball
    q = clear + MESH_TOLERANCE + MIN_STEP / 2.0 + FCL_SLACK
    flat = [(k, a, b) for k, segs in enumerate(segments) if segs for a, b in segs]
    if not flat:
        return result
    owner = np.array([k for k, _, _ in flat])
    a = np.array([s[1] for s in flat])
    b = np.array([s[2] for s in flat])
    hmap = height_map(obstacle)
    low = np.minimum(a[:, 2], b[:, 2])
    both = hmap.highest_along(a, b, max(stylus.ball, stylus.shank) + q) <= low - r - q
    shank = both | (hmap.highest_along(a, b, stylus.shank + q) <= low + r - q)
    body = np.ones(len(flat), dtype=bool)  # every mesh point near the body lies below it
    for radius, bottom, _ in stylus.cylinders()[1:]:
        body &= hmap.highest_along(a, b, radius + q) <= low + bottom - q
    above = hmap.highest_along(a, a, 0.0) < a[:, 2]
    table = obstacle.table
    off_table = np.ones(len(flat), dtype=bool)  # the table (exact) clears by q too
    if table is not None:
        elements: list[tuple[float, float | None, float | None]] = [(r, None, None)]
        elements += list(stylus.cylinders())
        off_table[:] = [min(table.swept(a[i], b[i], radius, lo, hi)
                            for radius, lo, hi in elements) >= q for i in range(len(flat))]
    swept = _Swept(obstacle, stylus, q)
    ok = np.ones(len(segments), dtype=bool)
    ok[[k for k, segs in enumerate(segments) if not segs]] = False
    first = np.ones(len(flat), dtype=bool)
    first[1:] = owner[1:] != owner[:-1]
    for i in range(len(flat)):
        k = owner[i]
        if not ok[k]:
            continue
        # a start inside the part: the exact check refuses; ends of cleared segments are
        # outside (a cleared sweep never meets the surface)
        if (first[i] and not above[i]) or not off_table[i]:
            ok[k] = False
        elif not both[i]:
            ok[k] = swept.ball(a[i], b[i]) and (bool(shank[i]) or swept.shank(a[i], b[i]))
        if ok[k] and not body[i]:
            ok[k] = swept.body(a[i], b[i])
        if ok[k]:
            _remember(obstacle, a[i], b[i], stylus, clear)
    result[:] = ok
    return result


def _remember(obstacle: MeshObstacle, a: np.ndarray, b: np.ndarray, stylus: Stylus,
              clear: float) -> None:
    """Record a cleared segment in the obstacle's sweep cache under the key the exact
    check uses, so checking the whole program again does not sweep it: with the
    clearances proven (``clear + FCL_SLACK`` for ball and shank, lower bounds of what
    sphere tracing would report); an exact result already there is kept."""
    key = ((float(a[0]), float(a[1]), float(a[2])), (float(b[0]), float(b[1]), float(b[2])),
           0.0, 0.0, stylus, clear)
    bound = clear + FCL_SLACK
    obstacle.sweeps.setdefault(key, (bound, bound, a))
