"""The runs of one part number, lined up across its characteristics.

Both exports write one value per run per characteristic: a run in which a characteristic
has no value at all (it was added to the spec later, or its feature was dropped from the
program) is written as NOT EVALUATED, never skipped (skipping would shift the values of
one characteristic against the others in the DFQ, where the n-th value of every
characteristic belongs to the n-th part measured) and never filled with a number.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from datetime import UTC, datetime

from probegen.errors import ProbegenError
from probegen.spc.series import Series, Value

NOT_EVALUATED = "NOT EVALUATED"


@dataclass(frozen=True, slots=True)
class Run:
    """One run of a part number: its key, when, and the part it measured.

    Attributes:
        key: the run's key in the store.
        time: ISO 8601 time as stored (the first series that has the run gives it).
        moment: ``time`` parsed; a time without a UTC offset is taken as UTC.
        serial: the part's serial number, or None.
        subgroup: the subgroup (batch, lot), or None.
    """

    key: str
    time: str
    moment: datetime
    serial: str | None
    subgroup: str | None


def parse_time(text: str, where: str) -> datetime:
    """``text`` (ISO 8601, as :class:`Value` stores it) as a datetime, UTC when no offset.

    Raises:
        ProbegenError: ``text`` is not an ISO 8601 date and time; the message names
            ``where``.
    """
    try:
        moment = datetime.fromisoformat(text)
    except (TypeError, ValueError):
        raise ProbegenError(f"{where}: expected an ISO 8601 date and time "
                            f"(2026-11-26T13:48:53+00:00), found {text!r}") from None
    return moment if moment.tzinfo is not None else moment.replace(tzinfo=UTC)


def part_runs(series: Sequence[Series]) -> list[Run]:
    """Every run that has a value in any of ``series`` (all of one part number), oldest
    first (time, then run key)."""
    runs: dict[str, Run] = {}
    for s in series:
        for v in s.values:
            if v.run not in runs:
                where = f"part {s.part}, {s.feature} {s.characteristic}, run {v.run}"
                runs[v.run] = Run(v.run, v.time, parse_time(v.time, where), v.serial,
                                  v.subgroup)
    return sorted(runs.values(), key=lambda r: (r.moment, r.key))


def aligned(s: Series, runs: Sequence[Run]) -> list[Value]:
    """The values of ``s``, one per run of ``runs`` in that order: the run's own value, or
    a NOT EVALUATED value (no measurement, no uncertainty) where ``s`` has none."""
    own = {v.run: v for v in s.values}
    return [own.get(r.key) or Value(r.key, r.time, r.serial, None, None, NOT_EVALUATED,
                                    r.subgroup)
            for r in runs]


def by_part(series: Sequence[Series]) -> list[list[Series]]:
    """``series`` grouped by part number, parts and series in their given order.

    Raises:
        ProbegenError: two series of one part number name the same feature and
            characteristic (the store never gives that; a hand-made list might).
    """
    groups: dict[str, list[Series]] = {}
    seen: set[tuple[str, str, str]] = set()
    for s in series:
        key = (s.part, s.feature, s.characteristic)
        if key in seen:
            raise ProbegenError(f"part {s.part}: expected one series per characteristic, "
                                f"found {s.feature} {s.characteristic} twice")
        seen.add(key)
        groups.setdefault(s.part, []).append(s)
    return list(groups.values())
