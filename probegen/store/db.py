"""Opening a store, recording a run, reading the series back.

One code for SQLite and PostgreSQL (SQLAlchemy Core); the schema is created and kept up
to date by the Alembic migrations shipped in ``migrations/`` (run to head on every open,
so a store written by an older probegen is upgraded in place, in one transaction).
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterable, Sequence
from dataclasses import astuple
from pathlib import Path
from typing import Any

from sqlalchemy import Connection, Engine, create_engine, delete, insert, select, update
from sqlalchemy.engine import URL, make_url
from sqlalchemy.exc import ArgumentError, DBAPIError, IntegrityError, SQLAlchemyError

from probegen.errors import ProbegenError
from probegen.evaluate.ingest import Ingested
from probegen.evaluate.run_identity import RunIdentity
from probegen.spc.series import Series, Value
from probegen.store.records import Row, log_digest, log_run, part_of, rows_of, run_key, utc
from probegen.store.schema import characteristics, runs

MIGRATIONS = Path(__file__).with_name("migrations")
"""Alembic's script folder, inside the package (shipped in the wheel)."""

SCHEMES = ("sqlite", "postgresql")
CONNECT = {"postgresql": {"connect_timeout": 10}}
"""Seconds a server may take to answer before the store is reported unreachable."""


class StoreError(ProbegenError):
    """The store cannot be opened or written: a bad URL, a server that does not answer,
    a database newer than this probegen.  The message names the URL (password masked)."""


class Store:
    """An open results store (:func:`open_store`); close it with :meth:`close`."""

    def __init__(self, engine: Engine, shown: str) -> None:
        self.engine = engine
        self.url = shown
        """The URL as shown to users (password masked)."""

    def add_run(self, ingested: Ingested, identity: RunIdentity) -> tuple[str, bool]:
        """Record a run and every characteristic of it, in one transaction.

        The same log (same bytes, same run read, same program) is one run: recording it
        again returns its key and ``False``, and the stored record becomes this one
        (a corrected spec's limits and verdicts, the options given this time) when it
        differs.  A failure part way leaves the store as it was.

        Returns:
            The run key and whether the run is new.

        Raises:
            StoreError: the database refused the write (nothing of the run is kept).
            ProbegenError: the log file cannot be read.
        """
        digest, number = log_digest(ingested.source), log_run(ingested)
        key = run_key(digest, number, identity.program)
        record = {"key": key, "part": part_of(identity), "part_number": identity.part_number,
                  "part_name": identity.part_name, "serial": identity.serial,
                  "operator": identity.operator, "machine": identity.machine,
                  "program": identity.program, "time": identity.time,
                  "time_utc": utc(identity.time), "batch": identity.batch,
                  "calibration": identity.calibration, "source": ingested.source,
                  "log_sha256": digest, "log_run": number, "status": ingested.status,
                  "decision_rule": ingested.rule}
        rows = rows_of(ingested)
        try:
            with self.engine.begin() as conn:
                return key, _write(conn, record, rows)
        except IntegrityError as exc:  # recorded meanwhile by another writer: the same run
            if key in self.runs():
                return key, False
            raise StoreError(f"{self.url}: expected to record run {key}, the database "
                             f"refused: {_reason(exc)}; nothing of the run was kept") from exc
        except SQLAlchemyError as exc:
            raise StoreError(f"{self.url}: expected to record run {key}, the database "
                             f"refused: {_reason(exc)}; nothing of the run was kept") from exc

    def series(self, *, part: str | None = None, feature: str | None = None,
               characteristic: str | None = None) -> list[Series]:
        """The history of every characteristic (filtered by part, feature and
        characteristic name when given), sorted by part, feature, characteristic; values
        oldest first (time in UTC, then run key).  Nominal, limits and unit are the
        newest run's that states them.

        Raises:
            StoreError: the database cannot be read.
        """
        c, r = characteristics, runs
        query = (select(r.c.part, c.c.feature, c.c.name, c.c.nominal, c.c.lower, c.c.upper,
                        c.c.unit, r.c.key, r.c.time, r.c.time_utc, r.c.serial, c.c.measured,
                        c.c.u, c.c.status, r.c.batch)
                 .join(r, r.c.key == c.c.run_key))
        for column, wanted in ((r.c.part, part), (c.c.feature, feature),
                               (c.c.name, characteristic)):
            if wanted is not None:
                query = query.where(column == wanted)
        rows = self._read(lambda conn: [tuple(row) for row in conn.execute(query)])
        return _series(rows)

    def runs(self, *, part: str | None = None) -> list[str]:
        """The keys of the stored runs (of ``part`` when given), oldest first."""
        query = select(runs.c.key, runs.c.time_utc)
        if part is not None:
            query = query.where(runs.c.part == part)
        found = self._read(lambda conn: [tuple(row) for row in conn.execute(query)])
        return [key for key, _ in sorted(found, key=lambda kt: (kt[1], kt[0]))]

    def close(self) -> None:
        """Release the connections."""
        self.engine.dispose()

    def __enter__(self) -> Store:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _read(self, work: Callable[[Connection], list[tuple[Any, ...]]]
              ) -> list[tuple[Any, ...]]:
        try:
            with self.engine.connect() as conn:
                return work(conn)
        except SQLAlchemyError as exc:
            raise StoreError(f"{self.url}: expected to read the store, the database "
                             f"refused: {_reason(exc)}") from exc


def _write(conn: Connection, record: dict[str, Any], rows: Sequence[Row]) -> bool:
    """Insert the run, or bring a stored one up to date; True when it is new."""
    key = record["key"]
    old = conn.execute(select(runs).where(runs.c.key == key)).mappings().first()
    if old is not None:
        stored = _stored_rows(conn, key)
        if dict(old) == record and stored == [astuple(row) for row in rows]:
            return False
        conn.execute(update(runs).where(runs.c.key == key).values(record))
        conn.execute(delete(characteristics).where(characteristics.c.run_key == key))
    else:
        conn.execute(insert(runs).values(record))
    for position, row in enumerate(rows):
        _insert_characteristic(conn, key, position, row)
    return old is None


def _insert_characteristic(conn: Connection, key: str, position: int, row: Row) -> None:
    """Insert one characteristic of run ``key`` (one statement per row: a run has tens)."""
    conn.execute(insert(characteristics).values(run_key=key, position=position,
                                                feature=row.feature, kind=row.kind,
                                                name=row.name, unit=row.unit,
                                                nominal=row.nominal, lower=row.lower,
                                                upper=row.upper, measured=row.measured,
                                                u=row.u, status=row.status))


def _stored_rows(conn: Connection, key: str) -> list[tuple[Any, ...]]:
    c = characteristics
    query = (select(c.c.feature, c.c.kind, c.c.name, c.c.unit, c.c.nominal, c.c.lower,
                    c.c.upper, c.c.measured, c.c.u, c.c.status)
             .where(c.c.run_key == key).order_by(c.c.position))
    return [tuple(row) for row in conn.execute(query)]


def _series(rows: Iterable[tuple[Any, ...]]) -> list[Series]:
    """Group the joined rows into series, sorted in Python (database collations differ)."""
    groups: dict[tuple[str, str, str], list[tuple[Any, ...]]] = {}
    for row in rows:
        groups.setdefault((row[0], row[1], row[2]), []).append(row)
    out = []
    for (part, feature, name), members in sorted(groups.items()):
        members.sort(key=lambda m: (m[9], m[7]))
        stated = [m for m in members if m[3] is not None] or members
        newest = stated[-1]
        values = tuple(Value(m[7], m[8], m[10], m[11], m[12], m[13], m[14]) for m in members)
        out.append(Series(part, feature, name, newest[3] if newest[3] is not None else 0.0,
                          newest[4], newest[5], newest[6], values))
    return out


def open_store(url: str) -> Store:
    """Open the store at ``url``, creating it or migrating it to the newest schema.

    ``url``: a file path (a SQLite file, created with its tables on first use),
    ``sqlite:///path``, or ``postgresql://user:password@host/database`` (the database
    must exist; the tables are created in it).

    Raises:
        StoreError: a URL of another kind, a folder that does not exist, a server that
            does not answer or refuses the login, a store of a newer schema; the message
            names the URL with its password masked.
    """
    target, shown = _url(url)
    try:
        engine = create_engine(target, connect_args=CONNECT.get(target.get_backend_name(),
                                                                {}))
    except (ArgumentError, ValueError, ImportError) as exc:
        raise StoreError(f"store {shown}: expected a database URL probegen can open, "
                         f"found {exc}") from None
    try:
        with engine.begin() as conn:
            _migrate(conn)
    except (DBAPIError, SQLAlchemyError) as exc:
        engine.dispose()
        raise StoreError(f"store {shown}: expected a database that answers, found: "
                         f"{_reason(exc)}") from None
    except StoreError as exc:
        engine.dispose()
        raise StoreError(f"store {shown}: {exc}") from None
    return Store(engine, shown)


def _url(url: str) -> tuple[URL, str]:
    """The SQLAlchemy URL of a path or URL (PostgreSQL through psycopg 3), and the URL
    as shown to users (the password masked)."""
    if "://" not in url:
        path = Path(url).expanduser()
        if not path.parent.is_dir():
            raise StoreError(f"store {url}: expected a SQLite file in an existing folder, "
                             f"found no folder {path.parent}")
        if path.is_dir():
            raise StoreError(f"store {url}: expected a SQLite file, found a folder")
        return URL.create("sqlite", database=os.fspath(path.resolve())), url
    shown = _mask(url)
    try:
        target = make_url(url)
    except (ArgumentError, ValueError):  # ValueError: a port that is not a number
        raise StoreError(f"store {shown}: expected a path, sqlite:///FILE or "
                         "postgresql://USER:PASSWORD@HOST/DATABASE, found a URL that "
                         "does not parse") from None
    scheme, _, driver = target.drivername.partition("+")
    if scheme not in SCHEMES:
        raise StoreError(f"store {shown}: expected "
                         f"a path, sqlite:///FILE or postgresql://..., found the scheme "
                         f"{target.drivername!r}")
    if scheme == "postgresql" and not driver:
        target = target.set(drivername="postgresql+psycopg")
    if scheme == "sqlite" and target.database and target.database != ":memory:":
        folder = Path(target.database).expanduser().parent
        if not folder.is_dir():
            raise StoreError(f"store {shown}: expected a SQLite file in an existing "
                             f"folder, found no folder {folder}")
    return target, shown


def _mask(url: str) -> str:
    """``url`` as the user wrote it, everything between the first ``:`` after the scheme's
    ``//`` and the last ``@`` masked (the password, however oddly the URL is written)."""
    scheme, sep, rest = url.partition("://")
    auth, at, host = rest.rpartition("@")
    if at and ":" in auth:
        auth = auth.split(":", 1)[0] + ":***"
    return scheme + sep + auth + at + host


def _migrate(conn: Connection) -> None:
    """Run the migrations to head on ``conn`` (inside its transaction)."""
    from alembic.command import upgrade
    from alembic.config import Config
    from alembic.script import ScriptDirectory
    from alembic.util import CommandError

    config = Config()
    config.set_main_option("script_location", os.fspath(MIGRATIONS))
    config.attributes["connection"] = conn
    try:
        upgrade(config, "head")
    except CommandError as exc:
        head = ScriptDirectory.from_config(config).get_current_head()
        raise StoreError(f"expected a store of schema {head} or older, found: {exc} "
                         "(written by a newer probegen?)") from None


def _reason(exc: BaseException) -> str:
    """The database's own words, first line only (no SQL, no traceback)."""
    orig = getattr(exc, "orig", None) or exc
    text = str(orig).strip().splitlines()
    return text[0] if text else type(orig).__name__
