"""The results store on SQLite and PostgreSQL alike (PostgreSQL from $PROBEGEN_TEST_PG_URL,
skipped with a message without it): schema, one run per log, a corrected spec, an
interrupted write, bad URLs, and the 30-run history giving the same series on both."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import sqlalchemy as sa
from conftest import REPO
from fuzzing import examples
from history import BACKENDS, DRIFT, RUNS, empty_store, postgres_url, simulated
from hypothesis import given, settings
from hypothesis import strategies as st

from probegen.cli.app import main
from probegen.evaluate.characteristics import NOT_EVALUATED
from probegen.evaluate.ingest import Ingested, identified, ingest
from probegen.evaluate.run_identity import IdentityOptions
from probegen.spc.series import Series
from probegen.spec.model import load_spec
from probegen.store import StoreError, open_store
from probegen.store import db as store_db
from probegen.store.schema import VERSION_TABLE, metadata

SAMPLE = REPO / "samples/sphere25"
LOG = SAMPLE / "sphere_test.log"
WHO = IdentityOptions(part_number="SPH-25", serial="S7", operator="A. Smith",
                      time="2026-11-26T13:48:53+01:00", batch="B1")
TOLERANCE = "tolerance = { form = 0.004, size = 0.004, position = 0.05 }\n"


@pytest.fixture(params=BACKENDS)
def store_url(request: pytest.FixtureRequest, tmp_path: Path) -> str:
    """An empty store on SQLite, then on PostgreSQL."""
    return empty_store(request.param, tmp_path)


def spec_variant(folder: Path, tolerance: str = "", name: str = "spec.toml") -> Path:
    """The sphere25 spec in ``folder`` (its paths made absolute), with ``tolerance``."""
    text = (SAMPLE / "sphere_test.toml").read_text()
    text = text.replace('model = "sphere25.step"', f'model = "{SAMPLE / "sphere25.step"}"')
    text = text.replace('profile = "../machines/vmc-fanuc.toml"',
                        f'profile = "{REPO / "samples/machines/vmc-fanuc.toml"}"')
    path = folder / name
    path.write_text(text + tolerance)
    return path


def ingested(log: Path, spec: Path, who: IdentityOptions = WHO) -> Ingested:
    s = load_spec(spec)
    return identified(ingest(log, s), s, who)


@pytest.fixture(scope="module")
def sample(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Ingested]:
    """The sphere25 log ingested against its spec, a toleranced variant of it, and a
    copy of the log cut short (its sphere test NOT EVALUATED)."""
    folder = tmp_path_factory.mktemp("sample")
    plain, tight = spec_variant(folder), spec_variant(folder, TOLERANCE, "tight.toml")
    lines = LOG.read_text().splitlines(keepends=True)
    cut = folder / "cut.log"
    cut.write_text("".join(line for line in lines if not line.startswith("PT SPH1 2")))
    return {"plain": ingested(LOG, plain), "tight": ingested(LOG, tight),
            "cut": ingested(cut, tight)}


def test_migrations_build_the_tables_the_code_uses(store_url: str) -> None:
    from alembic.autogenerate import compare_metadata
    from alembic.runtime.migration import MigrationContext

    store = open_store(store_url)
    try:
        with store.engine.connect() as conn:
            context = MigrationContext.configure(conn, opts={"version_table": VERSION_TABLE})
            assert compare_metadata(context, metadata) == []
            assert context.get_current_revision() == "0001"
    finally:
        store.close()
    open_store(store_url).close()  # opening again migrates nothing and keeps working


def test_the_same_log_twice_is_one_run(store_url: str, sample: dict[str, Ingested]) -> None:
    run = sample["plain"]
    assert run.run is not None
    with open_store(store_url) as store:
        key, new = store.add_run(run, run.run)
        assert new and len(key) == 16
        assert store.add_run(run, run.run) == (key, False)
        assert store.runs() == [key]
        series = store.series()
    names = [(s.part, s.feature, s.characteristic) for s in series]
    assert names == sorted(names) and len(names) == len(run.results[0].characteristics)
    d = next(s for s in series if s.characteristic == "D")
    (value,) = d.values
    chars = {c.name: c for c in run.results[0].characteristics}
    assert (d.part, d.nominal, d.lower, d.upper, d.unit) == ("SPH-25", chars["D"].nominal,
                                                             None, None, "mm")
    assert (value.run, value.time, value.serial, value.subgroup) == (
        key, "2026-11-26T13:48:53+01:00", "S7", "B1")
    assert (value.measured, value.u, value.status) == (chars["D"].measured, chars["D"].u, "-")


def test_a_corrected_spec_updates_the_same_run(store_url: str,
                                               sample: dict[str, Ingested]) -> None:
    plain, tight = sample["plain"], sample["tight"]
    assert plain.run is not None and tight.run is not None
    with open_store(store_url) as store:
        key, _ = store.add_run(plain, plain.run)
        assert store.add_run(tight, tight.run) == (key, False)
        assert store.runs() == [key]
        (form,) = store.series(characteristic="P_FTU")
    assert form.upper == 0.004 and form.values[0].status in ("OK", "NOT OK")


def test_a_not_evaluated_feature_is_stored_without_values(store_url: str,
                                                          sample: dict[str, Ingested]
                                                          ) -> None:
    cut = sample["cut"]
    assert cut.run is not None and cut.incomplete == ("SPH1",)
    with open_store(store_url) as store:
        store.add_run(cut, cut.run)
        series = store.series(feature="SPH1")
    statuses = {s.characteristic: s.values[0].status for s in series}
    assert {"P_FTU", "P_STU", "POS"} <= set(statuses)
    assert statuses["P_FTU"] == NOT_EVALUATED and statuses["X"] == "-"
    assert all(s.values[0].measured is None and s.values[0].u is None for s in series)


def test_an_interrupted_write_leaves_the_store_as_before(
        store_url: str, sample: dict[str, Ingested], tmp_path: Path,
        monkeypatch: pytest.MonkeyPatch) -> None:
    plain, tight = sample["plain"], sample["tight"]
    assert plain.run is not None and tight.run is not None
    other = tmp_path / "other.log"
    other.write_bytes(LOG.read_bytes() + b"\n")  # other bytes: another run
    second = ingested(other, spec_variant(tmp_path))
    assert second.run is not None
    with open_store(store_url) as store:
        key, _ = store.add_run(plain, plain.run)
        before = store.series()
        insert = store_db._insert_characteristic
        calls = []

        def failing(*args: object) -> None:
            calls.append(args)
            if len(calls) > 3:
                raise sa.exc.OperationalError("INSERT", {}, OSError("disk I/O error"))
            insert(*args)  # type: ignore[arg-type]

        monkeypatch.setattr(store_db, "_insert_characteristic", failing)
        for run in (second, tight):  # a new run, then an update of the stored one
            calls.clear()
            with pytest.raises(StoreError, match="disk I/O error; nothing of the run was kept"):
                store.add_run(run, run.run)  # type: ignore[arg-type]
            assert len(calls) == 4
            assert store.runs() == [key] and store.series() == before
        monkeypatch.undo()
        assert store.add_run(second, second.run)[1] is True
        assert len(store.runs()) == 2


@pytest.mark.parametrize(("url", "found"), [
    ("mysql://u:secret@host/db", "found the scheme 'mysql'"),
    ("postgresql://u:secret@127.0.0.1:1/db", "expected a database that answers"),
    ("/no/such/folder/store.db", "found no folder /no/such/folder"),
    ("sqlite:////no/such/folder/store.db", "found no folder /no/such/folder"),
])
def test_a_bad_url_is_one_error_with_the_password_masked(url: str, found: str) -> None:
    with pytest.raises(StoreError) as err:
        open_store(url)
    assert found in str(err.value) and "secret" not in str(err.value)
    assert err.value.__cause__ is None  # the driver's exception (and its URL) not chained


def test_cli_ingest_records_the_run_once(in_repo: Path, tmp_path: Path,
                                         capsys: pytest.CaptureFixture[str]) -> None:
    db = tmp_path / "store.db"
    args = ["ingest", str(LOG), "--spec", str(SAMPLE / "sphere_test.toml"), "-o",
            str(tmp_path), "--store", str(db), "--serial", "S1", "--time",
            "2026-11-26T13:48:53Z"]
    assert main(args) == 0
    first = capsys.readouterr().out.splitlines()[-1]
    assert first.startswith("stored run ") and first.endswith(f" in {db}")
    assert main(args) == 0
    key = first.split()[2]
    assert capsys.readouterr().out.splitlines()[-1] == f"run {key} already in {db}"
    bad = [*args[:-4], "--store", "postgresql://u:secret@127.0.0.1:1/db"]
    assert main(bad) == 1
    err = capsys.readouterr().err
    assert "expected a database that answers" in err and "secret" not in err
    assert len(err.strip().splitlines()) == 1  # one line, no traceback


def stored_history(url: str) -> list[Series]:
    """The 30 runs recorded in the store at ``url`` (plus one of them again): its series."""
    history = simulated()
    with open_store(url) as store:
        keys = [store.add_run(r, r.run)[0] for r in history.runs]  # type: ignore[arg-type]
        assert len(set(keys)) == RUNS and store.runs() == keys
        again = history.runs[4]
        assert store.add_run(again, again.run) == (keys[4], False)  # type: ignore[arg-type]
        assert len(store.runs()) == RUNS  # re-ingesting a log leaves 30 runs
        return store.series()


def test_history_keeps_30_runs_and_shows_the_drift(tmp_path: Path) -> None:
    history = simulated()
    series = stored_history(str(tmp_path / "history.db"))
    (d,) = [s for s in series if (s.feature, s.characteristic) == ("BORE", "D")]
    assert (d.part, d.nominal, d.lower, d.upper) == ("O1002", 50.0, 0.0, 0.025)
    assert [v.serial for v in d.values] == [f"S{i:03d}" for i in range(1, RUNS + 1)]
    assert [v.subgroup for v in d.values[:6]] == ["B1"] * 5 + ["B2"]
    measured = np.array([v.measured for v in d.values])
    assert np.allclose(measured, history.diameters, atol=0.002)
    slope = np.polyfit(np.arange(RUNS), measured, 1)[0]
    assert slope == pytest.approx(DRIFT, rel=0.25)  # the planted drift shows
    assert d.values[-1].status == "NOT OK" and d.values[0].status == "OK"
    assert all(len(s.values) == RUNS for s in series)


def test_history_gives_the_same_series_on_sqlite_and_postgresql(tmp_path: Path) -> None:
    postgres = stored_history(postgres_url())  # skips with a message without a server
    assert stored_history(str(tmp_path / "history.db")) == postgres


@settings(max_examples=examples(200))
@given(st.sampled_from(["postgresql", "postgresql+psycopg", "sqlite", "mysql", "http", ""]),
       st.text(alphabet="abc:@/?=.%+ -_19", max_size=24),
       st.text(alphabet="xyz:@/.19", max_size=12))
def test_a_random_url_is_read_or_refused_and_never_shows_its_password(
        scheme: str, user: str, rest: str) -> None:
    url = f"{scheme}://{user}:Pw0rd7@{rest}"
    try:
        target, shown = store_db._url(url)
    except StoreError as exc:
        message = str(exc)
    else:
        message = shown
        assert target.get_backend_name() in ("sqlite", "postgresql")
    assert "Pw0rd7" not in message
