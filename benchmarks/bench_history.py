"""Results over time: 30 simulated runs of the bore block with a planted drift (the runs of
tests/history.py), recorded in a SQLite store and, when ``$PROBEGEN_TEST_PG_URL`` names a
server, in PostgreSQL; then the SPC row of the bore and the exports.

Prints: the time to record the 30 runs per backend (and PostgreSQL's as a ratio of SQLite's,
run in this process), whether both give the same SPC table, the bore's row (n, mean,
sigma, Cp, Cpk, the run-rule signals), the planted against the measured drift, and the sizes
of the DFQ and CSV exports.

    PYTHONPATH=. .venv/bin/python benchmarks/bench_history.py
"""

from __future__ import annotations

import csv
import io
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO / "tests"))  # the simulated history the tests use

from history import DRIFT, PG_ENV, RUNS, simulated  # noqa: E402

from probegen.qdas import to_csv, to_dfq  # noqa: E402
from probegen.spc import spc_csv  # noqa: E402
from probegen.store import open_store  # noqa: E402


def record(url: str) -> tuple[float, str, list]:  # type: ignore[type-arg]
    """Record the 30 runs at ``url``; the seconds it took, the SPC CSV, the series."""
    history = simulated()
    with open_store(url) as store:
        start = time.perf_counter()
        for run in history.runs:
            assert run.run is not None
            store.add_run(run, run.run)
        seconds = time.perf_counter() - start
        series = store.series()
    return seconds, spc_csv(series), series


def main() -> None:
    t0 = time.perf_counter()
    simulated()
    print(f"30 runs simulated and ingested: {time.perf_counter() - t0:.1f} s")
    folder = Path(tempfile.mkdtemp(prefix="probegen-bench-history-"))
    sqlite_s, table, series = record(str(folder / "history.db"))
    print(f"recorded in SQLite: {sqlite_s * 1000 / RUNS:.1f} ms per run")
    pg = os.environ.get(PG_ENV)
    if pg:
        import sqlalchemy as sa

        engine = sa.create_engine(sa.engine.make_url(pg).set(drivername="postgresql+psycopg"))
        with engine.begin() as conn:
            for table_name in ("characteristics", "runs", "probegen_version"):
                conn.execute(sa.text(f"DROP TABLE IF EXISTS {table_name} CASCADE"))
        engine.dispose()
        pg_s, pg_table, _ = record(pg)
        print(f"recorded in PostgreSQL: {pg_s * 1000 / RUNS:.1f} ms per run "
              f"({pg_s / sqlite_s:.2f}x SQLite); same SPC table: {pg_table == table}")
    else:
        print(f"PostgreSQL: not measured (set {PG_ENV})")
    rows = list(csv.DictReader(io.StringIO(table)))
    (bore,) = [r for r in rows if (r["feature"], r["characteristic"]) == ("BORE", "D")]
    print(f"characteristics: {len(rows)}; BORE D: n {bore['n']}, mean {bore['mean']}, "
          f"sigma {bore['sigma']}, Cp {bore['cp']}, Cpk {bore['cpk']}, "
          f"Ppk {bore['ppk']}, chart {bore['chart']}")
    print(f"  signals: {bore['signals']}")
    (d,) = [s for s in series if (s.feature, s.characteristic) == ("BORE", "D")]
    measured = np.array([v.measured for v in d.values], dtype=float)
    slope = np.polyfit(np.arange(len(measured)), measured, 1)[0]
    print(f"  drift planted {DRIFT * 1000:.2f} um/run, measured {slope * 1000:.2f} um/run; "
          f"NOT OK runs: {sum(v.status == 'NOT OK' for v in d.values)}")
    by_part = [s for s in series if s.part == d.part]
    dfq, table_csv = to_dfq(by_part), to_csv(series)
    print(f"exports: DFQ {len(dfq.encode('cp1252'))} bytes, {dfq.count(chr(10))} lines; "
          f"CSV {len(table_csv)} bytes, {table_csv.count(chr(10)) - 1} rows")


if __name__ == "__main__":
    main()
