"""Alembic migrations of the store's schema (run to head by ``open_store``)."""
