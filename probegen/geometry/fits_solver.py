"""Shared machinery of the least-squares fits: input checks, normalisation, the solver.

Every fit works on *normalised* data: the points are translated to their centroid and
scaled so that their RMS distance from it is 1.  That makes the tolerances below
unit-free, keeps huge and tiny coordinates well inside double precision and conditions
the normal equations; results are mapped back to the caller's units at the end.

The iterative fits (circle, sphere, cylinder, cone, torus) use a Levenberg-Marquardt
loop in the style of the NIST Algorithm Testing System (Shakarji 1998): before each
step the data are moved into a *local frame* in which the current estimate sits at the
origin with its axis along +Z, so the Jacobian is evaluated at zero pose parameters
where it takes a short closed form.  The pose parameters are a translation
``(dx, dy, dz)`` and an axis tilt ``(a, b)`` (new axis along ``(a, b, 1)``); each model
declares which of them it uses and appends its own shape parameters (radius, angle...).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import ParamSpec, TypeVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from probegen.constants import tol
from probegen.errors import ProbegenError
from probegen.geometry.frames import rotation_to_z

FloatArray = NDArray[np.float64]
P = ParamSpec("P")
R = TypeVar("R")

#: Relative extent (normalised units) below which a principal direction of the data is
#: empty: exactly collinear / coplanar points computed in doubles give ~1e-16, while a
#: 1-degree arc of a circle still spreads ~1e-4 off its chord.
FLAT = 1e-10
#: Spread of the points, relative to their largest coordinate, below which they are
#: one point in double precision (doubles resolve ~2e-16 relative).
COINCIDENT = 1e-13
#: Smallest spread of points (input units) that can be fitted: the smallest normal double.
TINY = float(np.finfo(np.float64).tiny)
#: Smallest solver step (normalised units) treated as zero: near the resolution of
#: doubles for data scaled to 1; ``tol.fit`` (mm) is used instead when it is larger.
STEP_FLOOR = 1e-13
#: Levenberg-Marquardt damping: start, growth factor and give-up level.  The damping is
#: relative to the Jacobian's column norms (Marquardt scaling).
LAMBDA_START = 1e-6
LAMBDA_FLOOR = 1e-9
LAMBDA_GROWTH = 10.0
LAMBDA_GIVE_UP = 1e16
#: Iteration cap; Gauss-Newton from the algebraic starts converges in well under 50.
MAX_ITERATIONS = 200
#: Iterations given to each start of a multi-start fit before the best is polished.
SCOUT_ITERATIONS = 30
#: A step is accepted if it raises the sum of squares by at most this fraction: near the
#: optimum the true decrease is below the rounding of the sum (~n * 1e-16), and refusing
#: such steps would stall Gauss-Newton short of full convergence.
COST_SLACK = 1e-12
#: Above this many points a solver step solves the normal equations ``J^T J`` (a few
#: parameters) instead of a least-squares problem with one row per point: 15 times
#: faster at a million points, and as accurate while the problem is well conditioned
#: (the fits refuse a condition number above ``fits_conditioning.CONDITION_LIMIT``).
NORMAL_EQUATIONS_FROM = 20_000
#: Above this many points the starting guesses (and a multi-start's scouting) use a fixed
#: pseudo-random subset of this size; the solution found there is then polished on all
#: points.  Below it every point is used, exactly as before.
SAMPLE_SIZE = 4096


def fit_error(fit: str, expected: str, found: str) -> ProbegenError:
    """Return the error for input a fit cannot use.

    Args:
        fit: the fit's name, e.g. ``"sphere"``.
        expected: what the fit needs.
        found: what it got.
    """
    return ProbegenError(f"{fit} fit: expected {expected}, found {found}")


def guarded(fit: str) -> Callable[[Callable[P, R]], Callable[P, R]]:
    """Decorate a public fit: numpy warnings stay inside, ``LinAlgError`` becomes
    ``ProbegenError``.

    Args:
        fit: the fit's name, for messages.
    """

    def decorate(func: Callable[P, R]) -> Callable[P, R]:
        @functools.wraps(func)
        def wrapper(*args: P.args, **kwargs: P.kwargs) -> R:
            with np.errstate(all="ignore"):
                try:
                    return func(*args, **kwargs)
                except np.linalg.LinAlgError as exc:
                    raise fit_error(fit, "a solvable problem", f"{exc}") from exc

        return wrapper

    return decorate


def as_points(points: ArrayLike, *, fit: str, dim: int, minimum: int) -> FloatArray:
    """Check and normalise the input array.

    Args:
        points: ``(n, dim)`` float-like.
        fit: the fit's name, for messages.
        dim: 2 or 3.
        minimum: the least number of points the fit needs.

    Returns:
        ``(n, dim)`` float64 array.

    Raises:
        ProbegenError: wrong shape, too few points, non-numeric, NaN or inf.
    """
    try:
        arr = np.asanyarray(points, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise fit_error(fit, f"an (n, {dim}) array of numbers", f"{exc}") from exc
    if arr.ndim != 2 or arr.shape[1] != dim:
        raise fit_error(fit, f"an (n, {dim}) array of points", f"shape {arr.shape}")
    if arr.shape[0] < minimum:
        raise fit_error(fit, f"at least {minimum} points", f"{arr.shape[0]}")
    if not math.isfinite(float(np.sum(arr))):  # a NaN or inf makes the sum non-finite
        bad = np.flatnonzero(~np.all(np.isfinite(arr), axis=1))
        if bad.size:
            raise fit_error(fit, "finite coordinates", f"{arr[bad[0]].tolist()} at row {bad[0]}")
    return np.asarray(arr)


@dataclass(frozen=True, slots=True)
class Normalised:
    """Points moved to their centroid and scaled to unit RMS distance.

    Attributes:
        points: ``(n, dim)`` normalised points, ``mean == 0``, RMS norm 1.
        centre: ``(dim,)`` centroid in input units.
        scale: input units per normalised unit.
        extents: ``(dim,)`` RMS extent of the normalised points along their principal
            directions, largest first (``sum(extents**2) == 1``).
        directions: ``(dim, dim)`` principal directions as rows, matching ``extents``.
    """

    points: FloatArray
    centre: FloatArray
    scale: float
    extents: FloatArray
    directions: FloatArray

    def to_world(self, point: FloatArray) -> FloatArray:
        """Map a normalised point, ``(dim,)``, back to input units."""
        return np.asarray(self.centre + self.scale * point, dtype=np.float64)


def normalise(points: FloatArray, *, fit: str) -> Normalised:
    """Centre and scale ``points`` (``(n, dim)``, finite) and find their principal axes.

    Raises:
        ProbegenError: all points coincide, or the coordinates are too large to scale.
    """
    big = max(-float(np.min(points)), float(np.max(points)))
    centred = points / big if big > 0.0 else points.copy()
    mean = centred.mean(axis=0)
    centred -= mean
    spread = math.sqrt(float(np.einsum("ij,ij->", centred, centred)) / len(centred))
    if not spread > COINCIDENT:
        raise fit_error(fit, "points that are not all the same point", "coincident points")
    scale, centre = spread * big, mean * big
    if not (TINY <= scale < math.inf and np.all(np.isfinite(centre))):
        raise fit_error(fit, "a spread of points within the range of doubles",
                        f"a spread of {spread * big:g}")
    q = centred
    q /= spread
    _, sv, vt = np.linalg.svd(_triangle(q), full_matrices=False)
    extents = np.zeros(points.shape[1])
    extents[: sv.size] = sv / math.sqrt(len(q))
    directions = np.eye(points.shape[1])
    directions[: vt.shape[0]] = vt
    return Normalised(q, centre, scale, extents, directions)


def _triangle(q: FloatArray) -> FloatArray:
    """Return a small matrix with the singular values and right singular vectors of
    ``q : (n, dim)``: ``q`` itself when short, else the ``R`` of its QR factorisation
    (orthogonal, so as accurate, and 3 times faster than an SVD of a million rows)."""
    if len(q) <= 4 * q.shape[1]:
        return q
    return np.asarray(np.linalg.qr(q, mode="r"), dtype=np.float64)


def subsample(points: FloatArray, size: int | None = None) -> FloatArray:
    """Return ``points`` if there are at most ``size`` (default ``SAMPLE_SIZE``), else a
    fixed pseudo-random subset of ``size`` rows (seeded, so a fit is repeatable; random,
    so a grid of points does not alias)."""
    size = SAMPLE_SIZE if size is None else size
    if len(points) <= size:
        return points
    rows = np.random.default_rng(0).choice(len(points), size=size, replace=False)
    return np.asarray(points[np.sort(rows)])


def require_rank(data: Normalised, rank: int, *, fit: str, expected: str) -> None:
    """Raise unless the normalised points span ``rank`` dimensions.

    Args:
        data: normalised points.
        rank: 2 (not collinear) or 3 (not coplanar).
        fit: the fit's name.
        expected: the phrase for the message, e.g. ``"points not all coplanar"``.
    """
    extent = float(data.extents[rank - 1])
    if not extent > FLAT:
        shape = "collinear" if rank == 2 else "coplanar"
        raise fit_error(fit, expected, f"{shape} points (relative extent {extent:.1e})")


def canonical(direction: FloatArray) -> FloatArray:
    """Return ``direction`` with the sign that makes its largest-magnitude component
    positive (the first such component on a tie)."""
    k = int(np.argmax(np.abs(direction)))
    return -direction if direction[k] < 0.0 else direction


def summary(fit: str, residuals: FloatArray) -> tuple[tuple[float, ...], float, float]:
    """Return ``(residuals as floats, rms, max - min)`` for ``residuals : (n,)``.

    Raises:
        ProbegenError: a statistic overflows (coordinates near the double range).
    """
    big = float(np.max(np.abs(residuals)))
    rms = big * math.sqrt(float(np.mean(np.square(residuals / big)))) if big > 0.0 else 0.0
    form = float(np.max(residuals) - np.min(residuals))
    check_finite(fit, residuals, rms, form)
    return tuple(residuals.tolist()), rms, form


def vec2(v: FloatArray) -> tuple[float, float]:
    """Return a ``(2,)`` array as a tuple of Python floats."""
    return float(v[0]), float(v[1])


def vec3(v: FloatArray) -> tuple[float, float, float]:
    """Return a ``(3,)`` array as a tuple of Python floats."""
    return float(v[0]), float(v[1]), float(v[2])


def check_finite(fit: str, *values: float | FloatArray) -> None:
    """Raise unless every value is finite (the solver failed on degenerate data)."""
    if not all(np.all(np.isfinite(v)) for v in values):
        raise fit_error(fit, "points that determine the shape", "a non-finite solution")


# ---------------------------------------------------------------------------- solver


@dataclass(frozen=True, slots=True)
class Pose:
    """A local frame: ``local = (points - origin) @ rot.T``.

    Attributes:
        origin: ``(3,)`` the frame's origin in normalised coordinates.
        rot: ``(3, 3)`` rows ``(e1, e2, axis)``.
    """

    origin: FloatArray
    rot: FloatArray

    @property
    def axis(self) -> FloatArray:
        """The frame's third axis, ``(3,)``."""
        return np.asarray(self.rot[2], dtype=np.float64)

    def local(self, points: FloatArray) -> FloatArray:
        """Return ``points : (n, 3)`` in this frame, ``(n, 3)``."""
        # einsum: a (n, 3) @ (3, 3) product through BLAS is several times slower
        local = np.einsum("ij,kj->ik", points, self.rot)
        local -= self.rot @ self.origin
        return np.asarray(local)


LocalFn = Callable[[FloatArray, FloatArray], FloatArray]

#: Names of the pose parameters ``(dx, dy, dz, a, b)`` in messages.
POSE_NAMES = ("position", "position", "position", "axis direction", "axis direction")


@dataclass(frozen=True, slots=True)
class Model:
    """A shape for the solver, described in its local frame (axis +Z through origin).

    Attributes:
        name: the fit's name.
        dofs: which pose parameters of ``(dx, dy, dz, a, b)`` the shape uses.
        residuals: ``(q : (n, 3) local points, shape : (k,)) -> (n,)`` signed distances.
        jacobian: same arguments ``-> (n, len(dofs) + k)`` derivatives of the residuals
            with respect to the used pose parameters (at zero) and the shape parameters.
    """

    name: str
    dofs: tuple[int, ...]
    residuals: LocalFn
    jacobian: LocalFn
    shape_names: tuple[str, ...] = ("radius",)
    angular: tuple[str, ...] = ()

    @property
    def names(self) -> tuple[str, ...]:
        """Names of all solver parameters: the used pose parameters, then the shape's."""
        return tuple(POSE_NAMES[d] for d in self.dofs) + self.shape_names

    def is_angle(self, index: int) -> bool:
        """True if parameter ``index`` (see ``names``) is an angle (radians)."""
        if index < len(self.dofs):
            return self.dofs[index] >= 3
        return self.names[index] in self.angular


@dataclass(frozen=True, slots=True)
class Solution:
    """Solver output in normalised units: pose, shape parameters, residuals, cost, and
    the Jacobian at the solution when the solver computed it there (else None)."""

    pose: Pose
    shape: FloatArray
    residuals: FloatArray
    cost: float
    jacobian: FloatArray | None = None


def inverse(values: FloatArray) -> FloatArray:
    """Return ``1 / values`` for ``values >= 0``, with 0 where ``values`` is 0."""
    if float(np.min(values, initial=1.0)) > 0.0:  # the usual case, twice as fast
        return np.asarray(1.0 / values)
    return np.divide(1.0, values, out=np.zeros_like(values), where=values > 0.0)


def columns(n: int, *cols: FloatArray | float) -> FloatArray:
    """Return the ``(n, k)`` matrix with columns ``cols`` (arrays ``(n,)`` or constants),
    stored column by column: each column is one contiguous write."""
    out = np.empty((n, len(cols)), order="F")
    for k, col in enumerate(cols):
        out[:, k] = col
    return out


def norms(q: FloatArray) -> FloatArray:
    """Return the Euclidean norm of each row of ``q : (n, k)``, ``(n,)``."""
    return np.sqrt(np.einsum("ij,ij->i", q, q))


def _moved(pose: Pose, step: FloatArray, dofs: tuple[int, ...]) -> Pose:
    """Apply the pose part of a solver step (local coordinates) to ``pose``."""
    full = np.zeros(5)
    full[list(dofs)] = step
    origin = pose.origin + pose.rot.T @ full[:3]
    if full[3] == 0.0 and full[4] == 0.0:
        return Pose(origin, pose.rot)
    axis = pose.rot.T @ np.array([full[3], full[4], 1.0])
    return Pose(origin, rotation_to_z(axis))


class _Step:
    """The linearised problem at one solver iterate, solved for any damping.

    Computed once per Jacobian: a rejected step only changes the damping.  Few points:
    the damped least-squares problem itself; many: its normal equations.
    """

    def __init__(self, jac: FloatArray, res: FloatArray) -> None:
        self.jac, self.res = jac, res
        self.normal = len(jac) > NORMAL_EQUATIONS_FROM
        if self.normal:
            self.gram = jac.T @ jac
            self.rhs = -(jac.T @ res)
            self.norms2 = np.diag(self.gram).copy()
        else:
            self.norms2 = np.einsum("ij,ij->j", jac, jac)

    def solve(self, lam: float) -> FloatArray:
        """Solve ``min |J s + r|^2 + lam |D s|^2`` (``D`` = column norms of ``J``)."""
        if self.normal:
            lhs = self.gram + np.diag(lam * self.norms2)
            return np.asarray(np.linalg.solve(lhs, self.rhs), dtype=np.float64)
        lhs = np.vstack([self.jac, np.diag(math.sqrt(lam) * np.sqrt(self.norms2))])
        rhs = np.concatenate([-self.res, np.zeros(self.jac.shape[1])])
        step: FloatArray = np.linalg.lstsq(lhs, rhs, rcond=None)[0]
        return step


def refine(model: Model, points: FloatArray, pose: Pose, shape: FloatArray, *,
           step_tol: float, iterations: int = MAX_ITERATIONS) -> Solution:
    """Levenberg-Marquardt from ``(pose, shape)`` on normalised ``points : (n, 3)``.

    Stops when a step is below ``step_tol`` (normalised units and radians), when the
    damping reaches ``LAMBDA_GIVE_UP`` (no descent left in double precision) or after
    ``iterations`` steps.
    """
    m = len(model.dofs)
    q = pose.local(points)
    res = model.residuals(q, shape)
    cost, lam = float(res @ res), LAMBDA_START
    linear: _Step | None = None
    for _ in range(iterations):
        linear = linear or _Step(model.jacobian(q, shape), res)
        step = linear.solve(lam)
        if not np.all(np.isfinite(step)):
            break
        small = float(np.max(np.abs(step))) < step_tol
        if small and lam <= LAMBDA_START:
            break
        new_pose, new_shape = _moved(pose, step[:m], model.dofs), shape + step[m:]
        new_q = new_pose.local(points)
        new_res = model.residuals(new_q, new_shape)
        new_cost = float(new_res @ new_res)
        if new_cost <= cost * (1.0 + COST_SLACK):
            pose, shape, res, cost, q = new_pose, new_shape, new_res, new_cost, new_q
            lam, linear = max(lam / LAMBDA_GROWTH, LAMBDA_FLOOR), None
            if small:
                break
        else:
            lam *= LAMBDA_GROWTH
            if lam > LAMBDA_GIVE_UP:
                break
    return Solution(pose, shape, res, cost, linear.jac if linear else None)


def jacobian_at(model: Model, points: FloatArray, sol: Solution) -> FloatArray:
    """Return the Jacobian of ``model`` at ``sol`` (the solver's own when it has it)."""
    if sol.jacobian is not None:
        return sol.jacobian
    return model.jacobian(sol.pose.local(points), sol.shape)


def step_tolerance(data: Normalised) -> float:
    """The solver's step tolerance in normalised units for ``data``."""
    return max(tol.fit / data.scale, STEP_FLOOR)


def multi_start(model: Model, points: FloatArray, starts: list[tuple[Pose, FloatArray]],
                *, step_tol: float) -> Solution:
    """Scout from every start for ``SCOUT_ITERATIONS`` (on ``subsample(points)``), then
    polish the cheapest.

    Args:
        model: the shape.
        points: ``(n, 3)`` normalised points.
        starts: ``(pose, shape)`` starting guesses, for ``subsample(points)``.
        step_tol: see ``refine``.

    Raises:
        ProbegenError: no start gave a finite solution.
    """
    sample = subsample(points)
    scouts = [refine(model, sample, pose, shape, step_tol=step_tol,
                     iterations=SCOUT_ITERATIONS) for pose, shape in starts]
    finite = [s for s in scouts if math.isfinite(s.cost) and np.all(np.isfinite(s.shape))]
    if not finite:
        raise fit_error(model.name, "points that determine the shape", "no usable start")
    lead = min(finite, key=lambda s: s.cost)
    return polish(model, points, sample, lead.pose, lead.shape, step_tol=step_tol)


def polish(model: Model, points: FloatArray, sample: FloatArray, pose: Pose,
           shape: FloatArray, *, step_tol: float) -> Solution:
    """Refine ``(pose, shape)`` to convergence: on ``sample`` first when it is a subset
    of ``points`` (see ``subsample``), so that all points take only the last few steps."""
    if sample is not points:
        lead = refine(model, sample, pose, shape, step_tol=step_tol)
        pose, shape = lead.pose, lead.shape
    return refine(model, points, pose, shape, step_tol=step_tol)
