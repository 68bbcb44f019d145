"""Alembic environment: the target metadata is server.db.models; SQLite needs batch mode for ALTERs."""

from __future__ import annotations

from logging.config import fileConfig

from alembic import context
from sqlalchemy import engine_from_config, pool

from server.db.engine import _on_connect
from server.db.models import Base

config = context.config
data_dir = context.get_x_argument(as_dictionary=True).get("data_dir")
if data_dir:
    config.set_main_option("sqlalchemy.url", f"sqlite:///{data_dir}/tmeye.db")
if config.config_file_name is not None and config.attributes.get("configure_logger", True):
    fileConfig(config.config_file_name, disable_existing_loggers=False)

target_metadata = Base.metadata


def run_offline() -> None:
    context.configure(url=config.get_main_option("sqlalchemy.url"), target_metadata=target_metadata,
                      literal_binds=True, render_as_batch=True)
    with context.begin_transaction():
        context.run_migrations()


def run_online() -> None:
    from sqlalchemy import event

    engine = engine_from_config(config.get_section(config.config_ini_section, {}), prefix="sqlalchemy.",
                                poolclass=pool.NullPool)
    event.listen(engine, "connect", _on_connect)
    with engine.connect() as connection:
        context.configure(connection=connection, target_metadata=target_metadata, render_as_batch=True)
        with context.begin_transaction():
            context.run_migrations()


if context.is_offline_mode():
    run_offline()
else:
    run_online()
