"""Method M5: the seed's stepwise identification, on the modelled layout (``vmc-xyfz``).

Per plane, with the seed's lines (``L?0`` along u at v0, ``L?2`` along u at v1, ``L?3``
along v at u1, ``L?4`` along v at u0; the diagonal is left to the global fit), in the
model of :mod:`probegen.calibrate.identify_model` (z_r the read point's z, h the head):

1. squareness: ``S = a0 + a4`` (least-squares slopes of v-deviation along L?0 and of
   u-deviation along L?4, µrad), plus the yaw/pitch of the first axis at L?4's position
   (``+ECX(x10)`` XY, ``−EBX(x20)`` XZ, ``+EAY(y30)`` YZ) so that it is the plane
   squareness the global fit reports;
2. angles from the parallel lines L?0 and L?2: ``du2 − du0 = −ECX(x)·Δy`` (XY),
   ``+EBX(x)·Δz`` (XZ), ``−EAY(y)·Δz`` (YZ).  The seed's second pair (L?3 − L?4 giving
   the yaw of Y, the yaw of Z in XZ, the pitch of Z in YZ) gives a constant here: on
   this layout the Y saddle and the Z head do not carry the axis moved before them, so
   those angles have no lever arm across the plane;
3. with the angles, the Abbe terms leave L?0 and L?4: ``EXX = du0 − EBX·z_r + ECX·y10``
   (XY), ``EYY = dv4 + EAY·z_r`` (XY), ``EZZ = dv4`` (XZ), ``EZY = dv0`` (YZ, about its
   reference line);
4. rolls: with a riser setup of XY, ``dv0`` and ``du4`` change with the height by
   ``−EAX(x)·Δz`` and ``+EBY(y)·Δz`` (about their lines: each setup's plate turn is
   unknown); their slopes come from the difference of both changes in XY
   (``(b − a)·Δz``) and from the sum in
   XZ with its riser (``a·Δy + EBY(w2) − EBY(w1)``); or the rolls come from an
   electronic level.  Then ``EYX = dv0 + EAX·z_r``, ``EXY = du4 − EBY·z_r`` (XY),
   ``EZX = dv0 − EAX·y0`` (XZ).

What a plan leaves undetermined stays None (as in the global fit).  Each function is a
Legendre series with its degree chosen by cross-validation
(:func:`probegen.geometry.orthopoly.fit_cv`).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from probegen.calibrate.grating_io import GratingReading, LevelReading
from probegen.calibrate.identify import (
    SQUARENESS,
    FunctionResult,
    Identification,
    SquarenessResult,
    axis_ranges,
    reference_setups,
)
from probegen.calibrate.identify_model import FUNCTIONS, FloatArray, SetupKey, setup_of
from probegen.errors import CalibrationError
from probegen.geometry.orthopoly import AxisRange, PolyFit, fit_cv
from probegen.machine.kinematics import PLANES

Line = tuple[FloatArray, FloatArray, FloatArray]
"""Axis positions along the line (mm), du, dv (µm), sorted by position."""


class _Lines:
    """The readings of one setup by line role (``0``, ``2``, ``3``, ``4``)."""

    def __init__(self, setup: SetupKey, readings: Sequence[GratingReading]) -> None:
        self.setup = setup
        self.rows = [r for r in readings if setup_of(r) == setup]
        self.u, self.v, self.n = PLANES[setup.plane]
        self.prefix = f"L{list(PLANES).index(setup.plane) + 1}"  # L1 XY, L2 XZ, L3 YZ

    def line(self, role: str) -> Line:
        name = self.prefix + role
        rows = [r for r in self.rows if r.line == name]
        if len(rows) < 4:
            raise CalibrationError(f"stepwise identification, {self.setup.label}: expected "
                                   f"the seed's line {name} with at least 4 stops, found "
                                   f"{len(rows)}")
        along = self.u if role in "02" else self.v
        q = np.array([r.point[along] + (r.head if along == 2 else 0.0) for r in rows])
        order = np.argsort(q, kind="stable")
        du = np.array([r.du for r in rows])[order]
        dv = np.array([r.dv for r in rows])[order]
        return q[order], du, dv

    def fixed(self, role: str, axis: int) -> float:
        """The (constant) coordinate ``axis`` of the line's read points, mm."""
        r = next(r for r in self.rows if r.line == self.prefix + role)
        return float(r.point[axis])


def _same(a: Line, b: Line) -> tuple[np.ndarray, np.ndarray]:
    """Positions common to two lines and the index arrays into each."""
    qa, qb = np.round(a[0], 6), np.round(b[0], 6)
    common = np.intersect1d(qa, qb)
    if len(common) < 4:
        raise CalibrationError("stepwise identification: expected lines sampled at the same "
                               f"positions, found {len(common)} in common")
    return (np.searchsorted(qa, common), np.searchsorted(qb, common))


class _Stepwise:
    def __init__(self, readings: Sequence[GratingReading], max_degree: int) -> None:
        self.ranges = axis_ranges(readings)
        self.max_degree = max_degree
        keys = list(dict.fromkeys(setup_of(r) for r in readings))
        self.first = {s.plane: _Lines(s, readings) for s in reference_setups(keys)}
        self.second: dict[str, _Lines] = {}  # a riser: same plane and head, another w
        for s in keys:
            first = self.first[s.plane].setup
            if s.head == first.head and s.w != first.w and s.plane not in self.second:
                self.second[s.plane] = _Lines(s, readings)
        if set(self.first) != set(PLANES):
            raise CalibrationError(f"stepwise identification: expected the planes XY, XZ and "
                                   f"YZ, found {sorted(self.first)}")
        self.fits: dict[str, PolyFit] = {}

    def fit(self, name: str, q: FloatArray, values: FloatArray) -> PolyFit:
        f = next(f for f in FUNCTIONS if f.name == name)
        rng: AxisRange = self.ranges[f.axis]
        self.fits[name] = fit_cv(rng, q, values, f.lowest, self.max_degree)
        return self.fits[name]

    def slope(self, axis: int, q: FloatArray, values: FloatArray) -> float:
        """Least-squares slope over the axis range, in the values' unit per mm: the
        degree-1 Legendre coefficient of a cross-validated fit, ``2·c1/(hi − lo)``."""
        rng = self.ranges[axis]
        c1 = fit_cv(rng, q, values, 1, self.max_degree).coefficients[0]
        return float(2.0 * c1 / (rng.hi - rng.lo))

    def angles(self) -> None:
        """Step 2: ECX (XY), EBX (XZ), EAY (YZ) from L?2 − L?0."""
        for plane, name, sign in (("XY", "ECX", -1.0), ("XZ", "EBX", 1.0),
                                  ("YZ", "EAY", -1.0)):
            lines = self.first[plane]
            a, b = lines.line("0"), lines.line("2")
            ia, ib = _same(a, b)
            gap = lines.fixed("2", lines.v) - lines.fixed("0", lines.v)
            self.fit(name, a[0][ia], sign * (b[1][ib] - a[1][ia]) * 1e3 / gap)

    def translations(self) -> None:
        """Step 3: EXX, EYY (XY), EZZ (XZ), EZY (YZ)."""
        xy, xz, yz = self.first["XY"], self.first["XZ"], self.first["YZ"]
        q, du, _ = xy.line("0")
        zr, y10 = xy.setup.w, xy.fixed("0", 1)
        self.fit("EXX", q, du - (self.fits["EBX"](q) * zr - self.fits["ECX"](q) * y10) * 1e-3)
        q, _, dv = xy.line("4")
        self.fit("EYY", q, dv + self.fits["EAY"](q) * zr * 1e-3)
        q, _, dv = xz.line("4")
        self.fit("EZZ", q, dv)
        q, _, dv = yz.line("0")
        self.fit("EZY", q, dv)

    def squareness(self) -> list[SquarenessResult]:
        """Step 1 with the correction of the module docstring."""
        out = []
        for plane, corr in (("XY", ("ECX", 1.0)), ("XZ", ("EBX", -1.0)),
                            ("YZ", ("EAY", 1.0))):
            lines = self.first[plane]
            q0, _, dv0 = lines.line("0")
            q4, du4, _ = lines.line("4")
            a0 = self.slope(lines.u, q0, dv0) * 1e3  # µm/mm → µrad
            a4 = self.slope(lines.v, q4, du4) * 1e3
            at = lines.fixed("4", lines.u)
            value = a0 + a4 + corr[1] * float(self.fits[corr[0]]([at])[0])
            out.append(SquarenessResult(SQUARENESS[plane], lines.setup, float(value)))
        return out

    def rolls_from_risers(self) -> bool:
        """Step 4 with risers in XY and XZ; False when either is missing."""
        if "XY" not in self.second or "XZ" not in self.second:
            return False
        xy1, xy2 = self.first["XY"], self.second["XY"]
        dz = xy2.setup.w - xy1.setup.w
        a1, a2 = xy1.line("0"), xy2.line("0")
        i1, i2 = _same(a1, a2)
        q_x, d_eax = a1[0][i1], -(a2[2][i2] - a1[2][i1]) * 1e3 / dz
        b1, b2 = xy1.line("4"), xy2.line("4")
        j1, j2 = _same(b1, b2)
        q_y, d_eby = b1[0][j1], (b2[1][j2] - b1[1][j1]) * 1e3 / dz
        # the nonlinear parts; the slopes hold the two plates' turn, which cancels in b − a
        eby = fit_cv(self.ranges[1], q_y, d_eby, 2, self.max_degree)
        b_minus_a = self.slope(1, q_y, d_eby) - self.slope(0, q_x, d_eax)
        xz1, xz2 = self.first["XZ"], self.second["XZ"]
        dw = xz2.setup.w - xz1.setup.w
        c1, c2 = xz1.line("0"), xz2.line("0")
        k1, k2 = _same(c1, c2)
        s_dv = self.slope(0, c1[0][k1], c2[2][k2] - c1[2][k1]) * 1e3
        e1, e2 = xz1.line("4"), xz2.line("4")
        m1, m2 = _same(e1, e2)
        s_du = self.slope(2, e1[0][m1], e2[1][m2] - e1[1][m1]) * 1e3
        nonlinear = float(eby([xz2.setup.w])[0] - eby([xz1.setup.w])[0])
        # a·Δy + b·Δy + the nonlinear EBY change = the sum of the XZ slope changes
        a_plus_b = (s_dv + s_du - nonlinear) / dw
        a, b = (a_plus_b - b_minus_a) / 2.0, (a_plus_b + b_minus_a) / 2.0
        eax = fit_cv(self.ranges[0], q_x, d_eax, 2, self.max_degree)
        mid_x, mid_y = (self.ranges[0].lo + self.ranges[0].hi) / 2, (self.ranges[1].lo
                                                                    + self.ranges[1].hi) / 2
        self.fit("EAX", q_x, eax(q_x) + a * (q_x - mid_x))
        self.fit("EBY", q_y, eby(q_y) + b * (q_y - mid_y))
        return True

    def rolls_from_level(self, level: Sequence[LevelReading]) -> bool:
        """Step 4 with level readings of X and Y; False when either is missing."""
        axes = {r.axis for r in level}
        if not {"X", "Y"} <= axes:
            return False
        for axis, name in (("X", "EAX"), ("Y", "EBY")):
            rows = [r for r in level if r.axis == axis]
            self.fit(name, np.array([r.position for r in rows]),
                     np.array([r.roll for r in rows]))
        return True

    def straightness(self) -> None:
        """Step 4's end: EYX, EXY (XY) and EZX (XZ) with the rolls known."""
        xy, xz = self.first["XY"], self.first["XZ"]
        q, _, dv = xy.line("0")
        self.fit("EYX", q, dv + self.fits["EAX"](q) * xy.setup.w * 1e-3)
        q, du, _ = xy.line("4")
        self.fit("EXY", q, du - self.fits["EBY"](q) * xy.setup.w * 1e-3)
        q, _, dv = xz.line("0")
        self.fit("EZX", q, dv - self.fits["EAX"](q) * xz.setup.w * 1e-3)


def identify_stepwise(readings: Sequence[GratingReading], level: Sequence[LevelReading] = (),
                      *, max_degree: int = 6) -> Identification:
    """The seed's stepwise identification (module docstring).

    Raises:
        CalibrationError: a plane or a seed line is missing, or lines do not share
            their sampling positions.
    """
    s = _Stepwise(readings, max_degree)
    s.angles()
    s.translations()
    squareness = s.squareness()
    if s.rolls_from_level(level) or s.rolls_from_risers():
        s.straightness()
    functions = tuple(
        FunctionResult(f, s.ranges[f.axis], s.fits[f.name].coefficients)
        if f.name in s.fits else FunctionResult(f, s.ranges[f.axis], None)
        for f in FUNCTIONS)
    degree = max(fit.degree for fit in s.fits.values())
    fitted = sum(len(fit.coefficients) for fit in s.fits.values())
    return Identification("stepwise", degree, functions, tuple(squareness), fitted, fitted,
                          _dispersion(s))


def _dispersion(s: _Stepwise) -> float:
    """Pooled RMS residual of the stepwise fits that map readings one to one (µm)."""
    translation = [s.fits[n].residual_rms for n in ("EXX", "EYY", "EZZ", "EZY") if n in s.fits]
    return float(np.sqrt(np.mean(np.square(translation))))
