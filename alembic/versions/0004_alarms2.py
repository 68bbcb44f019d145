"""alarms 2: built-in device-fault rules as rows (alarm_rules.builtin), one-shot shelving (alarms.shelved_one_shot)

Revision ID: 0004_alarms2
Revises: 0003
Create Date: 2026-11-23 01:50:00
"""

from __future__ import annotations

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op

revision: str = '0004_alarms2'
down_revision: str | None = '0003'
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None


def upgrade() -> None:
    with op.batch_alter_table('alarm_rules', schema=None) as batch_op:
        batch_op.add_column(sa.Column('builtin', sa.String(length=16), nullable=True))
    with op.batch_alter_table('alarms', schema=None) as batch_op:
        batch_op.add_column(sa.Column('shelved_one_shot', sa.Boolean(), server_default=sa.false(), nullable=False))


def downgrade() -> None:
    with op.batch_alter_table('alarms', schema=None) as batch_op:
        batch_op.drop_column('shelved_one_shot')
    with op.batch_alter_table('alarm_rules', schema=None) as batch_op:
        batch_op.drop_column('builtin')
