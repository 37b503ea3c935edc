"""The store's tables (SQLAlchemy Core), as the newest migration leaves them.

``runs``: one row per measured run, its key and identity.  ``characteristics``: one row
per characteristic of a run, evaluated or not (``measured`` NULL when NOT EVALUATED).
Lengths are mm, angles degrees; limits are deviations from the nominal, as in
``evaluate.characteristics.Characteristic``.  The migrations in ``migrations/versions``
build exactly these tables (``tests/test_store.py`` compares them).
"""

from __future__ import annotations

from sqlalchemy import (
    Column,
    Double,
    ForeignKey,
    Integer,
    MetaData,
    String,
    Table,
    Text,
    UniqueConstraint,
)

VERSION_TABLE = "probegen_version"
"""Alembic's version table, named for probegen so a shared database stays readable."""

metadata = MetaData()

runs = Table(
    "runs", metadata,
    Column("key", String(32), primary_key=True),
    Column("part", Text, nullable=False, index=True),
    Column("part_number", Text),
    Column("part_name", Text),
    Column("serial", Text),
    Column("operator", Text),
    Column("machine", Text),
    Column("program", Text, nullable=False),
    Column("time", String(40), nullable=False),
    Column("time_utc", String(40), nullable=False),
    Column("batch", Text),
    Column("calibration", Text),
    Column("source", Text, nullable=False),
    Column("log_sha256", String(64), nullable=False),
    Column("log_run", Integer, nullable=False),
    Column("status", String(16), nullable=False),
    Column("decision_rule", String(16), nullable=False),
)

characteristics = Table(
    "characteristics", metadata,
    Column("id", Integer, primary_key=True, autoincrement=True),
    Column("run_key", String(32), ForeignKey("runs.key", ondelete="CASCADE"),
           nullable=False, index=True),
    Column("position", Integer, nullable=False),
    Column("feature", Text, nullable=False),
    Column("kind", Text, nullable=False),
    Column("name", Text, nullable=False),
    Column("unit", String(8), nullable=False),
    Column("nominal", Double),
    Column("lower", Double),
    Column("upper", Double),
    Column("measured", Double),
    Column("u", Double),
    Column("status", String(16), nullable=False),
    UniqueConstraint("run_key", "feature", "name", name="uq_characteristic"),
)
