"""Initial schema: joints, immutable joint versions, states, labels, audit log.

Revision ID: 0001
Revises: 
Create Date: 2026-11-21
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = '0001'
down_revision = None
branch_labels = None
depends_on = None


def upgrade() -> None:
    op.create_table('audit_log',
    sa.Column('id', sa.Integer(), nullable=False),
    sa.Column('at', sa.DateTime(timezone=True), nullable=False),
    sa.Column('actor', sa.String(length=200), nullable=False),
    sa.Column('action', sa.String(length=50), nullable=False),
    sa.Column('joint_name', sa.String(length=200), nullable=True),
    sa.Column('version', sa.Integer(), nullable=True),
    sa.Column('details', sa.JSON(), nullable=False),
    sa.PrimaryKeyConstraint('id', name=op.f('pk_audit_log'))
    )
    with op.batch_alter_table('audit_log', schema=None) as batch_op:
        batch_op.create_index(batch_op.f('ix_audit_log_at'), ['at'], unique=False)

    op.create_table('joints',
    sa.Column('id', sa.Integer(), nullable=False),
    sa.Column('name', sa.String(length=200), nullable=False),
    sa.Column('joint_type', sa.String(length=100), nullable=False),
    sa.Column('created_at', sa.DateTime(timezone=True), nullable=False),
    sa.Column('created_by', sa.String(length=200), nullable=False),
    sa.PrimaryKeyConstraint('id', name=op.f('pk_joints')),
    sa.UniqueConstraint('name', name=op.f('uq_joints_name'))
    )
    with op.batch_alter_table('joints', schema=None) as batch_op:
        batch_op.create_index(batch_op.f('ix_joints_joint_type'), ['joint_type'], unique=False)

    op.create_table('joint_states',
    sa.Column('id', sa.Integer(), nullable=False),
    sa.Column('joint_id', sa.Integer(), nullable=False),
    sa.Column('version', sa.Integer(), nullable=True),
    sa.Column('state', sa.String(length=20), nullable=False),
    sa.Column('reason', sa.Text(), nullable=False),
    sa.Column('author', sa.String(length=200), nullable=False),
    sa.Column('at', sa.DateTime(timezone=True), nullable=False),
    sa.CheckConstraint("state IN ('active', 'deprecated')", name=op.f('ck_joint_states_state_known')),
    sa.ForeignKeyConstraint(['joint_id'], ['joints.id'], name=op.f('fk_joint_states_joint_id_joints'), ondelete='RESTRICT'),
    sa.PrimaryKeyConstraint('id', name=op.f('pk_joint_states'))
    )
    with op.batch_alter_table('joint_states', schema=None) as batch_op:
        batch_op.create_index('ix_joint_states_joint_id_at', ['joint_id', 'at'], unique=False)

    op.create_table('joint_versions',
    sa.Column('id', sa.Integer(), nullable=False),
    sa.Column('joint_id', sa.Integer(), nullable=False),
    sa.Column('version', sa.Integer(), nullable=False),
    sa.Column('uuid', sa.String(length=36), nullable=False),
    sa.Column('created_at', sa.DateTime(timezone=True), nullable=False),
    sa.Column('author', sa.String(length=200), nullable=False),
    sa.Column('materials', sa.JSON(), nullable=False),
    sa.Column('preload_n', sa.Float(), nullable=True),
    sa.Column('torque_nm', sa.Float(), nullable=True),
    sa.Column('geometry', sa.JSON(), nullable=False),
    sa.Column('extra', sa.JSON(), nullable=False),
    sa.Column('model_kind', sa.String(length=50), nullable=False),
    sa.Column('dofs', sa.JSON(), nullable=False),
    sa.Column('quantity', sa.String(length=20), nullable=False),
    sa.Column('n_freq', sa.Integer(), nullable=False),
    sa.Column('freq_min_hz', sa.Float(), nullable=False),
    sa.Column('freq_max_hz', sa.Float(), nullable=False),
    sa.Column('blob_sha256', sa.String(length=64), nullable=False),
    sa.Column('raw_blobs', sa.JSON(), nullable=False),
    sa.Column('input_files', sa.JSON(), nullable=False),
    sa.Column('method', sa.String(length=200), nullable=False),
    sa.Column('method_params', sa.JSON(), nullable=False),
    sa.Column('software_version', sa.String(length=50), nullable=False),
    sa.Column('parent_version', sa.Integer(), nullable=True),
    sa.Column('quality', sa.JSON(), nullable=False),
    sa.Column('record_sha256', sa.String(length=64), nullable=False),
    sa.CheckConstraint('n_freq >= 1', name=op.f('ck_joint_versions_n_freq_positive')),
    sa.CheckConstraint('parent_version IS NULL OR parent_version < version', name=op.f('ck_joint_versions_parent_before')),
    sa.CheckConstraint('preload_n IS NULL OR preload_n >= 0', name=op.f('ck_joint_versions_preload_nonneg')),
    sa.CheckConstraint('torque_nm IS NULL OR torque_nm >= 0', name=op.f('ck_joint_versions_torque_nonneg')),
    sa.CheckConstraint('version >= 1', name=op.f('ck_joint_versions_version_positive')),
    sa.ForeignKeyConstraint(['joint_id'], ['joints.id'], name=op.f('fk_joint_versions_joint_id_joints'), ondelete='RESTRICT'),
    sa.PrimaryKeyConstraint('id', name=op.f('pk_joint_versions')),
    sa.UniqueConstraint('joint_id', 'version', name=op.f('uq_joint_versions_joint_id_version')),
    sa.UniqueConstraint('uuid', name=op.f('uq_joint_versions_uuid'))
    )
    with op.batch_alter_table('joint_versions', schema=None) as batch_op:
        batch_op.create_index(batch_op.f('ix_joint_versions_blob_sha256'), ['blob_sha256'], unique=False)
        batch_op.create_index('ix_joint_versions_joint_id_created_at', ['joint_id', 'created_at'], unique=False)

    op.create_table('labels',
    sa.Column('id', sa.Integer(), nullable=False),
    sa.Column('joint_id', sa.Integer(), nullable=False),
    sa.Column('label', sa.String(length=100), nullable=False),
    sa.Column('version', sa.Integer(), nullable=False),
    sa.Column('updated_at', sa.DateTime(timezone=True), nullable=False),
    sa.Column('updated_by', sa.String(length=200), nullable=False),
    sa.ForeignKeyConstraint(['joint_id', 'version'], ['joint_versions.joint_id', 'joint_versions.version'], name=op.f('fk_labels_joint_id_version_joint_versions'), ondelete='RESTRICT'),
    sa.ForeignKeyConstraint(['joint_id'], ['joints.id'], name=op.f('fk_labels_joint_id_joints'), ondelete='RESTRICT'),
    sa.PrimaryKeyConstraint('id', name=op.f('pk_labels')),
    sa.UniqueConstraint('joint_id', 'label', name=op.f('uq_labels_joint_id_label'))
    )


def downgrade() -> None:
    op.drop_table('labels')
    with op.batch_alter_table('joint_versions', schema=None) as batch_op:
        batch_op.drop_index('ix_joint_versions_joint_id_created_at')
        batch_op.drop_index(batch_op.f('ix_joint_versions_blob_sha256'))

    op.drop_table('joint_versions')
    with op.batch_alter_table('joint_states', schema=None) as batch_op:
        batch_op.drop_index('ix_joint_states_joint_id_at')

    op.drop_table('joint_states')
    with op.batch_alter_table('joints', schema=None) as batch_op:
        batch_op.drop_index(batch_op.f('ix_joints_joint_type'))

    op.drop_table('joints')
    with op.batch_alter_table('audit_log', schema=None) as batch_op:
        batch_op.drop_index(batch_op.f('ix_audit_log_at'))

    op.drop_table('audit_log')
