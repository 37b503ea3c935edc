"""The history of one characteristic: what the store hands to SPC, the exports and the report.

Plain records (stdlib only): the store (:mod:`probegen.store`) builds them from its tables,
:mod:`probegen.spc` computes capability and control limits on them, :mod:`probegen.qdas` and
the CSV export write them, the report draws them.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True, slots=True)
class Value:
    """One run's value of a characteristic.

    Attributes:
        run: the run's key in the store (stable: the same log ingested twice is one run).
        time: when the part was measured, ISO 8601 with its UTC offset
            (``2026-11-26T13:48:53+00:00``).
        serial: the part's serial number, or None when unknown.
        measured: the measured value (mm, or degrees for angles), None when the
            characteristic was NOT EVALUATED in that run.
        u: its standard uncertainty (same unit), or None when not estimated.
        status: ``OK``, ``NOT OK``, ``NOT EVALUATED`` or ``-`` (not toleranced).
        subgroup: the subgroup (batch, lot) the run belongs to, or None; runs sharing a
            subgroup form one sample of an X̄-R chart.
    """

    run: str
    time: str
    serial: str | None
    measured: float | None
    u: float | None
    status: str
    subgroup: str | None = None


@dataclass(frozen=True, slots=True)
class Series:
    """The values of one characteristic of one part number, oldest first.

    Attributes:
        part: the part number.
        feature: the feature id (``BORE``).
        characteristic: the characteristic's name (``D``, ``X``, ``P_FTU``).
        nominal: the nominal value.
        lower: the lowest allowed deviation from ``nominal`` (as in
            ``evaluate.characteristics.Characteristic``), None when not toleranced below.
        upper: the highest allowed deviation, None when not toleranced above.
        unit: ``mm`` or ``deg``.
        values: one per run, in the order measured (time, then run key).
    """

    part: str
    feature: str
    characteristic: str
    nominal: float
    lower: float | None
    upper: float | None
    unit: str
    values: tuple[Value, ...]

    @property
    def lsl(self) -> float | None:
        """The lower specification limit as a value (``nominal + lower``)."""
        return None if self.lower is None else self.nominal + self.lower

    @property
    def usl(self) -> float | None:
        """The upper specification limit as a value (``nominal + upper``)."""
        return None if self.upper is None else self.nominal + self.upper
