"""The SQLite engine (WAL, foreign keys, a busy timeout on every connection) and the schema upgrade:
`alembic upgrade head` is the only way the schema is made."""

from __future__ import annotations

import logging
import os
import sqlite3
import threading
from pathlib import Path
from typing import Any

from alembic import command
from alembic.config import Config
from sqlalchemy import Engine, create_engine, event
from sqlalchemy.orm import Session, sessionmaker

ROOT = Path(__file__).resolve().parents[2]
# The migrations: inside the package when installed from a wheel (setup.py puts them there), else the
# checkout's alembic/ with its alembic.ini.
_PACKAGED = Path(__file__).resolve().parents[1] / "migrations"
MIGRATIONS = _PACKAGED if (_PACKAGED / "env.py").is_file() else ROOT / "alembic"
BUSY_TIMEOUT_MS = 5000
log = logging.getLogger("tmeye.db")


def _on_connect(dbapi_conn: Any, _record: Any) -> None:
    cur = dbapi_conn.cursor()
    cur.execute("PRAGMA journal_mode=WAL")
    cur.execute("PRAGMA foreign_keys=ON")
    cur.execute(f"PRAGMA busy_timeout={BUSY_TIMEOUT_MS}")
    cur.execute("PRAGMA synchronous=NORMAL")  # WAL: durable at checkpoints, never corrupt
    cur.close()


def make_engine(url: str) -> Engine:
    engine = create_engine(url, connect_args={"check_same_thread": False, "timeout": BUSY_TIMEOUT_MS / 1000})
    event.listen(engine, "connect", _on_connect)
    return engine


def session_factory(engine: Engine) -> sessionmaker[Session]:
    return sessionmaker(engine, expire_on_commit=False)


def alembic_config(url: str) -> Config:
    ini = ROOT / "alembic.ini"
    cfg = Config(str(ini)) if MIGRATIONS == ROOT / "alembic" and ini.is_file() else Config()
    cfg.set_main_option("script_location", str(MIGRATIONS))
    cfg.set_main_option("path_separator", "os")
    cfg.set_main_option("sqlalchemy.url", url)
    cfg.attributes["configure_logger"] = False
    return cfg


_upgrade_lock = threading.Lock()


def upgrade(url: str) -> None:
    """Bring the database at `url` to the newest migration (creating it if absent)."""
    with _upgrade_lock:
        command.upgrade(alembic_config(url), "head")


def storage_problem(data_dir: Path, db_path: Path) -> str | None:
    """Why the server could not store anything in `data_dir` and its database (one line), or None: the
    directory must be creatable and writable and an existing database must take a write transaction."""
    try:
        data_dir.mkdir(parents=True, exist_ok=True)
        probe = data_dir / f".write-test-{os.getpid()}"
        os.close(os.open(probe, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600))
        probe.unlink()
    except OSError as exc:
        return f"the data directory {data_dir} is not writable: {exc.strerror or exc}"
    if not db_path.exists():
        return None
    try:
        con = sqlite3.connect(db_path, timeout=BUSY_TIMEOUT_MS / 1000)
        try:
            con.execute("BEGIN IMMEDIATE")
            con.execute("CREATE TABLE _tmeye_write_test (x INTEGER)")  # a real write, rolled back
            con.rollback()
        finally:
            con.close()
    except sqlite3.Error as exc:
        return f"the database {db_path} cannot be written: {exc}"
    return None
