"""Alembic environment: uses a connection handed over in ``config.attributes``
(the normal path, see jointdb.store._db) or the URL in the configuration."""

from __future__ import annotations

from alembic import context
from jointdb.store._models import Base

config = context.config
target_metadata = Base.metadata


def _configure(**kwargs) -> None:
    context.configure(
        target_metadata=target_metadata,
        compare_type=True,
        render_as_batch=True,
        **kwargs,
    )


def run_migrations_offline() -> None:
    _configure(url=config.get_main_option("sqlalchemy.url"), literal_binds=True)
    with context.begin_transaction():
        context.run_migrations()


def run_migrations_online() -> None:
    connection = config.attributes.get("connection")
    if connection is not None:
        _configure(connection=connection)
        with context.begin_transaction():
            context.run_migrations()
        return
    from jointdb.store._db import make_engines, resolve_url

    url = resolve_url(config.get_main_option("sqlalchemy.url") or None)
    _, write_engine = make_engines(url)
    with write_engine.begin() as conn:
        _configure(connection=conn)
        with context.begin_transaction():
            context.run_migrations()


if context.is_offline_mode():
    run_migrations_offline()
else:
    run_migrations_online()
