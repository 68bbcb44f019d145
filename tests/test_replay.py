"""Replay (issue #10 section 4) on a real server recording the simulated scene: a replay via the API runs the
tracker on the recorded frames, its tracks are listed apart and the live tracks are untouched; bad requests
are one-line 4xx that store nothing; the CLI rejects a bad range with one line. On the same server: the
evidence lock of an alarm's footage (issue #10 section 1)."""

from __future__ import annotations

import subprocess
import sys
import time
from collections.abc import Iterator
from typing import Any

import httpx
import pytest
from server_helpers import ROOT, Server, start_server

from server.db.models import Alarm
from server.services.evidence import alarm_range
from server.services.tracks import MIN_DETECTIONS

# The live tracker's time budgets (verify_budget_ms, sigma_budget_ms) put boxes off by the wall clock, so its
# result depends on the machine's load; a replay (unpaced) has none. A target entering the view was seen a
# frame later live than replayed in one of two runs here. A CI run, slower, gave same_detected 0.77 over 151
# frames with the objects' counts equal in all but one (0.99): the likely cause is such a frame starting the
# entering target a second track while the first one, the primary, coasted "not detected" for up to max_missed
# frames. Without the budgets a replay with unchanged settings must reproduce the live result.
NO_BUDGETS = {"TMEYE_VERIFY_BUDGET_MS": "0", "TMEYE_SIGMA_BUDGET_MS": "0"}


@pytest.fixture(scope="module")
def server(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Server]:
    s = start_server(tmp_path_factory.mktemp("replay") / "data", env={"TMEYE_SEGMENT_S": "3", **NO_BUDGETS})
    yield s
    s.stop()


def recorded_range(c: httpx.Client, segments: int = 2, timeout: float = 90.0) -> tuple[float, float]:
    """start..end of the first `segments` closed segments of the left camera (the right one has the same)."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        segs = [s for s in c.get("/api/recordings", params={"camera": "left"}).json() if s["status"] == "closed"]
        if len(segs) >= segments:
            return segs[0]["start"], segs[segments - 1]["end"]
        time.sleep(0.5)
    raise AssertionError(f"fewer than {segments} closed segments after {timeout} s")


def wait_done(c: httpx.Client, replay_id: int, timeout: float = 300.0) -> dict[str, Any]:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        job = c.get(f"/api/replays/{replay_id}").json()
        assert 0.0 <= job["progress"] <= 1.0
        if job["status"] in ("done", "failed"):
            return job
        time.sleep(0.5)
    raise AssertionError(f"replay {replay_id} not finished after {timeout} s")


def trajectories(c: httpx.Client, tracks: list[dict[str, Any]], before: float) -> dict[int, list[dict[str, Any]]]:
    return {t["id"]: [p for p in c.get(f"/api/tracks/{t['id']}").json()["trajectory"] if p["t"] <= before]
            for t in tracks}


def test_replay_tracks_are_stored_apart(server: Server) -> None:
    with server.client(server.add_user("olga", "operator")) as c:
        start, end = recorded_range(c)
        live_before = c.get("/api/tracks").json()
        snap_t = time.time() - 2.0  # the live writer has committed everything up to here (1 s flushes)
        kept = trajectories(c, live_before, snap_t)
        r = c.post("/api/replays", json={"start": start, "end": end})
        assert r.status_code == 202, r.text
        job = wait_done(c, r.json()["id"])
        assert job["status"] == "done", job
        assert c.get("/api/status").json()["deferred_boxes"] == 0  # the live run had no budget (NO_BUDGETS)
        assert job["settings"]["threshold"] == 12 and job["settings"]["rig"] == "live"
        live_tm = c.get("/api/telemetry", params={"start": start, "end": end}).json()
        assert job["frames"] == job["agreement"]["frames"] > 0.9 * len(live_tm)
        replayed = c.get("/api/tracks", params={"replay": job["id"]}).json()
        seen = "".join("1" if tm["detected"] else "0" for tm in live_tm)
        assert job["agreement"]["same_detected"] > 0.9, (job["agreement"], seen, replayed)  # nearly the live result
        live = c.get("/api/tracks").json()
        assert all(t["replay_id"] == job["id"] and t["run_id"].startswith("replay-") for t in replayed)
        assert all(t["replay_id"] is None for t in live)
        assert not {t["id"] for t in replayed} & {t["id"] for t in live}
        if sum(tm["detected"] for tm in live_tm) >= 2 * MIN_DETECTIONS:  # a track is written from MIN_DETECTIONS
            assert replayed, "the live run detected a target in the range, the replay found no track"
            pts = c.get(f"/api/tracks/{replayed[0]['id']}").json()["trajectory"]
            assert pts and all(start - 0.01 <= p["t"] <= end + 0.01 for p in pts)
        assert trajectories(c, live_before, snap_t) == kept  # the original tracks are untouched
        assert [j["id"] for j in c.get("/api/replays").json()] == [job["id"]]


@pytest.mark.parametrize("body, words", [
    ({"start": 2_000_000_000.0, "end": 1_999_999_999.0}, "end must be after start"),
    ({"start": 1.0, "end": 5.0}, "was recorded between"),
    ({"calibration_id": 999}, "no calibration with id 999"),
])
def test_bad_replays_store_nothing(server: Server, body: dict[str, Any], words: str) -> None:
    with server.client(server.login()) as c:
        start, end = recorded_range(c, 1)
        before = c.get("/api/replays").json()
        r = c.post("/api/replays", json={"start": start, "end": end, **body})
        assert 400 <= r.status_code < 500, r.text
        detail = r.json()["detail"]
        assert isinstance(detail, str) and words in detail and "\n" not in detail
        assert c.get("/api/replays").json() == before


def test_cli_bad_range_exits_with_one_line(server: Server) -> None:
    p = subprocess.run([sys.executable, "-m", "tmeye", "track", "--source", "recording", "--data-dir",
                        str(server.data_dir), "--start", "2000000000", "--end", "1999999990"],
                       cwd=ROOT, capture_output=True, text=True, timeout=60)
    assert p.returncode != 0
    assert len(p.stderr.strip().splitlines()) == 1 and "must be after start" in p.stderr


def test_alarm_range_is_its_footage_with_pre_and_post_roll() -> None:
    cleared = Alarm(activated_at=100.0, cleared_at=130.0)
    assert alarm_range(cleared, 5.0, 7.0, now=500.0) == (95.0, 137.0)
    active = Alarm(activated_at=100.0, cleared_at=None)
    assert alarm_range(active, 5.0, 7.0, now=112.5) == (95.0, 112.5)


NEAR = {"name": "anyone near", "priority": "critical", "on_delay_s": 0, "off_delay_s": 3,
        "condition": {"kind": "range_below", "distance_m": 100}}


def test_lock_an_alarms_footage(server: Server) -> None:
    with server.client(server.login()) as admin, server.client(server.add_user("omar", "operator")) as op:
        rid = admin.post("/api/alarm-rules", json=NEAR).json()["id"]
        deadline = time.monotonic() + 120.0
        alarms: list[dict[str, Any]] = []
        while not alarms and time.monotonic() < deadline:
            alarms = [a for a in op.get("/api/alarms").json() if a["rule_id"] == rid]
            time.sleep(0.3)
        assert alarms, "no alarm was raised"
        a = alarms[0]
        before = time.time()
        r = op.post("/api/locks", json={"alarm_id": a["id"], "note": "alarm footage"})
        assert r.status_code == 201, r.text
        lock = r.json()
        assert lock["alarm_id"] == a["id"] and lock["start"] == pytest.approx(a["activated_at"] - 5.0)
        a = op.get(f"/api/alarms/{a['id']}").json()
        if a["cleared_at"] is None:  # active when locked: up to the lock's moment
            assert before - 1.0 <= lock["end"] <= time.time() + 1.0
        else:
            assert lock["end"] == pytest.approx(a["cleared_at"] + 5.0)
        assert lock["id"] in [x["id"] for x in op.get("/api/locks").json()]
        n = len(op.get("/api/locks").json())
        for body, code, words in (({"alarm_id": 999999}, 404, "no alarm with id 999999"),
                                  ({"alarm_id": a["id"], "start": 1.0, "end": 2.0}, 422, "one of them")):
            r = op.post("/api/locks", json=body)
            assert r.status_code == code and words in r.json()["detail"], r.text
        assert len(op.get("/api/locks").json()) == n
        assert op.delete(f"/api/locks/{lock['id']}").status_code == 403  # only an admin unlocks
        assert admin.delete(f"/api/locks/{lock['id']}").status_code == 204
        admin.delete(f"/api/alarm-rules/{rid}")
