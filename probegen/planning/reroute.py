"""Make a planned revolved feature safe: reroute around what the collision check finds.

:func:`probegen.planning.revolved.plan_feature` builds the M2 path from the geometry of
the feature alone.  Here every move of that path is swept against the whole part
(:class:`Sweeper`: ball and shank, the program check's
required clearance) and the path is rebuilt from what clears:

1. *Stations*: each touch with its safe point.  A touch whose approach does not clear
   is dropped (only that touch).
2. *Legs*: between consecutive kept stations the planned moves (safe-circle
   transitions, axial links, and the safe points of dropped touches passed through);
   when they do not clear, or go by the clearance level (between arcs or sections that
   do not reach each other), a lift over what is in the way (:meth:`Sweeper.lift`: up,
   across at the lowest local height the collision check clears, down) or to the
   clearance level; when nothing clears, the stations fall into separate *runs*.
3. *Access*: a station can be entered or left straight along Z from the clearance
   level when that move clears.  A run is entered at its first station with access,
   goes back to its start, along to its end and back to its last station with access
   (out-and-back only where the ends lack access); a run with no access at all is
   dropped.  Runs are joined by a lift from the end of one to the start of the next
   where one clears (:meth:`Sweeper.lift`), else at the clearance level.

The result keeps every touch that can be made safe; :class:`RerouteError` (a
``CollisionError``) names the feature, the move and the obstacle face when none can.
Paths that cleared unchanged come back unchanged (byte-identical programs).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from itertools import pairwise

import numpy as np
from numpy.typing import ArrayLike

from probegen.errors import CollisionError
from probegen.machine.profile import MachineProfile
from probegen.planning.collision import (
    MESH_TOLERANCE,
    MIN_STEP,
    MeshObstacle,
    Obstacle,
    describe,
    fmt,
    probe_stylus,
    swept,
    touch_stop,
)
from probegen.planning.heightmap import FCL_SLACK, clear_segments, height_map
from probegen.planning.revolved import FeaturePlan, PathKind, PathPoint, path_length
from probegen.planning.text import Text

Vec3 = tuple[float, float, float]


LAZY = True
"""Whether :meth:`Sweeper.move` describes a refused move only when its text is read
(:class:`Text`); the same texts either way (``benchmarks/bench_lazy_refusals.py`` times
both)."""


LIFT_HEIGHTS = (5.0, 15.0)
"""Lift heights tried, mm above the higher end of a link, after the local height (or
instead of it when the obstacle has no mesh) and before the clearance level."""
LIFT_STEP = 0.5
"""Local heights are rounded up to this, mm (tidy coordinates in the program)."""


class Sweeper:
    """Clears single moves of a path being planned, before the program exists.

    Every answer is the check ``check_program`` makes of the same move (the same
    required clearance, half the machine's margin, and the same memo of sweeps), so a
    path built only of moves cleared here passes the program's check; a path is taken
    as outside the part because it is joined to the clearance plane by cleared moves.
    """

    def __init__(self, obstacle: Obstacle, machine: MachineProfile, ball: float) -> None:
        self.obstacle = obstacle
        self.stylus = probe_stylus(machine, ball)
        self.required = machine.margin / 2.0
        self.feeds = machine.feeds

    def move(self, a: ArrayLike, b: ArrayLike, *, touch: bool = False) -> Text | None:
        """None when the straight move ``a → b`` (mm) clears, else what it runs into,
        described when first read (:class:`Text`; ``touch``: the move is a touch, see
        :func:`swept`)."""
        pa, pb = np.array(a, dtype=np.float64), np.array(b, dtype=np.float64)
        ball, shank, worst = swept(self.obstacle, pa, pb, 0.0, 0.0, self.stylus,
                                   self.required, first=True, bound=not touch)
        if min(ball, shank) - self.required >= 0.0:
            return None
        q, obstacle, stylus, at = self.required, self.obstacle, self.stylus, np.array(worst)
        text = Text(lambda: f"from {fmt(pa)} to {fmt(pb)}: "
                    f"{describe(obstacle, ball - q, shank - q, q, at, stylus, pb)}")
        if not LAZY:
            str(text)
        return text

    def refused(self, a: ArrayLike, b: ArrayLike) -> bool:
        """True when the check certainly refuses the move ``a → b``: the ball swept along
        it (a capsule) comes within ``required + MESH_TOLERANCE - MIN_STEP/2`` (less
        fcl's slack) of the mesh, so a sample of the sweep lies closer than the check
        accepts (a python-fcl collision test, far cheaper than the sweep it saves).
        False when unsure."""
        if not isinstance(self.obstacle, MeshObstacle):
            return False
        fcl = self.obstacle.fcl
        pa, pb = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
        length = float(np.linalg.norm(pb - pa))
        radius = self.stylus.ball + self.required + MESH_TOLERANCE - MIN_STEP / 2 - FCL_SLACK
        if length < 1e-9:
            shape, rot = fcl.Sphere(radius), np.eye(3)
        else:
            shape = fcl.Capsule(radius, length)
            rot = _onto((pb - pa) / length)
        obj = fcl.CollisionObject(shape, fcl.Transform(rot, (pa + pb) / 2.0))
        return bool(fcl.collide(obj, self.obstacle.part, fcl.CollisionRequest(),
                                fcl.CollisionResult()))

    def path(self, points: Sequence[ArrayLike]) -> Text | None:
        """None when every move of the polyline clears, else the first collision (the
        height map's fast check first: :func:`probegen.planning.heightmap.clear_segments`,
        then the exact sweeps)."""
        ends = [np.asarray(p, dtype=np.float64) for p in points]
        if clear_segments([list(pairwise(ends))], self.obstacle, self.stylus,
                          self.required)[0]:
            return None
        for a, b in zip(points[:-1], points[1:], strict=True):
            why = self.move(a, b)
            if why is not None:
                return why
        return None

    def local_height(self, a: Vec3, b: Vec3) -> float | None:
        """The lowest ball-centre height (mm) at which the stylus crosses from above
        ``a`` to above ``b`` clear of the part by the required distance, from the part's
        height map (an upper bound of the mesh within the ball's and shank's reach of
        the segment in XY; :mod:`probegen.planning.heightmap`), rounded up to
        :data:`LIFT_STEP`; None without a mesh or with nothing under the way."""
        if not isinstance(self.obstacle, MeshObstacle):
            return None
        s = self.stylus
        q = self.required + MESH_TOLERANCE + MIN_STEP / 2.0 + FCL_SLACK
        pa, pb = np.array([a], dtype=np.float64), np.array([b], dtype=np.float64)
        top = float(height_map(self.obstacle).highest_along(pa, pb, max(s.ball, s.shank) + q)[0])
        if not math.isfinite(top):
            return None
        return math.ceil((top + s.ball + q) / LIFT_STEP) * LIFT_STEP

    def lift(self, a: Vec3, b: Vec3, ceiling: float) -> tuple[Vec3, ...] | None:
        """The points (``a`` and ``b`` included) of the lowest clear lift from ``a`` to
        ``b`` below ``ceiling`` (mm): straight up, across, straight down, at the lowest
        of the local height (:meth:`local_height`, an upper bound: the height map
        counts a triangle over its whole XY box) and :data:`LIFT_HEIGHTS` above the
        higher end that clears; None when none does.  A lift at the height of the
        higher end is a single climb or descent and the move across."""
        top = max(a[2], b[2])
        local = self.local_height(a, b)
        heights = {top + h for h in LIFT_HEIGHTS}
        if local is not None:
            heights = {z for z in heights if z < local} | {max(local, top)}
        for z in sorted(heights):
            if z >= ceiling:
                break
            points = lift_points(a, b, z)
            if not any(self.refused(p, q) for p, q in pairwise(points)) and (
                    self.path(points) is None):
                return points
        return None

    def touch(self, contact: ArrayLike, normal: ArrayLike,
              approach: float) -> Text | None:
        """None when a touch from ``approach`` mm off the contact clears (as checked in
        the program: up to the stop short of the contact), else what it runs into."""
        c, n = np.asarray(contact, dtype=np.float64), np.asarray(normal, dtype=np.float64)
        r = self.stylus.ball
        return self.move(c + (r + approach) * n, touch_stop(c, n, r, self.required),
                         touch=True)


def _onto(z: np.ndarray) -> np.ndarray:
    """A rotation (columns x, y, z) taking +Z onto the unit vector ``z``."""
    x = np.array([0.0, z[2], -z[1]]) if abs(z[0]) < 0.9 else np.array([-z[2], 0.0, z[0]])
    x /= math.sqrt(float(x @ x))
    y = np.array([z[1] * x[2] - z[2] * x[1], z[2] * x[0] - z[0] * x[2],
                  z[0] * x[1] - z[1] * x[0]])
    return np.column_stack([x, y, z])


def lift_points(a: Vec3, b: Vec3, z: float) -> tuple[Vec3, ...]:
    """``a``, above ``a`` at ``z``, above ``b`` at ``z``, ``b``; without the repeated
    point where an end lies at ``z``."""
    points = [a, (a[0], a[1], z), (b[0], b[1], z), b]
    return tuple(p for k, p in enumerate(points) if k == 0 or p != points[k - 1])


class RerouteError(CollisionError):
    """No touch of a feature can be reached by moves that clear the part."""


@dataclass(frozen=True, slots=True)
class Station:
    """One touch of the plan: its safe point and its target (the ball at contact)."""

    safe: PathPoint
    target: PathPoint


@dataclass(frozen=True, slots=True)
class Rerouted:
    """A feature plan after the reroute, with what was changed.

    Attributes:
        plan: the safe plan (touches renumbered from 1 in measuring order).
        dropped: touch indices of the input plan that were left out.
        notes: one line per change (dropped touches, lifts, split runs), with the
            collision that forced it (:class:`Text`: ``str`` of each reads it).
        first_drop: the first of the notes that drops touches (``""`` when none does).
    """

    plan: FeaturePlan
    dropped: tuple[int, ...]
    notes: tuple[Text | str, ...]
    first_drop: Text | str = ""


def _stations(plan: FeaturePlan) -> tuple[list[Station], list[list[PathPoint]]]:
    """The plan's stations in order and the points between consecutive ones."""
    stations: list[Station] = []
    legs: list[list[PathPoint]] = []
    between: list[PathPoint] = []
    path = plan.path
    k = 1
    while k < len(path) - 1:
        p = path[k]
        if p.kind is PathKind.SAFE and path[k + 1].kind is PathKind.TARGET:
            if stations:
                legs.append(between)
            stations.append(Station(p, path[k + 1]))
            between = []
            k += 3
            continue
        between.append(p)
        k += 1
    return stations, legs


def _pass(p: PathPoint) -> PathPoint:
    """A safe point passed through without touching."""
    return replace(p, kind=PathKind.TRANSITION, index=0)


def _at(p: PathPoint, z: float, kind: PathKind) -> PathPoint:
    return PathPoint(kind, (p.position[0], p.position[1], z))


class _Router:
    """Clears stations, legs and accesses of one plan (memoised per plan)."""

    def __init__(self, plan: FeaturePlan, sweeper: Sweeper) -> None:
        self.plan, self.sweeper = plan, sweeper
        self.stations, self.legs = _stations(plan)
        self.notes: list[Text | str] = []
        self.first_drop: Text | str = ""
        self._access: dict[int, Text | None] = {}

    def drop(self, note: Text) -> None:
        """Note touches dropped (the first such note is :attr:`Rerouted.first_drop`)."""
        self.notes.append(note)
        self.first_drop = self.first_drop or note

    def _positions(self, points: Sequence[PathPoint]) -> list[tuple[float, float, float]]:
        return [p.position for p in points]

    def touch_ok(self, k: int) -> Text | None:
        s = self.stations[k]
        section = self.plan.sections[s.safe.section]
        assert s.target.contact is not None and s.target.normal is not None
        return self.sweeper.touch(s.target.contact, s.target.normal, section.retract)

    def access(self, k: int) -> Text | None:
        """None when station ``k`` is reached straight down from the clearance level."""
        if k not in self._access:
            safe = self.stations[k].safe
            high = _at(safe, self.plan.clear_z, PathKind.CLEAR)
            self._access[k] = self.sweeper.move(high.position, safe.position)
        return self._access[k]

    def leg(self, a: int, b: int) -> tuple[list[PathPoint] | None, Text | str]:
        """The points strictly between stations ``a < b`` that clear, or None and why."""
        planned: list[PathPoint] = []
        for k in range(a, b):
            if k > a:
                planned.append(_pass(self.stations[k].safe))
            planned += self.legs[k]
        sa, sb = self.stations[a].safe, self.stations[b].safe
        why = self.sweeper.path(self._positions([sa, *planned, sb]))
        clear = self.plan.clear_z
        if why is None and not any(p.kind is PathKind.CLEAR for p in planned):
            return planned, ""
        points = self.sweeper.lift(sa.position, sb.position, clear)
        if why is None and (points is None or path_length(points) >= path_length(
                self._positions([sa, *planned, sb]))):
            return planned, ""
        if points is not None:
            lift = [PathPoint(PathKind.LIFT, q) for q in points[1:-1]]
            top = max(q[2] for q in points)
            self.notes.append(Text.format(
                "touches {}-{}: lifted to z = {:.3f}, {}{}", sa.index, sb.index, top,
                "not by the clearance level" if why is None else "the planned move ",
                "" if why is None else why))
            return lift, ""
        lift = [_at(sa, clear, PathKind.CLEAR), _at(sb, clear, PathKind.CLEAR)]
        if self.sweeper.path(self._positions([sa, *lift, sb])) is None:
            return lift, ""
        return None, why or ""


def _runs(router: _Router, kept: list[int]) -> list[list[tuple[int, list[PathPoint]]]]:
    """Kept stations split where no leg clears: per run ``(station, leg to it)``."""
    runs: list[list[tuple[int, list[PathPoint]]]] = []
    for k in kept:
        if runs:
            leg, why = router.leg(runs[-1][-1][0], k)
            if leg is not None:
                runs[-1].append((k, leg))
                continue
            i, j = router.stations[runs[-1][-1][0]].safe.index, router.stations[k].safe.index
            router.notes.append(Text.format(
                "touches {} and {}: no clear move between them ({}); left by the clearance "
                "level", i, j, why))
        runs.append([(k, [])])
    return runs


def _walk(router: _Router, run: list[tuple[int, list[PathPoint]]],
          entry: int, exit_: int) -> list[PathPoint]:
    """Points of one run from station ``entry`` (position in the run) back to its start,
    along to its end and back to ``exit_``; each station touched on its first visit."""
    stations = router.stations
    out: list[PathPoint] = []
    seen: set[int] = set()

    def visit(j: int) -> None:
        k = run[j][0]
        if k in seen:
            out.append(_pass(stations[k].safe))
        else:
            seen.add(k)
            out.extend((stations[k].safe, stations[k].target, stations[k].safe))

    visit(entry)
    for j in range(entry - 1, -1, -1):
        out += reversed(run[j + 1][1])
        visit(j)
    for j in range(1, len(run)):
        out += run[j][1]
        visit(j)
    for j in range(len(run) - 1, exit_, -1):
        out += reversed(run[j][1])
        visit(j - 1)
    return out


def reroute(plan: FeaturePlan, sweeper: Sweeper) -> Rerouted:
    """The safe version of ``plan`` (see the module docstring).

    Raises:
        RerouteError: no touch of the feature can be made safe (names the first move
            that refused each touch).
    """
    router = _Router(plan, sweeper)
    stations = router.stations
    kept: list[int] = []
    dropped: list[int] = []
    for k in range(len(stations)):
        why = router.touch_ok(k)
        if why is None:
            kept.append(k)
        else:
            dropped.append(k)
            router.drop(Text.format("touch {} dropped: its approach {}",
                                    stations[k].safe.index, why))
    pieces: list[list[PathPoint]] = []
    for run in _runs(router, kept):
        open_ = [j for j, (k, _) in enumerate(run) if router.access(k) is None]
        if not open_:
            first = stations[run[0][0]].safe.index
            last = stations[run[-1][0]].safe.index
            descent = router.access(run[0][0])
            router.drop(Text.format(
                "touches {}-{} dropped: no clear way down from the clearance level (the "
                "descent {})", first, last, descent))
            dropped += [k for k, _ in run]
            continue
        pieces.append(_walk(router, run, open_[0], open_[-1]))
    if not pieces:
        notes = tuple(router.notes)
        raise RerouteError(Text(lambda: f"feature {plan.feature}: no touch can be reached "
                                "safely: " + "; ".join(map(str, notes))))
    safe = _assemble(plan, pieces, sweeper)
    return Rerouted(plan if safe.path == plan.path else safe, tuple(sorted(
        stations[k].safe.index for k in dropped)), tuple(router.notes), router.first_drop)


def _assemble(plan: FeaturePlan, pieces: list[list[PathPoint]],
              sweeper: Sweeper) -> FeaturePlan:
    """Entry, the runs joined by a lift or at the clearance level, exit; touches
    renumbered."""
    z = plan.clear_z
    path: list[PathPoint] = [_at(pieces[0][0], z, PathKind.ENTRY)]
    for j, piece in enumerate(pieces):
        if j:
            lift = sweeper.lift(path[-1].position, piece[0].position, z)
            path += ([PathPoint(PathKind.LIFT, q) for q in lift[1:-1]] if lift is not None
                     else [_at(path[-1], z, PathKind.CLEAR), _at(piece[0], z, PathKind.CLEAR)])
        path += piece
    path.append(_at(path[-1], z, PathKind.EXIT))
    order = [p.index for p in path if p.kind is PathKind.TARGET]
    new = {old: k for k, old in enumerate(order, start=1)}
    numbered = tuple(replace(p, index=new[p.index]) if p.index else p for p in path)
    return replace(plan, path=numbered)
