"""The history commands end to end: 30 simulated runs with a planted drift (tests/history.py)
recorded by ``probegen ingest --store`` into SQLite and PostgreSQL, then ``probegen spc``,
``probegen export`` and ``probegen report --store`` (issue 20's done-when).

The capability index is checked against a computation written here from the stored values
(X̄-R: the runs come in batches of five), the drift against the run rules and the report's
trend chart, the DFQ export by reading it back.
"""

from __future__ import annotations

import csv
import io
from pathlib import Path

import numpy as np
import pytest
from conftest import REPO
from history import DRIFT, RUNS, SPEC, empty_store, identity_options, postgres_url, simulated

from probegen.cli.app import main
from probegen.errors import ExitCode
from probegen.qdas import decode_dfq, dfq_series, read_dfq

D2_5 = 2.326
"""d2 for subgroups of five (ASTM E2587, Montgomery table VI)."""


def bore_diameters() -> list[float]:
    """The measured bore diameter of each simulated run, as ingest evaluated it."""
    return [next(c.measured for r in run.revolved if r.feature == "BORE"
                 for c in r.characteristics if c.name == "D") for run in simulated().runs]


def ingest_all(url: str, out: Path) -> None:
    """``probegen ingest --store`` of the 30 logs with their identities, one log twice."""
    history = simulated()
    for i, log in enumerate((*history.logs, history.logs[3])):
        opts = identity_options(i if i < RUNS else 3)
        assert main(["-q", "ingest", str(log), "--spec", str(REPO / SPEC), "-o",
                     str(out / f"run{i}"), "--store", url, "--serial", str(opts.serial),
                     "--operator", str(opts.operator), "--time", str(opts.time),
                     "--batch", str(opts.batch)]) in (ExitCode.OK, ExitCode.NOT_OK)


@pytest.fixture(scope="module")
def sqlite_store(tmp_path_factory: pytest.TempPathFactory) -> str:
    folder = tmp_path_factory.mktemp("history")
    url = empty_store("sqlite", folder)
    ingest_all(url, folder)
    return url


def spc_csv(url: str, tmp: Path, name: str) -> str:
    out = tmp / name
    assert main(["-q", "spc", "--store", url, "--format", "csv", "-o", str(out)]) == ExitCode.OK
    return out.read_text()


def bore_row(text: str) -> dict[str, str]:
    rows = list(csv.DictReader(io.StringIO(text)))
    assert list(rows[0])[:7] == ["feature", "characteristic", "n", "mean", "sigma", "cp", "cpk"]
    (row,) = [r for r in rows if (r["feature"], r["characteristic"]) == ("BORE", "D")]
    return row


def test_cpk_agrees_with_an_independent_computation(sqlite_store: str, tmp_path: Path) -> None:
    row = bore_row(spc_csv(sqlite_store, tmp_path, "spc.csv"))
    measured = np.array(bore_diameters())
    assert int(row["n"]) == RUNS
    subgroups = measured.reshape(-1, 5)                      # batches B1..B6 of five runs
    sigma = np.mean(subgroups.max(axis=1) - subgroups.min(axis=1)) / D2_5
    mean = measured.mean()
    lsl, usl = 50.0, 50.025
    cp = (usl - lsl) / (6 * sigma)
    cpk = min(usl - mean, mean - lsl) / (3 * sigma)
    assert float(row["mean"]) == pytest.approx(mean, abs=1e-6)
    assert float(row["sigma"]) == pytest.approx(sigma, abs=1e-6)
    assert float(row["cp"]) == pytest.approx(cp, abs=2e-3)
    assert float(row["cpk"]) == pytest.approx(cpk, abs=2e-3)
    slope = np.polyfit(np.arange(RUNS), measured, 1)[0]
    assert slope == pytest.approx(DRIFT, rel=0.25)
    assert row["signals"], "the planted drift raises a run-rule signal"


def test_sqlite_and_postgresql_give_the_same_spc_table(sqlite_store: str,
                                                       tmp_path: Path) -> None:
    url = postgres_url()  # skips with a message where no server answers
    ingest_all(url, tmp_path)
    assert spc_csv(url, tmp_path, "pg.csv") == spc_csv(sqlite_store, tmp_path, "sqlite.csv")


def test_the_dfq_export_reads_back_the_stored_values(sqlite_store: str,
                                                     tmp_path: Path) -> None:
    out = tmp_path / "history.dfq"
    assert main(["-q", "export", "--store", sqlite_store, "--format", "dfq",
                 "-o", str(out)]) == ExitCode.OK
    data = out.read_bytes()
    assert b"\r\n" in data and data.count(b"K0001/") >= RUNS
    series = {(s.feature, s.characteristic): s
              for s in dfq_series(read_dfq(decode_dfq(data), str(out)))}
    measured = [v.measured for v in series[("BORE", "D")].values]
    assert measured == pytest.approx(bore_diameters(), abs=5e-5)          # 4 decimals written
    assert [v.serial for v in series[("BORE", "D")].values] == \
        [f"S{i:03d}" for i in range(1, RUNS + 1)]


def test_the_csv_export_has_one_row_per_run_and_characteristic(sqlite_store: str,
                                                                tmp_path: Path) -> None:
    out = tmp_path / "history.csv"
    assert main(["-q", "export", "--store", sqlite_store, "--format", "csv",
                 "-o", str(out)]) == ExitCode.OK
    rows = list(csv.DictReader(io.StringIO(out.read_bytes().decode("utf-8"), newline="")))
    bore = [r for r in rows if (r["feature"], r["characteristic"]) == ("BORE", "D")]
    assert len(bore) == RUNS and len(rows) % RUNS == 0


def test_the_report_draws_the_drift_from_the_store(sqlite_store: str, tmp_path: Path) -> None:
    last = tmp_path / "last"
    assert main(["-q", "ingest", str(simulated().logs[-1]), "--spec", str(REPO / SPEC),
                 "-o", str(last)]) in (ExitCode.OK, ExitCode.NOT_OK)
    with_history, plain = tmp_path / "report.html", tmp_path / "plain.html"
    assert main(["-q", "report", str(last / "results.json"), "-o", str(with_history),
                 "--store", sqlite_store]) == ExitCode.OK
    assert main(["-q", "report", str(last / "results.json"), "-o", str(plain)]) == ExitCode.OK
    page = with_history.read_text()
    assert '<section id="history">' in page and '<section id="history">' not in \
        plain.read_text()
    history = page.split('<section id="history">', 1)[1].split("</section>", 1)[0]
    assert ">BORE<" in history and history.count("<svg") >= 1
    (bore,) = [r for r in history.split("<tr>") if ">BORE<" in r and ">D<" in r]
    assert "&ndash;</td></tr>" not in bore  # the drift's signals are listed, not a dash


def test_an_empty_store_is_a_clear_error(tmp_path: Path,
                                         capsys: pytest.CaptureFixture[str]) -> None:
    url = str(tmp_path / "empty.db")
    assert main(["spc", "--store", url]) == ExitCode.ERROR
    assert "found none (record runs with probegen ingest --store)" in capsys.readouterr().err
