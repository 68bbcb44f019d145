"""Crash safety of a real `tmeye serve` (issue #13 section 3), measured from outside: an alarm acknowledged
through the API, then SIGKILL at random moments and restarts. Before each kill the rows the API shows
(committed: tracks, alarms and their history, presets, closed segments) are noted; after each restart the
database passes PRAGMA integrity_check, every noted row is still there (a track with at least its detections,
an alarm with at least its history, the acknowledged one still acknowledged by its user with its comment),
every segment row's file decodes to its frame count and none is missing. Last, SIGTERM: the server stops
within 5 s with every segment closed (no open row, nothing for the next start to reconcile).
Used by tests/test_crash_safety.py (a few kills) and `tmeye bench --crash --kills 20`."""

from __future__ import annotations

import json
import random
import signal
import sqlite3
import sys
import time
from pathlib import Path
from typing import Any

import httpx

from tmeye.benchserver import serve_ready
from tmeye.recordcheck import check_segment, start_pts_of, telemetry_by_pts

RULE = {"name": "anything within 1 km", "priority": "high", "on_delay_s": 0, "off_delay_s": 3600,
        "condition": {"kind": "range_below", "distance_m": 1000}}
ACK_COMMENT = "seen before the crashes"


def _client(data: Path, extra: list[str]) -> tuple[Any, httpx.Client]:
    data.mkdir(parents=True, exist_ok=True)
    proc, base, token = serve_ready(data, ["--stamp-frames", *extra])
    return proc, httpx.Client(base_url=base, headers={"Authorization": f"Bearer {token}"}, timeout=60)


def acknowledge_one(http: httpx.Client, timeout: float = 60.0) -> int:
    """Make a rule that fires on any target, wait for its alarm, acknowledge it; its id."""
    rule = http.post("/api/alarm-rules", json=RULE)
    rule.raise_for_status()
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        mine = [a for a in http.get("/api/alarms").json() if a["rule_id"] == rule.json()["id"]]
        if mine:
            r = http.post(f"/api/alarms/{mine[0]['id']}/ack", json={"comment": ACK_COMMENT})
            r.raise_for_status()
            return int(mine[0]["id"])
        time.sleep(0.2)
    raise RuntimeError("the rule raised no alarm")


def snapshot(http: httpx.Client) -> dict[str, Any]:
    """The committed rows the API shows now."""
    alarms = http.get("/api/alarms", params={"limit": 1000}).json()
    return {"tracks": {t["id"]: t["detections"] for t in http.get("/api/tracks", params={"limit": 10000}).json()},
            "alarms": {a["id"]: len(http.get(f"/api/alarms/{a['id']}").json()["history"]) for a in alarms},
            "presets": {p["name"] for p in http.get("/api/servo/presets").json()},
            "segments": {s["id"] for s in http.get("/api/recordings", params={"limit": 100000}).json()
                         if s["status"] != "open"}}


def lost_rows(before: dict[str, Any], after: dict[str, Any]) -> list[str]:
    """What `before` had that `after` lacks (segments may go only by retention, which these runs do not run)."""
    out = [f"track {i}" for i, n in before["tracks"].items() if after["tracks"].get(i, -1) < n]
    out += [f"alarm {i}" for i, n in before["alarms"].items() if after["alarms"].get(i, -1) < n]
    out += [f"preset {p}" for p in before["presets"] - after["presets"]]
    return out + [f"segment {i}" for i in before["segments"] - after["segments"]]


def ack_kept(http: httpx.Client, alarm_id: int) -> bool:
    a = http.get(f"/api/alarms/{alarm_id}").json()
    acks = [h for h in a["history"] if h["kind"] == "acknowledged"]
    return (a["acked_by"] == "admin" and a["acked_at"] is not None and a["state"] not in ("unack", "rtn_unack")
            and len(acks) == 1 and acks[0]["username"] == "admin" and acks[0]["comment"] == ACK_COMMENT)


def bad_segments(http: httpx.Client, data: Path, skip: set[int]) -> tuple[int, int, int]:
    """(segments checked, rows whose file is missing, segments that do not decode to their frame count)."""
    segs = [s for s in http.get("/api/recordings", params={"limit": 100000}).json()
            if s["status"] != "open" and s["id"] not in skip]
    if not segs:
        return 0, 0, 0
    tel = telemetry_by_pts(http, min(s["start"] for s in segs), max(s["end"] for s in segs))
    missing = sum(not (data / s["path"]).is_file() for s in segs)
    bad = 0
    for seg in segs:
        chk = check_segment(http, seg, tel, start_pts_of(seg))
        bad += chk.error is not None or chk.decoded != seg["frames"]
        skip.add(seg["id"])
    return len(segs), missing, bad


def integrity(data: Path) -> str:
    with sqlite3.connect(data / "tmeye.db") as db:
        return str(db.execute("PRAGMA integrity_check").fetchone()[0])


def _round(http: httpx.Client, data: Path, res: dict[str, Any], before: dict[str, Any] | None,
           checked: set[int]) -> None:
    """After restart k: rows kept, the acknowledgement kept, recordings sound."""
    if before is not None:
        res["rows_compared"] += sum(len(v) for v in before.values())
        lost = lost_rows(before, snapshot(http))
        res["rows_lost"] += len(lost)
        res["lost"] += lost[:5]
    res["ack_kept"] += ack_kept(http, res["alarm_id"])
    n, missing, bad = bad_segments(http, data, checked)
    res["segments_checked"] += n
    res["rows_missing_file"] += missing
    res["segments_not_decoding"] += bad


def run(data: Path, kills: int, extra: list[str] | None = None, seed: int = 0,
        moment_s: tuple[float, float] = (1.0, 8.0)) -> dict[str, Any]:
    """`kills` SIGKILL rounds then a SIGTERM on the data directory `data`; the figures."""
    rng, extra = random.Random(seed), list(extra or [])
    res: dict[str, Any] = {"kills": 0, "integrity_ok": 0, "rows_compared": 0, "rows_lost": 0, "lost": [], "ack_kept": 0,
                           "segments_checked": 0, "rows_missing_file": 0, "segments_not_decoding": 0,
                           "restarts": 0, "alarm_id": None}
    checked: set[int] = set()
    before: dict[str, Any] | None = None
    for k in range(kills + 1):
        proc, http = _client(data, extra)
        with http:
            if k == 0:
                res["alarm_id"] = acknowledge_one(http)
            else:
                res["restarts"] += 1
                _round(http, data, res, before, checked)
            if k == kills:
                break
            assert http.post("/api/servo/presets", json={"name": f"round-{k}", "pan_deg": 0, "tilt_deg": 0}
                             ).status_code == 201
            time.sleep(rng.uniform(*moment_s))
            before = snapshot(http)  # committed: the API showed them
        time.sleep(rng.uniform(0.0, 1.0))  # then a random moment
        proc.send_signal(signal.SIGKILL)
        proc.wait(10)
        res["kills"] += 1
        res["integrity_ok"] += integrity(data) == "ok"
        print(f"kill {k + 1}: {json.dumps({x: y for x, y in res.items() if x != 'lost'})}", file=sys.stderr,
              flush=True)
    res["sigterm"] = sigterm(proc, data)
    log = data / "server.log"
    offset = log.stat().st_size
    proc, http = _client(data, extra)  # the segments of the last run: closed by the SIGTERM, all playable
    with http:
        n, missing, bad = bad_segments(http, data, checked)
    proc.send_signal(signal.SIGTERM)
    proc.wait(30)
    res["sigterm"].update(segments_checked=n, rows_missing_file=missing, segments_not_decoding=bad,
                          reconciled_after="reconciled after an unclean stop" in log.read_text()[offset:])
    return res


def sigterm(proc: Any, data: Path) -> dict[str, Any]:
    """SIGTERM the running server: seconds to exit, open segment rows left, the log's reconciliation."""
    t0 = time.monotonic()
    proc.send_signal(signal.SIGTERM)
    try:
        proc.wait(30)
    except Exception:
        proc.kill()
        proc.wait(10)
    took = time.monotonic() - t0
    with sqlite3.connect(data / "tmeye.db") as db:
        open_rows = db.execute("SELECT count(*) FROM segments WHERE status = 'open'").fetchone()[0]
    return {"stop_s": round(took, 2), "open_rows": int(open_rows), "integrity": integrity(data)}
