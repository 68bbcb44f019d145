"""SIGKILL of a recording server at random moments, then restarts: every segment row's file decodes (a cut one
up to its last complete fragment), no row points to a missing file, the database passes integrity_check.
Then retention with a small quota deletes the oldest unlocked segments first and never a locked one."""

from __future__ import annotations

import random
import signal
import sqlite3
import time
from pathlib import Path
from typing import Any

import httpx
from server_helpers import Server, start_server

from tmeye.media.fmp4 import layout
from tmeye.recordcheck import check_segment, start_pts_of, telemetry_by_pts

ENV = {"TMEYE_SEGMENT_S": "3"}


def segments(c: httpx.Client) -> list[dict[str, Any]]:
    return list(c.get("/api/recordings").json())


def check_all(server: Server) -> list[dict[str, Any]]:
    with server.as_admin() as c:
        segs = [s for s in segments(c) if s["status"] != "open"]
        assert segs
        tel = telemetry_by_pts(c, min(s["start"] for s in segs), max(s["end"] for s in segs))
        for seg in segs:
            try:
                chk = check_segment(c, seg, tel, start_pts_of(seg))
            except httpx.HTTPStatusError as exc:
                if exc.response.status_code == 404:
                    continue  # retention deleted it after the listing, before its check
                raise
            gone = chk.error is not None or not (server.data_dir / seg["path"]).is_file()
            if gone and c.get(f"/api/recordings/{seg['id']}/file").status_code == 404:
                continue  # retention deleted it meanwhile, during or after its check (its row first: no row is
                # left without a file)
            assert (server.data_dir / seg["path"]).is_file(), seg
            assert chk.error is None and chk.decoded == seg["frames"] > 0, (seg, chk)
            assert chk.telemetry_ok >= chk.decoded - 2, (seg, chk)  # the last second's telemetry may be lost
    return segs


def wait_for_a_fragment(server: Server, timeout: float = 20.0) -> None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        open_rows = [r for r in _rows(server.data_dir) if r["status"] == "open"]
        if any(layout(server.data_dir / r["path"]).fragments for r in open_rows):
            return
        time.sleep(0.1)
    raise AssertionError("no open segment with a complete fragment")


def integrity(data_dir: Path) -> str:
    with sqlite3.connect(data_dir / "tmeye.db") as db:
        return str(db.execute("PRAGMA integrity_check").fetchone()[0])


def test_sigkill_reconcile_then_retention(tmp_path: Path) -> None:
    data = tmp_path / "data"
    rng = random.Random(7)
    cut = 0
    lock: tuple[float, float] | None = None
    for k in range(3):
        was_open = sum(r["status"] == "open" for r in _rows(data)) if k else 0
        s = start_server(data, "--stamp-frames", env=ENV)
        if k:
            assert not was_open or "reconciled after an unclean stop" in s.log_text()
            segs = check_all(s)
            cut += sum(seg["status"] == "cut" for seg in segs)
            if lock is None:
                first = min(segs, key=lambda x: x["start"])
                lock = (first["start"] + 0.5, first["start"] + 1.0)
                with s.as_admin() as c:
                    assert c.post("/api/locks", json={"start": lock[0], "end": lock[1]}).status_code == 201
        time.sleep(rng.uniform(4.0, 7.0))
        wait_for_a_fragment(s)  # then a random moment: the open segment has something to keep
        time.sleep(rng.uniform(0.0, 1.0))
        s.stop(signal.SIGKILL)
        assert integrity(data) == "ok"
    assert cut >= 1  # at least one segment was cut by a kill and repaired

    before = {seg["id"]: seg for seg in _rows(data) if seg["status"] != "open"}
    s = start_server(data, "--stamp-frames", env={**ENV, "TMEYE_RECORDING_QUOTA_MB": "5",
                                                  "TMEYE_RETENTION_INTERVAL_S": "1"})
    try:
        time.sleep(2.0)
        with s.as_admin() as c:
            after = {seg["id"]: seg for seg in segments(c)}
        assert lock is not None
        locked = {i for i, seg in before.items() if seg["start"] <= lock[1] and lock[0] <= (seg["end"] or 1e12)}
        assert locked and locked <= set(after), "a locked segment was deleted"
        deleted = set(before) - set(after)
        assert deleted, "the quota deleted nothing"
        kept = [before[i] for i in set(before) & set(after) if i not in locked]
        assert kept, "the quota left none of the older unlocked segments"
        assert max(before[i]["start"] for i in deleted) <= min(seg["start"] for seg in kept)
        assert not any((data / before[i]["path"]).exists() for i in deleted)
        closed = sum(seg["bytes"] for seg in after.values() if seg["status"] != "open")
        assert closed <= 5e6 + 2 * max(seg["bytes"] for seg in after.values())  # segments closed since the last pass
        assert check_all(s)
    finally:
        s.stop()
    assert integrity(data) == "ok"


def _rows(data: Path) -> list[dict[str, Any]]:
    """Segment rows straight from the database (before retention's first pass can be observed over HTTP)."""
    with sqlite3.connect(data / "tmeye.db") as db:
        db.row_factory = sqlite3.Row
        return [dict(r) for r in db.execute("SELECT id, start, end, bytes, path, status FROM segments")]
