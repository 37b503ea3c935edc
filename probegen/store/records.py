"""What the store keeps of an ingested run: its key and its characteristics' rows.

The run key identifies one measurement: the SHA-256 of the raw log bytes, the run of the
log that was read, and the program the log belongs to (number and identity token, as its
``PGSTART`` printed them).  The spec's tolerances are deliberately not part of it: a log
ingested again with a corrected spec is the same measurement of the same part, so it
stays one run, and the store keeps the newest evaluation of it (``docs/store.md``).
"""

from __future__ import annotations

import hashlib
import os
from dataclasses import dataclass
from datetime import UTC, datetime

from probegen.errors import ProbegenError
from probegen.evaluate.characteristics import NOT_EVALUATED, UNTOLERANCED, status_of
from probegen.evaluate.ingest import Ingested
from probegen.evaluate.run_identity import RunIdentity

KEY_DIGITS = 16
"""Hex digits of a run key (64 bits of the SHA-256)."""

ANGLES = frozenset({"ANGLE"})
"""Characteristics in degrees; every other one is in mm."""


@dataclass(frozen=True, slots=True)
class Row:
    """One characteristic of a run as stored (None: not known, not toleranced, or not
    measured because the feature was NOT EVALUATED)."""

    feature: str
    kind: str
    name: str
    unit: str
    nominal: float | None
    lower: float | None
    upper: float | None
    measured: float | None
    u: float | None
    status: str


def log_digest(path: str | os.PathLike[str]) -> str:
    """The SHA-256 (hex) of the raw log file.

    Raises:
        ProbegenError: the file cannot be read.
    """
    try:
        with open(path, "rb") as f:
            return hashlib.sha256(f.read()).hexdigest()
    except OSError as exc:
        raise ProbegenError(f"cannot read the log '{os.fspath(path)}' to store its run: "
                            f"{exc.strerror}") from exc


def log_run(ingested: Ingested) -> int:
    """The run of the log that was read (0-based, in log order; 0 for a DMIS output)."""
    return ingested.log.runs[-1].number if ingested.log.runs else 0


def run_key(digest: str, run: int, program: str) -> str:
    """The key of a run: ``digest`` of the log, the ``run`` read, the ``program`` label."""
    text = f"probegen run\0{digest}\0{run}\0{program}".encode()
    return hashlib.sha256(text).hexdigest()[:KEY_DIGITS].upper()


def utc(time: str) -> str:
    """An ISO 8601 time with offset as UTC (``...+00:00``), for ordering runs."""
    try:
        when = datetime.fromisoformat(time)
    except ValueError:
        raise ProbegenError(f"expected the run's time in ISO 8601, found {time!r}") from None
    if when.tzinfo is None:
        raise ProbegenError(f"expected the run's time with its UTC offset, found {time!r}")
    return when.astimezone(UTC).isoformat(timespec="seconds")


def part_of(identity: RunIdentity) -> str:
    """The part a run is filed under: its part number, else its program number (``O1001``)
    so runs without a part number still form a history."""
    return identity.part_number or identity.program.split(" ")[0] or "?"


def rows_of(ingested: Ingested) -> tuple[Row, ...]:
    """Every characteristic of the run, in results.json order: the evaluated features'
    (status under the run's decision rule), then the NOT EVALUATED features'
    characteristics with ``measured`` None: those of the partial fit where there was one
    (its nominal kept, its values not), and every toleranced one the spec asks for."""
    rows: list[Row] = []
    kinds = _kinds(ingested)
    for result in ingested.evaluated:
        for c in result.characteristics:
            rows.append(Row(result.feature, kinds.get(result.feature, ""), c.name,
                            _unit(c.name), c.nominal, c.lower, c.upper, c.measured, c.u,
                            status_of(c.accepted(ingested.rule))))
    for n in ingested.not_evaluated:
        limits = dict(zip(n.characteristics, n.limits, strict=True))
        partial = n.partial.characteristics if n.partial is not None else ()
        named: list[tuple[str, float | None, tuple[float | None, float | None]]] = [
            (c.name, c.nominal, limits.get(c.name, (c.lower, c.upper))) for c in partial]
        named += [(name, None, limits[name]) for name in n.characteristics
                  if name not in {c.name for c in partial}]
        for name, nominal, (lower, upper) in named:
            toleranced = lower is not None or upper is not None
            rows.append(Row(n.feature, n.kind, name, _unit(name), nominal, lower, upper,
                            None, None, NOT_EVALUATED if toleranced else UNTOLERANCED))
    return tuple(rows)


def _unit(name: str) -> str:
    return "deg" if name in ANGLES else "mm"


def _kinds(ingested: Ingested) -> dict[str, str]:
    """Each evaluated feature's kind."""
    out = {r.feature: "sphere_test" for r in ingested.results}
    out |= {r.feature: r.kind for r in ingested.revolved}
    out |= {r.feature: "freeform" for r in ingested.freeform}
    out |= {r.feature: r.kind for r in ingested.planar}
    return out
