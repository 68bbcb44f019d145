"""Colour from real cameras reaches the viewers: a server on a colour video source (the files source,
as a real camera pair would be read) sends colour MJPEG and colour H.264 while the tracker works on grey."""

from __future__ import annotations

import asyncio
from pathlib import Path

import cv2
import httpx
import numpy as np
from server_helpers import start_server
from test_sources import write_colour_video

from tmeye.webrtc_client import view
from tracker.geometry import save_rig
from tracker.sim.rig import default_rig

RED, BLUE = (30, 30, 220), (200, 60, 20)  # BGR, as written by write_colour_video


def _first_mjpeg(url: str, token: str) -> np.ndarray:
    headers = {"Authorization": f"Bearer {token}"}
    with httpx.stream("GET", f"{url}/api/live/left.mjpeg", headers=headers, timeout=20) as r:
        assert r.status_code == 200
        buf = b""
        for chunk in r.iter_bytes():
            buf += chunk
            if (start := buf.find(b"\xff\xd8")) >= 0 and (end := buf.find(b"\xff\xd9", start)) >= 0:
                return np.asarray(cv2.imdecode(np.frombuffer(buf[start:end + 2], np.uint8), cv2.IMREAD_COLOR))
    raise AssertionError("no MJPEG frame")


def _near(bgr: np.ndarray, colour: tuple[int, int, int], tol: int = 25) -> bool:
    return bool(np.abs(bgr.astype(int) - colour).max() <= tol)


def test_colour_source_is_seen_in_colour(tmp_path: Path) -> None:
    videos = [str(write_colour_video(tmp_path / f"{s}.mp4", 900, size=(640, 480))) for s in "lr"]
    save_rig(default_rig(), tmp_path / "rig.json")
    server = start_server(tmp_path / "data", "--source", "files", "--rig", str(tmp_path / "rig.json"), *videos)
    try:
        token = server.login()
        img = _first_mjpeg(server.url, token)
        assert img.shape == (480, 640, 3)
        assert _near(img[60, 80], RED) and _near(img[400, 560], BLUE)

        recs = asyncio.run(view(server.url, token, 3.0, read_stamps=False, keep_last=True))
        for rec in recs:
            assert rec.frames, rec.camera
            bgr = rec.last_bgr
            assert bgr.shape == (480, 640, 3)
            assert _near(bgr[60, 80], RED) and _near(bgr[400, 560], BLUE)  # decoded H.264 keeps the colour
    finally:
        server.stop()
