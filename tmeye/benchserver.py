"""`tmeye bench --server`: the server under its default load, measured from outside.

Starts `tmeye serve` (simulated endless scene, closed loop on the simulated gimbal, unless told otherwise)
in a temporary data directory, logs in, connects N WebSocket telemetry clients and, after a warm-up,
measures over a window: messages per second per client and whether every client's frames strictly
increase; the server's own figures over the window (skipped frames, event-loop lag and capture-to-send
latency percentiles, from /api/status, reset at the start of the window by a fresh monitor window);
and the CPU the server process used (user + system time from /proc, in cores)."""

from __future__ import annotations

import asyncio
import contextlib
import json
import os
import re
import signal
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

CLK_TCK = os.sysconf("SC_CLK_TCK")


def _cpu_s(pid: int) -> float:
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / CLK_TCK  # utime + stime


def end_with_parent() -> None:
    """In a child process before exec (Linux): SIGTERM when the parent ends, so that a measuring or test
    process that dies or is killed leaves no server running."""
    import ctypes

    with contextlib.suppress(OSError, AttributeError):
        ctypes.CDLL("libc.so.6", use_errno=True).prctl(1, signal.SIGTERM)  # PR_SET_PDEATHSIG


def _start(data: Path, extra: list[str]) -> tuple[subprocess.Popen[str], str]:
    proc = subprocess.Popen([sys.executable, "-m", "tmeye", "serve", "--port", "0", "--data-dir", str(data),
                             "--log-level", "warning", *extra], stdout=subprocess.PIPE,
                            stderr=(data / "server.log").open("a"), text=True, preexec_fn=end_with_parent)
    assert proc.stdout is not None
    m = re.search(r"(http://[\d.]+:\d+)/", proc.stdout.readline())
    if not m:
        proc.kill()
        raise RuntimeError("the server printed no URL")
    return proc, m.group(1)


async def _client(url: str, token: str, seconds: float, out: dict[str, Any], window_start: list[float]) -> None:
    import websockets

    frames: list[int] = []
    steps: list[float] = []  # the tracker's step_ms of the messages in the window
    counted = 0
    async with websockets.connect(url, additional_headers={"Authorization": f"Bearer {token}"},
                                  max_queue=None) as ws:
        end = time.monotonic() + seconds
        while (left := end - time.monotonic()) > 0:
            try:
                msg = await asyncio.wait_for(ws.recv(), left)
            except TimeoutError:
                break
            tm = json.loads(msg)
            frames.append(int(tm["frame"]))
            if window_start and time.monotonic() >= window_start[0]:
                counted += 1
                steps.append(float(tm.get("step_ms") or 0.0))
    out["messages"] = counted
    out["step_ms"] = steps
    out["increasing"] = all(b > a for a, b in zip(frames, frames[1:], strict=False))


async def _measure(base: str, token: str, clients: int, seconds: float, warmup: float) -> dict[str, Any]:
    import httpx

    async with httpx.AsyncClient(base_url=base, headers={"Authorization": f"Bearer {token}"}) as http:
        ws_url = base.replace("http://", "ws://") + "/ws/telemetry"
        results: list[dict[str, Any]] = [{} for _ in range(clients)]
        start: list[float] = []
        tasks = [asyncio.create_task(_client(ws_url, token, warmup + seconds, r, start)) for r in results]
        await asyncio.sleep(warmup)
        start.append(time.monotonic())
        s0 = (await http.get("/api/status")).json()
        await asyncio.gather(*tasks)
        elapsed = time.monotonic() - start[0]
        s1 = (await http.get("/api/status", params={"window_s": elapsed})).json()
    return {"clients": results, "status_before": s0, "status_after": s1}


def serve_ready(data: Path, extra: list[str]) -> tuple[subprocess.Popen[str], str, str]:
    """`tmeye serve` on `data` until /api/health says ok: (process, base URL, admin token)."""
    import httpx

    proc, base = _start(data, extra)
    deadline = time.monotonic() + 180
    while time.monotonic() < deadline:
        try:
            if httpx.get(f"{base}/api/health", timeout=2).json()["status"] == "ok":
                break
        except httpx.HTTPError:
            pass
        time.sleep(0.2)
    pw = (data / "initial-admin-password").read_text().strip()
    token = httpx.post(f"{base}/api/auth/login", data={"username": "admin", "password": pw}).json()["access_token"]
    return proc, base, token


@contextlib.contextmanager
def served(extra: list[str]) -> Iterator[tuple[int, str, str]]:
    """A `tmeye serve` in a temporary data directory: (pid, base URL, admin token); stopped on exit."""
    with tempfile.TemporaryDirectory(prefix="tmeye-bench-") as tmp:
        proc, base, token = serve_ready(Path(tmp), extra)
        try:
            yield proc.pid, base, token
        finally:
            proc.send_signal(signal.SIGTERM)
            proc.wait(15)
            log = (Path(tmp) / "server.log").read_text(errors="replace")
            if (i := log.find("Traceback")) >= 0:  # the server's errors outlive its temporary directory
                print(f"the server logged errors; the first:\n{log[max(i - 200, 0):i + 4000]}", file=sys.stderr)


def run_server_bench(seconds: float, clients: int, warmup: float, extra: list[str]) -> dict[str, Any]:
    with served(extra) as (pid, base, token):
        cpu0, t0 = _cpu_s(pid), time.monotonic()
        m = asyncio.run(_measure(base, token, clients, seconds, warmup))
        cpu = (_cpu_s(pid) - cpu0) / (time.monotonic() - t0)
    return _report(m, seconds, cpu)


def run_webrtc_bench(seconds: float, client_counts: list[int], extra: list[str]) -> dict[str, Any]:
    """WebRTC viewers (aiortc) on a server with --stamp-frames: for each number of clients, the decoded
    rate per camera, capture-to-decoded latency percentiles, and the server's CPU (cores) meanwhile."""
    from tmeye.webrtc_client import measure

    out: dict[str, Any] = {"seconds": seconds, "runs": []}
    with served(["--stamp-frames", *extra]) as (pid, base, token):
        time.sleep(3.0)
        for n in client_counts:
            cpu0, t0 = _cpu_s(pid), time.monotonic()
            m = asyncio.run(measure(base, token, n, seconds))
            m["server_cpu_cores"] = round((_cpu_s(pid) - cpu0) / (time.monotonic() - t0), 3)
            out["runs"].append(m)
    return out


def _report(m: dict[str, Any], seconds: float, cpu: float) -> dict[str, Any]:
    from server.services.monitor import percentiles

    s0, s1 = m["status_before"], m["status_after"]
    frames = (s1["frame"] - s0["frame"]) or 1
    skipped = s1["skipped_frames"] - s0["skipped_frames"]
    rates = [c["messages"] / seconds for c in m["clients"]]
    return {"seconds": seconds, "clients": len(rates), "source": s1["source"], "servo_mode": s1["servo"].get("mode"),
            "frames": frames, "skipped_frames": skipped, "skipped_pct": round(100.0 * skipped / frames, 3),
            "deferred_boxes": s1.get("deferred_boxes", 0) - s0.get("deferred_boxes", 0),
            "reused_sigma": s1.get("reused_sigma", 0) - s0.get("reused_sigma", 0),
            "fps": s1["fps"], "step_ms": percentiles(m["clients"][0]["step_ms"]),
            "event_loop_lag_ms": s1["event_loop_lag_ms"],
            "ws_send_latency_ms": s1["ws_send_latency_ms"], "ws_delivery_ms": s1["ws_delivery_ms"],
            "cpu_cores": round(cpu, 3),
            "messages_per_s_per_client": {"min": round(min(rates), 2), "max": round(max(rates), 2)},
            "frames_strictly_increasing": all(c["increasing"] for c in m["clients"]),
            "frame_errors": s1["frame_errors"]}
