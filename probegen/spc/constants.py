"""Control chart constants for subgroups of 2 to 10 values (normal distribution).

The values are the standard tabulated ones (ASTM Manual on Presentation of Data and
Control Chart Analysis, MNL 7; Montgomery, *Introduction to Statistical Quality Control*,
Appendix Table VI), rounded as printed there:

====  =====  =====  =====  =====  ======
 n     d2     A2     D3     D4     c4
====  =====  =====  =====  =====  ======
 2    1.128  1.880  0      3.267  0.7979
 3    1.693  1.023  0      2.574  0.8862
 4    2.059  0.729  0      2.282  0.9213
 5    2.326  0.577  0      2.114  0.9400
 6    2.534  0.483  0      2.004  0.9515
 7    2.704  0.419  0.076  1.924  0.9594
 8    2.847  0.373  0.136  1.864  0.9650
 9    2.970  0.337  0.184  1.816  0.9693
10    3.078  0.308  0.223  1.777  0.9727
====  =====  =====  =====  =====  ======

``d2(n)`` is the mean of the range of ``n`` standard normal values, so ``R̄ / d2``
estimates σ; ``A2 = 3 / (d2 √n)`` puts the X̄ limits at ±3 σ/√n; ``D3``, ``D4`` put the R
limits at ``R̄ (1 ∓ 3 d3/d2)`` (``D3`` clipped at 0); ``c4(n)`` is the mean of the sample
standard deviation of ``n`` standard normal values.  The individuals chart uses the
moving range of two successive values: ``d2(2) = 1.128``, ``E2 = 3 / d2(2) = 2.66`` and
``D4(2) = 3.267``.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True, slots=True)
class SubgroupConstants:
    """The constants of subgroups of ``n`` values (see the module's table)."""

    n: int
    d2: float
    a2: float
    d3: float
    d4: float
    c4: float


_TABLE = (
    (2, 1.128, 1.880, 0.0, 3.267, 0.7979),
    (3, 1.693, 1.023, 0.0, 2.574, 0.8862),
    (4, 2.059, 0.729, 0.0, 2.282, 0.9213),
    (5, 2.326, 0.577, 0.0, 2.114, 0.9400),
    (6, 2.534, 0.483, 0.0, 2.004, 0.9515),
    (7, 2.704, 0.419, 0.076, 1.924, 0.9594),
    (8, 2.847, 0.373, 0.136, 1.864, 0.9650),
    (9, 2.970, 0.337, 0.184, 1.816, 0.9693),
    (10, 3.078, 0.308, 0.223, 1.777, 0.9727),
)

CONSTANTS: dict[int, SubgroupConstants] = {row[0]: SubgroupConstants(*row) for row in _TABLE}
"""Subgroup size → its constants, for sizes 2 to 10 (X̄-R charts beyond 10 are not
drawn: the range wastes information there and an X̄-s chart is the rule)."""

E2 = 2.66
"""Individuals chart: the limits are ``x̄ ± E2 · MR̄`` (``3 / d2(2)``, as tabulated)."""

D4_MR = CONSTANTS[2].d4
"""Moving range chart: upper limit ``D4(2) · MR̄ = 3.267 MR̄`` (lower limit 0)."""

D2_MR = CONSTANTS[2].d2
"""σ from the moving range: ``MR̄ / 1.128``."""
