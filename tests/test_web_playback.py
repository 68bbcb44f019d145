"""The Playback page in chromium on a real recording server (--stamp-frames, 3 s segments): it loads a
range, shows both cameras' frame with its telemetry, steps frames with `.` and `,` (each step is the next
recorded frame, its stamp the frame index shown), plays through hls.js at another rate, seeks, and exports
a clip that decodes."""

from __future__ import annotations

import io
import time
import zipfile
from collections.abc import Iterator
from typing import Any

import httpx
import pytest
from server_helpers import Server, start_server
from web_helpers import login, new_page, require_browser, screenshot, skip_reason, user, wait_for

from tmeye.recordcheck import decode_stamps

pytestmark = pytest.mark.skipif(skip_reason() is not None, reason=skip_reason() or "")
READ_STAMP = """(sel) => { const img = document.querySelector(sel); if (!img || !img.naturalWidth) return null;
  const c = document.createElement('canvas'); c.width = img.naturalWidth; c.height = img.naturalHeight;
  const g = c.getContext('2d'); g.drawImage(img, 0, 0); let v = 0;
  for (let k = 0; k < 16; k++) { const d = g.getImageData(k * 8 + 3, 3, 2, 2).data;
    v = v * 2 + ((d[0] + d[4] + d[8] + d[12]) / 4 > 127 ? 1 : 0); }
  return v; }"""


@pytest.fixture(scope="module")
def server(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Server]:
    require_browser()
    s = start_server(tmp_path_factory.mktemp("webplay") / "data", "--stamp-frames", env={"TMEYE_SEGMENT_S": "3"})
    try:
        with s.as_admin() as c:
            wait_for(lambda: sum(x["status"] == "closed" for x in c.get("/api/recordings").json()) >= 8, 60,
                     what="8 closed segments")
        yield s
    finally:
        s.stop()


def shown(page: Any) -> tuple[int, int | None, int | None]:
    """(frame index shown, left still's stamp, right still's stamp)."""
    text = page.get_by_test_id("frame-index").text_content()
    return (int(text) if text and text.isdigit() else -1, page.evaluate(READ_STAMP, "[data-testid=still-left]"),
            page.evaluate(READ_STAMP, "[data-testid=still-right]"))


def recorded_frames(server: Server) -> list[int]:
    with server.as_admin() as c:
        return [m["frame"] for m in c.get("/api/telemetry", params={"start": 0, "end": time.time() + 60,
                                                                     "limit": 200000}).json()]


def test_playback_steps_plays_seeks_and_exports(server: Server, chromium: Any) -> None:
    page = new_page(chromium, server)
    login(page, *user(server, "petra", "operator"))
    page.goto("/#/playback")
    page.get_by_role("heading", name="Playback").wait_for()
    wait_for(lambda: shown(page)[0] >= 0 and shown(page)[1] is not None, 30, what="a frame shown")
    frames = recorded_frames(server)
    f0, sl, sr = shown(page)
    assert sl == sr == f0 % 65536 and f0 in frames  # both cameras show exactly the frame named
    assert "Frame" in (page.get_by_test_id("frame-telemetry").text_content() or "")
    assert page.locator(".track-plots canvas").count() >= 2  # plan and side views of the range's tracks
    page.locator("body").click(position={"x": 5, "y": 5})
    steps = []
    for _ in range(6):
        before = shown(page)[0]
        page.keyboard.press(".")
        wait_for(lambda before=before: shown(page)[0] != before, 10, what="a step forward")
        steps.append(shown(page))
    seq = [f0] + [s[0] for s in steps]
    for a, b in zip(seq, seq[1:], strict=False):
        assert frames[frames.index(a) + 1] == b  # the next recorded frame (+1 unless the tracker skipped one)
    assert all(s[1] == s[2] == s[0] % 65536 for s in steps)
    print("frame index changes per step:", [b - a for a, b in zip(seq, seq[1:], strict=False)])
    page.keyboard.press(",")
    wait_for(lambda: shown(page)[0] == seq[-2], 10, what="a step back")
    screenshot(page, "playback-step")

    page.get_by_label("Rate").select_option("2")
    page.get_by_role("button", name="Play").click()
    t_start = page.evaluate("() => document.querySelector('video').currentTime")
    time.sleep(3.0)
    t_left, t_right, rate = page.evaluate("() => { const v = [...document.querySelectorAll('video')];"
                                          " return [v[0].currentTime, v[1].currentTime, v[0].playbackRate]; }")
    assert rate == 2 and t_left - t_start > 1.5, (t_start, t_left)  # it plays (at about 2x, on a busy machine)
    assert abs(t_right - t_left) < 0.5
    page.get_by_role("button", name="Pause").click()
    wait_for(lambda: shown(page)[0] >= 0, 10, what="the frame at the pause")
    f_pause = shown(page)[0]
    assert f_pause > seq[-1] and shown(page)[1] == f_pause % 65536

    page.evaluate("() => { const s = document.querySelector('input.scrub'); s.value = '0.02';"
                  " s.dispatchEvent(new Event('change')); }")
    wait_for(lambda: 0 <= shown(page)[0] < f_pause, 10, what="a seek back")
    assert shown(page)[1] == shown(page)[0] % 65536

    page.get_by_role("button", name="Export the range").click()
    link = page.get_by_test_id("export-link")
    link.wait_for(timeout=60000)
    href = link.get_attribute("href")
    cookies = {c["name"]: c["value"] for c in page.context.cookies()}
    z = zipfile.ZipFile(io.BytesIO(httpx.get(server.url + href, cookies=cookies, timeout=60).content))
    stamps, err = decode_stamps(z.read("left.mp4"))
    frames = recorded_frames(server)  # the range ends now: it holds frames recorded since the first look
    assert err is None and len(stamps) > 30 and {s for _, s in stamps} <= {f % 65536 for f in frames}
    screenshot(page, "playback-export")
    page.context.close()


def test_a_link_with_a_time_opens_playback_at_that_frame(server: Server, chromium: Any) -> None:
    """An alarm's playback link (#/playback?t=T) shows the frame captured at or before T, T inside the range."""
    with server.as_admin() as c:
        tel = c.get("/api/telemetry", params={"start": 0, "end": time.time() + 60, "limit": 200000}).json()
    want = tel[len(tel) * 3 // 8]  # a frame of a closed segment
    page = new_page(chromium, server)
    login(page, *user(server, "paula", "viewer"))
    page.goto(f"/#/playback?t={want['captured_at'] + 0.001:.3f}")
    page.get_by_role("heading", name="Playback").wait_for()
    index = page.get_by_test_id("frame-index")
    wait_for(lambda: (index.text_content() or "").isdigit(), 30, what="a frame shown")
    assert int(index.text_content() or "-1") == want["frame"]
    page.context.close()
