"""Disk full on a real small filesystem: a `tmeye serve` whose data directory (database and recordings) is a
40 MiB tmpfs. A filler file first takes all the free space while a segment is being written (recording stops;
database writes answer 503 or succeed, never 500; the server keeps running and tracking), then gives some back
but stays under the recording floor (the recording, disk and database alarms are stored and shown), then is
deleted: recording resumes, the alarms clear, and nothing stored before is lost (segments decode, rows
intact, integrity_check ok); the track samples taken while the disk was full were kept in memory and
written once it could store again."""

from __future__ import annotations

import os
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import httpx
import pytest
from fault_helpers import fill, integrity_check, start_on_tmpfs, unshare_refused
from server_helpers import Server

from tmeye.recordcheck import check_segment, start_pts_of, telemetry_by_pts

FLOOR_MB = 8
NEAR = {"name": "anyone within 1 km", "priority": "high", "on_delay_s": 0, "off_delay_s": 3600,
        "condition": {"kind": "range_below", "distance_m": 1000}}
ENV = {"TMEYE_SEGMENT_S": "2", "TMEYE_MIN_FREE_MB": str(FLOOR_MB)}


def wait_for(what: str, cond: Callable[[], Any], timeout: float = 15.0) -> tuple[Any, float]:
    """(the first truthy value of cond(), seconds it took)."""
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout:
        v = cond()
        if v:
            return v, time.monotonic() - t0
        time.sleep(0.05)
    raise AssertionError(f"not within {timeout} s: {what}")


def open_faults(c: httpx.Client) -> dict[str, dict[str, Any]]:
    r = c.get("/api/alarms", params={"state": "open"})
    assert r.status_code == 200, r.text
    return {a["rule_key"]: a for a in r.json() if str(a["rule_key"]).startswith("fault:")}


def closed_segments(c: httpx.Client) -> list[dict[str, Any]]:
    return [s for s in c.get("/api/recordings").json() if s["status"] != "open"]


def decodes(c: httpx.Client, segs: list[dict[str, Any]]) -> None:
    tel = telemetry_by_pts(c, min(s["start"] for s in segs), max(s["end"] for s in segs))
    for seg in segs:
        chk = check_segment(c, seg, tel, start_pts_of(seg))
        assert chk.error is None and chk.decoded == seg["frames"] > 0, (seg, chk)


@pytest.fixture
def server(tmp_path: Path) -> Any:
    why = unshare_refused(tmp_path)
    if why:
        pytest.skip(why)
    s = start_on_tmpfs(tmp_path / "mnt", 40, "--stamp-frames", env=ENV)
    yield s
    s.stop()


def test_disk_full_stops_recording_fails_writes_safely_and_recovers(server: Server) -> None:
    s, filler = server, server.data_dir / "filler"
    with s.as_admin() as c:
        wait_for("closed segments of both cameras", lambda: len({x["camera"] for x in closed_segments(c)}) == 2)
        assert c.post("/api/servo/presets", json={"name": "before", "pan_deg": 1, "tilt_deg": 2}).status_code == 201
        rule = c.post("/api/alarm-rules", json=NEAR).json()["id"]
        (alarm, *_), _ = wait_for("the rule's alarm", lambda: [a for a in c.get("/api/alarms").json()
                                                                if a["rule_id"] == rule])
        before = closed_segments(c)
        tracks_before = len(c.get("/api/tracks", params={"limit": 10000}).json())

        # 1. full at once, while a segment is being written: recording stops (the status says so at once;
        # the database cannot store an alarm yet); database writes answer 201 or 503, never 500; reads go on
        fill(filler)
        t_full = time.time()
        _, dt = wait_for("the recording fault", lambda: c.get("/api/status").json()["recording"]["state"] == "fault")
        print(f"disk full: recording fault in /api/status after {dt:.2f} s")
        frame = c.get("/api/status").json()["frame"]
        codes = []
        for i in range(20):
            r = c.post("/api/servo/presets", json={"name": f"full-{i}", "pan_deg": 1, "tilt_deg": 2})
            assert r.status_code in (201, 503), r.text
            if r.status_code == 503:
                assert "database unavailable" in r.json()["detail"] and "\n" not in r.json()["detail"]
            codes.append(r.status_code)
            time.sleep(0.1)
        print("preset writes on the full disk:", {k: codes.count(k) for k in set(codes)})
        r = c.post(f"/api/alarms/{alarm['id']}/ack", json={"comment": "on a full disk"})
        assert r.status_code == 503, r.text  # not stored, so not acknowledged: it can be done again later
        stored = {p["name"] for p in c.get("/api/servo/presets").json()}
        assert all((f"full-{i}" in stored) == (code == 201) for i, code in enumerate(codes))  # nothing half-way
        assert c.get("/api/tracks").status_code == 200 and c.get("/api/alarms").status_code == 200
        assert c.get("/api/status").json()["frame"] > frame and s.proc.poll() is None  # tracking goes on

        # 2. some space back, still under the floor: the alarms are stored and shown; no recording
        os.truncate(filler, filler.stat().st_size - FLOOR_MB * 10**6 // 2)
        t_some = time.time()
        faults, dt = wait_for("recording, disk and database alarms", lambda: (f := open_faults(c)) and
                              {"fault:recording", "fault:disk", "fault:database"} <= set(f) and f)
        print(f"alarms recording, disk and database shown {dt:.2f} s after the database could store again")
        assert faults["fault:recording"]["activated_at"] < t_some  # stored with the time it happened
        assert c.post("/api/servo/presets", json={"name": "under-floor", "pan_deg": 1, "tilt_deg": 2}
                      ).status_code == 201
        time.sleep(2.5)
        assert not [x for x in c.get("/api/recordings").json() if x["start"] > t_full + 1.0]
        assert all(x["status"] != "open" for x in c.get("/api/recordings").json())  # the cut one was repaired

        # 3. space returns: recording resumes, the alarms clear
        filler.unlink()
        t_free = time.time()
        _, dt = wait_for("a new segment after the space returned",
                         lambda: [x for x in closed_segments(c) if x["start"] > t_free], timeout=20)
        print(f"recording resumed (a closed segment) {dt:.2f} s after the filler was deleted")
        _, dt = wait_for("the fault alarms cleared", lambda: all(
            c.get(f"/api/alarms/{faults[k]['id']}").json()["cleared_at"] is not None
            for k in ("fault:recording", "fault:disk")), timeout=20)
        print(f"recording and disk alarms cleared within {dt:.2f} s more")

        # 4. nothing stored before is lost: rows unchanged, segments decode, tracks and presets kept
        now = {x["id"]: x for x in c.get("/api/recordings").json()}
        assert all(now.get(x["id"]) == x for x in before), "a segment row changed or went"
        decodes(c, before)
        decodes(c, [x for x in closed_segments(c) if x["start"] > before[-1]["start"]])  # the cut one and new ones
        assert len(c.get("/api/tracks", params={"limit": 10000}).json()) >= tracks_before
        during = [p["t"] for t in c.get("/api/tracks", params={"start": t_full, "end": t_some}).json()
                  for p in c.get(f"/api/tracks/{t['id']}").json()["trajectory"]]
        assert any(t_full + 0.5 < t < t_some - 0.5 for t in during)  # samples kept in memory, written later
        assert {"before", "under-floor"} <= {p["name"] for p in c.get("/api/servo/presets").json()}
        r = c.post(f"/api/alarms/{alarm['id']}/ack", json={"comment": "space is back"})
        assert r.status_code == 200 and r.json()["acked_by"] == "admin", r.text
        hist = c.get(f"/api/alarms/{alarm['id']}").json()["history"]
        assert [h["comment"] for h in hist if h["kind"] == "acknowledged"] == ["space is back"]
    assert integrity_check(s) == "ok"
