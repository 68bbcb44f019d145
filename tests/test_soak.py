"""The CI version of the soak run: `tmeye soak --minutes 2` on the default simulated scene with 4 WebRTC
viewers, 10 WebSocket clients and a REST poller. Asserts behaviour (every client served throughout, no
server error, the runtime running, descriptors and threads sampled); the figures are in its output and the
60-minute run is reported in the closing notes."""

from __future__ import annotations

import json
import subprocess
import sys

from server_helpers import ROOT


def test_two_minute_soak_serves_every_client_throughout() -> None:
    out = subprocess.run([sys.executable, "-m", "tmeye", "soak", "--minutes", "2", "--sample-s", "10", "--json"],
                         cwd=ROOT, capture_output=True, text=True, timeout=400)
    assert out.returncode == 0, out.stderr[-2000:]
    report = json.loads(out.stdout)
    s = report["summary"]
    print(json.dumps(s))
    assert s["states"] == ["running"] and s["rest_errors"] == [] and s["rest_requests"] > 100
    assert s["status_errors"] == 0
    assert len(report["samples"]) == 12
    rec = s["recording"]  # recording on (the default): segments closed, no fault
    assert rec is not None and rec["segments"] >= 4 and rec["fault"] is None and rec["errors"] == 0
    assert len(s["ws_messages_per_s"]) == 10 and min(s["ws_messages_per_s"]) > 5  # each client kept receiving
    assert len(s["webrtc_frames_per_s"]) == 4 and min(s["webrtc_frames_per_s"]) > 5
    for row in report["samples"]:
        assert row["rss_mb"] > 0 and row["fds"] > 0 and row["threads"] > 0 and row["frame_gap_max_ms"] is not None
