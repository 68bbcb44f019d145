"""The browser console on a real server: logging in through the form, the Live page's status and
telemetry, a viewer's disabled controls, jogging by keyboard and on-screen pad, the Tracks, Settings,
Users and Calibration pages, and screenshots of the Live page at 1280x720 and tablet width."""

from __future__ import annotations

import re
from collections.abc import Iterator
from typing import Any

import numpy as np
import pytest
from server_helpers import Server, start_server
from web_helpers import admin, debug, login, new_page, require_browser, screenshot, skip_reason, user, wait_for

pytestmark = pytest.mark.skipif(skip_reason() is not None, reason=skip_reason() or "")


@pytest.fixture(scope="module")
def server(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Server]:
    require_browser()
    s = start_server(tmp_path_factory.mktemp("web") / "data")
    yield s
    s.stop()


@pytest.fixture
def page_of(chromium: Any, server: Server) -> Iterator[Any]:
    pages: list[Any] = []

    def make(width: int = 1280, height: int = 720, init_script: str | None = None) -> Any:
        p = new_page(chromium, server, width, height, init_script)
        pages.append(p)
        return p
    yield make
    for p in pages:
        p.context.close()


def _servo(server: Server) -> dict[str, Any]:
    with server.as_admin() as c:
        r = c.get("/api/servo")
        r.raise_for_status()
        out: dict[str, Any] = r.json()
        return out


def _goto(server: Server, pan: float, tilt: float) -> None:
    with server.as_admin() as c:
        c.post("/api/servo/goto", json={"pan_deg": pan, "tilt_deg": tilt}).raise_for_status()
    wait_for(lambda: abs((_servo(server)["pan_deg"] or 0) - pan) < 0.5, 10, what=f"mount at pan {pan}")


def test_login_through_the_form(server: Server, page_of: Any) -> None:
    page = page_of()
    page.goto("/")
    page.get_by_label("Username").fill("admin")
    page.get_by_label("Password").fill("not the password")
    page.get_by_role("button", name="Log in").click()
    page.get_by_role("alert").filter(has_text="Wrong username or password").wait_for()
    login(page, *admin(server))
    assert page.get_by_test_id("who").inner_text() == "admin (admin)"
    assert page.get_by_role("link", name="Users").is_visible()
    # the session is the cookie: a reload stays logged in; logging out shows the form again
    page.reload()
    page.get_by_role("navigation", name="Pages").wait_for()
    page.get_by_role("button", name="Log out").click()
    page.get_by_label("Username").wait_for()
    assert page.context.cookies() == [] or all(c["name"] != "tmeye_session" for c in page.context.cookies())


def test_live_page_shows_status_and_updating_telemetry(server: Server, page_of: Any) -> None:
    page = page_of()
    login(page, *admin(server))
    page.get_by_test_id("sb-fps").filter(has_text=re.compile(r"\d+(\.\d)? fps")).wait_for()
    assert "Skipped frames:" in page.get_by_test_id("sb-skipped").inner_text()
    assert page.get_by_test_id("sb-servo").inner_text().startswith("Servo: ")
    page.get_by_test_id("sb-telemetry").filter(has_text="Telemetry: connected").wait_for()
    frame = page.get_by_test_id("ro-frame")

    def frame_no() -> int:
        m = re.match(r"(\d+)", frame.inner_text())
        return int(m.group(1)) if m else -1
    first = wait_for(lambda: frame_no() if frame_no() > 0 else 0, 15, what="a frame number")
    wait_for(lambda: frame_no() > first + 5, 10, what="the frame number advancing")
    wait_for(lambda: debug(page)["telemetryMessages"] > 30, 15, what="30 telemetry messages")
    # a target appears in the endless scene within a while: r, θ, φ with their σ
    r, theta = page.get_by_test_id("ro-r"), page.get_by_test_id("ro-theta")
    shown: dict[str, str] = {}

    def target_shown() -> bool:  # read together: the target may be lost between two reads (endless scene)
        shown["r"], shown["theta"] = r.inner_text(), theta.inner_text()
        return "±" in shown["r"] and "±" in shown["theta"]
    wait_for(target_shown, 60, what="a target's range and azimuth")
    assert re.search(r"\d+\.\d+ ± \d+\.\d+ m", shown["r"])
    # the plots' field of view is the rig's (the simulated rig: 57.7 x 44.3 degrees), at the mount's angles
    with server.as_admin() as c:
        fov = c.get("/api/status").json()["source"]
    plan = page.get_by_test_id("fov-plan")
    wait_for(lambda: plan.text_content().startswith("FOV"), 10, what="the plan view's field of view")
    assert plan.text_content().startswith(f"FOV {fov['hfov_deg']:.0f}°, pan ")
    assert page.get_by_test_id("fov-side").text_content().startswith(f"FOV {fov['vfov_deg']:.0f}°, tilt ")


def test_viewer_sees_controls_disabled_with_the_reason(server: Server, page_of: Any) -> None:
    page = page_of()
    login(page, *user(server, "vera", "viewer"))
    reason = page.get_by_test_id("drive-reason")
    assert "needs the operator role" in reason.inner_text() and "viewer" in reason.inner_text()
    for name in ("Auto", "Manual", "Hold", "Home", "Pan left", "Tilt up", "Go to", "Save current position"):
        assert page.get_by_role("button", name=name, exact=True).is_disabled(), name
    assert page.get_by_label("Jog speed").is_disabled()
    # the keyboard does not move the mount either, and says why
    before = _servo(server)["pan_deg"]
    page.locator("body").press("ArrowRight")
    page.get_by_role("status").filter(has_text="needs the operator role").first.wait_for()
    assert abs(_servo(server)["pan_deg"] - before) < 5 or _servo(server)["mode"] == "auto"
    # no Users page in the navigation; Settings readable, not editable
    assert page.get_by_role("link", name="Users").count() == 0
    page.get_by_role("link", name="Settings").click()
    assert "needs the admin role" in page.get_by_test_id("settings-reason").inner_text()
    assert page.get_by_role("button", name="Save changes").is_disabled()
    assert page.locator("input[name='detector.epsilon']").get_attribute("readonly") is not None


def test_jog_by_keyboard_and_pad_moves_the_mount(server: Server, page_of: Any) -> None:
    page = page_of()
    login(page, *user(server, "otto", "operator"))
    page.get_by_test_id("sb-telemetry").filter(has_text="Telemetry: connected").wait_for()
    _goto(server, 0.0, 0.0)

    def pan() -> float:
        s = debug(page).get("servo") or {}
        return float(s.get("pan_deg") or 0.0)
    wait_for(lambda: abs(pan()) < 0.5, 10, what="telemetry pan near 0")
    page.get_by_label("Jog speed").fill("20")
    page.locator("main").focus()
    page.keyboard.down("ArrowRight")
    page.wait_for_timeout(1500)
    page.keyboard.up("ArrowRight")
    moved = wait_for(lambda: pan() if pan() > 10 else 0, 5, what="the mount panning right")
    assert moved < 60
    page.wait_for_timeout(800)
    settled = pan()
    page.wait_for_timeout(700)
    assert abs(pan() - settled) < 1.0, "the mount stops when the key is released"
    assert _servo(server)["mode"] == "manual"
    # the on-screen pad: hold "Pan left"
    box = page.get_by_role("button", name="Pan left").bounding_box()
    page.mouse.move(box["x"] + box["width"] / 2, box["y"] + box["height"] / 2)
    page.mouse.down()
    page.wait_for_timeout(1500)
    page.mouse.up()
    wait_for(lambda: pan() < settled - 10, 5, what="the mount panning left")
    # mode buttons reflect and set the mode
    page.get_by_role("button", name="Auto", exact=True).click()
    wait_for(lambda: page.get_by_role("button", name="Auto", exact=True).get_attribute("aria-pressed") == "true", 5,
             what="Auto pressed")
    assert _servo(server)["mode"] == "auto"


# Jog requests reach the server 400 ms late, as on a slow link: the stop sent when the pad is released is
# still on its way when the operator clicks a mode.
SLOW_JOG = """const realFetch = window.fetch.bind(window);
window.fetch = async (input, init) => {
  if (String(input).endsWith('/api/servo/jog')) await new Promise((r) => setTimeout(r, 400));
  return realFetch(input, init);
};"""


def test_a_mode_clicked_while_a_jog_stop_is_in_flight_is_not_undone(server: Server, page_of: Any) -> None:
    page = page_of(init_script=SLOW_JOG)
    login(page, *user(server, "olga", "operator"))
    page.get_by_test_id("sb-telemetry").filter(has_text="Telemetry: connected").wait_for()
    _goto(server, 0.0, 0.0)
    page.get_by_label("Jog speed").fill("20")
    box = page.get_by_role("button", name="Pan left").bounding_box()
    page.mouse.move(box["x"] + box["width"] / 2, box["y"] + box["height"] / 2)
    page.mouse.down()
    page.wait_for_timeout(1200)
    page.mouse.up()
    page.get_by_role("button", name="Auto", exact=True).click()  # the stop has not reached the server yet
    wait_for(lambda: page.get_by_role("button", name="Auto", exact=True).get_attribute("aria-pressed") == "true", 10,
             what="Auto pressed")
    page.wait_for_timeout(1000)  # every jog request has been answered by now
    assert _servo(server)["mode"] == "auto"
    assert page.get_by_role("button", name="Auto", exact=True).get_attribute("aria-pressed") == "true"


# A gamepad the test holds: navigator.getGamepads() returns it while window.__pad.connected (the Gamepad API
# of a headless browser has no device to report).
FAKE_PAD = """window.__pad = {id: 'Test pad (STANDARD GAMEPAD)', index: 0, connected: false, mapping: 'standard',
  timestamp: 0, axes: [0, 0, 0, 0],
  buttons: Array.from({length: 17}, () => ({pressed: false, touched: false, value: 0}))};
navigator.getGamepads = () => [window.__pad.connected ? window.__pad : null, null, null, null];"""


def test_gamepad_stick_and_dpad_jog_the_mount(server: Server, page_of: Any) -> None:
    page = page_of(init_script=FAKE_PAD)
    login(page, *user(server, "gail", "operator"))
    page.get_by_test_id("sb-telemetry").filter(has_text="Telemetry: connected").wait_for()
    _goto(server, 0.0, 0.0)

    def pan() -> float:
        return float((debug(page).get("servo") or {}).get("pan_deg") or 0.0)
    wait_for(lambda: abs(pan()) < 0.5, 10, what="telemetry pan near 0")
    page.get_by_label("Jog speed").fill("20")
    page.evaluate("window.__pad.connected = true; window.dispatchEvent(new Event('gamepadconnected'))")
    page.get_by_test_id("gamepad").filter(has_text="Test pad").wait_for()
    page.evaluate("window.__pad.axes[0] = 0.9")  # left stick to the right
    page.wait_for_timeout(1500)
    page.evaluate("window.__pad.axes[0] = 0.1")  # back inside the dead zone
    moved = wait_for(lambda: pan() if pan() > 10 else 0, 5, what="the mount panning right")

    def still() -> bool:  # no more than 1 deg in 0.7 s: stopped (a loaded machine may see the release late)
        before = pan()
        page.wait_for_timeout(700)
        return abs(pan() - before) < 1.0
    wait_for(still, 8, what="the mount stopping once the stick is released")
    settled = pan()
    page.wait_for_timeout(700)
    assert abs(pan() - settled) < 1.0, "the mount stays stopped"
    assert moved < 90 and _servo(server)["mode"] == "manual"
    page.evaluate("window.__pad.buttons[14].pressed = true")  # d-pad left
    page.wait_for_timeout(1500)
    page.evaluate("window.__pad.buttons[14].pressed = false")
    wait_for(lambda: pan() < settled - 10, 5, what="the mount panning left")
    page.evaluate("window.__pad.connected = false; window.dispatchEvent(new Event('gamepaddisconnected'))")
    page.get_by_test_id("gamepad").filter(has_text="none connected").wait_for()


def test_tracks_page_lists_tracks_and_plots_one(server: Server, page_of: Any) -> None:
    page = page_of()
    login(page, *admin(server))
    with server.as_admin() as c:
        wait_for(lambda: c.get("/api/tracks").json(), 60, every=1.0, what="a recorded track")
    page.goto("/#/tracks")
    page.get_by_role("button", name="Show tracks").click()
    page.get_by_role("status").filter(has_text=re.compile(r"\d+ tracks?")).wait_for()
    page.get_by_role("button", name=re.compile(r"Show trajectory of track \d+")).first.click()
    detail = page.get_by_test_id("track-detail")
    wait_for(lambda: "points from" in detail.inner_text(), 10, what="the trajectory")
    assert page.locator(".tracks-layout canvas").count() >= 2
    page.get_by_label("Time range").select_option("custom")
    assert page.get_by_label("From").is_enabled()


def test_settings_page_edits_the_tracker_config(server: Server, page_of: Any) -> None:
    page = page_of()
    login(page, *admin(server))
    page.goto("/#/settings")
    eps = page.locator("input[name='detector.epsilon']")
    wait_for(lambda: eps.input_value() != "", 10, what="the settings")
    new = 13 if eps.input_value() != "13" else 14
    eps.fill(str(new))
    page.get_by_role("button", name="Save changes").click()
    page.get_by_role("status").filter(has_text="Saved 1 setting").wait_for()
    with server.as_admin() as c:
        assert c.get("/api/tracker/config").json()["detector"]["epsilon"] == new
    eps.fill("999")
    page.get_by_role("button", name="Save changes").click()
    page.get_by_role("status").filter(has_text="Not saved").wait_for()


def test_users_page_creates_edits_deletes_and_shows_the_audit(server: Server, page_of: Any) -> None:
    page = page_of()
    login(page, *admin(server))
    page.goto("/#/users")
    page.get_by_label("New username").fill("walter")
    page.get_by_label("Password", exact=True).fill("a long enough password")
    page.get_by_label("Role", exact=True).select_option("operator")
    page.get_by_role("button", name="Create user").click()
    page.get_by_role("status").filter(has_text="Created walter (operator)").wait_for()
    row = page.locator("tr[data-user='walter']")
    row.get_by_label("Role of walter").select_option("viewer")
    row.get_by_role("button", name="Save walter").click()
    page.get_by_role("status").filter(has_text="Saved walter").wait_for()
    with server.as_admin() as c:
        assert {u["username"]: u["role"] for u in c.get("/api/users").json()}["walter"] == "viewer"
    pw = row.get_by_label("New password for walter")
    assert pw.evaluate("el => el.form !== null")  # in the row's own form (password managers need one)
    pw.fill("another long password")
    pw.press("Enter")  # Enter in the row's fields saves the row
    page.get_by_role("status").filter(has_text="Saved walter (its sessions were ended)").wait_for()
    page.get_by_role("button", name="Show audit log").click()
    page.locator("td code", has_text="user.update").first.wait_for()
    page.once("dialog", lambda d: d.accept())
    page.locator("tr[data-user='walter']").get_by_role("button", name="Delete walter").click()
    page.get_by_role("status").filter(has_text="Deleted walter").wait_for()
    page.locator("tr[data-user='walter']").wait_for(state="detached")
    assert page.get_by_role("button", name="Delete admin").is_disabled()


def test_calibration_page_uploads_and_follows_progress(server: Server, page_of: Any, tmp_path: Any) -> None:
    import cv2

    page = page_of()
    login(page, *admin(server))
    page.goto("/#/calibration")
    page.get_by_label("Board (inner corners)").wait_for()
    files = []
    for side in ("left", "right"):
        for i in range(3):
            img = np.full((120, 160), 40 + 60 * i, np.uint8)
            path = tmp_path / f"{side}{i}.png"
            cv2.imwrite(str(path), img)
            files.append(path)
    page.get_by_label("Left images").set_input_files([str(p) for p in files[:3]])
    page.get_by_label("Right images").set_input_files([str(p) for p in files[3:]])
    page.get_by_label("Board (inner corners)").fill("9x6")
    page.get_by_label("Square size (m)").fill("0.025")
    page.get_by_role("button", name="Upload and calibrate").click()
    status = page.get_by_role("status").filter(has_text=re.compile("Uploaded|Upload refused"))
    status.wait_for()
    if "Uploaded" in status.inner_text():
        # blank pictures have no chessboard: the run fails, and the page hears it on /ws/events
        wait_for(lambda: "failed" in page.get_by_test_id("cal-progress").inner_text(), 60, what="the failure event")
        page.locator("table.data td", has_text="failed").first.wait_for()


def test_live_page_screenshots(server: Server, page_of: Any) -> None:
    for width, height, name in ((1280, 720, "live-1280x720"), (800, 1100, "live-800x1100")):
        page = page_of(width, height)
        login(page, *admin(server))
        page.get_by_test_id("sb-telemetry").filter(has_text="Telemetry: connected").wait_for()
        page.wait_for_timeout(4000)
        path = screenshot(page, name)
        assert path.stat().st_size > 10000
        # nothing wider than the window
        assert page.evaluate("() => document.documentElement.scrollWidth") <= width
        for other in ("tracks", "settings", "users", "calibration"):
            page.goto(f"/#/{other}")
            page.wait_for_timeout(1200)
            screenshot(page, f"{other}-{width}x{height}")
