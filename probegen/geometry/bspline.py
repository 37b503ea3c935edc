"""Tensor-product (rational) B-spline surfaces, evaluated with numpy, vectorised over points.

``BSplineSurface`` implements ``probegen.geometry.offset_surface.ParamSurface``: the point
and its first and second partial derivatives at many ``(u, v)`` at once, from one basis
computation per call (the NURBS Book's algorithms A2.2/A2.3, vectorised over points, and
the quotient rule for rational surfaces).  It needs no CAD kernel, so a STEP face's B-spline
(poles, weights, knots with multiplicities, degrees) can be copied into it once and the
offset-surface solver then runs at numpy speed.

Knot vectors are *full* (each knot repeated by its multiplicity), of length
``n_poles + degree + 1``; the parameter domain is ``[knots[degree], knots[n_poles]]``.
Outside the domain the end polynomial pieces are extrapolated.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from probegen.errors import ModelError
from probegen.geometry.frames import FloatArray
from probegen.geometry.offset_surface import Domain, SurfaceJet

IntArray = np.ndarray


def find_spans(knots: FloatArray, degree: int, n_poles: int, x: FloatArray) -> IntArray:
    """Index ``i`` of the knot span ``[knots[i], knots[i+1])`` holding each ``x``.

    Args:
        knots: full knot vector, ``(n_poles + degree + 1,)``.
        degree: polynomial degree ``p``.
        n_poles: number of control points along this direction.
        x: ``(m,)`` parameters.

    Returns:
        ``(m,)`` int spans in ``[p, n_poles - 1]``, never of zero length; the domain's end
        belongs to the last non-empty span, values outside the domain to the end spans.
    """
    span = np.searchsorted(knots, x, side="right") - 1
    # inside the domain 'right' never picks a span of zero length (it skips repeated
    # knots); at and beyond the ends, clip to the first and last non-empty spans
    inside = np.flatnonzero(knots[degree:n_poles] < knots[degree + 1:n_poles + 1]) + degree
    return np.clip(span, inside[0], inside[-1])


def basis_derivatives(knots: FloatArray, degree: int, span: IntArray, x: FloatArray,
                      order: int) -> FloatArray:
    """Non-zero B-spline basis functions and their derivatives (NURBS Book A2.3).

    Args:
        knots: full knot vector.
        degree: polynomial degree ``p``.
        span: ``(m,)`` spans from ``find_spans``.
        x: ``(m,)`` parameters.
        order: highest derivative wanted.

    Returns:
        ``(m, order + 1, p + 1)`` float: ``[:, k, j]`` is the ``k``-th derivative of basis
        function ``N_{span - p + j, p}`` at ``x``; derivatives above ``p`` are zero.
    """
    p, m = degree, len(x)
    ndu = np.zeros((m, p + 1, p + 1))
    ndu[:, 0, 0] = 1.0
    left = np.zeros((m, p + 1))
    right = np.zeros((m, p + 1))
    for j in range(1, p + 1):
        left[:, j] = x - knots[span + 1 - j]
        right[:, j] = knots[span + j] - x
        saved = np.zeros(m)
        for r in range(j):
            ndu[:, j, r] = right[:, r + 1] + left[:, j - r]  # knot differences
            temp = ndu[:, r, j - 1] / ndu[:, j, r]
            ndu[:, r, j] = saved + right[:, r + 1] * temp
            saved = left[:, j - r] * temp
        ndu[:, j, j] = saved
    ders = np.zeros((m, order + 1, p + 1))
    ders[:, 0, :] = ndu[:, :, p]
    for r in range(p + 1):
        _derivative_row(ndu, ders, p, r, min(order, p))
    factor = float(p)
    for k in range(1, min(order, p) + 1):
        ders[:, k, :] *= factor
        factor *= p - k
    return ders


def _derivative_row(ndu: FloatArray, ders: FloatArray, p: int, r: int, n: int) -> None:
    """Fill ``ders[:, 1..n, r]`` (unscaled) for basis function ``r`` (inner loop of A2.3)."""
    m = ndu.shape[0]
    a = np.zeros((2, m, p + 1))
    a[0, :, 0] = 1.0
    s1, s2 = 0, 1
    for k in range(1, n + 1):
        d = np.zeros(m)
        rk, pk = r - k, p - k
        if r >= k:
            a[s2, :, 0] = a[s1, :, 0] / ndu[:, pk + 1, rk]
            d += a[s2, :, 0] * ndu[:, rk, pk]
        j1 = 1 if rk >= -1 else -rk
        j2 = k - 1 if r - 1 <= pk else p - r
        for j in range(j1, j2 + 1):
            a[s2, :, j] = (a[s1, :, j] - a[s1, :, j - 1]) / ndu[:, pk + 1, rk + j]
            d += a[s2, :, j] * ndu[:, rk + j, pk]
        if r <= pk:
            a[s2, :, k] = -a[s1, :, k - 1] / ndu[:, pk + 1, r]
            d += a[s2, :, k] * ndu[:, r, pk]
        ders[:, k, r] = d
        s1, s2 = s2, s1


@dataclass(frozen=True, eq=False)
class BSplineSurface:
    """A tensor-product B-spline (or NURBS) surface ``S(u, v)`` in mm.

    Attributes:
        poles: ``(nu, nv, 3)`` float control points, mm (part frame).
        knots_u: full knot vector in u, ``(nu + degree_u + 1,)``, non-decreasing.
        knots_v: full knot vector in v, ``(nv + degree_v + 1,)``, non-decreasing.
        degree_u: degree in u (>= 1).
        degree_v: degree in v (>= 1).
        weights: ``(nu, nv)`` positive weights of a rational surface, or ``None``.

    Raises:
        ModelError: shapes, knots, degrees or weights that do not make a surface.
    """

    poles: FloatArray
    knots_u: FloatArray
    knots_v: FloatArray
    degree_u: int
    degree_v: int
    weights: FloatArray | None = None
    _homogeneous: FloatArray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        poles = _finite(self.poles, "poles")
        if poles.ndim != 3 or poles.shape[2] != 3:
            raise ModelError(f"B-spline poles: expected an (nu, nv, 3) array, found shape "
                             f"{poles.shape}")
        nu, nv = poles.shape[:2]
        ku = _knots(self.knots_u, self.degree_u, nu, "u")
        kv = _knots(self.knots_v, self.degree_v, nv, "v")
        w = np.ones((nu, nv)) if self.weights is None else _finite(self.weights, "weights")
        if w.shape != (nu, nv) or not np.all(w > 0.0):
            raise ModelError(f"B-spline weights: expected {nu}x{nv} positive numbers, found "
                             f"shape {w.shape}, minimum {np.min(w) if w.size else 'n/a'}")
        object.__setattr__(self, "poles", poles)
        object.__setattr__(self, "knots_u", ku)
        object.__setattr__(self, "knots_v", kv)
        if self.weights is not None:
            object.__setattr__(self, "weights", w)
        object.__setattr__(self, "_homogeneous",
                           np.concatenate([poles * w[..., None], w[..., None]], axis=2))

    @property
    def domain(self) -> Domain:
        """``((u_min, u_max), (v_min, v_max))``: the parameter rectangle."""
        nu, nv = self.poles.shape[:2]
        return ((float(self.knots_u[self.degree_u]), float(self.knots_u[nu])),
                (float(self.knots_v[self.degree_v]), float(self.knots_v[nv])))

    def evaluate(self, u: ArrayLike, v: ArrayLike) -> FloatArray:
        """Points ``S(u, v)``: ``(m,)`` u and v (broadcast) → ``(m, 3)`` float, mm."""
        return self._homogeneous_derivatives(u, v, 0)[0][:, 0, 0, :]

    def derivatives(self, u: ArrayLike, v: ArrayLike) -> SurfaceJet:
        """Point and first and second partials at ``(m,)`` u, v (broadcast); see ``SurfaceJet``."""
        s, _ = self._homogeneous_derivatives(u, v, 2)
        return SurfaceJet(point=s[:, 0, 0], su=s[:, 1, 0], sv=s[:, 0, 1],
                          suu=s[:, 2, 0], suv=s[:, 1, 1], svv=s[:, 0, 2])

    def _homogeneous_derivatives(self, u: ArrayLike, v: ArrayLike,
                                 order: int) -> tuple[FloatArray, FloatArray]:
        """Cartesian partials ``S^(a,b)`` for ``a + b <= order``: ``(m, o+1, o+1, 3)``, and w."""
        uu, vv = np.broadcast_arrays(np.asanyarray(u, dtype=np.float64).ravel(),
                                     np.asanyarray(v, dtype=np.float64).ravel())
        nu, nv = self.poles.shape[:2]
        pu, pv = self.degree_u, self.degree_v
        su = find_spans(self.knots_u, pu, nu, uu)
        sv = find_spans(self.knots_v, pv, nv, vv)
        bu = basis_derivatives(self.knots_u, pu, su, uu, order)
        bv = basis_derivatives(self.knots_v, pv, sv, vv, order)
        iu = su[:, None] - pu + np.arange(pu + 1)
        iv = sv[:, None] - pv + np.arange(pv + 1)
        patch = self._homogeneous[iu[:, :, None], iv[:, None, :]]  # (m, pu+1, pv+1, 4)
        aw = np.einsum("mai,mbj,mijc->mabc", bu, bv, patch)
        return _rational(aw, order), aw[..., 3]


def _rational(aw: FloatArray, order: int) -> FloatArray:
    """Cartesian partials from homogeneous ones (quotient rule, NURBS Book A4.4)."""
    a, w = aw[..., :3], aw[..., 3]
    s = np.zeros_like(a)
    for k in range(order + 1):
        for j in range(order + 1 - k):
            value = a[:, k, j].copy()
            for i in range(k + 1):
                for jj in range(j + 1):
                    if i == 0 and jj == 0:
                        continue
                    coef = _binom(k, i) * _binom(j, jj)
                    value -= coef * w[:, i, jj, None] * s[:, k - i, j - jj]
            s[:, k, j] = value / w[:, 0, 0, None]
    return s


def _binom(n: int, k: int) -> float:
    """Binomial coefficient for the small orders used here."""
    out = 1.0
    for i in range(k):
        out = out * (n - i) / (i + 1)
    return out


def _finite(values: ArrayLike, what: str) -> FloatArray:
    try:
        array = np.array(values, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ModelError(f"B-spline {what}: expected numbers, found {exc}") from None
    if not np.all(np.isfinite(array)):
        raise ModelError(f"B-spline {what}: expected finite numbers, found NaN or infinity")
    return array


def _knots(values: ArrayLike, degree: int, n_poles: int, which: str) -> FloatArray:
    """Validate one full knot vector; returns it as a float array."""
    if isinstance(degree, bool) or not isinstance(degree, int | np.integer) or degree < 1:
        raise ModelError(f"B-spline degree in {which}: expected an integer >= 1, found {degree!r}")
    knots = _finite(values, f"knots in {which}")
    expected = n_poles + degree + 1
    if knots.ndim != 1 or len(knots) != expected:
        raise ModelError(f"B-spline knots in {which}: expected {expected} knots "
                         f"({n_poles} poles, degree {degree}), found shape {knots.shape}")
    if np.any(np.diff(knots) < 0.0):
        raise ModelError(f"B-spline knots in {which}: expected a non-decreasing sequence")
    if not knots[n_poles] > knots[degree]:
        raise ModelError(f"B-spline knots in {which}: the domain [{knots[degree]}, "
                         f"{knots[n_poles]}] is empty")
    if np.any(np.bincount(np.unique(knots, return_inverse=True)[1]) > degree + 1):
        raise ModelError(f"B-spline knots in {which}: a knot repeats more than degree + 1 "
                         f"= {degree + 1} times")
    return knots


def clamped_knots(n_poles: int, degree: int, lo: float, hi: float) -> FloatArray:
    """Clamped uniform full knot vector on ``[lo, hi]`` for ``n_poles`` poles."""
    inner = np.linspace(lo, hi, n_poles - degree + 1)
    return np.concatenate([np.full(degree, lo), inner, np.full(degree, hi)])


def greville(knots: FloatArray, degree: int) -> FloatArray:
    """Greville abscissae: the pole parameters that make a spline reproduce ``x = u``."""
    n_poles = len(knots) - degree - 1
    return np.array([knots[i + 1:i + degree + 1].mean() for i in range(n_poles)])


def height_field(heights: ArrayLike, *, x: tuple[float, float], y: tuple[float, float],
                 degree: int = 3) -> BSplineSurface:
    """A graph surface ``S(u, v) = (u, v, h(u, v))`` over a rectangle.

    The poles sit at the Greville abscissae of clamped uniform knots, so the x and y
    coordinates are exactly ``u`` and ``v`` (B-splines reproduce linear functions) and a
    vertical guide line through ``(x, y)`` is seeded with ``(u, v) = (x, y)``.

    Args:
        heights: ``(nu, nv)`` pole heights (z), mm; ``nu, nv > degree``.
        x: ``(x_min, x_max)`` = the u domain, mm.
        y: ``(y_min, y_max)`` = the v domain, mm.
        degree: degree in both directions.

    Returns:
        The surface.
    """
    h = _finite(heights, "heights")
    if h.ndim != 2 or min(h.shape) <= degree:
        raise ModelError(f"height field: expected an (nu, nv) array with nu, nv > {degree}, "
                         f"found shape {h.shape}")
    ku = clamped_knots(h.shape[0], degree, *x)
    kv = clamped_knots(h.shape[1], degree, *y)
    gu, gv = np.meshgrid(greville(ku, degree), greville(kv, degree), indexing="ij")
    return BSplineSurface(np.stack([gu, gv, h], axis=2), ku, kv, degree, degree)
