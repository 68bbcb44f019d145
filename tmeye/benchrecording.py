"""`tmeye bench --recording`: the recording acceptance figures, measured from outside a real `tmeye serve`.

1. Coverage: a server with --stamp-frames records continuously; a telemetry WebSocket client notes every frame
   captured over `seconds`; then every closed segment is fetched over HTTP and decoded with PyAV: the share
   of captured frames held by exactly one segment per camera, segments that decode to their end, and frames
   whose stamp equals the frame index of their recorded telemetry.
2. Playback: `/api/playback/frame` at `probes` random times: frames that are the last captured at or before
   the time (and whose stamp is X-Frame-Index), and the median response time.
3. Worker cost: in-process, the runtime's frame time (capture to end of processing) with the media pipeline
   encoding for one packet consumer, without and with the recorder writing, alternated.
4. Crashes: `kills` SIGKILLs at random moments, each restart checked (rows' files decode, none missing,
   PRAGMA integrity_check)."""

from __future__ import annotations

import asyncio
import json
import random
import signal
import sqlite3
import statistics
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import httpx

from tmeye.benchserver import serve_ready
from tmeye.recordcheck import (
    CameraFrames,
    check_segment,
    coverage,
    probe_frames,
    random_times,
    start_pts_of,
    telemetry_by_pts,
)
from tmeye.webrtc_client import telemetry_messages


def _serve(data: Path, extra: list[str]) -> tuple[Any, str, httpx.Client]:
    proc, base, token = serve_ready(data, ["--stamp-frames", *extra])
    return proc, base, httpx.Client(base_url=base, headers={"Authorization": f"Bearer {token}"}, timeout=60)


def _media_dropped(http: httpx.Client) -> int:
    subs = http.get("/api/status").json()["subscriptions"]
    return int(sum(s["dropped"] for s in subs if s["name"] == "media"))


def check_recordings(http: httpx.Client, seen: list[tuple[int, float]]) -> dict[str, Any]:
    segs = [s for s in http.get("/api/recordings", params={"limit": 100000}).json() if s["status"] != "open"]
    tel = telemetry_by_pts(http, min(s["start"] for s in segs), max(s["end"] for s in segs))
    holders = {"left": CameraFrames(), "right": CameraFrames()}
    decoded = matched = bad = 0
    for seg in segs:
        chk = check_segment(http, seg, tel, start_pts_of(seg))
        bad += chk.error is not None or chk.decoded != seg["frames"]
        decoded, matched = decoded + chk.decoded, matched + chk.telemetry_ok
        for f in chk.stamps:
            holders[seg["camera"]].counts[f] = holders[seg["camera"]].counts.get(f, 0) + 1
    lo = max(min(s["start"] for s in segs if s["camera"] == c) for c in holders)
    hi = min(max(s["end"] for s in segs if s["camera"] == c) for c in holders)
    inside = {f % 65536 for f, t in seen if lo <= t <= hi}
    cov = coverage(inside, holders)
    return {"segments": len(segs), "segments_not_decoding_to_end": bad, "frames_captured": len(inside),
            "in_exactly_one_segment_pct": {c: round(100 * v, 3) for c, v in cov.items()},
            "frames_decoded": decoded, "stamp_equals_telemetry_index": matched}


def run_coverage(seconds: float, probes: int, extra: list[str]) -> dict[str, Any]:
    with tempfile.TemporaryDirectory(prefix="tmeye-bench-rec-") as tmp:
        proc, base, http = _serve(Path(tmp), extra)
        try:
            token = http.headers["Authorization"].split()[1]
            media0 = _media_dropped(http)
            seen = asyncio.run(telemetry_messages(base, token, seconds))
            media1 = _media_dropped(http)
            time.sleep(13.0)  # the last segment holding the window's frames closes
            out = check_recordings(http, seen)
            segs = [s for s in http.get("/api/recordings", params={"limit": 100000}).json() if s["status"] != "open"]
            tel = telemetry_by_pts(http, min(s["start"] for s in segs), max(s["end"] for s in segs))
            times = sorted(r["captured_at"] for r in tel.values())
            frames = [tel[round(t * 90000)]["frame"] for t in times]
            ts = random_times(segs, probes, seed=1)
            out["playback_frame"] = probe_frames(http, "left", ts, times, frames)
            st = http.get("/api/status").json()
            out["status"] = st["recording"]
            out["media_dropped_in_window"] = media1 - media0  # frames never encoded (overload): not recordable
            out["skipped_frames"], out["fps"] = st["skipped_frames"], st["fps"]
        finally:
            proc.send_signal(signal.SIGTERM)
            proc.wait(20)
    return out


def run_kills(kills: int, extra: list[str], seed: int = 0) -> dict[str, Any]:
    rng = random.Random(seed)
    res = {"kills": kills, "restarts_ok": 0, "cut_segments_kept": 0, "rows_missing_file": 0,
           "segments_not_decoding": 0, "frames_without_telemetry": 0, "integrity_ok": 0}
    checked: set[int] = set()
    with tempfile.TemporaryDirectory(prefix="tmeye-bench-kill-") as tmp:
        data = Path(tmp)
        for k in range(kills + 1):
            proc, _, http = _serve(data, extra)
            if k:
                segs = [s for s in http.get("/api/recordings", params={"limit": 100000}).json()
                        if s["status"] != "open"]
                res["rows_missing_file"] += sum(not (data / s["path"]).is_file() for s in segs)
                fresh = [s for s in segs if s["id"] not in checked]  # written or cut since the last restart
                tel = telemetry_by_pts(http, min(s["start"] for s in fresh), max(s["end"] for s in fresh))
                bad = 0
                for seg in fresh:
                    chk = check_segment(http, seg, tel, start_pts_of(seg))
                    bad += chk.error is not None or chk.decoded != seg["frames"]
                    res["frames_without_telemetry"] += chk.decoded - chk.telemetry_ok
                    checked.add(seg["id"])
                res["segments_not_decoding"] += bad
                res["restarts_ok"] += bad == 0
                res["cut_segments_kept"] = sum(s["status"] == "cut" for s in segs)
                print(f"restart {k}: {json.dumps(res)}", file=sys.stderr, flush=True)
            if k == kills:
                proc.send_signal(signal.SIGTERM)
                proc.wait(20)
                break
            time.sleep(rng.uniform(2.0, 14.0))
            proc.send_signal(signal.SIGKILL)
            proc.wait(10)
            with sqlite3.connect(data / "tmeye.db") as db:
                res["integrity_ok"] += db.execute("PRAGMA integrity_check").fetchone()[0] == "ok"
    return res


def worker_cost(seconds: float, rounds: int = 2) -> dict[str, Any]:
    """Runtime frame time (ms, capture to end of processing) with encoding for a packet consumer, without
    and with the recorder, alternated `rounds` times for `seconds` each."""
    from server.db.engine import make_engine, session_factory, upgrade
    from server.services.recorder import Recorder, RecorderConfig
    from tmeye.media.pipeline import MediaConfig, MediaPipeline
    from tmeye.runtime import Runtime, RuntimeConfig

    times: dict[str, list[float]] = {"without": [], "with": []}
    with tempfile.TemporaryDirectory(prefix="tmeye-bench-cost-") as tmp:
        url = f"sqlite:///{tmp}/tmeye.db"
        upgrade(url)
        sessions = session_factory(make_engine(url))
        rt = Runtime(RuntimeConfig())
        rt.start()
        media = MediaPipeline(rt, MediaConfig(stamp_frames=True))
        media.start()
        viewer = [media.packets[c].subscribe(maxsize=1000, name="bench") for c in ("left", "right")]
        try:
            time.sleep(3.0)
            for _ in range(rounds):
                for mode in ("without", "with"):
                    rec = Recorder(media, rt, sessions, Path(tmp), RecorderConfig()) if mode == "with" else None
                    if rec is not None:
                        rec.start()
                    sub = rt.hub.subscribe(maxsize=100000, name="bench-times")
                    time.sleep(seconds)
                    rt.hub.unsubscribe(sub)
                    times[mode] += [(ev.done_at - ev.captured_at) * 1e3 for ev in sub.drain()]
                    if rec is not None:
                        rec.stop()
                    for v in viewer:
                        v.drain()
        finally:
            rt.stop()
            media.stop()
    med = {k: round(statistics.median(v), 3) for k, v in times.items()}
    p95 = {k: round(sorted(v)[int(0.95 * (len(v) - 1))], 3) for k, v in times.items()}
    return {"frames": {k: len(v) for k, v in times.items()}, "frame_time_median_ms": med, "frame_time_p95_ms": p95,
            "added_median_ms": round(med["with"] - med["without"], 3)}


def run_recording_bench(seconds: float, probes: int, kills: int, cost_s: float, extra: list[str]) -> dict[str, Any]:
    """seconds 0: no coverage/playback run; cost_s 0: no worker-cost run; kills 0: no SIGKILL run."""
    out: dict[str, Any] = {"seconds": seconds}
    if seconds > 0:
        out["recording"] = run_coverage(seconds, probes, extra)
    if cost_s > 0:
        out["worker_cost"] = worker_cost(cost_s)
    if kills > 0:
        out["sigkill"] = run_kills(kills, extra)
    return out
