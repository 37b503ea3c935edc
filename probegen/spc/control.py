"""Control charts of one characteristic: individuals / moving range or X̄-R, and run rules.

Chart choice (``docs/spc.md``):

* **X̄-R** when every evaluated value carries a subgroup, the subgroups (in order of their
  first value) all hold the same number ``n`` of evaluated values, ``2 <= n <= 10``, and
  there are at least two of them: centre ``X̿``, limits ``X̿ ± A2 R̄``; range chart
  ``D3 R̄ .. D4 R̄``; σ̂ = ``R̄ / d2(n)``.
* **I-MR** otherwise (no subgroups, subgroups of unequal size — a NOT EVALUATED value
  makes its subgroup smaller —, subgroups larger than 10, or only one subgroup): the
  values one by one in run order, centre ``x̄``, limits ``x̄ ± 2.66 MR̄``; moving range
  chart ``0 .. 3.267 MR̄``; σ̂ = ``MR̄ / 1.128``.  The chart's ``note`` says why
  subgroups, when there were some, were not used.

Run rules on the plotted statistic (values or subgroup means), each hit a
:class:`Signal` naming the runs involved:

* ``beyond``: a point outside the control limits (beyond 3 σ; Western Electric rule 1,
  Nelson rule 1);
* ``range``: a moving range or subgroup range above its upper limit;
* ``run``: 8 or more points in a row strictly on one side of the centre line (Western
  Electric Statistical Quality Control Handbook, 1956, and Montgomery use 8; Nelson
  1984 uses 9 — 8 is chosen as the earlier warning); a point on the line ends the run;
* ``trend``: 6 or more points in a row each strictly above (or below) the one before
  (Nelson 1984, rule 3).

A run or trend longer than its minimum is one signal naming all its points.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from probegen.spc.constants import CONSTANTS, D2_MR, D4_MR, E2
from probegen.spc.series import Series

RUN_LENGTH = 8
"""Points in a row on one side of the centre line that make a ``run`` signal."""

TREND_LENGTH = 6
"""Points in a row steadily increasing or decreasing that make a ``trend`` signal."""

RULES = ("beyond", "range", "run", "trend")
"""The rule names, in the order signals are listed."""


@dataclass(frozen=True, slots=True)
class Point:
    """One plotted point of the X (or X̄) chart.

    Attributes:
        x: its position on the run axis: the 1-based index of the value in
            ``Series.values`` (for a subgroup mean, the mean index of its values).
        value: the value (or subgroup mean), in the series' unit.
        runs: the run keys behind the point (one, or the subgroup's).
        indices: the 0-based indices in ``Series.values`` of those runs.
    """

    x: float
    value: float
    runs: tuple[str, ...]
    indices: tuple[int, ...]


@dataclass(frozen=True, slots=True)
class Signal:
    """One run-rule hit.

    Attributes:
        rule: ``beyond``, ``range``, ``run`` or ``trend`` (module docstring).
        points: the indices into ``ControlChart.points`` of the points involved.
        runs: the run keys of those points, in run order.
    """

    rule: str
    points: tuple[int, ...]
    runs: tuple[str, ...]


@dataclass(frozen=True, slots=True)
class ControlChart:
    """The control chart of one characteristic.

    Attributes:
        kind: ``I-MR`` or ``Xbar-R``.
        subgroup_size: ``n`` of the X̄-R chart, 1 for I-MR.
        points: the plotted points in run order.
        ranges: the moving ranges (``len(points) - 1`` of them; the range ending at point
            ``k + 1`` is ``ranges[k]``) or the subgroup ranges (one per point).
        centre: the X chart's centre line (x̄ or X̿).
        lcl: its lower control limit.
        ucl: its upper control limit.
        range_centre: MR̄ or R̄.
        range_lcl: the range chart's lower limit (0 for I-MR, ``D3 R̄`` for X̄-R).
        range_ucl: its upper limit (``3.267 MR̄`` or ``D4 R̄``).
        sigma: the within (short-term) standard deviation of single values,
            ``MR̄ / 1.128`` or ``R̄ / d2(n)``.
        signals: the run-rule hits, by rule (``RULES`` order) then position.
        note: why subgroups were not used, or empty.
    """

    kind: str
    subgroup_size: int
    points: tuple[Point, ...]
    ranges: tuple[float, ...]
    centre: float
    lcl: float
    ucl: float
    range_centre: float
    range_lcl: float
    range_ucl: float
    sigma: float
    signals: tuple[Signal, ...]
    note: str = ""

    def flagged(self, rules: Sequence[str] = RULES) -> set[int]:
        """Indices into ``points`` of the points some signal of ``rules`` involves."""
        return {k for s in self.signals if s.rule in rules for k in s.points}


def evaluated(series: Series) -> list[tuple[int, float]]:
    """(0-based index in ``series.values``, measured) of the values that were evaluated."""
    return [(i, v.measured) for i, v in enumerate(series.values) if v.measured is not None]


def mean_of(x: npt.ArrayLike) -> float:
    """The mean of ``x`` taken about its first value, so that equal values have exactly
    their value as the mean (``np.mean`` leaves a rounding residue that would put
    constant values off the centre line)."""
    a = np.asarray(x, dtype=float)
    return float(a[0] + (a - a[0]).mean())


def control_chart(series: Series) -> ControlChart | None:
    """The chart of ``series`` (module docstring), or None with fewer than 2 evaluated
    values or when the statistics are not finite (values beyond float range)."""
    values = evaluated(series)
    if len(values) < 2:
        return None
    groups, note = _subgroups(series, values)
    with np.errstate(all="ignore"):
        chart = _xbar_r(series, groups) if groups else _individuals(series, values)
    finite = np.isfinite([chart.centre, chart.lcl, chart.ucl, chart.range_ucl, chart.sigma,
                          *(p.value for p in chart.points), *chart.ranges])
    if not finite.all():
        return None
    return _with_signals(chart, note)


def _subgroups(series: Series, values: list[tuple[int, float]],
               ) -> tuple[list[list[tuple[int, float]]], str]:
    """The X̄-R subgroups (empty when the chart is I-MR) and why not, if subgroups exist."""
    keys = [series.values[i].subgroup for i, _ in values]
    if all(k is None for k in keys):
        return [], ""
    if any(k is None for k in keys):
        return [], "some values without subgroup: individuals chart"
    groups: dict[str, list[tuple[int, float]]] = {}
    for key, item in zip(keys, values, strict=True):
        groups.setdefault(str(key), []).append(item)
    sizes = sorted({len(g) for g in groups.values()})
    if len(sizes) > 1:
        return [], (f"subgroups of unequal size ({', '.join(map(str, sizes))} evaluated "
                    "values): individuals chart")
    if sizes[0] == 1:
        return [], ""
    if sizes[0] > max(CONSTANTS):
        return [], f"subgroups of {sizes[0]} values (more than {max(CONSTANTS)}): individuals chart"
    if len(groups) < 2:
        return [], "a single subgroup: individuals chart"
    return list(groups.values()), ""


def _point(series: Series, items: Sequence[tuple[int, float]]) -> Point:
    idx = tuple(i for i, _ in items)
    return Point(x=float(np.mean(idx)) + 1.0, value=mean_of([v for _, v in items]),
                 runs=tuple(series.values[i].run for i in idx), indices=idx)


def _individuals(series: Series, values: list[tuple[int, float]]) -> ControlChart:
    x = np.array([v for _, v in values])
    mr = np.abs(np.diff(x))
    centre, mr_bar = mean_of(x), float(mr.mean())
    return ControlChart(
        kind="I-MR", subgroup_size=1, points=tuple(_point(series, [item]) for item in values),
        ranges=tuple(float(r) for r in mr), centre=centre, lcl=centre - E2 * mr_bar,
        ucl=centre + E2 * mr_bar, range_centre=mr_bar, range_lcl=0.0,
        range_ucl=D4_MR * mr_bar, sigma=mr_bar / D2_MR, signals=())


def _xbar_r(series: Series, groups: list[list[tuple[int, float]]]) -> ControlChart:
    n = len(groups[0])
    k = CONSTANTS[n]
    points = tuple(_point(series, g) for g in groups)
    ranges = [max(v for _, v in g) - min(v for _, v in g) for g in groups]
    centre, r_bar = mean_of([p.value for p in points]), float(np.mean(ranges))
    return ControlChart(
        kind="Xbar-R", subgroup_size=n, points=points, ranges=tuple(ranges), centre=centre,
        lcl=centre - k.a2 * r_bar, ucl=centre + k.a2 * r_bar, range_centre=r_bar,
        range_lcl=k.d3 * r_bar, range_ucl=k.d4 * r_bar, sigma=r_bar / k.d2, signals=())


def _with_signals(chart: ControlChart, note: str) -> ControlChart:
    """``chart`` with its run-rule hits and ``note``."""
    values = [p.value for p in chart.points]
    hits: list[tuple[str, tuple[int, ...]]] = []
    hits += [("beyond", (k,)) for k, v in enumerate(values) if v > chart.ucl or v < chart.lcl]
    pair = chart.kind == "I-MR"  # a moving range spans two points, a subgroup range one
    hits += [("range", (k, k + 1) if pair else (k,)) for k, r in enumerate(chart.ranges)
             if r > chart.range_ucl]
    side = [1 if v > chart.centre else -1 if v < chart.centre else 0 for v in values]
    hits += [("run", span) for span in _streaks(side, RUN_LENGTH)]
    steps = [0, *(1 if b > a else -1 if b < a else 0
                  for a, b in zip(values[:-1], values[1:], strict=True))]
    hits += [("trend", (span[0] - 1, *span)) for span in _streaks(steps, TREND_LENGTH - 1)]
    signals = tuple(
        Signal(rule, span, tuple(r for k in span for r in chart.points[k].runs))
        for rule, span in sorted(hits, key=lambda h: (RULES.index(h[0]), h[1])))
    return dataclasses.replace(chart, signals=signals, note=note)


def _streaks(codes: Sequence[int], length: int) -> list[tuple[int, ...]]:
    """Maximal spans of at least ``length`` equal non-zero codes, as index tuples."""
    spans, start = [], 0
    for k in range(1, len(codes) + 1):
        if k == len(codes) or codes[k] != codes[start]:
            if codes[start] != 0 and k - start >= length:
                spans.append(tuple(range(start, k)))
            start = k
    return spans

