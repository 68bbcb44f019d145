"""The database: Alembic builds an empty database to head with no drift from the models; WAL, foreign keys
and the busy timeout on every connection; a SIGKILL while tracks are written leaves a sound database that
the next start opens."""

from __future__ import annotations

import signal
import sqlite3
import time
from pathlib import Path

import httpx
import pytest
from alembic import command
from server_helpers import start_server
from sqlalchemy import text

from server.db.engine import alembic_config, make_engine, upgrade


def test_upgrade_empty_database_to_head_without_drift(tmp_path: Path) -> None:
    url = f"sqlite:///{tmp_path / 'tmeye.db'}"
    upgrade(url)
    command.check(alembic_config(url))  # raises when the models and the migrations differ
    con = sqlite3.connect(tmp_path / "tmeye.db")
    tables = {r[0] for r in con.execute("SELECT name FROM sqlite_master WHERE type='table'")}
    assert tables >= {"users", "sessions", "audit_log", "calibrations", "tracks", "track_points",
                      "settings_changes", "servo_presets", "alembic_version"}
    assert con.execute("PRAGMA journal_mode").fetchone()[0] == "wal"


def test_connections_have_wal_foreign_keys_and_busy_timeout(tmp_path: Path) -> None:
    url = f"sqlite:///{tmp_path / 'tmeye.db'}"
    upgrade(url)
    engine = make_engine(url)
    with engine.connect() as c:
        assert c.execute(text("PRAGMA journal_mode")).scalar() == "wal"
        assert c.execute(text("PRAGMA foreign_keys")).scalar() == 1
        assert c.execute(text("PRAGMA busy_timeout")).scalar() == 5000
        with pytest.raises(Exception, match="FOREIGN KEY"):
            c.execute(text("INSERT INTO track_points (track_id, t, x, y, z, r, theta_deg, phi_deg) "
                           "VALUES (4242, 0, 0, 0, 0, 0, 0, 0)"))
    engine.dispose()


def test_sigkill_while_writing_tracks_leaves_a_sound_database(tmp_path: Path) -> None:
    data = tmp_path / "data"
    server = start_server(data, "--scenario", "walk", "--servo", "none")
    tok = server.login()
    deadline = time.monotonic() + 30
    while time.monotonic() < deadline:
        pts = httpx.get(f"{server.url}/api/tracks", headers={"Authorization": f"Bearer {tok}"}).json()
        if pts and pts[0]["detections"] > 30:
            break
        time.sleep(0.3)
    assert pts, "no tracks were being written"
    server.stop(signal.SIGKILL)
    con = sqlite3.connect(data / "tmeye.db")
    assert con.execute("PRAGMA integrity_check").fetchone()[0] == "ok"
    n_before = con.execute("SELECT count(*) FROM track_points").fetchone()[0]
    con.close()
    assert n_before > 0
    again = start_server(data, "--scenario", "walk", "--servo", "none")
    try:
        tracks = httpx.get(f"{again.url}/api/tracks", headers={"Authorization": f"Bearer {again.login()}"}).json()
        assert len({t["run_id"] for t in tracks}) >= 1 and tracks
    finally:
        again.stop()
    con = sqlite3.connect(data / "tmeye.db")
    assert con.execute("PRAGMA integrity_check").fetchone()[0] == "ok"
    assert con.execute("SELECT count(*) FROM track_points").fetchone()[0] >= n_before


def test_sigint_stops_the_server_with_everything_flushed(tmp_path: Path) -> None:
    """Ctrl-C (SIGINT) stops `tmeye serve` as SIGTERM does: the application shuts down (then uvicorn exits
    with the signal's conventional status, 130), the tracks the API showed are stored with at least the
    detections it showed, no recording segment is left open, the database is sound."""
    data = tmp_path / "data"
    server = start_server(data, "--scenario", "walk", "--servo", "none")
    tok = server.login()
    deadline = time.monotonic() + 30
    shown: list[dict[str, object]] = []
    while time.monotonic() < deadline:
        shown = httpx.get(f"{server.url}/api/tracks", headers={"Authorization": f"Bearer {tok}"}).json()
        if shown and int(str(shown[0]["detections"])) > 30:
            break
        time.sleep(0.3)
    assert shown, "no tracks were being written"
    assert server.stop(signal.SIGINT, timeout=30.0) in (0, 128 + signal.SIGINT)
    log = server.log_text()
    assert "Traceback" not in log and "tmeye.server: stopped" in log and "Application shutdown complete" in log
    con = sqlite3.connect(data / "tmeye.db")
    try:
        assert con.execute("PRAGMA integrity_check").fetchone()[0] == "ok"
        stored = dict(con.execute("SELECT id, detections FROM tracks").fetchall())
        assert all(stored[int(str(t["id"]))] >= int(str(t["detections"])) for t in shown)
        assert con.execute("SELECT count(*) FROM segments WHERE status = 'open'").fetchone()[0] == 0
    finally:
        con.close()
