"""Recording on a real server with --stamp-frames (3 s segments): closed segments decode with PyAV and each
frame's stamp is the frame index of its recorded telemetry; every frame seen on the telemetry WebSocket while
recording is in exactly one segment per camera; frame-exact playback; the HLS playlist's byte ranges decode;
exports; locks and bookmarks with their roles; bad input."""

from __future__ import annotations

import asyncio
import io
import json
import time
import zipfile
from collections.abc import Iterator
from typing import Any

import httpx
import pytest
from server_helpers import Server, start_server

from tmeye.media.encoder import CLOCK_HZ
from tmeye.recordcheck import (
    CameraFrames,
    check_segment,
    coverage,
    decode_stamps,
    probe_frames,
    random_times,
    start_pts_of,
    telemetry_by_pts,
)
from tmeye.webrtc_client import telemetry_messages


@pytest.fixture(scope="module")
def server(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Server]:
    s = start_server(tmp_path_factory.mktemp("rec") / "data", "--stamp-frames", env={"TMEYE_SEGMENT_S": "3"})
    yield s
    s.stop()


def closed_segments(c: httpx.Client, n: int, timeout: float = 60.0, **params: Any) -> list[dict[str, Any]]:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        segs = [s for s in c.get("/api/recordings", params=params).json() if s["status"] == "closed"]
        if len(segs) >= n:
            return segs
        time.sleep(0.5)
    raise AssertionError(f"fewer than {n} closed segments after {timeout} s")


def captured_frames(server: Server, seconds: float) -> list[tuple[int, float]]:
    """(frame, captured_at) of every telemetry message over `seconds`."""
    return asyncio.run(telemetry_messages(server.url, server.login(), seconds))


def media_dropped(c: httpx.Client) -> int:
    """Frames the media thread dropped before encoding (an overloaded machine): never shown nor recorded."""
    return sum(s["dropped"] for s in c.get("/api/status").json()["subscriptions"] if s["name"] == "media")


def test_segments_decode_and_match_telemetry(server: Server) -> None:
    with server.as_admin() as c:
        dropped0 = media_dropped(c)
    seen = captured_frames(server, 8.0)  # while recording
    with server.as_admin() as c:
        time.sleep(4.0)  # the segments holding those frames close
        segs = closed_segments(c, 4)
        # counted once the window's frames have passed the media thread: on a busy machine it may drop one
        # seen near the window's end after the window (CI: 5 missing against 4 counted at its end)
        dropped = media_dropped(c) - dropped0
        st = c.get("/api/status").json()["recording"]
        assert st["state"] == "recording" and st["fault"] is None and st["mode"] == "continuous"
        tel = telemetry_by_pts(c, min(s["start"] for s in segs), max(s["end"] for s in segs))
        holders = {"left": CameraFrames(), "right": CameraFrames()}
        for seg in segs:
            assert seg["path"].startswith("recordings/") and seg["path"].endswith(".mp4")
            assert f"/{seg['camera']}/" in seg["path"] and seg["keyframes"][0] == 0.0
            chk = check_segment(c, seg, tel, start_pts_of(seg))
            assert chk.error is None and chk.decoded == seg["frames"] > 0 and chk.ordered, chk
            assert chk.telemetry_ok == chk.decoded, chk  # each frame's stamp is its telemetry's frame index
            for f in chk.stamps:  # frame index mod 65536 of each decoded frame
                holders[seg["camera"]].counts[f] = holders[seg["camera"]].counts.get(f, 0) + 1
    first = max(min(s["start"] for s in segs if s["camera"] == cam) for cam in holders)
    last = min(max(s["end"] for s in segs if s["camera"] == cam) for cam in holders)
    inside = {f % 65536 for f, t in seen if first <= t <= last}
    assert len(inside) > 60
    cov = coverage(inside, holders)
    for cam, cf in holders.items():
        assert not [f for f, n in cf.counts.items() if n > 1], "a frame in two segments"
        missing = round((1 - cov[cam]) * len(inside))
        assert missing <= dropped, (cam, cov, dropped)  # every frame encoded is in exactly one segment


def test_playback_frame_is_the_last_frame_at_or_before_t(server: Server) -> None:
    with server.as_admin() as c:
        segs = closed_segments(c, 2, camera="right")
        tel = telemetry_by_pts(c, segs[0]["start"], segs[-1]["end"])
        times = sorted(r["captured_at"] for r in tel.values())
        frames = [tel[round(t * CLOCK_HZ)]["frame"] for t in times]
        probes = random_times(segs, 15, seed=3) + [times[5], times[5] + 1e-4]  # exactly at, and just after, a frame
        res = probe_frames(c, "right", probes, times, frames)
        assert res["correct"] == res["probes"], res
        r = c.get("/api/playback/frame", params={"camera": "left", "t": 1000.0})
        assert r.status_code == 404 and "no recording" in r.json()["detail"]
        assert c.get("/api/playback/frame", params={"camera": "top", "t": 1.0}).status_code == 422


def test_file_ranges_and_hls_playlist(server: Server) -> None:
    with server.as_admin() as c:
        segs = closed_segments(c, 2, camera="left")
        seg = segs[-1]
        r = c.get(f"/api/recordings/{seg['id']}/file", headers={"Range": "bytes=0-99"})
        assert r.status_code == 206 and len(r.content) == 100 and r.content[4:8] == b"ftyp"
        pl = c.get("/api/playback/left.m3u8", params={"start": segs[0]["start"], "end": seg["end"]})
        assert pl.status_code == 200 and pl.text.startswith("#EXTM3U") and "#EXT-X-ENDLIST" in pl.text
        lines = pl.text.splitlines()
        assert sum(line == "#EXT-X-DISCONTINUITY" for line in lines) == len(segs) - 1
        init = lines[[i for i, line in enumerate(lines) if line.startswith("#EXT-X-MAP")][-1]]
        n_init = int(init.split('BYTERANGE="')[1].split("@")[0])
        brs = [i for i, line in enumerate(lines) if line.startswith("#EXT-X-BYTERANGE")]
        n, off = (int(v) for v in lines[brs[-2]].split(":")[1].split("@"))
        uri = lines[brs[-2] + 1]
        head = c.get(uri, headers={"Range": f"bytes=0-{n_init - 1}"}).content
        frag = c.get(uri, headers={"Range": f"bytes={off}-{off + n - 1}"}).content
        stamps, err = decode_stamps(head + frag)  # an init segment and one media segment, as hls.js appends them
        assert err is None and len(stamps) >= 10
        assert all(b[1] == (a[1] + 1) % 65536 or b[1] > a[1] for a, b in zip(stamps, stamps[1:], strict=False))


def test_export_zip(server: Server) -> None:
    op = server.add_user("oscar", "operator")
    with server.client(op) as c:
        segs = closed_segments(c, 4)
        start, end = segs[0]["start"] + 1.0, segs[-1]["end"] - 0.5
        r = c.post("/api/exports", json={"start": start, "end": end, "cameras": ["left", "right"]})
        assert r.status_code == 202, r.text
        job = r.json()
        deadline = time.monotonic() + 60
        while job["status"] in ("queued", "running") and time.monotonic() < deadline:
            time.sleep(0.3)
            job = c.get(f"/api/exports/{job['id']}").json()
        assert job["status"] == "done", job
        z = zipfile.ZipFile(io.BytesIO(c.get(f"/api/exports/{job['id']}/download").content))
        assert sorted(z.namelist()) == ["left.mp4", "right.mp4", "telemetry.csv", "telemetry.json"]
        tel = json.loads(z.read("telemetry.json"))
        assert tel and all(start <= m["captured_at"] <= end for m in tel)
        header = z.read("telemetry.csv").decode().splitlines()[0]
        assert header.startswith("frame,captured_at") and header.endswith("left_clip_t,right_clip_t")
        for cam in ("left", "right"):
            stamps, err = decode_stamps(z.read(f"{cam}.mp4"))
            assert err is None
            by_t = {round(m["clip_t"][cam] * CLOCK_HZ): m["frame"] % 65536 for m in tel if m["clip_t"][cam] is not None}
            assert sum(by_t.get(p) == s for p, s in stamps) >= len(by_t) > 30  # each frame is its telemetry's
        assert c.post("/api/exports", json={"start": end, "end": start}).status_code == 422
        bad = c.post("/api/exports", json={"start": 1000.0, "end": 1010.0})
        assert bad.status_code == 422 and "nothing was recorded" in bad.json()["detail"]
        assert c.get("/api/exports/999999/download").status_code == 404


def test_locks_and_bookmarks(server: Server) -> None:
    viewer, op = server.add_user("vera", "viewer"), server.add_user("otto", "operator")
    now = time.time()
    with server.client(viewer) as v:
        assert v.post("/api/locks", json={"start": now - 10, "end": now}).status_code == 403
        assert v.post("/api/bookmarks", json={"t": now, "note": "x"}).status_code == 403
    with server.client(op) as o:
        lock = o.post("/api/locks", json={"start": now - 10, "end": now, "note": "gate"})
        assert lock.status_code == 201, lock.text
        assert o.post("/api/locks", json={"start": now, "end": now - 1}).status_code == 422
        assert o.post("/api/locks", json={"track_id": 999999}).status_code == 404
        assert o.delete(f"/api/locks/{lock.json()['id']}").status_code == 403  # only an admin unlocks
        bm = o.post("/api/bookmarks", json={"t": now - 5, "note": "van at the gate"})
        assert bm.status_code == 201
        assert [b["note"] for b in o.get("/api/bookmarks", params={"start": now - 6}).json()] == ["van at the gate"]
        assert o.delete(f"/api/bookmarks/{bm.json()['id']}").status_code == 204
    with server.as_admin() as a:
        assert len(a.get("/api/locks", params={"start": now - 5, "end": now - 4}).json()) == 1
        assert a.delete(f"/api/locks/{lock.json()['id']}").status_code == 204
        actions = [e["action"] for e in a.get("/api/audit").json()]
        assert {"evidence.lock", "evidence.unlock", "bookmark.add", "bookmark.delete"} <= set(actions)
