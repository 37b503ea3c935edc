"""Method M4: the rotary-axis errors of a five-axis B/C machine from its DPRNT log.

Input: the plan of the test (``planning.rotary``, recomputed from its spec) and the log
the program printed.  Every skip position is the commanded point (the ball centre as it
is at B = 0); the ball centre is that plus ``head_shift(b)`` of its station.

**The seed's test** (``m4``), with ``l1`` the pivot length, ``R1`` the ball radius and
``r1 = r2`` the sphere radius from the circle through the equator touches at B = 0
(so ``r1 + R1`` is the circle's radius ``ρ``, the probe's lateral pre-travel included):
``x1`` = X at the touch with B = +90° (approaching along −X), ``x2`` = −X at B = −90°::

    rigid:      x1 + δ = l1 + r1 + R1                 δ = l1 + r1 + R1 − x1
    compliant:  x1 + δ = l1 + r1 + R1 + ε,  x2 − δ = l1 + r2 + R1 + ε
                δ = ((x2 − x1) − (r2 − r1)) / 2,       ε = x1 + δ − l1 − r1 − R1

``δ`` is how far the C axis lies along −X from the B axis' place at X = 0 (with the
ISO 230-7 terms: ``δ = EX0B − EX0C``); the compensation moves the work offset by ``−δ``
along X.  ``ε`` collects everything symmetric in B: deflection, the difference of axial
and lateral pre-travel, and an error of ``l1`` (``EZ0B``).

**The pivot calibration** (``pivot``): a least-squares sphere per station, then the
location errors of each axis (ISO 230-7, the signs of ``machine.errors_model``) fitted
by least squares to the station centres with the station angles known:

* C (stations at B = 0): ``m(c) = p_C + Rot(a_C, −c)·S``, unknowns ``EX0C, EY0C``
  (``p_C``), ``EA0C, EB0C`` (``a_C = Rot(tilt)·z``) and the sphere ``S``.
* B (stations at C = 0): ``m(b) = S − [p_B + Rot(a_B, b)·(t − p_B) − Rot(y, b)·t]``
  with ``t = (0, 0, −l1)``: unknowns ``EX0B, EZ0B``, ``EA0B, EC0B`` and ``S``.

Uncertainties: the touch repeatability ``s`` comes from the residuals of all the
stations' sphere fits (``Σ r² / Σ (n − 4)``); each centre's covariance is then
``s²·[(JᵀJ)⁻¹]`` of its sphere fit (larger along the stylus, since a cap is probed),
the axis fit is weighted by the inverse covariances, and the parameters' standard
uncertainties are the diagonal of ``(Jᵀ W J)⁻¹``.  The residual vector of each station
is reported (with ``χ²/dof``, near 1 when the model explains the centres to within the
touch noise), and the 3-D circle through the centres (for B: through the tool vectors
``Rot(y, b)·t + S − m``, whose radius is the actual pivot length ``l1 + EZ0B``) as the
kinematics cycles show it.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares
from scipy.spatial.transform import Rotation

from probegen.errors import CalibrationError
from probegen.geometry.fits import fit_circle_2d, fit_circle_3d, fit_sphere
from probegen.geometry.fits_results import Circle3dFit
from probegen.geometry.uncertainty import t_factor
from probegen.machine.calibration import ProbeCalibration, calibrated_centres, for_stylus
from probegen.machine.kinematics import head_shift
from probegen.machine.probe_model import tilted_probe_frame
from probegen.planning.rotary import RotaryPlan, Station
from probegen.results.dprnt import DprntLog

Vec3 = tuple[float, float, float]
Model = Callable[[np.ndarray], np.ndarray]
NAMES = {"C": ("EX0C", "EY0C", "EA0C", "EB0C"), "B": ("EX0B", "EZ0B", "EA0B", "EC0B")}
"""ISO 230-7 names of the four location errors of each axis: position (mm), tilt (rad)."""


@dataclass(frozen=True, slots=True)
class M4Result:
    """The seed's B ±90° test (lengths mm; see the module docstring).

    Attributes:
        l1: pivot length.  ball_radius: ``R1``.
        r1, r2: sphere radius at B = +90° and −90° (both from the B = 0 circle).
        x1, x2: X travel to the touch at B = +90° and −90° (mean of the repeats).
        delta_rigid: the rigid solution.  delta: the compliant one.  epsilon: ``ε``.
        u_delta_rigid, u_delta, u_epsilon: their standard uncertainties.
        sigma: the touch repeatability the uncertainties rest on (pooled from the
            circle residuals and the repeats).
        sphere_xy: the sphere's centre at B = 0 from the circle, work X, Y.
        compensation: the work-offset shift (X, Y, Z) that moves the origin by −δ.
        dof: degrees of freedom of ``sigma`` (``n − 3 + 2(k − 1)``).
    """

    l1: float
    ball_radius: float
    r1: float
    r2: float
    x1: float
    x2: float
    delta_rigid: float
    delta: float
    epsilon: float
    u_delta_rigid: float
    u_delta: float
    u_epsilon: float
    sigma: float
    sphere_xy: tuple[float, float]
    compensation: Vec3
    dof: int = 0

    @property
    def k95(self) -> float:
        """Student's t factor of the 95 % intervals ``±k95·u`` (few samples: not 1.96)."""
        return t_factor(self.dof)


@dataclass(frozen=True, slots=True)
class AxisResult:
    """The location errors of one rotary axis from the pivot calibration.

    Attributes:
        axis: ``"B"`` or ``"C"``.
        names: ISO 230-7 names of ``values`` (see :data:`NAMES`).
        values: two positions (mm) and two tilts (rad).
        uncertainties: their standard uncertainties, same units.
        angles: the station angles, deg.
        centres: the measured sphere centres, work frame, mm.
        residuals: measured less fitted centre per station, mm.
        sphere: the fitted sphere centre ``S``, mm.
        sigma: touch repeatability from the sphere fits, mm.
        dof: degrees of freedom of the axis fit.
        chi2: weighted sum of squared residuals of the axis fit over ``dof``.
        circle: the 3-D circle through the centres (C) or the tool vectors (B).
        sigma_dof: degrees of freedom of ``sigma`` (``Σ (n − 4)`` over the stations).
    """

    axis: str
    names: tuple[str, ...]
    values: tuple[float, ...]
    uncertainties: tuple[float, ...]
    angles: tuple[float, ...]
    centres: tuple[Vec3, ...]
    residuals: tuple[Vec3, ...]
    sphere: Vec3
    sigma: float
    dof: int
    chi2: float
    circle: Circle3dFit
    sigma_dof: int = 0

    @property
    def k95(self) -> float:
        """Student's t factor of the 95 % intervals ``±k95·u`` (on ``sigma_dof``)."""
        return t_factor(self.sigma_dof)


@dataclass(frozen=True, slots=True)
class PivotResult:
    """The pivot calibration: both axes, and the work-offset shift onto the C axis."""

    c: AxisResult
    b: AxisResult
    compensation: Vec3


# ---------------------------------------------------------------------------- log


def station_points(plan: RotaryPlan, log: DprntLog,
                   calibration: ProbeCalibration | None = None) -> dict[str, np.ndarray]:
    """The ball centres of every station's touches, in index order: ``(n, 3)`` mm.

    With a probe calibration each centre is moved by ``r(n) − r_ref`` along its
    normal (``compensate.calibrated_centres``; the map looked up in the probe frame
    of the station's head tilt), so one radius, ``r_ref`` = the calibration's mean
    effective radius, compensates them all.

    Raises:
        CalibrationError: a touch is missing (the message names the feature and index).
    """
    found = {(t.feature, t.index): t.xyz for t in log.latest_touches() if t.kind == "PT"}
    for_stylus(calibration, plan.spec.machine.probe.ball_radius, "--calibration")
    out: dict[str, np.ndarray] = {}
    for st in plan.stations:
        missing = [k for k in range(1, len(st.directions) + 1) if (st.feature, k) not in found]
        if missing:
            raise CalibrationError(
                f"{log.source}: expected touches 1-{len(st.directions)} of {st.feature}, "
                f"missing {', '.join(str(k) for k in missing)} (did the program finish?)")
        shift = np.array(head_shift(st.b, plan.spec.pivot_length))
        xyz = np.array([found[(st.feature, k)] for k in range(1, len(st.directions) + 1)])
        if calibration is not None:
            xyz = calibrated_centres(xyz, st.directions, calibration,
                                     calibration.effective_radius,
                                     probe_normals=tilted_probe_frame(st.directions, st.b))
        out[st.feature] = xyz + shift
    return out


# -------------------------------------------------------------------------- the seed


def identify_m4(plan: RotaryPlan, log: DprntLog,
                calibration: ProbeCalibration | None = None) -> M4Result:
    """Solve the seed's equations (module docstring) from an ``m4`` test's log (with
    the probe calibration's radii, see :func:`station_points`)."""
    pts = station_points(plan, log, calibration)
    spec = plan.spec
    circle = fit_circle_2d(pts["RAD"][:, :2])
    ball = spec.machine.probe.ball_radius if calibration is None else \
        calibration.effective_radius
    r1 = r2 = circle.radius - ball
    x1s, x2s = pts["BP90"][:, 0], pts["BM90"][:, 0]
    # the touch X less the shift back to the pivot's X: the axis' own reading
    x1 = float(np.mean(x1s)) + spec.pivot_length - spec.sphere_centre[0]
    x2 = -(float(np.mean(x2s)) - spec.pivot_length - spec.sphere_centre[0])
    l1 = spec.pivot_length
    delta = ((x2 - x1) - (r2 - r1)) / 2.0
    sigma, dof = _pooled_sigma(np.asarray(circle.residuals), x1s, x2s)
    n, k = len(circle.residuals), len(x1s)
    return M4Result(
        l1=l1, ball_radius=ball, r1=r1, r2=r2, x1=x1, x2=x2,
        delta_rigid=l1 + r1 + ball - x1, delta=delta, epsilon=x1 + delta - l1 - r1 - ball,
        u_delta_rigid=sigma * math.sqrt(1.0 / k + 1.0 / n),
        u_delta=sigma / math.sqrt(2.0 * k),
        u_epsilon=sigma * math.sqrt(1.0 / (2.0 * k) + 1.0 / n),
        sigma=sigma, sphere_xy=circle.centre, compensation=(-delta, 0.0, 0.0), dof=dof)


def _pooled_sigma(circle: np.ndarray, *repeats: np.ndarray) -> tuple[float, int]:
    """Touch repeatability from the circle residuals (n − 3 dof) and the repeats, and
    its degrees of freedom."""
    ss = float(np.sum(circle**2))
    dof = len(circle) - 3
    for r in repeats:
        ss += float(np.sum((r - r.mean()) ** 2))
        dof += len(r) - 1
    return (math.sqrt(ss / dof) if dof > 0 else math.nan), max(dof, 0)


# --------------------------------------------------------------------- the pivot


def _axis_vector(tilt: np.ndarray, nominal: np.ndarray) -> np.ndarray:
    return np.asarray(Rotation.from_rotvec(tilt).apply(nominal))


def _turn(axis: np.ndarray, deg: float) -> np.ndarray:
    return np.asarray(Rotation.from_rotvec(axis / np.linalg.norm(axis) * math.radians(deg))
                      .as_matrix())


def c_model(angles: np.ndarray) -> Model:
    """Sphere centres at C positions ``angles`` (deg) for parameters
    ``(EX0C, EY0C, EA0C, EB0C, Sx, Sy, Sz)``: flat ``(3n,)``."""
    def model(q: np.ndarray) -> np.ndarray:
        a = _axis_vector(np.array([q[2], q[3], 0.0]), np.array([0.0, 0.0, 1.0]))
        p = np.array([q[0], q[1], 0.0])
        return np.concatenate([p + _turn(a, -c) @ q[4:7] for c in angles])
    return model


def b_model(angles: np.ndarray, pivot_length: float) -> Model:
    """Sphere centres (nominal ball frame) at B positions ``angles`` (deg) for parameters
    ``(EX0B, EZ0B, EA0B, EC0B, Sx, Sy, Sz)``: flat ``(3n,)``."""
    t = np.array([0.0, 0.0, -pivot_length])
    y = np.array([0.0, 1.0, 0.0])

    def model(q: np.ndarray) -> np.ndarray:
        a = _axis_vector(np.array([q[2], 0.0, q[3]]), y)
        p = np.array([q[0], 0.0, q[1]])
        return np.concatenate([q[4:7] - (p + _turn(a, b) @ (t - p) - _turn(y, b) @ t)
                               for b in angles])
    return model


@dataclass(frozen=True, slots=True)
class _Centres:
    """Sphere centres of some stations (k, 3), their whitening matrices (k, 3, 3) (the
    Cholesky factors of the inverse covariances) and the touch repeatability, mm."""

    centres: np.ndarray
    whiten: np.ndarray
    sigma: float
    dof: int


def _sphere_centres(points: list[np.ndarray]) -> _Centres:
    """Fit a sphere to each station's ball centres; covariances from the touch noise."""
    fits = [fit_sphere(p) for p in points]
    dof = sum(len(p) - 4 for p in points)
    ss = sum(float(np.sum(np.square(f.residuals))) for f in fits)
    sigma = math.sqrt(ss / dof) if dof > 0 else math.nan
    whiten = []
    for f, p in zip(fits, points, strict=True):
        unit = (p - np.array(f.centre)) / f.radius
        jac = np.column_stack([-unit, -np.ones(len(p))])
        normal = jac.T @ jac  # the centre's information: the Schur complement of the radius
        info = normal[:3, :3] - np.outer(normal[:3, 3], normal[3, :3]) / normal[3, 3]
        whiten.append(np.linalg.cholesky(info).T / (sigma if sigma > 0 else 1.0))
    return _Centres(np.array([f.centre for f in fits]), np.array(whiten), sigma, max(dof, 0))


def _fit_axis(axis: str, model: Model, start: np.ndarray, data: _Centres,
              angles: np.ndarray, circle_points: Callable[[np.ndarray], np.ndarray]
              ) -> AxisResult:
    """Weighted least squares of ``model`` to the centres; uncertainties from the touch
    noise through the Jacobian (module docstring)."""
    flat = data.centres.reshape(-1)

    def weighted(q: np.ndarray) -> np.ndarray:
        res = (model(q) - flat).reshape(-1, 3)
        return np.einsum("kij,kj->ki", data.whiten, res).reshape(-1)

    fit = least_squares(weighted, start, method="lm", xtol=1e-15, ftol=1e-15, gtol=1e-15,
                        x_scale=np.array([1e-3] * 2 + [1e-5] * 2 + [1.0] * 3))
    dof = len(flat) - len(start)
    jac = np.asarray(fit.jac)
    try:
        cov = np.linalg.inv(jac.T @ jac)
    except np.linalg.LinAlgError:
        raise CalibrationError(f"{axis} axis: the stations do not determine its location "
                               f"(singular fit); use at least three distinct angles") from None
    if not data.sigma > 0.0:  # noise-free data (0) or no redundancy (nan): no figure
        cov = cov * (0.0 if data.sigma == 0.0 else math.nan)
    q = fit.x
    return AxisResult(
        axis=axis, names=NAMES[axis], values=tuple(float(v) for v in q[:4]),
        uncertainties=tuple(float(math.sqrt(max(cov[i, i], 0.0))) for i in range(4)),
        angles=tuple(float(a) for a in angles), centres=tuple(_vec(c) for c in data.centres),
        residuals=tuple(_vec(r) for r in (flat - model(q)).reshape(-1, 3)),
        sphere=_vec(q[4:7]), sigma=data.sigma, dof=dof,
        chi2=float(np.sum(fit.fun**2)) / dof if dof > 0 else math.nan,
        circle=fit_circle_3d(circle_points(q)), sigma_dof=data.dof)


def _vec(v: np.ndarray) -> Vec3:
    return (float(v[0]), float(v[1]), float(v[2]))


def _centres(plan: RotaryPlan, pts: dict[str, np.ndarray], prefix: str
             ) -> tuple[list[Station], _Centres]:
    stations = [s for s in plan.stations if s.feature.startswith(prefix)]
    return stations, _sphere_centres([pts[s.feature] for s in stations])


def identify_pivot(plan: RotaryPlan, log: DprntLog,
                   calibration: ProbeCalibration | None = None) -> PivotResult:
    """The location errors of C and B from a ``pivot`` test's log (module docstring;
    with the probe calibration's radii, see :func:`station_points`)."""
    pts = station_points(plan, log, calibration)
    length = plan.spec.pivot_length
    cs, c_data = _centres(plan, pts, "C")
    c_angles = np.array([s.c for s in cs])
    back = np.mean([_turn(np.array([0.0, 0.0, 1.0]), c) @ m
                    for c, m in zip(c_angles, c_data.centres, strict=True)], axis=0)
    c = _fit_axis("C", c_model(c_angles), np.concatenate([np.zeros(4), back]), c_data,
                  c_angles, lambda q: c_data.centres)
    bs, b_data = _centres(plan, pts, "B")
    b_centres = b_data.centres
    b_angles = np.array([s.b for s in bs])
    start = np.concatenate([np.zeros(4), b_centres[int(np.argmin(np.abs(b_angles)))]])
    t = np.array([0.0, 0.0, -length])

    def tool_vectors(q: np.ndarray) -> np.ndarray:
        return np.array([_turn(np.array([0.0, 1.0, 0.0]), b) @ t + q[4:7] - m
                         for b, m in zip(b_angles, b_centres, strict=True)])

    b = _fit_axis("B", b_model(b_angles, length), start, b_data, b_angles, tool_vectors)
    return PivotResult(c, b, (c.values[0], c.values[1], 0.0))
