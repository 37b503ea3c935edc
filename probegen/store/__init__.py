"""The results store: every ingested run kept in a database (SQLite or PostgreSQL).

``open_store(url)`` opens (and creates, or migrates to the newest schema) a store;
``Store.add_run`` records a run in one transaction, ``Store.series`` reads the history of
each characteristic for SPC and the exports.  ``docs/store.md`` is the user's page.
This room is the only one that imports SQLAlchemy, Alembic and the PostgreSQL driver.
"""

from __future__ import annotations

from probegen.store.db import Store, StoreError, open_store

__all__ = ["Store", "StoreError", "open_store"]
