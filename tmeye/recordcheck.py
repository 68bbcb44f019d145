"""Checks of a recording server from outside (HTTP), shared by the tests and `tmeye bench --recording`:
every segment's file decoded back with PyAV and its frames' stamps (`--stamp-frames`) compared with the
row's frame indices and the recorded telemetry; which captured frames are in exactly one segment per camera;
`/api/playback/frame` at random times against the telemetry."""

from __future__ import annotations

import bisect
import io
import random
import statistics
import time
from dataclasses import dataclass, field
from typing import Any

import av
import cv2
import httpx
import numpy as np

from tmeye.media.encoder import CLOCK_HZ, read_stamp


@dataclass
class SegmentCheck:
    id: int
    camera: str
    frames: int
    decoded: int
    ordered: bool
    telemetry_ok: int = field(metadata={"doc": "decoded frames whose stamp is the frame index of their telemetry"})
    stamps: list[int] = field(default_factory=list)
    error: str | None = None


@dataclass
class CameraFrames:
    """frame index -> number of segments of one camera holding it."""

    counts: dict[int, int] = field(default_factory=dict)


def decode_stamps(data: bytes) -> tuple[list[tuple[int, int]], str | None]:
    """[(pts in the segment, stamp)] of an MP4 file's frames; the error that ended decoding, if any."""
    out: list[tuple[int, int]] = []
    try:
        with av.open(io.BytesIO(data), "r") as c:
            for f in c.decode(video=0):
                out.append((int(f.pts or 0), read_stamp(np.asarray(f.to_ndarray(format="gray"), np.uint8))))
    except av.error.FFmpegError as exc:
        return out, f"{type(exc).__name__}: {exc}"
    return out, None


def telemetry_by_pts(http: httpx.Client, start: float, end: float) -> dict[int, dict[str, Any]]:
    rows = http.get("/api/telemetry", params={"start": start - 0.001, "end": end + 0.001, "limit": 200000})
    rows.raise_for_status()
    return {round(float(r["captured_at"]) * CLOCK_HZ): r for r in rows.json()}


def check_segment(http: httpx.Client, seg: dict[str, Any], tel: dict[int, dict[str, Any]],
                  start_pts: int) -> SegmentCheck:
    """Decode one segment through /api/recordings/{id}/file: each frame's stamp must equal the frame index
    of the telemetry recorded at its capture time (start_pts + pts, 90 kHz; +-1 tick of rounding)."""
    r = http.get(f"/api/recordings/{seg['id']}/file")
    r.raise_for_status()
    frames, err = decode_stamps(r.content)
    tel_ok = 0
    for pts, stamp in frames:
        t = start_pts + pts
        row = tel.get(t) or tel.get(t - 1) or tel.get(t + 1)
        tel_ok += row is not None and int(row["frame"]) % 65536 == stamp
    ordered = all(b[0] > a[0] for a, b in zip(frames, frames[1:], strict=False))
    return SegmentCheck(seg["id"], seg["camera"], seg["frames"], len(frames), ordered, tel_ok,
                        [stamp for _, stamp in frames], err)


def start_pts_of(seg: dict[str, Any]) -> int:
    return round(float(seg["start"]) * CLOCK_HZ)


def coverage(captured: set[int], holders: dict[str, CameraFrames]) -> dict[str, float]:
    """Per camera: the fraction of `captured` frame indices held by exactly one segment."""
    return {cam: sum(1 for f in captured if cf.counts.get(f) == 1) / max(len(captured), 1)
            for cam, cf in holders.items()}


def probe_frames(http: httpx.Client, camera: str, times: list[float], tel_times: list[float],
                 tel_frames: list[int]) -> dict[str, Any]:
    """GET /api/playback/frame at each time: the answer must be the last frame captured at or before it
    (from the recorded telemetry), its stamp must equal X-Frame-Index. Latencies in ms."""
    ok, lat, bad = 0, [], []
    for t in times:
        i = bisect.bisect_right(tel_times, t + 1.5 / CLOCK_HZ) - 1  # the server takes "at or before" within a tick
        want = tel_frames[i] if i >= 0 else None
        t0 = time.perf_counter()
        r = http.get("/api/playback/frame", params={"camera": camera, "t": f"{t:.6f}"})
        lat.append((time.perf_counter() - t0) * 1e3)
        if r.status_code != 200:
            bad.append({"t": t, "status": r.status_code, "detail": r.text[:200]})
            continue
        img = np.asarray(cv2.imdecode(np.frombuffer(r.content, np.uint8), cv2.IMREAD_GRAYSCALE), np.uint8)
        got, stamp = int(r.headers["X-Frame-Index"]), read_stamp(img)
        good = got == want and stamp == got % 65536
        ok += good
        if not good:
            bad.append({"t": t, "want": want, "got": got, "stamp": stamp})
    return {"probes": len(times), "correct": ok, "median_ms": round(statistics.median(lat), 2) if lat else None,
            "p95_ms": round(sorted(lat)[int(0.95 * (len(lat) - 1))], 2) if lat else None, "wrong": bad[:5]}


def random_times(segs: list[dict[str, Any]], n: int, seed: int = 0) -> list[float]:
    """n times uniformly inside the closed segments' spans."""
    rng = random.Random(seed)
    spans = [(float(s["start"]), float(s["end"])) for s in segs if s["status"] != "open" and s["end"]]
    return [rng.uniform(*rng.choice(spans)) for _ in range(n)] if spans else []
