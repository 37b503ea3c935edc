"""Hand-made :class:`~probegen.spc.series.Series` for the SPC and trend chart tests."""

from __future__ import annotations

from collections.abc import Sequence

from probegen.spc.series import Series, Value


def make_series(values: Sequence[float | None], *, lower: float | None = -0.01,
                upper: float | None = 0.01, nominal: float = 0.0, u: float | None = None,
                subgroups: Sequence[str | None] | None = None, feature: str = "BORE",
                characteristic: str = "D") -> Series:
    """A series of ``values`` in run order, run keys ``r01``, ``r02``, …, serials ``S01``…"""
    groups = list(subgroups) if subgroups is not None else [None] * len(values)
    return Series(
        part="P-100", feature=feature, characteristic=characteristic, nominal=nominal,
        lower=lower, upper=upper, unit="mm",
        values=tuple(
            Value(run=f"r{k + 1:02d}", time=f"2026-11-{1 + k // 24:02d}T{k % 24:02d}:00:00+00:00",
                  serial=f"S{k + 1:02d}", measured=v, u=None if v is None else u,
                  status="NOT EVALUATED" if v is None else "OK", subgroup=g)
            for k, (v, g) in enumerate(zip(values, groups, strict=True))))
