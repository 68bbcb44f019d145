"""Live video on a real server with --stamp-frames: an aiortc viewer decodes both cameras (each frame's
stamp matches a telemetry frame, in order), several viewers share one encoder, the MJPEG fallback, and
click-to-point / primary selection over the API."""

from __future__ import annotations

import asyncio
import time
from collections.abc import Iterator

import cv2
import httpx
import numpy as np
import pytest
from server_helpers import Server, start_server

from tmeye.media.encoder import read_stamp
from tmeye.webrtc_client import latency_ms, telemetry_times, view


@pytest.fixture(scope="module")
def server(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Server]:
    s = start_server(tmp_path_factory.mktemp("media") / "data", "--stamp-frames")
    yield s
    s.stop()


def test_webrtc_viewers_get_both_cameras_stamped_in_order(server: Server) -> None:
    token = server.login()

    async def main() -> tuple[list[list[object]], dict[int, float]]:
        tel = asyncio.create_task(telemetry_times(server.url, token, 6.0))
        views = await asyncio.gather(view(server.url, token, 4.0), view(server.url, token, 4.0))
        return [list(v) for v in views], await tel
    views, captured = asyncio.run(main())
    for recs in views:
        for rec in recs:
            stamps = [s for _, _, s in rec.frames]  # type: ignore[attr-defined]
            assert len(stamps) >= 60, (rec.camera, len(stamps))  # type: ignore[attr-defined]
            assert all(b > a for a, b in zip(stamps, stamps[1:], strict=False))
            assert sum(s in captured for s in stamps) >= 0.9 * len(stamps)  # frames are the tracker's frames
            lat = latency_ms(rec, captured)  # type: ignore[arg-type]
            assert lat and lat[0] > 0  # decoded after capture
    with server.as_admin() as c:
        st = c.get("/api/status").json()
    names = [s["name"] for s in st["subscriptions"]]
    assert names.count("media") == 1  # one encoder path however many viewers


def _mjpeg_frames(server: Server, camera: str, n: int) -> list[tuple[int, np.ndarray]]:
    out = []
    headers = {"Authorization": f"Bearer {server.login()}"}
    with httpx.stream("GET", f"{server.url}/api/live/{camera}.mjpeg", headers=headers, timeout=20) as r:
        assert r.status_code == 200 and r.headers["content-type"].startswith("multipart/x-mixed-replace")
        buf = b""
        for chunk in r.iter_bytes():
            buf += chunk
            while (start := buf.find(b"\xff\xd8")) >= 0 and (end := buf.find(b"\xff\xd9", start)) >= 0:
                head = buf[:start].decode(errors="replace")
                idx = int(head.split("X-Frame-Index: ")[1].split("\r\n")[0])
                img = cv2.imdecode(np.frombuffer(buf[start:end + 2], np.uint8), cv2.IMREAD_GRAYSCALE)
                out.append((idx, img))
                buf = buf[end + 2:]
                if len(out) >= n:
                    return out
    return out


def test_mjpeg_fallback_plays_stamped_frames(server: Server) -> None:
    frames = _mjpeg_frames(server, "right", 5)
    assert len(frames) == 5
    for idx, img in frames:
        assert img.shape == (480, 640) and read_stamp(img) == idx % 65536
    assert [i for i, _ in frames] == sorted(i for i, _ in frames)


def test_point_and_primary_over_the_api(server: Server) -> None:
    tok = server.add_user("opal", "operator")
    with server.client(tok) as c:
        c.put("/api/servo/mode", json={"mode": "hold"})
        time.sleep(0.5)
        before = c.get("/api/servo").json()
        r = c.post("/api/servo/point", json={"camera": "left", "u": 600, "v": 100})
        assert r.status_code == 200 and r.json()["mode"] == "manual"
        goal = r.json()["goal"]  # 280 px right of and 140 px above the centre, f = 600 px: about 25° and 13°
        assert 18 < goal["pan_deg"] - before["pan_deg"] < 32 and 7 < goal["tilt_deg"] - before["tilt_deg"] < 19
        r = c.post("/api/servo/point", json={"camera": "left", "u": 900, "v": 100})
        assert r.status_code == 422 and "outside the 640x480 image" in r.json()["detail"]
        r = c.post("/api/tracks/987654/primary")
        assert r.status_code == 404 and "no live track" in r.json()["detail"]
        c.put("/api/servo/mode", json={"mode": "auto"})
        deadline = time.monotonic() + 30
        while time.monotonic() < deadline:
            dets = c.get("/api/telemetry/latest").json()["detections"]
            if dets:
                assert c.post(f"/api/tracks/{dets[0]['track_id']}/primary").status_code in (204, 404)
                break
            time.sleep(0.2)
