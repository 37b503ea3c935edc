"""Probe-radius compensation on free-form surfaces (method M3): four ways to find the normal.

A touch-trigger probe reports the ball centre ``O`` at the trigger; the contact point is
``P = O − r·n`` with ``n`` the *actual* outward unit normal where the ball touched, which
is unknown.  The methods differ only in how they estimate ``n``:

=============  ================================  ============================================
method         normal used                       extra touches per point
=============  ================================  ============================================
naive          ``−d`` (against the travel)        none
2-D            ⟂ chord of two centres ±h along    2, at ±``spacing`` along the slope direction
               the slope, in the plane (d, slope)
micro-plane    normal of the plane through three  3, on a circle of radius ``ρ`` ⟂ ``d``
               centres on a circle around the
               guide line
vector         the nominal normal (probing        none; the probe travels along ``−n_nominal``
               along it)
=============  ================================  ============================================

Why the plane through ball *centres* gives the part's normal: the centres lie on the
surface offset by ``r``, whose normal at ``S + r·n`` is ``n`` itself.

Error model (``δ`` = angle between the normal used and the actual one): the contact point
moves by ``r·δ`` along the surface and by ``r·(1 − cos δ) ≈ r·δ²/2`` along the normal;
the deviation along the nominal normal (and the form seen by any fit) carries the second,
the point's *location* the first.  Where ``δ`` comes from, per method, is in each function's
docstring.  Noise ``σ`` on the trigger positions enters ``P`` once directly and once through
``δ`` (amplified by ``r/spacing``, but only into the along-surface part to first order).

Frames and units: part frame, mm; ``d`` (``probe_direction``) is the unit direction the
ball travels while probing (``(0, 0, −1)`` probing straight down); normals point out of the
material, i.e. against ``d``.  ``radius`` is a number or a ``ProbeCalibration`` (effective
radius by direction, method M1), applied through ``probegen.machine.calibration.compensate``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from probegen.errors import ProbegenError
from probegen.geometry.frames import FloatArray
from probegen.geometry.freeform_offsets import (
    DEGENERATE,
    DOWN,
    finite_rows,
    travel_direction,
)
from probegen.machine.calibration import ProbeCalibration, compensate

COLLINEAR = 1e-12
"""Point sets whose second principal variance is below this fraction of the first are
collinear: no plane."""

CONDITION = 1e8
"""Local plane fits of the deviation map with a worse condition number are not trusted."""

QUADRIC_CONDITION = 1e4
"""A local quadric fit (unit-free coordinates) worse conditioned than this falls back to
the plane: its neighbours do not surround the point (a grid's edge)."""

Radius = float | ProbeCalibration


@dataclass(frozen=True, eq=False)
class Compensated:
    """Contact points found by one method.

    Attributes:
        method: ``"naive"``, ``"2d"``, ``"micro-plane"`` or ``"vector"``.
        contacts: ``(m, 3)`` contact points ``O − r(n)·n``, mm.
        normals: ``(m, 3)`` the unit normals used (assumed, estimated or nominal).
    """

    method: str
    contacts: FloatArray
    normals: FloatArray


def _outward(normals: FloatArray, d: FloatArray) -> FloatArray:
    """Unit normals turned to point against the travel ``d``."""
    flip = np.where(normals @ d > 0.0, -1.0, 1.0)
    return np.asarray(normals * flip[:, None])


def naive(centres: ArrayLike, radius: Radius, *,
          probe_direction: ArrayLike = DOWN) -> Compensated:
    """Compensate along the probing axis: ``P = O + r·d`` (``O − r·ẑ`` probing down).

    Error model: exact only where the actual normal is ``−d``.  On a slope ``θ`` (angle
    between the actual normal and ``−d``) the contact point is off by ``r·(1 − cos θ)``
    along the normal and ``r·sin θ`` along the surface, for any curvature: 45 µm at 10°
    with a 3 mm ball, 1.5 mm at 60°.  Kept as the baseline the others are measured against.
    """
    o = finite_rows(centres, (-1, 3), "naive: centres")
    d = travel_direction(probe_direction)
    normals = np.broadcast_to(-d, o.shape).copy()
    return Compensated("naive", compensate(o, normals, radius), normals)


def two_d(centres: ArrayLike, pairs: ArrayLike, radius: Radius, *,
          probe_direction: ArrayLike = DOWN) -> Compensated:
    """The seed's 2-D method: two extra touches ±h along the slope give the tangent.

    ``t = unit(O₂ − O₁)``; the normal is the unit vector ⟂ ``t`` in the plane of ``t`` and
    ``d``, turned against ``d``; ``P = O − r·n``.

    Error model: (1) the normal's component across that plane (the cross-slope) is
    invisible: ``δ`` = the cross-slope angle, so only cylindrical surfaces whose rulings are
    ⟂ the plane come out exact; (2) the chord's direction equals the tangent at the middle
    of the chord only to ``O(h²·κ')`` (``κ'`` the change of curvature along the slope):
    exact on a parabola; (3) noise: ``δ ≈ σ·√2 / (2h)``.

    Args:
        centres: ``(m, 3)`` ball centres of the touches at the guide points.
        pairs: ``(m, 2, 3)`` ball centres of the two extra touches of each point (either
            order), e.g. at the guide point ∓/± ``freeform_offsets.two_d_offsets``.
        radius: effective ball radius, mm, or a calibration.
        probe_direction: travel direction of all the touches.
    """
    o = finite_rows(centres, (-1, 3), "2-D: centres")
    pair = finite_rows(pairs, (len(o), 2, 3), "2-D: extra touches")
    d = travel_direction(probe_direction)
    chord = pair[:, 1] - pair[:, 0]
    tangent = _unit_rows(chord, "2-D: the two extra touches coincide")
    up = -d - np.outer(tangent @ -d, 1.0) * tangent
    normals = _unit_rows(up, "2-D: the extra touches lie along the probing direction")
    return Compensated("2d", compensate(o, normals, radius), normals)


def micro_plane(centres: ArrayLike, touches: ArrayLike, radius: Radius, *,
                probe_direction: ArrayLike = DOWN) -> Compensated:
    """The seed's 3-D method: the plane through nearby ball centres gives the normal.

    Three touches: ``n = unit((O₂ − O₁) × (O₃ − O₁))`` (the seed); ``k > 3`` touches: the
    least-squares plane's normal (smallest principal axis).  Turned against ``d``;
    ``P = O − r·n``.

    Error model (``k`` touches on a circle of radius ``ρ`` around the guide line, equally
    spaced): (1) curvature: the ``k`` samples alias the offset surface's height harmonic
    ``(k − 1)·φ`` onto the tilt.  With three touches that is the quadratic ``2φ`` term:
    ``δ ≈ ρ·|κ₁ − κ₂|/4`` (zero only where ``κ₁ = κ₂``: sphere, plane); with four touches
    90° apart the ``2φ`` term drops out and ``δ = O(ρ²·κ')``; (2) the plane's normal belongs
    to the circle's centre, i.e. the guide line, where ``O`` also lies; (3) noise: each
    tilt component ``≈ σ·√(2/k)/ρ``.  Larger ``ρ`` trades (3) for (1).

    Args:
        centres: ``(m, 3)`` ball centres of the touches at the guide points.
        touches: ``(m, k, 3)``, ``k >= 3``, ball centres of the extra touches of each point,
            e.g. at the guide point + ``freeform_offsets.micro_plane_offsets``.
        radius: effective ball radius, mm, or a calibration.
        probe_direction: travel direction of all the touches (orients the normal).
    """
    o = finite_rows(centres, (-1, 3), "micro-plane: centres")
    tri = finite_rows(touches, (len(o), -1, 3), "micro-plane: extra touches")
    if tri.shape[1] < 3:
        raise ProbegenError(f"micro-plane: expected at least 3 extra touches per point, "
                            f"found {tri.shape[1]}")
    d = travel_direction(probe_direction)
    if tri.shape[1] == 3:
        cross = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        normals = _unit_rows(cross, "micro-plane: the three extra touches are collinear")
    else:
        normals = _plane_normals(tri)
    normals = _outward(normals, d)
    return Compensated("micro-plane", compensate(o, normals, radius), normals)


def _plane_normals(points: FloatArray) -> FloatArray:
    """Normals of the least-squares planes through ``(m, k, 3)`` point sets."""
    centred = points - points.mean(axis=1, keepdims=True)
    values, vectors = np.linalg.eigh(np.einsum("mki,mkj->mij", centred, centred))
    bad = np.flatnonzero(values[:, 1] <= COLLINEAR * values[:, 2])
    if len(bad):
        raise ProbegenError(f"micro-plane: the extra touches are collinear at point "
                            f"{int(bad[0])}; cannot estimate the normal")
    return np.asarray(vectors[:, :, 0])


def vector(centres: ArrayLike, nominal_normals: ArrayLike, radius: Radius) -> Compensated:
    """Vector probing: the ball travels along ``−n_nominal``; ``P = O − r·n_nominal``.

    Error model: ``δ`` is the angle between the nominal and the actual normal, i.e. the
    local slope of the form error (``|∇e|``); along the nominal normal the deviation comes
    out ``r·(1/cos δ − 1) ≈ r·δ²/2`` too large (0.15 µm for ``δ`` = 10 mrad and r = 3 mm);
    along the surface the point sits ``r·δ`` off.  No extra touches, no amplification of
    noise.  Where the deviation map's slope makes ``r·δ²/2`` too large, measure that point
    with the micro-plane method instead (``normal_error_limit`` / ``needs_micro_plane``).

    Args:
        centres: ``(m, 3)`` ball centres at the trigger.
        nominal_normals: ``(m, 3)`` nominal outward unit normals (the probing axes).
        radius: effective ball radius, mm, or a calibration.
    """
    o = finite_rows(centres, (-1, 3), "vector: centres")
    n = _unit_rows(finite_rows(nominal_normals, (len(o), 3), "vector: nominal normals"),
                   "vector: a nominal normal is zero")
    return Compensated("vector", compensate(o, n, radius), n)


def _unit_rows(vectors: FloatArray, problem: str) -> FloatArray:
    """Rows scaled to unit length; a row shorter than ``DEGENERATE`` is an error."""
    length = np.linalg.norm(vectors, axis=1)
    bad = np.flatnonzero(length < DEGENERATE)
    if len(bad):
        raise ProbegenError(f"{problem} at point {int(bad[0])} (length "
                            f"{length[bad[0]]:.3g} mm); cannot estimate the normal")
    return np.asarray(vectors / length[:, None])


def normal_error_limit(radius: float, allowed: float) -> float:
    """Largest normal error ``δ`` (rad) that keeps ``r·(1/cos δ − 1) <= allowed``.

    Args:
        radius: ball radius, mm.
        allowed: error along the normal that is acceptable, mm (e.g. 0.0001).
    """
    if not (radius > 0.0 and allowed > 0.0):
        raise ProbegenError(f"normal error limit: expected a positive radius and error, "
                            f"found {radius!r} and {allowed!r}")
    return math.acos(radius / (radius + allowed))


@dataclass(frozen=True, slots=True)
class DeviationSummary:
    """Figures of a deviation map, mm: count, smallest, largest, mean and RMS deviation."""

    count: int
    min: float
    max: float
    mean: float
    rms: float


@dataclass(frozen=True, eq=False)
class DeviationMap:
    """Deviations of measured contact points from their nominal points.

    Attributes:
        method: the compensation method that produced ``measured``.
        nominal: ``(m, 3)`` theoretical contact points ``P_t``, mm.
        normals: ``(m, 3)`` nominal outward unit normals at ``P_t``.
        measured: ``(m, 3)`` compensated contact points ``P_a``, mm.
        deviation: ``(m,)`` ``e = (P_a − P_t)·n``, mm; positive = material added.
    """

    method: str
    nominal: FloatArray
    normals: FloatArray
    measured: FloatArray
    deviation: FloatArray

    @property
    def vectors(self) -> FloatArray:
        """``(m, 3)`` full error vectors ``P_a − P_t``, mm."""
        return np.asarray(self.measured - self.nominal)

    def summary(self) -> DeviationSummary:
        """Count, min, max, mean and RMS of the deviations (NaN for an empty map)."""
        return summarise(self.deviation)


def summarise(deviations: ArrayLike) -> DeviationSummary:
    """Count, min, max, mean and RMS of ``(m,)`` deviations, mm (NaN when there are none)."""
    e = np.asarray(deviations, dtype=np.float64).ravel()
    if not len(e):
        nan = float("nan")
        return DeviationSummary(0, nan, nan, nan, nan)
    return DeviationSummary(len(e), float(e.min()), float(e.max()), float(e.mean()),
                            float(np.sqrt(np.mean(e * e))))


def deviation_map(compensated: Compensated, nominal_points: ArrayLike,
                  nominal_normals: ArrayLike) -> DeviationMap:
    """Deviation of each compensated contact along its nominal normal (M3 step 3).

    Args:
        compensated: the result of one of the methods.
        nominal_points: ``(m, 3)`` theoretical contact points ``P_t``, mm.
        nominal_normals: ``(m, 3)`` nominal outward normals at ``P_t`` (normalised here).
    """
    m = len(compensated.contacts)
    p = finite_rows(nominal_points, (m, 3), "deviation map: nominal points")
    n = _unit_rows(finite_rows(nominal_normals, (m, 3), "deviation map: nominal normals"),
                   "deviation map: a nominal normal is zero")
    e = np.einsum("ij,ij->i", compensated.contacts - p, n)
    return DeviationMap(compensated.method, p, n, compensated.contacts, e)


def form_slopes(dmap: DeviationMap, *, candidates: int = 32) -> FloatArray:
    """Estimated angle between nominal and actual normal at each point, rad.

    The actual surface is the nominal one displaced by ``e`` along the normal, so its normal
    is tilted by ``atan|∇e|``.  ``∇e`` comes from a least-squares quadric
    ``e = c₀ + g·(a, b) + quadratic terms`` through the point and its nearest neighbour in
    each of 8 sectors of its tangent plane (coordinates ``(a, b)``), found among its
    ``candidates`` nearest points: sectors keep a grid that is stretched (an XY grid on a
    steep face) from giving a neighbourhood that lies in one row.  Where the neighbours do
    not determine a quadric (a grid's edge) a plane is fitted.  Only meaningful where the
    points are dense against the form error's wavelength (the slope of a wave is
    underestimated by ``sin(kh)/(kh)``, ``h`` the spacing).  NaN where not even a plane is
    determined.

    Returns:
        ``(m,)`` float angles, rad.
    """
    from scipy.spatial import cKDTree

    m = len(dmap.deviation)
    k = min(candidates, m)
    if k < 3:
        return np.full(m, np.nan)
    _, idx = cKDTree(dmap.nominal).query(dmap.nominal, k=k)
    offsets = dmap.nominal[idx] - dmap.nominal[:, None, :]          # (m, k, 3)
    ea = np.cross(dmap.normals, _helper_axis(dmap.normals))
    ea /= np.linalg.norm(ea, axis=1, keepdims=True)
    eb = np.cross(dmap.normals, ea)
    a = np.einsum("mkj,mj->mk", offsets, ea)
    b = np.einsum("mkj,mj->mk", offsets, eb)
    weight = _sector_nearest(a, b)
    size = np.sqrt(np.sum(weight * (a * a + b * b), axis=1, keepdims=True)
                   / np.sum(weight, axis=1, keepdims=True)) + DEGENERATE
    a, b = a / size, b / size  # unit-free: the matrix is O(1) whatever the spacing
    values = dmap.deviation[idx]
    one = np.ones((m, k))
    coef = _local_fit(np.stack([one, a, b], axis=2), weight, values, CONDITION)
    quadric = _local_fit(np.stack([one, a, b, a * a, a * b, b * b], axis=2), weight, values,
                         QUADRIC_CONDITION)
    coef = np.where(np.isnan(quadric[:, :3]), coef, quadric[:, :3])
    gradient = coef[:, 1:3] / size
    return np.asarray(np.arctan(np.hypot(gradient[:, 0], gradient[:, 1])))


def _sector_nearest(a: FloatArray, b: FloatArray) -> FloatArray:
    """``(m, k)`` 0/1 weights: each row's first column (the point itself) and, per 45°
    sector of the tangent plane around it, its nearest candidate (columns are sorted by
    distance)."""
    # sectors centred on the axes and diagonals, so a square grid's 8 neighbours never sit
    # on a sector boundary
    sector = np.floor((np.arctan2(b, a) + np.pi * 9.0 / 8.0) / (np.pi / 4.0)).astype(int) % 8
    sector[:, 0] = -1  # the point itself
    weight = np.zeros(a.shape)
    weight[:, 0] = 1.0
    rows = np.arange(a.shape[0])
    for s in range(8):
        hit = sector == s
        first = np.argmax(hit, axis=1)
        found = hit[rows, first]
        weight[rows[found], first[found]] = 1.0
    return weight


def _local_fit(design: FloatArray, weight: FloatArray, values: FloatArray,
               condition: float) -> FloatArray:
    """Weighted least-squares coefficients per point, ``(m, p)``; NaN rows where the normal
    matrix's condition number exceeds ``condition``."""
    lhs = np.einsum("mki,mk,mkj->mij", design, weight, design)
    ok = np.linalg.cond(lhs) < condition
    coef = np.full((design.shape[0], design.shape[2]), np.nan)
    if ok.any():
        rhs = np.einsum("mki,mk,mk->mi", design, weight, values)
        coef[ok] = np.linalg.solve(lhs[ok], rhs[ok][..., None])[..., 0]
    return coef


def _helper_axis(normals: FloatArray) -> FloatArray:
    """Per row, the world axis least parallel to the normal (for a tangent frame)."""
    axes = np.eye(3)[np.argmin(np.abs(normals), axis=1)]
    return np.asarray(axes)


def needs_micro_plane(dmap: DeviationMap, radius: float, allowed: float, *,
                      candidates: int = 32) -> np.ndarray:
    """Points of a vector-probing map whose form slope makes its error exceed ``allowed``.

    ``True`` where ``form_slopes`` exceeds ``normal_error_limit(radius, allowed)`` or
    cannot be estimated: measure those points again with the micro-plane method.
    """
    slopes = form_slopes(dmap, candidates=candidates)
    limit = normal_error_limit(radius, allowed)
    return np.asarray(~(slopes <= limit))
