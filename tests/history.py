"""A 30-run history for the store and SPC tests, and the store URLs of both backends.

:func:`simulated` runs the bore_block sample's Fanuc program 30 times on the virtual
machine (the program is generated once, the model loaded once): each run's part has the
50 mm bore bigger by a planted drift (:data:`DRIFT` of diameter per run) plus a
part-to-part size scatter, and the probe has a trigger noise.  Each log is ingested with
serial ``S001`` ... ``S030``, times one hour apart from :data:`START`, batches of five.
It is cached for the test session (one simulation, however many modules use it).

:func:`empty_store` (for a fixture parametrised with :data:`BACKENDS`) gives an empty
store of each backend: PostgreSQL from ``$PROBEGEN_TEST_PG_URL``, that half
skipped with a message where the variable is unset or the server does not answer.
"""

from __future__ import annotations

import atexit
import functools
import os
import shutil
import tempfile
from dataclasses import dataclass
from datetime import UTC, datetime, timedelta
from pathlib import Path
from types import ModuleType
from typing import TYPE_CHECKING

import numpy as np
import pytest
from conftest import REPO

from probegen import cad
from probegen.dialects import get_dialect
from probegen.evaluate.ingest import Ingested, identified, ingest
from probegen.evaluate.run_identity import IdentityOptions
from probegen.machine.probe_model import ProbeModel
from probegen.planning import part_of, plan_program
from probegen.sim.contact import PlacedPart
from probegen.sim.form import FormError
from probegen.sim.vm import VirtualMachine, run_text
from probegen.spec.model import Spec, load_spec

if TYPE_CHECKING:
    from sqlalchemy.engine import URL

SPEC = REPO / "samples/bore_block/bore_block.toml"
RUNS = 30
BORE_FACE = 8
"""The bore's face in bore_block.step (as tests/test_closed_loop_forms.py plants it)."""
NOMINAL = 50.0
"""The bore's nominal diameter, mm (tolerance 0 / +0.025)."""
START_SIZE = 0.004
"""The first part's bore above nominal (diameter), mm."""
DRIFT = 0.0008
"""How much bigger the bore gets per run (diameter), mm: the last runs leave the
tolerance (tool wear)."""
PART_SIGMA = 0.001
"""Part-to-part scatter of the bore diameter (standard deviation), mm."""
PROBE_SIGMA = 0.0005
"""Trigger repeatability of the probe (standard deviation), mm."""
START = datetime(2026, 11, 2, 6, 0, tzinfo=UTC)
"""The first run's time; each next one an hour later."""
SEED = 20


@dataclass(frozen=True)
class History:
    """The 30 runs: logs, the planted bore diameters, and the identified results.

    Attributes:
        spec: the bore_block spec.
        logs: one DPRNT log per run, oldest first.
        diameters: the true bore diameter of each run's part, mm.
        runs: each log ingested, with its identity (``run``).
    """

    spec: Spec
    logs: tuple[Path, ...]
    diameters: tuple[float, ...]
    runs: tuple[Ingested, ...]


def identity_options(i: int) -> IdentityOptions:
    """The options run ``i`` (0-based) is ingested with."""
    when = START + timedelta(hours=i)
    return IdentityOptions(serial=f"S{i + 1:03d}", operator="history",
                           time=when.isoformat(), batch=f"B{i // 5 + 1}")


@functools.cache
def simulated() -> History:
    """Simulate and ingest the 30 runs (once per test session)."""
    folder = Path(tempfile.mkdtemp(prefix="probegen-history-"))
    atexit.register(shutil.rmtree, folder, ignore_errors=True)
    spec = load_spec(SPEC)
    assert spec.model is not None
    fanuc = get_dialect("fanuc")
    part = part_of(spec)
    program = fanuc.generate(plan_program(spec, runtime_variables=fanuc.RUNTIME_VARIABLES,
                                          part=part).program)
    model = cad.load_step(spec.model)
    rng = np.random.default_rng(SEED)
    logs, diameters, runs = [], [], []
    for i in range(RUNS):
        size = START_SIZE + DRIFT * i + rng.normal(0.0, PART_SIGMA)
        placed = PlacedPart.from_model(model, forms=(FormError(BORE_FACE, offset=size / 2),))
        vm = VirtualMachine(placed, ProbeModel(3.0, noise_sigma=PROBE_SIGMA, seed=SEED + i))
        res = run_text(program, vm, kind="macrob")
        assert res.alarm is None, res.alarm
        log = folder / f"run{i + 1:02d}.log"
        log.write_text(res.output)
        ingested = identified(ingest(log, spec, part=part), spec, identity_options(i))
        logs.append(log)
        diameters.append(NOMINAL + size)
        runs.append(ingested)
    return History(spec, tuple(logs), tuple(diameters), tuple(runs))


PG_ENV = "PROBEGEN_TEST_PG_URL"


def postgres_url() -> str:
    """The test server's URL, its tables dropped (an empty store); skips the test with a
    message where ``$PROBEGEN_TEST_PG_URL`` is unset or the server does not answer."""
    url = os.environ.get(PG_ENV)
    if not url:
        pytest.skip(f"PostgreSQL half skipped: set {PG_ENV} (e.g. "
                    "postgresql://probegen:probegen@localhost/probegen_test) to run it")
    import sqlalchemy as sa

    target = sa.engine.make_url(url)
    if "+" not in target.drivername:
        target = target.set(drivername="postgresql+psycopg")
    try:
        target = _worker_database(sa, target)
        engine = sa.create_engine(target, connect_args={"connect_timeout": 5})
        try:
            with engine.begin() as conn:
                for table in ("characteristics", "runs", "probegen_version"):
                    conn.execute(sa.text(f"DROP TABLE IF EXISTS {table} CASCADE"))
        finally:
            engine.dispose()
    except sa.exc.OperationalError as exc:
        pytest.skip(f"PostgreSQL half skipped: {PG_ENV} names a server that does not "
                    f"answer ({str(exc.orig).splitlines()[0]})")
    return sa.engine.make_url(url).set(database=target.database).render_as_string(
        hide_password=False)


def _worker_database(sa: ModuleType, target: URL) -> URL:
    """``target`` itself, or under pytest-xdist the worker's own database beside it
    (``probegen_test_gw0``, made on first use: the role needs CREATEDB, as
    ``.ci/postgres`` grants), so that two workers never drop each other's tables."""
    worker = os.environ.get("PYTEST_XDIST_WORKER")
    if not worker:
        return target
    name = f"{target.database}_{worker}"
    engine = sa.create_engine(target, isolation_level="AUTOCOMMIT",
                              connect_args={"connect_timeout": 5})
    try:
        with engine.connect() as conn:
            known = conn.execute(sa.text("SELECT 1 FROM pg_database WHERE datname = :n"),
                                 {"n": name}).first()
            if known is None:
                conn.execute(sa.text(f'CREATE DATABASE "{name}"'))
    finally:
        engine.dispose()
    return target.set(database=name)


BACKENDS = ("sqlite", "postgresql")
"""The store backends a test runs on (parametrise a ``store_url`` fixture with them)."""


def empty_store(backend: str, folder: Path) -> str:
    """The URL of an empty store of ``backend``: a SQLite file in ``folder``, or the
    PostgreSQL test server (:func:`postgres_url`, which may skip)."""
    return str(folder / "store.db") if backend == "sqlite" else postgres_url()
