"""Method M5 outputs as text: summary, per-axis tables, Fanuc pitch table, volumetric map.

* ``summary``: rank, what the plan determines, each determined function's RMS and
  coefficients, the squareness values, the dispersion, and the largest difference
  between the global and the stepwise identifications.  A function the plan does not
  determine is printed ``NOT IDENTIFIABLE`` with what it is confounded with: never a value.
* ``axis_table``: CSV per axis, every ``step`` mm: the axis' determined functions (µm,
  µrad) about their ISO 230-1 references, each followed by the half width of its 95 %
  confidence band (``<name>_<unit>_ci95``: Student's t on the dispersion's degrees of
  freedom times the standard uncertainty from the least-squares covariance of the
  Legendre coefficients; empty for an identification without covariance, the stepwise
  one); undetermined ones have no column.
* ``fanuc_pitch_table``: the positioning error as a Fanuc-type pitch error compensation
  table (layout below).
* ``volumetric_map``: CSV of the error vector over a grid of the work volume, from the
  determined functions and squareness only (the header lists what is left out).

Fanuc-type pitch error compensation layout chosen (0i/30i style; check your control's
manual before loading): compensation points every ``interval`` mm from the axis range's
low end, point numbers from ``first_point``; the value of each point is the
*incremental* compensation from the previous point, ``−(δ(q_k) − δ(q_{k−1}))``, in
0.001 mm units divided by the magnification, an integer in −7..7, rounded so that the
running sum is the rounded compensation (no accumulated rounding); the magnification is
the smallest integer that keeps every value in range.  The header names the parameters
it implies: 3620 reference point number, 3621/3622 first/last point, 3623
magnification, 3624 interval (0.001 mm units).  The reference point is the first point
(its value 0): the table is relative to the low end of the range.
"""

from __future__ import annotations

import math

import numpy as np

from probegen.calibrate.identify import FunctionResult, Identification
from probegen.calibrate.identify_model import AXIS, FUNCTIONS, FloatArray, VolumetricModel
from probegen.geometry.orthopoly import evaluate, rms, rms_difference

PITCH_LIMIT = 7
"""Largest magnitude of one incremental pitch compensation value (times magnification)."""


def summary(result: Identification, other: Identification | None = None) -> list[str]:
    """Human-readable lines (see the module docstring)."""
    unknowns = (f"rank {result.rank} of {result.columns} unknowns"
                if result.method == "global" else f"{result.rank} coefficients fitted")
    out = [f"M5 identification ({result.method}): Legendre degree {result.degree}, {unknowns}, "
           f"dispersion {result.dispersion:.5f} um"]
    for f in result.functions:
        fn = f.function
        if f.coefficients is None:
            out.append(f"  {fn.name:4} {fn.kind:12} NOT IDENTIFIABLE ({_why(result, f)})")
            if f.curvature is not None:
                coeffs = " ".join(f"{c:+.4f}" for c in f.curvature)
                out.append(f"       but about its least-squares line: rms "
                           f"{rms(f.range, f.curvature, fn.lowest + 1):.4f} {fn.unit} "
                           f"P{fn.lowest + 1}.. {coeffs}")
            continue
        size = rms(f.range, f.coefficients, fn.lowest)
        coeffs = " ".join(f"{c:+.4f}" for c in f.coefficients)
        out.append(f"  {fn.name:4} {fn.kind:12} rms {size:8.4f} {fn.unit:4} "
                   f"P{fn.lowest}.. {coeffs}")
    for c in result.slopes:
        terms = " ".join(f"{w:+.4g}*slope({name})" for name, w in c.terms)
        if c.value is None:
            out.append(f"  slope combination {terms}: NOT IDENTIFIABLE")
        else:
            out.append(f"  slope combination {terms} = {c.value:+.4f} per m")
    for s in result.squareness:
        value = "NOT IDENTIFIABLE" if s.value is None else f"{s.value:+.4f} urad"
        out.append(f"  {s.name} at {s.setup.label}: {value}")
    if other is not None:
        out.append(f"  largest difference {other.method} - {result.method} "
                   f"(rms over the range, both determined):")
        for name, diff, unit in differences(result, other):
            out.append(f"    {name:4} {diff:.5f} {unit}")
    return out


def _why(result: Identification, f: FunctionResult) -> str:
    if result.method != "global":
        return "no step of the method reaches it with these readings"
    if not f.partners:
        return "it does not move the read point: no lever arm with this head"
    return f"confounded with {', '.join(f.partners)}"


def differences(a: Identification, b: Identification) -> list[tuple[str, float, str]]:
    """RMS over the range of ``b − a`` for each function both determine."""
    out = []
    for fa, fb in zip(a.functions, b.functions, strict=True):
        if fa.coefficients is None or fb.coefficients is None:
            continue
        out.append((fa.function.name, rms_difference(fa.range, fb.coefficients,
                                                     fa.coefficients, fa.function.lowest),
                    fa.function.unit))
    return out


def axis_table(result: Identification, axis: int, step: float = 10.0) -> str:
    """CSV of axis ``axis``' determined functions every ``step`` mm (module docstring)."""
    funcs = [f for f in result.functions if f.function.axis == axis and f.determined]
    rng = result.functions[FUNCTIONS.index(funcs[0].function)].range if funcs else None
    lines = [f"# M5 {AXIS[axis]} axis error functions ({result.method}); um and urad; "
             "straightness about its least-squares line, others about their mean"]
    missing = [f.function.name for f in result.functions
               if f.function.axis == axis and not f.determined]
    lines.append(f"# not identifiable (no column): {' '.join(missing) or '-'}")
    lines.append(f"# ci95: half width of the 95 % confidence band, Student t "
                 f"{result.k95:.3f} on {result.dof} dof"
                 if math.isfinite(result.k95) else "# ci95: no confidence band")
    lines.append(",".join(["position_mm"] + [f"{f.function.name}_{f.function.unit}{end}"
                                             for f in funcs for end in ("", "_ci95")]))
    if rng is None:
        return "\n".join(lines) + "\n"
    q = _positions(rng.lo, rng.hi, step)
    columns: list[FloatArray | None] = []
    for f in funcs:
        if f.coefficients is not None:
            columns += [evaluate(f.range, q, f.coefficients, f.function.lowest),
                        f.band(q, result.k95)]
    for i, x in enumerate(q):
        lines.append(",".join([f"{x:.3f}"] + ["" if c is None else f"{c[i]:.4f}"
                                              for c in columns]))
    return "\n".join(lines) + "\n"


def _positions(lo: float, hi: float, step: float) -> FloatArray:
    count = int(math.floor((hi - lo) / step + 1e-9))
    return np.asarray(lo + step * np.arange(count + 1))


def fanuc_pitch_table(result: Identification, axis: int, interval: float = 10.0,
                      first_point: int = 0) -> str:
    """The positioning error of ``axis`` as a Fanuc-type pitch table (module docstring).

    The positioning function is always determined by a full plan; if not, the table says
    so and holds no values.
    """
    f = result.functions[FUNCTIONS.index(next(g for g in FUNCTIONS if g.axis == axis
                                                  and not g.angular
                                                  and g.component == axis))]
    name = f"{AXIS[axis]} axis ({f.function.name})"
    if f.coefficients is None:
        return f"# pitch error compensation {name}: NOT IDENTIFIABLE, no table\n"
    q = _positions(f.range.lo, f.range.hi, interval)
    error = evaluate(f.range, q, f.coefficients, 1) * 1e-3  # mm
    values, magnification = _pitch_values(-(error - error[0]) * 1e3)  # 0.001 mm units
    last = first_point + len(q) - 1
    lines = [f"# pitch error compensation, {name}, from M5 ({result.method})",
             f"# parameter 3620 (reference point) = {first_point}",
             f"# parameter 3621 (first point) = {first_point}",
             f"# parameter 3622 (last point) = {last}",
             f"# parameter 3623 (magnification) = {magnification}",
             f"# parameter 3624 (interval, 0.001 mm) = {round(interval * 1000)}",
             "# value: incremental compensation from the previous point, 0.001 mm / "
             "magnification",
             "point,position_mm,error_um,value"]
    for k, x in enumerate(q):
        lines.append(f"{first_point + k},{x:.3f},{error[k] * 1e3:.4f},{values[k]:d}")
    return "\n".join(lines) + "\n"


def _pitch_values(compensation: FloatArray) -> tuple[np.ndarray, int]:
    """Incremental integer values (and the magnification) whose running sum is the
    rounded ``compensation`` (0.001 mm): the rounding never accumulates."""
    magnification = 1
    while True:
        total = np.rint(compensation / magnification).astype(int)
        values = np.diff(total, prepend=0)
        if np.all(np.abs(values) <= PITCH_LIMIT):
            return values, magnification
        magnification += 1


def reported_parameters(result: Identification, model: VolumetricModel) -> FloatArray:
    """The model's raw parameters from the determined reported quantities only
    (below-``lowest`` degrees zero; squareness as the plane values)."""
    p = np.zeros(model.size)
    for k, f in enumerate(result.functions):
        if f.coefficients is not None:
            n = min(len(f.coefficients), model.width - f.function.lowest)
            start = k * model.width + f.function.lowest
            p[start:start + n] = f.coefficients[:n]
    for s in result.squareness:
        if s.value is not None:
            p[model.squareness_column(s.name[2:].lower())] = s.value
    return p


def volumetric_map(result: Identification, head: float, count: int = 5) -> str:
    """CSV ``x,y,z`` (axis positions, mm) and ``ex,ey,ez`` (µm) on a ``count``³ grid."""
    ranges = tuple(f.range for f in (result.functions[0], result.functions[6],
                                     result.functions[12]))
    model = VolumetricModel(ranges, result.degree)
    p = reported_parameters(result, model)
    axes = [np.linspace(r.lo, r.hi, count) for r in ranges]
    grid = np.array(np.meshgrid(*axes, indexing="ij")).reshape(3, -1).T
    t = np.tile([0.0, 0.0, -head], (len(grid), 1))
    e = model.sensitivity(grid, t) @ p
    left = [f.function.name for f in result.functions if f.coefficients is None]
    left += [s.name for s in result.squareness if s.value is None]
    lines = [f"# M5 volumetric error ({result.method}), head {head:g} mm: actual - nominal "
             "tool point, um; axis positions mm",
             f"# left out (not identifiable): {' '.join(left) or '-'}",
             "x_mm,y_mm,z_mm,ex_um,ey_um,ez_um"]
    for q, v in zip(grid, e, strict=True):
        lines.append(",".join([f"{c:.3f}" for c in q] + [f"{c:.4f}" for c in v]))
    return "\n".join(lines) + "\n"
