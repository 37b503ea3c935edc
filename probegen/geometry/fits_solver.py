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
    big = float(np.max(np.abs(points)))
    unit_points = points / big if big > 0.0 else points
    mean = unit_points.mean(axis=0)
    centred = unit_points - mean
    spread = math.sqrt(float(np.mean(np.sum(centred * centred, axis=1))))
    if not spread > COINCIDENT:
        raise fit_error(fit, "points that are not all the same point", "coincident points")
    scale, centre = spread * big, mean * big
    if not (TINY <= scale < math.inf and np.all(np.isfinite(centre))):
        raise fit_error(fit, "a spread of points within the range of doubles",
                        f"a spread of {spread * big:g}")
    q = centred / spread
    _, sv, vt = np.linalg.svd(q, full_matrices=False)
    extents = np.zeros(points.shape[1])
    extents[: sv.size] = sv / math.sqrt(len(q))
    directions = np.eye(points.shape[1])
    directions[: vt.shape[0]] = vt
    return Normalised(q, centre, scale, extents, directions)


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
        return np.asarray((points - self.origin) @ self.rot.T, dtype=np.float64)


LocalFn = Callable[[FloatArray, FloatArray], FloatArray]


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


@dataclass(frozen=True, slots=True)
class Solution:
    """Solver output in normalised units: pose, shape parameters, residuals, cost."""

    pose: Pose
    shape: FloatArray
    residuals: FloatArray
    cost: float


def safe_ratio(num: FloatArray, den: FloatArray) -> FloatArray:
    """Return ``num / den`` with 0 where ``den`` is 0 (points on an axis)."""
    ok = den > 0.0
    return np.where(ok, num / np.where(ok, den, 1.0), 0.0)


def _moved(pose: Pose, step: FloatArray, dofs: tuple[int, ...]) -> Pose:
    """Apply the pose part of a solver step (local coordinates) to ``pose``."""
    full = np.zeros(5)
    full[list(dofs)] = step
    origin = pose.origin + pose.rot.T @ full[:3]
    if full[3] == 0.0 and full[4] == 0.0:
        return Pose(origin, pose.rot)
    axis = pose.rot.T @ np.array([full[3], full[4], 1.0])
    return Pose(origin, rotation_to_z(axis))


def _damped_step(jac: FloatArray, res: FloatArray, lam: float) -> FloatArray:
    """Solve ``min |J s + r|^2 + lam |D s|^2`` (``D`` = column norms of ``J``)."""
    damping = math.sqrt(lam) * np.sqrt(np.sum(jac * jac, axis=0))
    lhs = np.vstack([jac, np.diag(damping)])
    rhs = np.concatenate([-res, np.zeros(jac.shape[1])])
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
    res = model.residuals(pose.local(points), shape)
    cost, lam = float(res @ res), LAMBDA_START
    for _ in range(iterations):
        step = _damped_step(model.jacobian(pose.local(points), shape), res, lam)
        if not np.all(np.isfinite(step)):
            break
        small = float(np.max(np.abs(step))) < step_tol
        if small and lam <= LAMBDA_START:
            break
        new_pose, new_shape = _moved(pose, step[:m], model.dofs), shape + step[m:]
        new_res = model.residuals(new_pose.local(points), new_shape)
        new_cost = float(new_res @ new_res)
        if new_cost <= cost * (1.0 + COST_SLACK):
            pose, shape, res, cost = new_pose, new_shape, new_res, new_cost
            lam = max(lam / LAMBDA_GROWTH, LAMBDA_FLOOR)
            if small:
                break
        else:
            lam *= LAMBDA_GROWTH
            if lam > LAMBDA_GIVE_UP:
                break
    return Solution(pose, shape, res, cost)


def step_tolerance(data: Normalised) -> float:
    """The solver's step tolerance in normalised units for ``data``."""
    return max(tol.fit / data.scale, STEP_FLOOR)


def multi_start(model: Model, points: FloatArray, starts: list[tuple[Pose, FloatArray]],
                *, step_tol: float) -> Solution:
    """Scout from every start for ``SCOUT_ITERATIONS``, then polish the cheapest.

    Args:
        model: the shape.
        points: ``(n, 3)`` normalised points.
        starts: ``(pose, shape)`` starting guesses.
        step_tol: see ``refine``.

    Raises:
        ProbegenError: no start gave a finite solution.
    """
    scouts = [refine(model, points, pose, shape, step_tol=step_tol,
                     iterations=SCOUT_ITERATIONS) for pose, shape in starts]
    finite = [s for s in scouts if math.isfinite(s.cost) and np.all(np.isfinite(s.shape))]
    if not finite:
        raise fit_error(model.name, "points that determine the shape", "no usable start")
    lead = min(finite, key=lambda s: s.cost)
    return refine(model, points, lead.pose, lead.shape, step_tol=step_tol)
