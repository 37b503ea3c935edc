"""Process capability of one characteristic (ISO 22514-2, normal distribution).

From the evaluated values ``x_1 … x_n`` of a :class:`~probegen.spc.series.Series` (NOT
EVALUATED runs are counted apart and left out):

* ``mean`` μ̂ = x̄;
* ``sigma`` σ̂ (within, short term): from the control chart (``probegen.spc.control``),
  ``MR̄ / 1.128`` for individuals or ``R̄ / d2(n)`` for subgroups of ``n``;
* ``sigma_overall`` s: the sample standard deviation (``n − 1`` in the denominator);
* ``Cp = (USL − LSL) / 6σ̂``, ``Cpk = min(USL − μ̂, μ̂ − LSL) / 3σ̂`` (capability);
  ``Pp``, ``Ppk`` the same with s (performance);
* one-sided tolerance: no ``Cp``/``Pp``; ``Cpk`` is ``CPU = (USL − μ̂) / 3σ̂`` or
  ``CPL = (μ̂ − LSL) / 3σ̂`` (``Ppk`` likewise).

No index is given (None, with the reason in ``notes``) from fewer than
:data:`MIN_VALUES` values, for an untoleranced characteristic, or when σ is 0 (constant
values) or the arithmetic leaves the float range.  ``u_mean`` is the mean of the values'
standard uncertainties and ``u_ratio = u_mean / σ̂``: above :data:`U_RATIO_FLAG` the
measurement makes a noticeable part of the observed spread and the indices describe the
measuring as much as the process (``docs/spc.md``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from probegen.spc.control import ControlChart, control_chart, evaluated, mean_of
from probegen.spc.series import Series

MIN_VALUES = 10
"""Fewest evaluated values from which a capability index is given.  At n = 10 the 95 %
confidence interval of Cp is still about −45 % … +55 % of its value (χ² with 9 degrees of
freedom); below that the number would mislead more than inform.  σ and the mean are
given from 2 values."""

U_RATIO_FLAG = 0.3
"""``u_mean / σ̂`` above which a note says the measurement uncertainty is not small
against the process spread (u² is then more than 9 % of the observed variance)."""

RESOLUTION = 1e-12
"""A standard deviation below ``RESOLUTION · |mean|`` is rounding in float arithmetic, not
process spread: the values count as constant (no index)."""


@dataclass(frozen=True, slots=True)
class Capability:
    """The capability figures of one series (module docstring).

    Attributes:
        n: evaluated values.
        not_evaluated: NOT EVALUATED values (measured None).
        mean: x̄, or None without values.
        sigma: within standard deviation σ̂, None with fewer than 2 values.
        sigma_overall: overall standard deviation s (n − 1), None with fewer than 2.
        cp: Cp, None when two-sided limits are missing or as the notes say.
        cpk: Cpk (CPU or CPL with a one-sided tolerance).
        pp: Pp.
        ppk: Ppk.
        u_mean: mean standard uncertainty of the evaluated values that carry one.
        u_ratio: ``u_mean / sigma``.
        out_of_tolerance: evaluated values outside ``[lsl, usl]``.
        chart: the control chart σ̂ came from, None with fewer than 2 values.
        notes: why an index is missing, which side a one-sided index is, warnings.
    """

    n: int
    not_evaluated: int
    mean: float | None
    sigma: float | None
    sigma_overall: float | None
    cp: float | None
    cpk: float | None
    pp: float | None
    ppk: float | None
    u_mean: float | None
    u_ratio: float | None
    out_of_tolerance: int
    chart: ControlChart | None
    notes: tuple[str, ...]


def capability(series: Series) -> Capability:
    """The capability figures of ``series`` (module docstring); never raises on values."""
    x = np.array([v for _, v in evaluated(series)], dtype=float)
    n = int(x.size)
    lsl, usl = series.lsl, series.usl
    notes: list[str] = []
    with np.errstate(all="ignore"):
        # about the first value: a constant series has s = 0 exactly (x.std() would leave
        # a rounding residue of 1e-19 and a Pp of 1e15)
        mean = _finite(mean_of(x)) if n else None
        overall = _finite(float((x - x[0]).std(ddof=1))) if n >= 2 else None
    chart = control_chart(series) if mean is not None and overall is not None else None
    sigma = chart.sigma if chart is not None else None
    if n < 2:
        notes.append(f"{n} evaluated value{'' if n == 1 else 's'}: no standard deviation")
    elif sigma is None or mean is None:
        notes.append("values beyond the float range: no statistics")
    cp = cpk = pp = ppk = None
    if sigma is not None and mean is not None and overall is not None:
        (cp, cpk), why = _indices(lsl, usl, mean, sigma, n, "sigma")
        (pp, ppk), why_p = _indices(lsl, usl, mean, overall, n, "s")
        notes += dict.fromkeys([*why, *why_p])
    u_mean, u_ratio = _uncertainty(series, sigma)
    if u_ratio is not None and u_ratio > U_RATIO_FLAG:
        notes.append(f"u/sigma = {u_ratio:.2f} > {U_RATIO_FLAG}: the measurement uncertainty "
                     "is not small against the process spread")
    out = sum(1 for v in x if (lsl is not None and v < lsl) or (usl is not None and v > usl))
    return Capability(n=n, not_evaluated=len(series.values) - n, mean=mean,
                      sigma=sigma if mean is not None else None,
                      sigma_overall=overall if sigma is not None else None, cp=cp, cpk=cpk,
                      pp=pp, ppk=ppk, u_mean=u_mean, u_ratio=u_ratio, out_of_tolerance=out,
                      chart=chart, notes=tuple(notes))


def _indices(lsl: float | None, usl: float | None, mean: float, sigma: float, n: int,
             symbol: str) -> tuple[tuple[float | None, float | None], list[str]]:
    """(Cp, Cpk) from ``sigma`` (or Pp, Ppk from s) and the reasons for a missing one."""
    if lsl is None and usl is None:
        return (None, None), ["not toleranced: no capability index"]
    if n < MIN_VALUES:
        return (None, None), [f"n = {n} < {MIN_VALUES}: no capability index"]
    if lsl is not None and usl is not None and not usl > lsl:
        return (None, None), ["empty tolerance zone (USL <= LSL): no capability index"]
    if not sigma > RESOLUTION * abs(mean):
        return (None, None), [f"constant values ({symbol} = 0): no capability index"]
    with np.errstate(all="ignore"):
        upper = None if usl is None else _finite((usl - mean) / (3.0 * sigma))
        lower = None if lsl is None else _finite((mean - lsl) / (3.0 * sigma))
        spread = (None if lsl is None or usl is None
                  else _finite((usl - lsl) / (6.0 * sigma)))
    if lsl is None or usl is None:
        side = "USL only: Cpk = CPU" if lsl is None else "LSL only: Cpk = CPL"
        return (None, upper if lsl is None else lower), [f"one-sided tolerance ({side})"]
    ks = [k for k in (upper, lower) if k is not None]
    if spread is None or len(ks) < 2:
        return (None, None), ["values beyond the float range: no capability index"]
    return (spread, min(ks)), []


def _uncertainty(series: Series, sigma: float | None) -> tuple[float | None, float | None]:
    """(mean u of the evaluated values that carry one, its ratio to ``sigma``)."""
    us = [v.u for v in series.values if v.measured is not None and v.u is not None]
    with np.errstate(all="ignore"):
        u_mean = _finite(float(np.mean(us))) if us else None
        ratio = (_finite(u_mean / sigma) if u_mean is not None and sigma is not None
                 and sigma > 0.0 else None)
    return u_mean, ratio


def _finite(value: float) -> float | None:
    return value if math.isfinite(value) else None
