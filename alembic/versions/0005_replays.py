"""replays: the tracker re-run on recordings; tracks carry the replay that found them; evidence locks of an alarm

Revision ID: 0005_replays
Revises: 0004_alarms2
Create Date: 2026-11-23 01:31:21.565340
"""

from __future__ import annotations

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op

revision: str = '0005_replays'
down_revision: str | None = '0004_alarms2'
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None


def upgrade() -> None:
    op.create_table('replays',
    sa.Column('id', sa.Integer(), nullable=False),
    sa.Column('status', sa.String(length=16), nullable=False),
    sa.Column('progress', sa.Float(), nullable=False),
    sa.Column('start', sa.Float(), nullable=False),
    sa.Column('end', sa.Float(), nullable=False),
    sa.Column('settings', sa.JSON(), nullable=False),
    sa.Column('frames', sa.Integer(), nullable=False),
    sa.Column('agreement', sa.JSON(), nullable=True),
    sa.Column('error', sa.Text(), nullable=True),
    sa.Column('created_at', sa.Float(), nullable=False),
    sa.Column('created_by', sa.Integer(), nullable=True),
    sa.Column('finished_at', sa.Float(), nullable=True),
    sa.ForeignKeyConstraint(['created_by'], ['users.id'], ondelete='SET NULL'),
    sa.PrimaryKeyConstraint('id')
    )
    with op.batch_alter_table('evidence_locks', schema=None) as batch_op:
        batch_op.add_column(sa.Column('alarm_id', sa.Integer(), nullable=True))
        batch_op.create_foreign_key('fk_evidence_locks_alarm_id', 'alarms', ['alarm_id'], ['id'], ondelete='SET NULL')
    with op.batch_alter_table('tracks', schema=None) as batch_op:
        batch_op.add_column(sa.Column('replay_id', sa.Integer(), nullable=True))
        batch_op.create_index(batch_op.f('ix_tracks_replay_id'), ['replay_id'], unique=False)
        batch_op.create_foreign_key('fk_tracks_replay_id', 'replays', ['replay_id'], ['id'], ondelete='CASCADE')



def downgrade() -> None:
    with op.batch_alter_table('tracks', schema=None) as batch_op:
        batch_op.drop_constraint('fk_tracks_replay_id', type_='foreignkey')
        batch_op.drop_index(batch_op.f('ix_tracks_replay_id'))
        batch_op.drop_column('replay_id')

    with op.batch_alter_table('evidence_locks', schema=None) as batch_op:
        batch_op.drop_constraint('fk_evidence_locks_alarm_id', type_='foreignkey')
        batch_op.drop_column('alarm_id')
    op.drop_table('replays')
