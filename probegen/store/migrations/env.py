"""Alembic's environment for the store: migrates on the connection ``open_store`` passes
(``config.attributes["connection"]``), never one of its own."""

from __future__ import annotations

from alembic import context

from probegen.store.schema import VERSION_TABLE

connection = context.config.attributes["connection"]
context.configure(connection=connection, version_table=VERSION_TABLE,
                  render_as_batch=connection.dialect.name == "sqlite")
with context.begin_transaction():
    context.run_migrations()
