"""`tmeye soak`: the server under a console's full load for a long time, watched from outside.

Starts `tmeye serve` (the default simulated scene, closed loop; extra serve arguments passed through) in a
temporary data directory and, for the whole run, keeps WebRTC viewers (aiortc, both cameras decoded), WebSocket
telemetry clients and a REST client polling the status, servo and tracks. Every `sample_s` seconds it reads
the server process's resident memory, open file descriptors and threads from /proc and its status over that
interval (skipped frames, event-loop lag p99, the longest interval between frames). The report gives those
samples and a summary against the soak goals: RSS growth after the first 5 minutes (of the run's length when
shorter), the longest frame stall, and whether descriptors and threads stay flat."""

from __future__ import annotations

import asyncio
import os
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

SETTLE_S = 300.0  # RSS growth is measured from this far into the run
GRACE_S = 3.0


@dataclass
class Load:
    """What the clients saw."""

    ws_messages: list[int] = field(default_factory=list)
    rest_requests: int = 0
    rest_errors: list[str] = field(default_factory=list)
    webrtc_frames: list[int] = field(default_factory=list)


def proc_figures(pid: int) -> dict[str, float]:
    """RSS (MB), threads and open file descriptors of a process, from /proc."""
    status = Path(f"/proc/{pid}/status").read_text()
    fields = {k: v.split() for k, _, v in (line.partition(":") for line in status.splitlines())}
    return {"rss_mb": round(int(fields["VmRSS"][0]) / 1024, 1), "threads": int(fields["Threads"][0]),
            "fds": len(os.listdir(f"/proc/{pid}/fd"))}


async def _ws_client(url: str, token: str, until: float, load: Load, k: int) -> None:
    import websockets

    async with websockets.connect(url, additional_headers={"Authorization": f"Bearer {token}"},
                                  max_queue=64) as ws:
        while (left := until - time.monotonic()) > 0:
            try:
                await asyncio.wait_for(ws.recv(), left)
            except TimeoutError:
                break
            load.ws_messages[k] += 1


async def _rest_client(http: Any, until: float, load: Load) -> None:
    paths = ["/api/status", "/api/servo", "/api/tracks", "/api/telemetry/latest"]
    i = 0
    while time.monotonic() < until:
        path = paths[i % len(paths)]
        i += 1
        try:
            r = await http.get(path)
            load.rest_requests += 1
            if r.status_code >= 500:
                load.rest_errors.append(f"{path}: {r.status_code}")
        except Exception as exc:  # the server stopped answering: report it, keep polling
            load.rest_errors.append(f"{path}: {type(exc).__name__}")
        await asyncio.sleep(0.25)


async def _webrtc_client(base: str, token: str, seconds: float, load: Load, k: int) -> None:
    from tmeye.webrtc_client import view

    recs = await view(base, token, seconds, read_stamps=False)
    load.webrtc_frames[k] = sum(len(r.frames) for r in recs)


async def _sampler(http: Any, pid: int, t0: float, until: float, every: float, out: list[dict[str, Any]]) -> None:
    last: dict[str, Any] | None = None  # the last good sample
    while (left := until - time.monotonic()) > 0:
        await asyncio.sleep(min(every, left))
        r = await http.get("/api/status", params={"window_s": every})
        if r.status_code != 200:  # counted by the REST client's figures too; the next sample tries again
            out.append({"t_s": round(time.monotonic() - t0, 1), "error": f"/api/status: {r.status_code}"})
            continue
        st = r.json()
        row = {"t_s": round(time.monotonic() - t0, 1), **proc_figures(pid), "frame": st["frame"],
               "skipped_frames": st["skipped_frames"], "loop_lag_p99_ms": st["event_loop_lag_ms"].get("p99"),
               "frame_gap_max_ms": st.get("frame_gap_max_ms"), "state": st["state"],
               "recording": _recording(st.get("recording"))}
        row["skipped_in_interval"] = row["skipped_frames"] - (last["skipped_frames"] if last else 0)
        out.append(row)
        last = row


def _recording(rec: dict[str, Any] | None) -> dict[str, Any] | None:
    """The recorder's state, segments closed, errors and fault (None when the server does not record)."""
    if not rec:
        return None
    return {k: rec.get(k) for k in ("state", "segments", "errors", "dropped_packets", "fault")}


async def _soak(pid: int, base: str, token: str, seconds: float, webrtc: int, ws: int,
                every: float) -> tuple[Load, list[dict[str, Any]]]:
    import httpx

    load = Load(ws_messages=[0] * ws, webrtc_frames=[0] * webrtc)
    samples: list[dict[str, Any]] = []
    t0 = time.monotonic()
    until = t0 + seconds
    load_until = until + GRACE_S  # the clients outlast the last sample
    ws_url = base.replace("http://", "ws://") + "/ws/telemetry"
    async with httpx.AsyncClient(base_url=base, headers={"Authorization": f"Bearer {token}"}, timeout=10) as http:
        tasks = [*(_ws_client(ws_url, token, load_until, load, k) for k in range(ws)),
                 *(_webrtc_client(base, token, seconds + GRACE_S, load, k) for k in range(webrtc)),
                 _rest_client(http, load_until, load), _sampler(http, pid, t0, until, every, samples)]
        results = await asyncio.gather(*tasks, return_exceptions=True)
    for r in results:
        if isinstance(r, BaseException):
            load.rest_errors.append(f"client failed: {type(r).__name__}: {r}")
    return load, samples


def summarise(samples: list[dict[str, Any]], load: Load, seconds: float) -> dict[str, Any]:
    """The figures the soak goals are judged by (status errors are counted, their rows left out)."""
    failed = [s for s in samples if "error" in s]
    samples = [s for s in samples if "error" not in s]
    settle = min(SETTLE_S, seconds / 2)
    after = [s for s in samples if s["t_s"] >= settle] or samples[-1:]
    rss0, rss1 = after[0]["rss_mb"], samples[-1]["rss_mb"]
    frames = (samples[-1]["frame"] or 0) - (samples[0]["frame"] or 0)
    skipped = samples[-1]["skipped_frames"] - samples[0]["skipped_frames"]
    gaps = [s["frame_gap_max_ms"] for s in samples if s["frame_gap_max_ms"] is not None]
    lags = [s["loop_lag_p99_ms"] for s in samples if s["loop_lag_p99_ms"] is not None]
    return {
        "minutes": round(seconds / 60, 2),
        "rss_mb": {"first": samples[0]["rss_mb"], "at_settle": rss0, "last": rss1,
                   "max": max(s["rss_mb"] for s in samples)},
        "rss_growth_after_settle_pct": round(100.0 * (rss1 - rss0) / rss0, 2),
        "settle_s": settle,
        "longest_frame_stall_ms": max(gaps) if gaps else None,
        "event_loop_lag_p99_ms_worst_interval": max(lags) if lags else None,
        "skipped_pct": round(100.0 * skipped / max(frames + skipped, 1), 3),
        "fds": {"min": min(s["fds"] for s in after), "max": max(s["fds"] for s in after)},
        "threads": {"min": min(s["threads"] for s in after), "max": max(s["threads"] for s in after)},
        "ws_messages_per_s": [round(n / (seconds + GRACE_S), 1) for n in load.ws_messages],
        "webrtc_frames_per_s": [round(n / (seconds + GRACE_S) / 2, 1) for n in load.webrtc_frames],  # per camera
        "rest_requests": load.rest_requests, "rest_errors": load.rest_errors[:20],
        "states": sorted({s["state"] for s in samples}),
        "status_errors": len(failed),
        "recording": samples[-1].get("recording"),
    }


def run_soak(minutes: float, webrtc: int, ws: int, every: float, extra: list[str]) -> dict[str, Any]:
    from tmeye.benchserver import served

    seconds = minutes * 60.0
    with served(extra) as (pid, base, token):
        load, samples = asyncio.run(_soak(pid, base, token, seconds, webrtc, ws, every))
    if not any("error" not in s for s in samples):
        raise RuntimeError("no sample was taken (run longer than one sampling interval, or the status failed)")
    return {"summary": summarise(samples, load, seconds), "samples": samples}
