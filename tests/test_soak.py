"""`tmeye soak` (short): the load runs and the report holds its figures. The long run and its limits
(RSS growth, stalls, loop lag) are a command to run, not a timed test."""

from __future__ import annotations

import json
import subprocess
import sys

from server_helpers import ROOT


def test_soak_reports_its_figures() -> None:
    p = subprocess.run([sys.executable, "-m", "tmeye", "soak", "--minutes", "0.25", "--viewers", "2",
                        "--clients", "3", "--json"], cwd=ROOT, capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stderr[-3000:]
    r = json.loads(p.stdout)
    assert r["frames"] > 0 and r["frame_errors"] == 0 and 0 <= r["skipped_pct"] <= 100
    assert r["ws_clients"] == 3 and r["ws_frames_strictly_increasing"] and r["ws_messages_min"] > 0
    assert r["webrtc_viewers"] == 2 and r["webrtc_frames_per_camera_min"] > 0
    assert r["longest_frame_stall_ms"] > 0 and r["event_loop_lag_p99_ms"] is not None
    assert len(r["samples"]) >= 3 and all(s["rss_mib"] > 0 and s["fds"] > 0 and s["threads"] > 0
                                          for s in r["samples"])
    assert r["fds_start_end_max"][2] >= r["fds_start_end_max"][0]


def test_soak_rejects_bad_arguments() -> None:
    p = subprocess.run([sys.executable, "-m", "tmeye", "soak", "--minutes", "0"], cwd=ROOT, capture_output=True,
                       text=True, timeout=60)
    assert p.returncode == 2 and "--minutes must be" in p.stderr and len(p.stderr.strip().splitlines()) == 1
