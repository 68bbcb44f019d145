"""The Live page reconnects by itself after a server restart: the status bar says the server is gone and
the telemetry is reconnecting, then (same data directory and port, so the session cookie stays valid)
telemetry flows again and the video comes back, without logging in again."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import pytest
from server_helpers import start_server
from web_helpers import admin, browser, debug, free_port, has_route, login, new_page, skip_reason, wait_for

pytestmark = pytest.mark.skipif(skip_reason() is not None, reason=skip_reason() or "")


def _frame(page: Any) -> int:
    m = re.match(r"(\d+)", page.get_by_test_id("ro-frame").inner_text())
    return int(m.group(1)) if m else -1


def test_live_page_reconnects_after_a_server_restart(tmp_path: Path) -> None:
    data, port = tmp_path / "data", free_port()
    server = start_server(data, "--port", str(port))
    try:
        video = has_route(server, "POST", "/api/webrtc/offer")
        with browser() as b:
            page = new_page(b, server)
            login(page, *admin(server))
            page.get_by_test_id("sb-telemetry").filter(has_text="Telemetry: connected").wait_for()
            wait_for(lambda: _frame(page) > 0, 15, what="telemetry on the page")
            if video:
                wait_for(lambda: debug(page).get("source") == "webrtc", 40, what="WebRTC video")
            opens = debug(page)["socketOpens"]
            last = _frame(page)

            server.stop()
            page.get_by_test_id("sb-server").filter(has_text="unreachable").wait_for(timeout=15000)
            page.get_by_test_id("sb-telemetry").filter(has_text="reconnecting").wait_for(timeout=15000)

            server = start_server(data, "--port", str(port))
            page.get_by_test_id("sb-telemetry").filter(has_text="Telemetry: connected").wait_for(timeout=30000)
            page.get_by_test_id("sb-server").filter(has_text="Server: connected").wait_for(timeout=15000)
            assert debug(page)["socketOpens"] > opens
            # a restarted server counts frames from 0 again: wait for the page to show the new ones advancing
            first = wait_for(lambda: (f := _frame(page)) > 0 and f != last and f, 15,
                             what="telemetry after the restart")
            wait_for(lambda: _frame(page) > first, 10, what="frames advancing after the restart")
            assert page.get_by_label("Username").count() == 0, "the session survived the restart"
            if video:
                wait_for(lambda: debug(page).get("source") == "webrtc", 40, what="WebRTC video after the restart")
                n = debug(page)["frames"]["left"]
                wait_for(lambda: debug(page)["frames"]["left"] > n + 20, 20, what="video frames after the restart")
    finally:
        server.stop()
