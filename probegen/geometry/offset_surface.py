"""Theoretical ball centres: guide lines meet the surface offset by the ball radius (M3).

A ball of radius ``r`` that touches a surface ``S(u, v)`` at ``S`` has its centre at
``S + r·n`` (``n`` the unit normal on the ball's side).  Its centre moving along a guide
line ``o + t·d`` first touches where the line meets that *offset surface*; so the
theoretical ball centre of a guide point is the solution ``(u, v, t)`` of

    F(u, v, t) = S(u, v) + r·n(u, v) − o − t·d = 0.

Newton's method with the exact Jacobian ``J = [S_u + r·n_u, S_v + r·n_v, −d]``, the normal's
derivatives from the Weingarten equations (first fundamental form ``E, F, G``, second
``L, M, N`` taken with the signed normal):

    n_u = ((M·F − L·G)·S_u + (L·F − M·E)·S_v) / (E·G − F²)
    n_v = ((N·F − M·G)·S_u + (M·F − N·E)·S_v) / (E·G − F²)

Both offset tangents are orthogonal to ``n``, so the 3×3 step splits exactly: ``δt`` from
the normal component, ``(δu, δv)`` from cross products in the tangent plane.  The
denominator ``(A × B)·n`` with ``A, B`` the offset tangents equals
``s·(1 − r·κ₁)(1 − r·κ₂)·|S_u × S_v|`` (``s`` = ``normal_sign``, ``κ`` the principal
curvatures, negative where the surface bends away from the ball): it vanishes where the
offset folds, i.e. where ``r`` reaches the radius of curvature on the concave side.
There the offset surface is locally self-intersecting, no ball of radius ``r`` touches
the surface at one point, and the solver says so.

Conventions: lengths in mm in the part frame; ``n = sign·(S_u × S_v)/|S_u × S_v|`` with
``normal_sign`` ±1 chosen by the caller so that ``n`` points out of the material (towards
the ball).  Only the *local* fold is detected; whether the ball touches another, distant
part of the surface first is the collision check's business (planning/collision.py).
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import IntEnum
from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike

from probegen.errors import PlanningError
from probegen.geometry.frames import FloatArray

Domain = tuple[tuple[float, float], tuple[float, float]]
"""``((u_min, u_max), (v_min, v_max))`` of a parametric surface."""

TOLERANCE = 1e-10
"""Default convergence: ``|F|`` (mm) below this.  Coordinates of a few hundred mm carry
rounding of ~1e-13 mm, so 1e-10 mm is reachable and far below the 1e-7 mm the plan needs."""

MAX_ITERATIONS = 40
"""Newton iterations before a line is declared not converging."""

TANGENT_COSINE = 1e-6
"""``|d·n|`` below this: the guide line is tangent to the offset surface (no crossing)."""

MAX_STEP = 0.25
"""Largest Newton step in ``(u, v)`` as a fraction of the domain's extent: far from the
solution a full step can jump across the face (or onto a pole of its parametrisation)."""

HALVINGS = 16
"""Step halvings before a line counts as stalled (the step is then 1.5e-5 of Newton's)."""

FOLD_MARGIN = 1e-9
"""``1 − r·κ_max`` below this: the offset is folded (self-intersecting) at the point."""


@dataclass(frozen=True, eq=False)
class SurfaceJet:
    """A surface's point and partial derivatives at ``m`` parameter pairs (all ``(m, 3)``, mm)."""

    point: FloatArray
    su: FloatArray
    sv: FloatArray
    suu: FloatArray
    suv: FloatArray
    svv: FloatArray


class ParamSurface(Protocol):
    """A parametric surface ``S(u, v)`` (mm, part frame), evaluated for many ``(u, v)`` at once."""

    @property
    def domain(self) -> Domain:
        """``((u_min, u_max), (v_min, v_max))``: where the surface is defined."""
        ...

    def evaluate(self, u: ArrayLike, v: ArrayLike) -> FloatArray:
        """Points ``S(u, v)``: ``(m,)`` u and v → ``(m, 3)`` float, mm."""
        ...

    def derivatives(self, u: ArrayLike, v: ArrayLike) -> SurfaceJet:
        """``S, S_u, S_v, S_uu, S_uv, S_vv`` at ``(m,)`` u and v, each ``(m, 3)``."""
        ...


class Status(IntEnum):
    """Outcome of one guide line."""

    OK = 0
    NO_CONVERGENCE = 1
    OUTSIDE_DOMAIN = 2
    SELF_INTERSECTING = 3
    TANGENT = 4
    DEGENERATE = 5
    BACK_SIDE = 6


@dataclass(frozen=True, slots=True)
class Differential:
    """Unit normal, its derivatives and the principal curvatures at ``m`` points.

    Attributes:
        normal: ``(m, 3)`` unit normal ``sign·(S_u × S_v)/|S_u × S_v|``.
        nu: ``(m, 3)`` ``∂n/∂u`` (Weingarten), 1/param-unit.
        nv: ``(m, 3)`` ``∂n/∂v``.
        kappa_max: ``(m,)`` larger principal curvature, 1/mm, sign convention of the module
            docstring (positive = surface bends towards the normal's side: concave).
        area: ``(m,)`` ``|S_u × S_v|``; zero at a degenerate (singular) point.
    """

    normal: FloatArray
    nu: FloatArray
    nv: FloatArray
    kappa_max: FloatArray
    area: FloatArray


def differential(jet: SurfaceJet, normal_sign: float = 1.0) -> Differential:
    """Normal, normal derivatives and largest principal curvature from a jet.

    Degenerate points (``S_u × S_v = 0``) get NaN entries and ``area == 0``.
    """
    cross = np.cross(jet.su, jet.sv)
    area = np.linalg.norm(cross, axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        n = normal_sign * cross / area[:, None]
        e, f, g = _dot(jet.su, jet.su), _dot(jet.su, jet.sv), _dot(jet.sv, jet.sv)
        ll, mm, nn = _dot(jet.suu, n), _dot(jet.suv, n), _dot(jet.svv, n)
        det = e * g - f * f
        nu = (((mm * f - ll * g) / det)[:, None] * jet.su
              + ((ll * f - mm * e) / det)[:, None] * jet.sv)
        nv = (((nn * f - mm * g) / det)[:, None] * jet.su
              + ((mm * f - nn * e) / det)[:, None] * jet.sv)
        kappa = _largest_curvature(e, f, g, ll, mm, nn)
    return Differential(n, nu, nv, kappa, area)


def _largest_curvature(e: FloatArray, f: FloatArray, g: FloatArray, ll: FloatArray,
                       mm: FloatArray, nn: FloatArray) -> FloatArray:
    """Larger eigenvalue of the shape operator, from the second fundamental form written in
    an orthonormal tangent frame (``e1 = S_u/|S_u|``), so the eigenvalues of a symmetric
    2×2 matrix come without the cancellation of ``H ± √(H² − K)`` at umbilics."""
    alpha = np.sqrt(e)
    beta = f / alpha                      # S_v · e1
    gamma = np.sqrt(e * g - f * f) / alpha  # S_v · e2
    ratio = beta / alpha
    h11 = ll / e
    h12 = (mm - ll * ratio) / (alpha * gamma)
    h22 = (nn - 2.0 * mm * ratio + ll * ratio * ratio) / (gamma * gamma)
    return np.asarray(0.5 * (h11 + h22) + np.hypot(0.5 * (h11 - h22), h12))


def _dot(a: FloatArray, b: FloatArray) -> FloatArray:
    return np.einsum("ij,ij->i", a, b)


@dataclass(frozen=True, slots=True)
class BallCentre:
    """The theoretical ball centre of one guide line.

    Attributes:
        uv: surface parameters of the contact point.
        contact: contact point ``S(u, v)``, mm.
        normal: unit normal at the contact, towards the ball.
        centre: ball centre ``o + t·d`` on the guide line, mm.
        t: distance along the guide line from its origin to the centre, mm.
        iterations: Newton iterations used.
        residual: ``|S + r·n − o − t·d|`` at the end, mm.
    """

    uv: tuple[float, float]
    contact: tuple[float, float, float]
    normal: tuple[float, float, float]
    centre: tuple[float, float, float]
    t: float
    iterations: int
    residual: float


@dataclass(frozen=True, eq=False)
class BallCentres:
    """Ball centres of ``m`` guide lines (arrays, row ``i`` = line ``i``).

    Attributes:
        uv: ``(m, 2)``; contact: ``(m, 3)``; normal: ``(m, 3)``; centre: ``(m, 3)``;
        t: ``(m,)``; iterations: ``(m,)`` int; residual: ``(m,)`` mm;
        status: ``(m,)`` int ``Status`` codes; kappa_max: ``(m,)`` 1/mm at the last iterate.
        radius: the ball radius used, mm.
    """

    uv: FloatArray
    contact: FloatArray
    normal: FloatArray
    centre: FloatArray
    t: FloatArray
    iterations: np.ndarray
    residual: FloatArray
    status: np.ndarray
    kappa_max: FloatArray
    radius: float

    @property
    def ok(self) -> np.ndarray:
        """``(m,)`` bool: the line has a valid ball centre."""
        return np.asarray(self.status == Status.OK)

    def record(self, i: int) -> BallCentre:
        """Line ``i`` as a ``BallCentre`` (raises ``PlanningError`` if it failed)."""
        if self.status[i] != Status.OK:
            raise PlanningError(self.message(i))
        return BallCentre(
            uv=(float(self.uv[i, 0]), float(self.uv[i, 1])),
            contact=_triple(self.contact[i]), normal=_triple(self.normal[i]),
            centre=_triple(self.centre[i]), t=float(self.t[i]),
            iterations=int(self.iterations[i]), residual=float(self.residual[i]))

    def message(self, i: int) -> str:
        """What went wrong on line ``i`` (or that it is fine), with the numbers."""
        status = Status(int(self.status[i]))
        where = (f"guide line {i}: at (u, v) = ({self.uv[i, 0]:.6g}, {self.uv[i, 1]:.6g}) "
                 f"after {int(self.iterations[i])} iterations, ")
        kappa = float(self.kappa_max[i])
        texts = {
            Status.OK: "converged",
            Status.NO_CONVERGENCE: f"Newton did not converge (residual "
                                   f"{self.residual[i]:.3g} mm); seed it closer",
            Status.OUTSIDE_DOMAIN: "the line meets the offset surface outside the surface's "
                                   "parameter domain (the guide point is off the face)",
            Status.SELF_INTERSECTING: (
                f"the offset surface is locally self-intersecting: ball radius "
                f"{self.radius:.6g} mm >= radius of curvature "
                f"{(1.0 / kappa if kappa > 0 else float('inf')):.6g} mm on the concave side; "
                f"use a smaller ball"),
            Status.TANGENT: "the guide line is tangent to the offset surface",
            Status.DEGENERATE: "the surface is degenerate there (S_u x S_v = 0)",
            Status.BACK_SIDE: "the line meets the offset surface from behind (the normal "
                              "points along the travel): the seed is on the far side, or "
                              "normal_sign is wrong",
        }
        return where + texts[status]

    def raise_failures(self) -> None:
        """Raise ``PlanningError`` naming the first failed line and how many failed."""
        bad = np.flatnonzero(self.status != Status.OK)
        if len(bad):
            more = f" ({len(bad)} of {len(self.status)} lines failed)" if len(bad) > 1 else ""
            raise PlanningError(f"offset-surface intersection: {self.message(int(bad[0]))}{more}")


def _triple(a: FloatArray) -> tuple[float, float, float]:
    return (float(a[0]), float(a[1]), float(a[2]))


def ball_centre(surface: ParamSurface, origin: ArrayLike, direction: ArrayLike,
                radius: float, seed_uv: ArrayLike, *, normal_sign: float = 1.0,
                tolerance: float = TOLERANCE,
                max_iterations: int = MAX_ITERATIONS) -> BallCentre:
    """The theoretical ball centre of one guide line; see ``ball_centres``.

    Raises:
        PlanningError: no valid centre (message says why and where).
    """
    try:
        rows = (np.asarray(origin, dtype=np.float64).reshape(1, 3),
                np.asarray(direction, dtype=np.float64).reshape(1, 3),
                np.asarray(seed_uv, dtype=np.float64).reshape(1, 2))
    except (TypeError, ValueError) as exc:
        raise PlanningError(f"offset-surface intersection: expected origins (m, 3), "
                            f"directions (m, 3) or (3,), seeds (m, 2) or (2,) and a radius; "
                            f"for one line (3,), (3,), (2,); {exc}") from None
    batch = ball_centres(surface, rows[0], rows[1], radius, rows[2], normal_sign=normal_sign,
                         tolerance=tolerance, max_iterations=max_iterations)
    return batch.record(0)


def ball_centres(surface: ParamSurface, origins: ArrayLike, directions: ArrayLike,
                 radius: float, seeds: ArrayLike, *, normal_sign: float = 1.0,
                 tolerance: float = TOLERANCE, max_iterations: int = MAX_ITERATIONS,
                 strict: bool = False) -> BallCentres:
    """Intersect guide lines with the surface offset by ``radius`` (vectorised Newton).

    Args:
        surface: the nominal (or, in a simulation, the true) surface.
        origins: ``(m, 3)`` points on the guide lines, mm (e.g. the guide points).
        directions: ``(m, 3)`` or ``(3,)`` line directions (normalised here); ``t`` is
            measured along them, so the ball centre is ``origin + t·direction``.
        radius: ball radius ``r >= 0``, mm (0 gives the plain line-surface intersection).
        seeds: ``(m, 2)`` or ``(2,)`` starting ``(u, v)``, e.g. from a mesh query.
        normal_sign: +1 if ``S_u × S_v`` points towards the ball (out of the material),
            −1 otherwise.  A solution whose normal points along ``d`` (the ball would
            arrive from inside the material) is reported as ``BACK_SIDE``, never returned.
        tolerance: convergence on ``|F|``, mm.
        max_iterations: Newton iterations per line.
        strict: raise on the first failed line instead of reporting it in ``status``.

    Returns:
        ``BallCentres``; a line's status says whether and why it failed.

    Raises:
        PlanningError: malformed arguments; with ``strict``, any failed line.
    """
    o, d, seed, r = _arguments(origins, directions, seeds, radius, normal_sign)
    (u0, u1), (v0, v1) = surface.domain
    u = np.clip(seed[:, 0], u0, u1)
    v = np.clip(seed[:, 1], v0, v1)
    state = _evaluate(surface, u, v, o, d, r, normal_sign, _initial_t(surface, u, v, o, d, r,
                                                                      normal_sign))
    iterations = np.zeros(len(o), dtype=np.int64)
    active = state.norm > tolerance
    for _ in range(max_iterations):
        idx = np.flatnonzero(active & np.isfinite(state.norm))
        if not len(idx):
            break
        moved = _newton_step(surface, state, idx, o, d, r, normal_sign, (u0, u1, v0, v1))
        iterations[idx] += 1
        active[idx] = moved & (state.norm[idx] > tolerance)
    result = _finish(state, o, d, r, (u0, u1, v0, v1), iterations, tolerance)
    if strict:
        result.raise_failures()
    return result


def _arguments(origins: ArrayLike, directions: ArrayLike, seeds: ArrayLike, radius: float,
               normal_sign: float) -> tuple[FloatArray, FloatArray, FloatArray, float]:
    """Validate and broadcast the solver's arguments."""
    try:
        o = np.asarray(origins, dtype=np.float64).reshape(-1, 3)
        d = np.broadcast_to(np.asarray(directions, dtype=np.float64).reshape(-1, 3),
                            o.shape).copy()
        seed = np.broadcast_to(np.asarray(seeds, dtype=np.float64).reshape(-1, 2),
                               (len(o), 2)).copy()
        r = float(radius)
    except (TypeError, ValueError) as exc:
        raise PlanningError(f"offset-surface intersection: expected origins (m, 3), "
                            f"directions (m, 3) or (3,), seeds (m, 2) or (2,) and a radius; "
                            f"{exc}") from None
    if not (np.all(np.isfinite(o)) and np.all(np.isfinite(d)) and np.all(np.isfinite(seed))):
        raise PlanningError("offset-surface intersection: origins, directions and seeds must "
                            "be finite numbers")
    if not (np.isfinite(r) and r >= 0.0):
        raise PlanningError(f"offset-surface intersection: expected a ball radius >= 0 mm, "
                            f"found {radius!r}")
    if normal_sign not in (1.0, -1.0):
        raise PlanningError(f"offset-surface intersection: normal_sign must be +1 or -1, "
                            f"found {normal_sign!r}")
    length = np.linalg.norm(d, axis=1)
    if np.any(length == 0.0):
        raise PlanningError("offset-surface intersection: a guide-line direction is zero")
    return o, d / length[:, None], seed, r


@dataclass(frozen=True, slots=True)
class _State:
    """Mutable-by-row arrays of the iteration (the record itself is never rebound)."""

    uv: FloatArray          # (m, 2)
    t: FloatArray           # (m,)
    point: FloatArray       # (m, 3) S
    normal: FloatArray      # (m, 3)
    tan_u: FloatArray       # (m, 3) S_u + r n_u
    tan_v: FloatArray       # (m, 3) S_v + r n_v
    kappa: FloatArray       # (m,)
    area: FloatArray        # (m,)
    residual: FloatArray    # (m, 3) F
    norm: FloatArray        # (m,) |F|


def _initial_t(surface: ParamSurface, u: FloatArray, v: FloatArray, o: FloatArray,
               d: FloatArray, r: float, sign: float) -> FloatArray:
    """``t`` of the foot of the seed's offset point on each line."""
    jet = surface.derivatives(u, v)
    n = differential(jet, sign).normal
    centre = jet.point + r * np.nan_to_num(n)
    return np.asarray(_dot(centre - o, d))


def _evaluate(surface: ParamSurface, u: FloatArray, v: FloatArray, o: FloatArray,
              d: FloatArray, r: float, sign: float, t: FloatArray) -> _State:
    """Everything the next Newton step needs at ``(u, v, t)``."""
    jet = surface.derivatives(u, v)
    diff = differential(jet, sign)
    f = jet.point + r * diff.normal - o - t[:, None] * d
    norm = np.linalg.norm(f, axis=1)
    return _State(np.stack([u, v], axis=1), t.copy(), jet.point, diff.normal,
                  jet.su + r * diff.nu, jet.sv + r * diff.nv, diff.kappa_max, diff.area,
                  f, np.where(np.isfinite(norm), norm, np.inf))


def _newton_step(surface: ParamSurface, state: _State, idx: np.ndarray, o: FloatArray,
                 d: FloatArray, r: float, sign: float,
                 box: tuple[float, float, float, float]) -> np.ndarray:
    """One damped Newton step for lines ``idx``; updates ``state`` in place.

    Returns ``(len(idx),)`` bool: the line's residual decreased (False = stalled).
    """
    n, a, b, f = state.normal[idx], state.tan_u[idx], state.tan_v[idx], state.residual[idx]
    dn = _dot(d[idx], n)
    abn = _dot(np.cross(a, b), n)
    with np.errstate(divide="ignore", invalid="ignore"):
        dt = _dot(f, n) / dn
        g = f - d[idx] * dt[:, None]
        du = -_dot(np.cross(g, b), n) / abn
        dv = -_dot(np.cross(a, g), n) / abn
    step = np.stack([du, dv, dt], axis=1)
    usable = np.all(np.isfinite(step), axis=1)
    moved = np.zeros(len(idx), dtype=bool)
    with np.errstate(divide="ignore", invalid="ignore"):  # trust region in (u, v)
        lam = np.minimum(1.0, MAX_STEP * np.minimum((box[1] - box[0]) / np.abs(du),
                                                    (box[3] - box[2]) / np.abs(dv)))
    todo = usable.copy()
    for _ in range(HALVINGS):  # backtracking: halve until |F| decreases
        k = np.flatnonzero(todo)
        if not len(k):
            break
        rows = idx[k]
        u = np.clip(state.uv[rows, 0] + lam[k] * step[k, 0], box[0], box[1])
        v = np.clip(state.uv[rows, 1] + lam[k] * step[k, 1], box[2], box[3])
        trial = _evaluate(surface, u, v, o[rows], d[rows], r, sign,
                          state.t[rows] + lam[k] * step[k, 2])
        better = trial.norm < state.norm[rows]
        _assign(state, trial, rows[better], better)
        moved[k[better]] = True
        todo[k[better]] = False
        lam[k] *= 0.5
    return moved


def _assign(state: _State, trial: _State, rows: np.ndarray, mask: np.ndarray) -> None:
    """Copy the accepted rows of ``trial`` into ``state``."""
    for name in _State.__slots__:
        getattr(state, name)[rows] = getattr(trial, name)[mask]


def _finish(state: _State, o: FloatArray, d: FloatArray, r: float,
            box: tuple[float, float, float, float], iterations: np.ndarray,
            tolerance: float) -> BallCentres:
    """Classify each line and assemble the result."""
    status = np.full(len(o), Status.NO_CONVERGENCE, dtype=np.int8)
    converged = state.norm <= tolerance
    status[converged] = Status.OK
    on_edge = ((state.uv[:, 0] <= box[0]) | (state.uv[:, 0] >= box[1])
               | (state.uv[:, 1] <= box[2]) | (state.uv[:, 1] >= box[3]))
    status[~converged & on_edge] = Status.OUTSIDE_DOMAIN
    with np.errstate(invalid="ignore"):
        folded = 1.0 - r * state.kappa < FOLD_MARGIN
        facing = _dot(d, state.normal)
    status[converged & (facing > 0.0)] = Status.BACK_SIDE
    status[np.abs(facing) < TANGENT_COSINE] = Status.TANGENT
    status[folded & (r > 0.0)] = Status.SELF_INTERSECTING
    status[~(state.area > 0.0)] = Status.DEGENERATE
    centre = o + state.t[:, None] * d
    return BallCentres(uv=state.uv, contact=state.point, normal=state.normal, centre=centre,
                       t=state.t, iterations=iterations, residual=state.norm, status=status,
                       kappa_max=state.kappa, radius=r)
