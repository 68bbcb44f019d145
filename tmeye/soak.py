"""`tmeye soak --minutes N`: the server's default (simulated endless scene, closed loop) under a long,
steady load, measured from outside.

Load: WebRTC viewers (aiortc, both cameras decoded), WebSocket telemetry clients and a REST client
polling /api/status once a second. Recording is not part of the load yet (the server has no recorder).
Report: frames and skipped frames; the event-loop lag p99 (the worst of the server's per-minute p99s);
the longest frame stall (the longest gap between two telemetry messages at any WebSocket client); the
frames each WebRTC viewer decoded per camera; the server's RSS, open file descriptors and threads
sampled every 5 s (from /proc), with the RSS growth after the first fifth of the run (at most 5 min)."""

from __future__ import annotations

import asyncio
import json
import os
import time
from pathlib import Path
from typing import Any

from tmeye.benchserver import served


def proc_sample(pid: int) -> dict[str, float]:
    """RSS (MiB), open file descriptors and threads of a process, from /proc."""
    status = Path(f"/proc/{pid}/status").read_text()
    fields = dict(line.split(":", 1) for line in status.splitlines() if ":" in line)
    rss_kib = int(fields["VmRSS"].split()[0])
    return {"rss_mib": round(rss_kib / 1024, 1), "fds": len(os.listdir(f"/proc/{pid}/fd")),
            "threads": int(fields["Threads"])}


async def _ws_client(url: str, token: str, until: float, out: dict[str, Any]) -> None:
    import websockets

    last: float | None = None
    frames, gaps, increasing, prev = 0, 0.0, True, -1
    async with websockets.connect(url, additional_headers={"Authorization": f"Bearer {token}"},
                                  max_queue=None) as ws:
        while (left := until - time.monotonic()) > 0:
            try:
                msg = await asyncio.wait_for(ws.recv(), left)
            except TimeoutError:
                break
            now = time.monotonic()
            frame = int(json.loads(msg)["frame"])
            increasing &= frame > prev
            prev, frames = frame, frames + 1
            if last is not None:
                gaps = max(gaps, now - last)
            last = now
    out.update(messages=frames, longest_gap_ms=round(gaps * 1000, 1), increasing=increasing)


async def _poller(http: Any, pid: int, until: float, samples: list[dict[str, float]], p99s: list[float]) -> None:
    t0 = time.monotonic()
    next_sample = next_window = t0
    errors = 0
    while time.monotonic() < until:
        r = await http.get("/api/status")
        errors += r.status_code != 200
        now = time.monotonic()
        if now >= next_sample:
            samples.append({"t_s": round(now - t0, 1), **proc_sample(pid)})
            next_sample += 5.0
        if now >= next_window + 60.0:
            lag = (await http.get("/api/status", params={"window_s": 60})).json()["event_loop_lag_ms"]
            if lag.get("p99") is not None:
                p99s.append(float(lag["p99"]))
            next_window = now
        await asyncio.sleep(1.0)
    samples.append({"t_s": round(time.monotonic() - t0, 1), **proc_sample(pid)})
    if errors:
        raise RuntimeError(f"{errors} status polls failed")


async def _soak(pid: int, base: str, token: str, seconds: float, viewers: int, clients: int) -> dict[str, Any]:
    import httpx

    from tmeye.webrtc_client import view

    until = time.monotonic() + seconds
    ws_url = base.replace("http://", "ws://") + "/ws/telemetry"
    ws_out: list[dict[str, Any]] = [{} for _ in range(clients)]
    samples: list[dict[str, float]] = []
    p99s: list[float] = []
    async with httpx.AsyncClient(base_url=base, headers={"Authorization": f"Bearer {token}"}, timeout=30) as http:
        s0 = (await http.get("/api/status")).json()
        tasks = [asyncio.create_task(_ws_client(ws_url, token, until, o)) for o in ws_out]
        rtc = [asyncio.create_task(view(base, token, seconds, read_stamps=False)) for _ in range(viewers)]
        await _poller(http, pid, until, samples, p99s)
        await asyncio.gather(*tasks)
        received = await asyncio.gather(*rtc)
        s1 = (await http.get("/api/status", params={"window_s": min(seconds, 600.0)})).json()
    if not p99s and s1["event_loop_lag_ms"].get("p99") is not None:
        p99s.append(float(s1["event_loop_lag_ms"]["p99"]))
    return _report(s0, s1, seconds, ws_out, [[len(r.frames) for r in recs] for recs in received], samples, p99s)


def _report(s0: dict[str, Any], s1: dict[str, Any], seconds: float, ws_out: list[dict[str, Any]],
            rtc_frames: list[list[int]], samples: list[dict[str, float]], p99s: list[float]) -> dict[str, Any]:
    frames = max((s1["frame"] or 0) - (s0["frame"] or 0), 1)
    skipped = s1["skipped_frames"] - s0["skipped_frames"]
    settle = min(seconds / 5.0, 300.0)  # RSS growth is measured after this warm-up
    after = [s for s in samples if s["t_s"] >= settle] or samples
    rss0, rss1 = after[0]["rss_mib"], samples[-1]["rss_mib"]
    return {
        "minutes": round(seconds / 60.0, 2), "frames": frames, "skipped_frames": skipped,
        "skipped_pct": round(100.0 * skipped / frames, 3), "frame_errors": s1["frame_errors"] - s0["frame_errors"],
        "event_loop_lag_p99_ms": max(p99s) if p99s else None,
        "longest_frame_stall_ms": max(o["longest_gap_ms"] for o in ws_out),
        "ws_clients": len(ws_out), "ws_messages_min": min(o["messages"] for o in ws_out),
        "ws_frames_strictly_increasing": all(o["increasing"] for o in ws_out),
        "webrtc_viewers": len(rtc_frames), "webrtc_frames_per_camera_min": min(min(f) for f in rtc_frames)
        if rtc_frames else None,
        "rss_mib_start_end": [samples[0]["rss_mib"], rss1],
        "rss_growth_pct_after_warmup": round(100.0 * (rss1 - rss0) / rss0, 2),
        "fds_start_end_max": [samples[0]["fds"], samples[-1]["fds"], max(s["fds"] for s in samples)],
        "threads_start_end_max": [samples[0]["threads"], samples[-1]["threads"], max(s["threads"] for s in samples)],
        "recording": "not part of the load (the server has no recorder yet)",
        "samples": samples,
    }


def run_soak(minutes: float, viewers: int = 4, clients: int = 10, extra: list[str] | None = None) -> dict[str, Any]:
    with served(extra or []) as (pid, base, token):
        time.sleep(3.0)  # the media pipeline's first keyframes
        return asyncio.run(_soak(pid, base, token, minutes * 60.0, viewers, clients))
