"""The first schema: runs and their characteristics.

Revision ID: 0001
Revises:
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "0001"
down_revision = None
branch_labels = None
depends_on = None


def upgrade() -> None:
    op.create_table(
        "runs",
        sa.Column("key", sa.String(32), primary_key=True),
        sa.Column("part", sa.Text, nullable=False),
        sa.Column("part_number", sa.Text),
        sa.Column("part_name", sa.Text),
        sa.Column("serial", sa.Text),
        sa.Column("operator", sa.Text),
        sa.Column("machine", sa.Text),
        sa.Column("program", sa.Text, nullable=False),
        sa.Column("time", sa.String(40), nullable=False),
        sa.Column("time_utc", sa.String(40), nullable=False),
        sa.Column("batch", sa.Text),
        sa.Column("calibration", sa.Text),
        sa.Column("source", sa.Text, nullable=False),
        sa.Column("log_sha256", sa.String(64), nullable=False),
        sa.Column("log_run", sa.Integer, nullable=False),
        sa.Column("status", sa.String(16), nullable=False),
        sa.Column("decision_rule", sa.String(16), nullable=False),
    )
    op.create_index("ix_runs_part", "runs", ["part"])
    op.create_table(
        "characteristics",
        sa.Column("id", sa.Integer, primary_key=True, autoincrement=True),
        sa.Column("run_key", sa.String(32), sa.ForeignKey("runs.key", ondelete="CASCADE"),
                  nullable=False),
        sa.Column("position", sa.Integer, nullable=False),
        sa.Column("feature", sa.Text, nullable=False),
        sa.Column("kind", sa.Text, nullable=False),
        sa.Column("name", sa.Text, nullable=False),
        sa.Column("unit", sa.String(8), nullable=False),
        sa.Column("nominal", sa.Double),
        sa.Column("lower", sa.Double),
        sa.Column("upper", sa.Double),
        sa.Column("measured", sa.Double),
        sa.Column("u", sa.Double),
        sa.Column("status", sa.String(16), nullable=False),
        sa.UniqueConstraint("run_key", "feature", "name", name="uq_characteristic"),
    )
    op.create_index("ix_characteristics_run_key", "characteristics", ["run_key"])


def downgrade() -> None:
    op.drop_table("characteristics")
    op.drop_table("runs")
