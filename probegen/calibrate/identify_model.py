"""The linearised volumetric model of a ``vmc-xyfz`` machine and its identifiability (M5).

Volumetric model (first order of :mod:`probegen.machine.kinematics`' chain
``L_X(x)·L_Y(y)·L_Z(z)``, workpiece → X table → Y saddle → bed → Z head → tool), with
``q = (x, y, z)`` the axis positions and ``t`` the tool (reading head) offset from the
spindle gauge point; µm and µrad, positions mm::

    e = δ_X(x) + ε_X(x) × ((0, y, z) + t) + δ_Y(y) + ε_Y(y) × ((0, 0, z) + t)
        + δ_Z(z) + ε_Z(z) × t + (S_xy·y + S_xz·z, S_yz·z, 0)

A grating in plane (u, v) reads ``e_u``, ``e_v`` plus, per setup, an unknown zero
(``o_u``, ``o_v``) and an unknown turn ``θ`` of the plate in its plane
(``−θ·v``, ``+θ·u``).  Each of the 21 error functions is a Legendre series of degree
``0..d`` on its axis range (:mod:`probegen.geometry.orthopoly`); all coefficients are
unknowns, so the design matrix's null space holds every gauge freedom and every
confounding of the plan.

Quantities reported (ISO 230-1 conventions), each a linear functional of the unknowns:

* positioning ``δ_jj``: degrees 1..d (about its mean; the constant is a setup zero);
* straightness ``δ_ij``: degrees 2..d (about its least-squares reference line: the slope
  belongs to squareness, see below);
* angular ``ε_ij``: degrees 1..d (about its mean: a constant angle turns whole lines, so
  it is one with squareness and the plate's turn);
* squareness of each plane as the seed measures it: the sum of the least-squares slopes,
  over the plane's square, of the two cross components (``∂e_u/∂v + ∂e_v/∂u``, µrad) at
  the plane's first setup (its height and head).  In the modelled layout it depends on
  where it is measured (roll slopes times height, e.g. ``S_XY(z) = S_xy + (β_EBY − β_EAX)·
  (z + t_z)``): it is reported where it was measured.

A quantity is determined by the plan iff its functional is orthogonal to the null space.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.polynomial import legendre
from numpy.typing import NDArray

from probegen.calibrate.grating_io import GratingReading, LevelReading
from probegen.geometry.orthopoly import AxisRange, basis
from probegen.machine.kinematics import PLANES

FloatArray = NDArray[np.float64]
AXIS = "XYZ"
ISO_TRANSLATION = "XYZ"
ISO_ROTATION = "ABC"
RANK_TOL = 1e-9
"""Singular values below this fraction of the largest count as zero (columns scaled)."""
DETERMINED_TOL = 1e-6
"""A functional whose component in the null space is below this fraction of its size is
determined."""


@dataclass(frozen=True)
class ErrorFunction:
    """One of the 21 error motions.

    Attributes:
        axis: the moving axis, 0..2 for X, Y, Z.
        angular: a rotation (µrad) or a translation (µm).
        component: the direction (translation) or rotation axis, 0..2.
    """

    axis: int
    angular: bool
    component: int

    @property
    def name(self) -> str:
        """ISO 230-1 name, e.g. ``EXX``, ``EYX``, ``EAX``."""
        letters = ISO_ROTATION if self.angular else ISO_TRANSLATION
        return f"E{letters[self.component]}{AXIS[self.axis]}"

    @property
    def kind(self) -> str:
        """positioning, straightness, roll or angular (pitch / yaw)."""
        if self.angular:
            return "roll" if self.component == self.axis else "angular"
        return "positioning" if self.component == self.axis else "straightness"

    @property
    def lowest(self) -> int:
        """Lowest Legendre degree reported (see the module docstring)."""
        return 2 if self.kind == "straightness" else 1

    @property
    def unit(self) -> str:
        """``urad`` or ``um``."""
        return "urad" if self.angular else "um"


FUNCTIONS: tuple[ErrorFunction, ...] = tuple(
    ErrorFunction(j, ang, i) for j in range(3) for ang in (False, True) for i in range(3))
"""The 18 error motions (6 per axis, in :class:`~probegen.machine.errors_model.AxisErrors`
row order); with the 3 squareness errors, the 21 terms of a 3-axis machine."""


@dataclass(frozen=True)
class SetupKey:
    """One mounting of the grating: plane, out-of-plane coordinate (mm), head length (mm)."""

    plane: str
    w: float
    head: float

    @property
    def label(self) -> str:
        """E.g. ``XY Z=-200 head 100``."""
        n = "XYZ"[PLANES[self.plane][2]]
        return f"{self.plane} {n}={self.w:g} head {self.head:g}"


def setup_of(r: GratingReading) -> SetupKey:
    """The setup a reading belongs to."""
    p = r.point
    return SetupKey(r.plane, round(p[PLANES[r.plane][2]], 6), r.head)


def axis_positions(point: FloatArray, head: FloatArray) -> FloatArray:
    """Axis positions (gauge point) of read points ``point`` (n, 3) with head lengths (n,)."""
    q = np.array(point, dtype=np.float64)
    q[:, 2] += head
    return q


class VolumetricModel:
    """The linearised model's columns: 21 functions × (d + 1) Legendre coefficients, then
    S_xy, S_xz, S_yz (µrad).

    Args:
        ranges: the axis range of each axis (X, Y, Z).
        degree: the highest Legendre degree of every function.
    """

    def __init__(self, ranges: Sequence[AxisRange], degree: int) -> None:
        self.ranges = tuple(ranges)
        self.degree = degree
        self.width = degree + 1
        self.size = len(FUNCTIONS) * self.width + 3

    def block(self, k: int) -> slice:
        """Columns of function ``FUNCTIONS[k]``."""
        return slice(k * self.width, (k + 1) * self.width)

    def squareness_column(self, pair: str) -> int:
        """Column of ``xy``, ``xz`` or ``yz``."""
        return len(FUNCTIONS) * self.width + ("xy", "xz", "yz").index(pair)

    def sensitivity(self, q: FloatArray, t: FloatArray) -> FloatArray:
        """∂e/∂parameters at axis positions ``q`` (n, 3) with tool offsets ``t`` (n, 3):
        (n, 3, size), e in µm."""
        n = len(q)
        out = np.zeros((n, 3, self.size))
        zero = np.zeros(n)
        arms = (np.column_stack([zero, q[:, 1], q[:, 2]]) + t,
                np.column_stack([zero, zero, q[:, 2]]) + t, t)
        for k, f in enumerate(FUNCTIONS):
            p = basis(self.ranges[f.axis], q[:, f.axis], range(self.width))
            if f.angular:
                unit = np.zeros(3)
                unit[f.component] = 1.0
                lever = np.cross(unit, arms[f.axis]) * 1e-3
                out[:, :, self.block(k)] = lever[:, :, None] * p[:, None, :]
            else:
                out[:, f.component, self.block(k)] = p
        out[:, 0, self.squareness_column("xy")] = q[:, 1] * 1e-3
        out[:, 0, self.squareness_column("xz")] = q[:, 2] * 1e-3
        out[:, 1, self.squareness_column("yz")] = q[:, 2] * 1e-3
        return out

    def function_selector(self, k: int) -> FloatArray:
        """Rows selecting the reported coefficients of ``FUNCTIONS[k]``: (m, size)."""
        f = FUNCTIONS[k]
        rows = np.zeros((self.width - f.lowest, self.size))
        for r, deg in enumerate(range(f.lowest, self.width)):
            rows[r, k * self.width + deg] = 1.0
        return rows

    def plane_squareness(self, setup: SetupKey) -> FloatArray:
        """The functional (size,) of the plane squareness at ``setup`` (module docstring)."""
        u, v, n = PLANES[setup.plane]
        s, w = legendre.leggauss(self.degree + 3)
        ru, rv = self.ranges[u], self.ranges[v]
        pu = ru.lo + (s + 1.0) * (ru.hi - ru.lo) / 2.0
        pv = rv.lo + (s + 1.0) * (rv.hi - rv.lo) / 2.0
        gu, gv = np.meshgrid(pu, pv, indexing="ij")
        q = np.zeros((gu.size, 3))  # axis positions over the plane's square
        q[:, u], q[:, v] = gu.ravel(), gv.ravel()
        q[:, n] = setup.w + (setup.head if n == 2 else 0.0)
        sens = self.sensitivity(q, np.tile([0.0, 0.0, -setup.head], (gu.size, 1)))
        weight_u = np.outer(w / 2.0, 1.5 * w * s).ravel()  # mean over u, P1 over v
        weight_v = np.outer(1.5 * w * s, w / 2.0).ravel()  # P1 over u, mean over v
        slope_v = 2.0 / (rv.hi - rv.lo) * 1e3  # P1 coefficient (µm) → µrad
        slope_u = 2.0 / (ru.hi - ru.lo) * 1e3
        return np.asarray(slope_v * weight_u @ sens[:, u, :]
                          + slope_u * weight_v @ sens[:, v, :])


@dataclass(frozen=True)
class Design:
    """The full design matrix of a set of readings.

    Attributes:
        model: the volumetric model (its columns come first).
        setups: the setups, in the order of their nuisance columns (3 each).
        level_axes: the axes with level readings (one zero column each, last).
        matrix: (m, columns) float.
        values: (m,) float, the readings (µm; level rows µrad times ``level_weight``).
        kinds: (m,) str, ``grating`` or ``level``.
    """

    model: VolumetricModel
    setups: tuple[SetupKey, ...]
    level_axes: tuple[int, ...]
    matrix: FloatArray
    values: FloatArray
    kinds: tuple[str, ...]


def design(model: VolumetricModel, readings: Sequence[GratingReading],
           level: Sequence[LevelReading] = (), level_weight: float = 1.0) -> Design:
    """The design matrix of grating readings (two rows each) and level readings."""
    setups = tuple(dict.fromkeys(setup_of(r) for r in readings))
    level_axes = tuple(sorted({"XYZ".index(r.axis) for r in level}))
    n_model = model.size
    width = n_model + 3 * len(setups) + len(level_axes)
    point = np.array([r.point for r in readings], dtype=np.float64)
    head = np.array([r.head for r in readings])
    t = np.zeros((len(readings), 3))
    t[:, 2] = -head
    sens = model.sensitivity(axis_positions(point, head), t)
    rows = np.zeros((2 * len(readings) + len(level), width))
    values = np.zeros(len(rows))
    for i, r in enumerate(readings):
        u, v, _ = PLANES[r.plane]
        col = n_model + 3 * setups.index(setup_of(r))
        rows[2 * i, :n_model], rows[2 * i + 1, :n_model] = sens[i, u], sens[i, v]
        rows[2 * i, col], rows[2 * i + 1, col + 1] = 1.0, 1.0
        rows[2 * i, col + 2] = -point[i, v] * 1e-3
        rows[2 * i + 1, col + 2] = point[i, u] * 1e-3
        values[2 * i], values[2 * i + 1] = r.du, r.dv
    base = 2 * len(readings)
    for i, lv in enumerate(level):
        axis = "XYZ".index(lv.axis)
        k = FUNCTIONS.index(ErrorFunction(axis, True, axis))
        p = basis(model.ranges[axis], [lv.position], range(model.width))[0]
        rows[base + i, model.block(k)] = level_weight * p
        rows[base + i, n_model + 3 * len(setups) + level_axes.index(axis)] = level_weight
        values[base + i] = level_weight * lv.roll
    kinds = ("grating",) * base + ("level",) * len(level)
    return Design(model, setups, level_axes, rows, values, kinds)


@dataclass(frozen=True)
class Identifiability:
    """The rank of a design and what it determines.

    Attributes:
        rank: numerical rank.
        columns: number of unknowns.
        null: (columns, columns − rank) float, a basis of the null space (unscaled units).
        scale: (columns,) float, the column norms used for the rank decision.
    """

    rank: int
    columns: int
    null: FloatArray
    scale: FloatArray

    def determined(self, functional: FloatArray) -> bool:
        """Whether every row of ``functional`` (k, n_model or columns) is determined."""
        g = np.atleast_2d(functional)
        g = np.pad(g, ((0, 0), (0, self.columns - g.shape[1])))
        gs = g / self.scale
        size = np.linalg.norm(gs, axis=1)
        leak = np.linalg.norm(gs @ self.null, axis=1)
        return bool(np.all(leak <= DETERMINED_TOL * np.maximum(size, 1e-300)))

    def partners(self, k: int, model: VolumetricModel) -> list[str]:
        """The other functions ``FUNCTIONS[k]`` is confounded with: those whose reported
        coefficients couple with its own through the null-space projector."""
        n = self.null[:model.size]
        mine = (model.function_selector(k) / self.scale[:model.size]) @ n
        out = []
        for j, f in enumerate(FUNCTIONS):
            other = (model.function_selector(j) / self.scale[:model.size]) @ n
            if j != k and np.abs(other @ mine.T).max(initial=0.0) > DETERMINED_TOL:
                out.append(f.name)
        return out


def combinations(ident: Identifiability, functionals: FloatArray
                 ) -> tuple[FloatArray, FloatArray]:
    """Which combinations of ``functionals`` (k, n) the plan determines.

    Returns:
        (determined, undetermined): rows are weight vectors over the k functionals
        (largest weight 1); the undetermined rows span the orthogonal complement of the
        determined ones, so together they span all combinations.
    """
    g = np.pad(functionals, ((0, 0), (0, ident.columns - functionals.shape[1])))
    gs = g / ident.scale
    size = np.linalg.norm(gs, axis=1)
    leak = (gs / size[:, None]) @ ident.null
    u, s, _ = np.linalg.svd(leak, full_matrices=True)
    r = int(np.count_nonzero(s > DETERMINED_TOL))
    known = (u[:, r:] / size[:, None]).T  # back to the functionals' own units
    _, sk, vk = np.linalg.svd(known if len(known) else np.zeros((1, len(g))))
    rest = vk[int(np.count_nonzero(sk > 1e-12 * max(sk.max(), 1e-300))):]

    def unit(rows: FloatArray) -> FloatArray:
        lead = rows[np.arange(len(rows)), np.argmax(np.abs(rows), axis=1)]
        return np.asarray(rows / lead[:, None])

    return unit(known), unit(rest)


def analyse(d: Design) -> Identifiability:
    """Rank and null space of a design (columns scaled to unit norm for the decision)."""
    a = d.matrix
    scale = np.linalg.norm(a, axis=0)
    scale[scale == 0.0] = 1.0
    _, s, vt = np.linalg.svd(a / scale, full_matrices=False)
    rank = int(np.count_nonzero(s > RANK_TOL * s[0])) if len(s) else 0
    return Identifiability(rank, a.shape[1], vt[rank:].T, scale)
