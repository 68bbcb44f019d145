"""Calibration records over the API: upload rendered board pairs, progress and completion on /ws/events,
the report and rig file, activation switching the running tracker's rig; bad uploads refused with
nothing stored."""

from __future__ import annotations

import asyncio
import json
import time
from collections.abc import Iterator
from pathlib import Path

import httpx
import pytest
import websockets
from calib_helpers import chess_dir, write_sim_pairs
from server_helpers import Server, start_server


@pytest.fixture(scope="module")
def server(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Server]:
    s = start_server(tmp_path_factory.mktemp("cal") / "data", "--scenario", "walk", "--servo", "none")
    yield s
    s.stop()


@pytest.fixture(scope="module")
def pairs(tmp_path_factory: pytest.TempPathFactory) -> tuple[list[Path], list[Path]]:
    d = tmp_path_factory.mktemp("boards")
    write_sim_pairs(d, 12, seed=3)
    return sorted((d / "left").glob("*.png")), sorted((d / "right").glob("*.png"))


def _files(left: list[Path], right: list[Path]) -> list[tuple[str, tuple[str, bytes, str]]]:
    return [("left", (p.name, p.read_bytes(), "image/png")) for p in left] + \
        [("right", (p.name, p.read_bytes(), "image/png")) for p in right]


async def _events_until_done(server: Server, token: str, started: asyncio.Event) -> list[dict[str, object]]:
    url = server.url.replace("http://", "ws://") + "/ws/events"
    got = []
    async with websockets.connect(url, additional_headers={"Authorization": f"Bearer {token}"}) as ws:
        started.set()
        while True:
            ev = json.loads(await asyncio.wait_for(ws.recv(), 120))
            got.append(ev)
            if ev["type"] in ("calibration.done", "calibration.failed"):
                return got


def test_upload_progress_report_activate_download(server: Server, pairs: tuple[list[Path], list[Path]]) -> None:
    token = server.login()

    async def main() -> tuple[httpx.Response, list[dict[str, object]]]:
        started = asyncio.Event()
        listener = asyncio.create_task(_events_until_done(server, token, started))
        await started.wait()
        async with httpx.AsyncClient(base_url=server.url, headers={"Authorization": f"Bearer {token}"},
                                     timeout=60) as c:
            r = await c.post("/api/calibrations", data={"board": "9x6", "square": "0.05"}, files=_files(*pairs))
        return r, await listener
    r, events = asyncio.run(main())
    assert r.status_code == 202, r.text
    rec = r.json()
    assert rec["status"] == "running" and rec["images"] == 12 and len(rec["image_hashes"][0][0]) == 64
    assert any(e["type"] == "calibration.progress" for e in events)
    assert events[-1]["type"] == "calibration.done", events[-3:]
    with server.client(token) as c:
        done = c.get(f"/api/calibrations/{rec['id']}").json()
        assert done["status"] == "done" and done["report"]["views_used"] >= 10
        assert done["report"]["rms_px"] < 0.5
        rig = c.get(f"/api/calibrations/{rec['id']}/rig")
        assert rig.status_code == 200 and "left" in rig.json()
        frame0 = c.get("/api/status").json()["frame"]
        act = c.post(f"/api/calibrations/{rec['id']}/activate")
        assert act.status_code == 200 and act.json()["active"] is True
        time.sleep(0.5)
        st = c.get("/api/status").json()
        assert st["state"] == "running" and st["frame"] > frame0
        assert c.get("/api/audit", params={"action": "calibration.activate"}).json()[0]["target"] == str(rec["id"])


@pytest.mark.parametrize(("case", "needle"), [
    ("not-images", "is not an image"),
    ("no-board", "board"),
    ("bad-board", "COLSxROWS"),
    ("unpaired", "upload them in pairs"),
    ("too-few", "upload 4 to 200 image pairs"),
])
def test_bad_uploads_are_refused_and_nothing_is_stored(server: Server, pairs: tuple[list[Path], list[Path]],
                                                       case: str, needle: str) -> None:
    left, right = pairs
    data: dict[str, str] = {"board": "9x6", "square": "0.05"}
    files = _files(left[:6], right[:6])
    if case == "not-images":
        files = [(k, (name, b"this is not a picture", "image/png")) for k, (name, _, _) in files]
    elif case == "no-board":
        data.pop("board")
    elif case == "bad-board":
        data["board"] = "nine by six"
    elif case == "unpaired":
        files = _files(left[:6], right[:5])
    elif case == "too-few":
        files = _files(left[:2], right[:2])
    with server.as_admin() as c:
        before = c.get("/api/calibrations").json()
        r = c.post("/api/calibrations", data=data, files=files)
        assert r.status_code == 422, r.text
        assert needle in r.json()["detail"] and "\n" not in r.json()["detail"]
        assert c.get("/api/calibrations").json() == before
    assert not [p for p in (server.data_dir / "calibration").iterdir() if p.name.startswith(".upload")]


def test_real_photos_without_a_matching_board_fail_cleanly(server: Server) -> None:
    photos = sorted(chess_dir().glob("chess*.png"))[:6]
    with server.as_admin() as c:
        r = c.post("/api/calibrations", data={"board": "9x6", "square": "0.03"}, files=_files(photos, photos))
        assert r.status_code == 202
        rid = r.json()["id"]
        deadline = time.monotonic() + 120
        while (rec := c.get(f"/api/calibrations/{rid}").json())["status"] == "running" and time.monotonic() < deadline:
            time.sleep(0.3)
        assert rec["status"] == "failed" and rec["error"] and "\n" not in rec["error"]
        r = c.post(f"/api/calibrations/{rid}/activate")
        assert r.status_code == 409 and "only a finished calibration" in r.json()["detail"]


def test_viewers_cannot_upload(server: Server, pairs: tuple[list[Path], list[Path]]) -> None:
    tok = server.add_user("viv", "viewer")
    with server.client(tok) as c:
        assert c.post("/api/calibrations", data={"board": "9x6", "square": "0.05"},
                      files=_files(pairs[0][:4], pairs[1][:4])).status_code == 403
