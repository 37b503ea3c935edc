"""The results store: every ingested run kept in a database (SQLite or PostgreSQL)."""
