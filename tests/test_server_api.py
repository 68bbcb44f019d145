"""The server's REST API on a real uvicorn server (default: endless simulated scene, closed loop): login
and roles on every route of the OpenAPI document, servo control, presets, tracker settings, users,
audit, and bad input answered with a one-line 4xx."""

from __future__ import annotations

import time
from collections.abc import Iterator
from pathlib import Path

import httpx
import pytest
from server_helpers import Server, openapi_routes, start_server

from tracker.sim.rig import default_rig

PUBLIC = {("GET", "/api/health"), ("POST", "/api/auth/login")}
# The role each operation needs; every operation of the document must be listed (a new route must be placed).
ROLE = {
    ("GET", "/api/status"): "viewer", ("GET", "/api/telemetry/latest"): "viewer",
    ("POST", "/api/auth/logout"): "viewer", ("GET", "/api/auth/me"): "viewer", ("GET", "/api/servo"): "viewer",
    ("PUT", "/api/servo/mode"): "operator", ("POST", "/api/servo/goto"): "operator",
    ("POST", "/api/servo/jog"): "operator", ("GET", "/api/servo/presets"): "viewer",
    ("POST", "/api/servo/presets"): "operator", ("POST", "/api/servo/presets/{preset_id}/goto"): "operator",
    ("DELETE", "/api/servo/presets/{preset_id}"): "operator", ("GET", "/api/tracks"): "viewer",
    ("GET", "/api/tracks/{track_id}"): "viewer", ("GET", "/api/tracker/config"): "viewer",
    ("PATCH", "/api/tracker/config"): "admin", ("POST", "/api/calibrations"): "admin",
    ("GET", "/api/calibrations"): "viewer", ("GET", "/api/calibrations/{rec_id}"): "viewer",
    ("POST", "/api/calibrations/{rec_id}/activate"): "admin", ("GET", "/api/calibrations/{rec_id}/rig"): "viewer",
    ("POST", "/api/servo/point"): "operator", ("POST", "/api/tracks/{track_id}/primary"): "operator",
    ("GET", "/api/webrtc/config"): "viewer", ("POST", "/api/webrtc/offer"): "viewer",
    ("GET", "/api/live/{camera}.mjpeg"): "viewer",
    ("GET", "/api/users"): "admin", ("POST", "/api/users"): "admin", ("PATCH", "/api/users/{user_id}"): "admin",
    ("DELETE", "/api/users/{user_id}"): "admin", ("GET", "/api/audit"): "admin",
    ("GET", "/api/recordings"): "viewer", ("GET", "/api/recordings/{seg_id}/file"): "viewer",
    ("GET", "/api/playback/frame"): "viewer", ("GET", "/api/playback/{camera}.m3u8"): "viewer",
    ("GET", "/api/telemetry"): "viewer", ("GET", "/api/locks"): "viewer", ("POST", "/api/locks"): "operator",
    ("DELETE", "/api/locks/{lock_id}"): "admin", ("GET", "/api/bookmarks"): "viewer",
    ("POST", "/api/bookmarks"): "operator", ("DELETE", "/api/bookmarks/{bookmark_id}"): "operator",
    ("POST", "/api/exports"): "operator", ("GET", "/api/exports"): "operator",
    ("GET", "/api/exports/{export_id}"): "operator", ("GET", "/api/exports/{export_id}/download"): "operator",
    ("POST", "/api/replays"): "operator", ("GET", "/api/replays"): "operator",
    ("GET", "/api/replays/{replay_id}"): "operator",
    ("GET", "/api/alarm-rules"): "viewer", ("POST", "/api/alarm-rules"): "admin",
    ("PATCH", "/api/alarm-rules/{rule_id}"): "admin", ("DELETE", "/api/alarm-rules/{rule_id}"): "admin",
    ("GET", "/api/alarms"): "viewer", ("GET", "/api/alarms/summary"): "viewer",
    ("GET", "/api/alarms/{alarm_id}"): "viewer", ("POST", "/api/alarms/{alarm_id}/ack"): "operator",
    ("POST", "/api/alarms/{alarm_id}/shelve"): "operator", ("POST", "/api/alarms/{alarm_id}/unshelve"): "operator",
}
RANK = {"viewer": 0, "operator": 1, "admin": 2}


@pytest.fixture(scope="module")
def server(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Server]:
    s = start_server(tmp_path_factory.mktemp("serve") / "data")
    yield s
    s.stop()


@pytest.fixture(scope="module")
def tokens(server: Server) -> dict[str, str]:
    return {"admin": server.login(), "operator": server.add_user("olga", "operator"),
            "viewer": server.add_user("victor", "viewer")}


def _call(c: httpx.Client, method: str, path: str) -> httpx.Response:
    url = path.replace("{preset_id}", "999999").replace("{track_id}", "999999").replace("{rec_id}", "999999") \
        .replace("{user_id}", "999999").replace("{camera}", "left")
    for name in ("seg_id", "lock_id", "bookmark_id", "export_id", "alarm_id", "rule_id", "replay_id"):
        url = url.replace("{" + name + "}", "999999")
    if url.endswith(".mjpeg"):  # a stream that never ends: its status line is enough
        with c.stream(method, url) as r:
            return r
    if method in ("GET", "DELETE"):
        return c.request(method, url)
    return c.request(method, url, json={})


def test_health_and_initial_admin(server: Server) -> None:
    assert httpx.get(f"{server.url}/api/health").json()["status"] == "ok"
    pw = server.data_dir / "initial-admin-password"
    assert pw.stat().st_mode & 0o777 == 0o600 and len(server.admin_password) >= 12
    assert str(pw.resolve()) in server.log_text()


def test_every_route_needs_its_role(server: Server, tokens: dict[str, str]) -> None:
    spec = httpx.get(f"{server.url}/api/openapi.json").json()
    routes = set(openapi_routes(spec))
    assert routes - PUBLIC == set(ROLE), "classify every new route in ROLE"
    for method, path in sorted(routes - PUBLIC):
        with server.client() as anon:
            assert _call(anon, method, path).status_code == 401, (method, path)
        for role, token in tokens.items():
            if role == "admin" or (method, path) == ("POST", "/api/auth/logout"):
                continue
            with server.client(token) as c:
                code = _call(c, method, path).status_code
            if RANK[role] < RANK[ROLE[(method, path)]]:
                assert code == 403, (role, method, path, code)
            else:
                assert code not in (401, 403), (role, method, path, code)


def test_viewer_cannot_drive_operator_can(server: Server, tokens: dict[str, str]) -> None:
    with server.client(tokens["viewer"]) as c:
        r = c.post("/api/servo/goto", json={"pan_deg": 5, "tilt_deg": 0})
        assert r.status_code == 403 and "operator" in r.json()["detail"]
        assert c.get("/api/users").status_code == 403
    with server.client(tokens["operator"]) as c:
        assert c.post("/api/servo/goto", json={"pan_deg": 5, "tilt_deg": 0}).status_code == 200
        assert c.get("/api/users").status_code == 403
        assert c.put("/api/servo/mode", json={"mode": "auto"}).status_code == 200


def test_goto_reaches_the_goal(server: Server, tokens: dict[str, str]) -> None:
    with server.client(tokens["operator"]) as c:
        r = c.post("/api/servo/goto", json={"pan_deg": 25.0, "tilt_deg": 6.0})
        assert r.status_code == 200 and r.json()["mode"] == "manual"
        deadline = time.monotonic() + 5.0
        while time.monotonic() < deadline:
            s = c.get("/api/servo").json()
            if abs(s["pan_deg"] - 25.0) <= 0.5 and abs(s["tilt_deg"] - 6.0) <= 0.5:
                break
            time.sleep(0.05)
        assert abs(s["pan_deg"] - 25.0) <= 0.5 and abs(s["tilt_deg"] - 6.0) <= 0.5, s
        assert c.get("/api/status").json()["servo"]["mode"] == "manual"
        pan0 = c.get("/api/servo").json()["pan_deg"]
        assert c.post("/api/servo/jog", json={"pan_dps": -20, "tilt_dps": 0, "duration_s": 0.5}).status_code == 200
        # 20 deg/s for 0.5 s of source time: 10 deg, however late a loaded machine runs the frames
        deadline = time.monotonic() + 10.0
        while time.monotonic() < deadline and c.get("/api/servo").json()["pan_deg"] > pan0 - 8.5:
            time.sleep(0.05)
        time.sleep(1.0)  # and there it stops: the jog ended
        pan1 = c.get("/api/servo").json()["pan_deg"]
        assert pan1 == pytest.approx(pan0 - 10.0, abs=1.5)
        assert c.put("/api/servo/mode", json={"mode": "home"}).status_code == 200
        assert c.put("/api/servo/mode", json={"mode": "auto"}).json()["mode"] == "auto"


def test_presets(server: Server, tokens: dict[str, str]) -> None:
    with server.client(tokens["operator"]) as c:
        r = c.post("/api/servo/presets", json={"name": "gate", "pan_deg": -12.5, "tilt_deg": 3.0})
        assert r.status_code == 201, r.text
        pid = r.json()["id"]
        assert c.post("/api/servo/presets", json={"name": "gate", "pan_deg": 1, "tilt_deg": 1}).status_code == 409
        assert [p["name"] for p in c.get("/api/servo/presets").json()] == ["gate"]
        r = c.post(f"/api/servo/presets/{pid}/goto")
        assert r.status_code == 200 and r.json()["goal"] == {"pan_deg": -12.5, "tilt_deg": 3.0}
        assert c.post("/api/servo/presets/424242/goto").json()["detail"] == "no preset with id 424242"
        assert c.delete(f"/api/servo/presets/{pid}").status_code == 204
        assert c.get("/api/servo/presets").json() == []
        c.put("/api/servo/mode", json={"mode": "auto"})


@pytest.mark.parametrize(("method", "path", "body", "code", "needle"), [
    ("POST", "/api/servo/goto", '{"pan_deg": 10,', 400, "not valid JSON"),
    ("POST", "/api/servo/goto", '{"pan_deg": "left", "tilt_deg": 0}', 422, "pan_deg"),
    ("POST", "/api/servo/goto", '{"pan_deg": 200, "tilt_deg": 0}', 422, "outside the mount's range"),
    ("POST", "/api/servo/goto", '{"pan_deg": 10}', 422, "tilt_deg: Field required"),
    ("PUT", "/api/servo/mode", '{"mode": "dance"}', 422, "mode"),
    ("POST", "/api/servo/jog", '{"pan_dps": 10, "tilt_dps": 0, "duration_s": 60}', 422, "duration_s"),
    ("POST", "/api/servo/presets/77/goto", "", 404, "no preset"),
    ("PATCH", "/api/tracker/config", '{"detector": {"epsilon": 0}}', 422, "detector.epsilon"),
    ("PATCH", "/api/tracker/config", '{"detector": {"stride": 2}}', 422, "stride"),
    ("POST", "/api/users", '{"username": "x", "password": "short", "role": "admin"}', 422, "password"),
    ("POST", "/api/users", '{"username": "y", "password": "long enough pw", "role": "king"}', 422, "role"),
    ("GET", "/api/tracks/123456", None, 404, "no track"),
    ("GET", "/api/tracks?start=yesterday", None, 422, "start"),
    # numbers JSON has no word for, which Python's parser reads, and ids and times past what is stored
    ("POST", "/api/bookmarks", '{"t": NaN, "note": "x"}', 422, "t: Input should be a finite number"),
    ("POST", "/api/bookmarks", '{"t": 1e308, "note": "x"}', 422, "t: Input should be less than"),
    ("POST", "/api/locks", '{"start": 1795376480, "end": Infinity}', 422, "end: Input should be a finite"),
    ("POST", "/api/locks", '{"track_id": 100000000000000000000000}', 422, "track_id"),
    ("POST", "/api/alarm-rules", '{"name": "z", "priority": "high", "condition": {"kind": "zone", "x_min": NaN}}',
     422, "x_min: Input should be a finite number"),
    ("POST", "/api/exports", '{"start": -5, "end": 5}', 422, "start"),
    ("GET", "/api/tracks?replay=100000000000000000000000", None, 422, "replay"),
])
def test_bad_input_is_a_one_line_4xx(server: Server, method: str, path: str, body: str | None, code: int,
                                     needle: str) -> None:
    with server.as_admin() as c:
        before = c.get("/api/audit").json()
        r = c.request(method, path, content=body, headers={"content-type": "application/json"})
    assert r.status_code == code, r.text
    detail = r.json()["detail"]
    assert isinstance(detail, str) and "\n" not in detail and needle in detail, detail
    with server.as_admin() as c:
        after = c.get("/api/audit").json()
    assert [a for a in after if a["action"] not in ("auth.login",)] == \
        [a for a in before if a["action"] not in ("auth.login",)]  # nothing stored


def test_tracker_config_applies_and_is_audited(server: Server) -> None:
    with server.as_admin() as c:
        r = c.patch("/api/tracker/config", json={"detector": {"epsilon": 15}, "aim": {"deadband_frac": 0.03}})
        assert r.status_code == 200
        cfg = c.get("/api/tracker/config").json()
        assert cfg["detector"]["epsilon"] == 15 and cfg["aim"]["deadband_frac"] == 0.03
        entry = c.get("/api/audit", params={"action": "tracker.config"}).json()[0]
        assert entry["username"] == "admin" and entry["address"] == "127.0.0.1"
        assert entry["detail"] == {"detector": {"epsilon": 15}, "aim": {"deadband_frac": 0.03}}
        c.patch("/api/tracker/config", json={"detector": {"epsilon": 12}, "aim": {"deadband_frac": 0.02}})


def test_logout_and_password_change_end_sessions(server: Server) -> None:
    tok = server.add_user("temp", "viewer")
    with server.client(tok) as c:
        assert c.get("/api/status").status_code == 200
        assert c.post("/api/auth/logout").status_code == 204
        r = c.get("/api/status")
        assert r.status_code == 401 and "session ended" in r.json()["detail"]
    tok = server.login("temp", "correct horse battery")
    with server.as_admin() as a:
        uid = next(u["id"] for u in a.get("/api/users").json() if u["username"] == "temp")
        assert a.patch(f"/api/users/{uid}", json={"password": "a brand new password"}).status_code == 200
        with server.client(tok) as c:
            assert c.get("/api/status").status_code == 401
        assert server.login("temp", "a brand new password")
        assert a.delete(f"/api/users/{uid}").status_code == 204
        assert a.delete(f"/api/users/{uid}").status_code == 404
        admin_id = next(u["id"] for u in a.get("/api/users").json() if u["username"] == "admin")
        r = a.patch(f"/api/users/{admin_id}", json={"role": "viewer"})
        assert r.status_code == 409 and "last admin" in r.json()["detail"]


def test_cookie_session_needs_csrf_header(server: Server) -> None:
    with httpx.Client(base_url=server.url) as c:
        r = c.post("/api/auth/login", data={"username": "admin", "password": server.admin_password})
        csrf = r.json()["csrf_token"]
        cookie = r.headers.get_list("set-cookie")
        assert any("tmeye_session=" in h and "HttpOnly" in h and "SameSite=strict" in h for h in cookie), cookie
        assert c.get("/api/status").status_code == 200  # the cookie alone serves safe requests
        r = c.put("/api/servo/mode", json={"mode": "auto"})
        assert r.status_code == 403 and "X-CSRF-Token" in r.json()["detail"]
        assert c.put("/api/servo/mode", json={"mode": "auto"}, headers={"X-CSRF-Token": csrf}).status_code == 200


def test_login_throttling(server: Server) -> None:
    for _ in range(5):
        assert httpx.post(f"{server.url}/api/auth/login", data={"username": "olga", "password": "wrong!"}
                          ).status_code == 401
    r = httpx.post(f"{server.url}/api/auth/login", data={"username": "olga", "password": "correct horse battery"})
    assert r.status_code == 429 and int(r.headers["Retry-After"]) > 0


def test_status_telemetry_and_tracks(server: Server) -> None:
    with server.as_admin() as c:
        st = c.get("/api/status").json()
        assert st["state"] == "running" and st["source"]["scenario"] == "endless" and st["servo"]["mode"]
        assert set(st) >= {"frame", "fps", "skipped_frames", "source", "servo", "faults"}
        assert isinstance(st["deferred_boxes"], int) and st["deferred_boxes"] >= 0
        hfov, vfov = default_rig().left.field_of_view_deg()  # the simulated rig's: what the console's plots draw
        assert st["source"]["hfov_deg"] == pytest.approx(hfov, abs=1e-3)
        assert st["source"]["vfov_deg"] == pytest.approx(vfov, abs=1e-3)
        tm = c.get("/api/telemetry/latest").json()
        assert tm["frame"] >= st["frame"] and abs(tm["captured_at"] - time.time()) < 5.0
        deadline = time.monotonic() + 30
        while not (tracks := c.get("/api/tracks").json()) and time.monotonic() < deadline:
            time.sleep(0.5)
        assert tracks, "no track written"
        one = c.get(f"/api/tracks/{tracks[-1]['id']}").json()
        assert one["trajectory"] and one["first_seen"] <= one["last_seen"]
        ts = [p["t"] for p in one["trajectory"]]
        assert ts == sorted(ts) and all(b - a >= 0.099 for a, b in zip(ts, ts[1:], strict=False))


def test_audit_records_control_actions(server: Server, tokens: dict[str, str]) -> None:
    with server.client(tokens["operator"]) as c:
        c.put("/api/servo/mode", json={"mode": "hold"})
        c.put("/api/servo/mode", json={"mode": "auto"})
    with server.as_admin() as a:
        entries = a.get("/api/audit", params={"action": "servo.mode"}).json()
    assert entries[0]["username"] == "olga" and entries[0]["target"] == "auto"
    assert entries[1]["target"] == "hold"


def test_data_dir_layout(server: Server) -> None:
    d: Path = server.data_dir
    assert (d / "tmeye.db").exists() and (d / "secret-key").stat().st_mode & 0o777 == 0o600
