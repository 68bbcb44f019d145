"""`tmeye track --servo`: the closed loop from the command line, and its one-line errors."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest


def tmeye(*args: str, timeout: float = 240) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "tmeye", *args], capture_output=True, text=True,
                          timeout=timeout)


def test_track_servo_sim_prints_servo_telemetry() -> None:
    out = tmeye("track", "--servo", "sim", "--scenario", "manoeuvre", "--frames", "40", "--json", "--fast")
    assert out.returncode == 0, out.stderr
    lines = [json.loads(x) for x in out.stdout.splitlines()]
    assert [x["frame"] for x in lines] == list(range(40))
    for x in lines:
        assert set(x["servo"]) >= {"pan_deg", "tilt_deg", "command", "fault", "mode"}
        assert x["servo"]["fault"] is None and x["latency_ms"] > 0.0
    sent = [x["servo"]["command"] for x in lines if x["servo"]["command"] is not None]
    assert sent and all(c["reason"] in ("track", "centroid") for c in sent)
    assert lines[-1]["servo"]["pan_deg"] > 10.0  # the mount turned right after the target
    assert all(x["detected"] for x in lines[2:])


def _one_line_error(out: subprocess.CompletedProcess[str], *needles: str) -> None:
    assert out.returncode == 2, out.stderr
    assert len(out.stderr.strip().splitlines()) == 1 and "Traceback" not in out.stderr
    for n in needles:
        assert n in out.stderr


@pytest.mark.parametrize(
    ("url", "needles"),
    [
        ("nope:/dev/x", ("unknown scheme 'nope'",)),
        ("maestro:", ("no serial port given",)),
        ("maestro:/dev/ttyTMEYE_MISSING", ("/dev/ttyTMEYE_MISSING",)),
        ("ascii:/dev/ttyTMEYE_MISSING", ("/dev/ttyTMEYE_MISSING",)),
        ("sim?speed=3", ("unknown option",)),
    ],
)
def test_bad_servo_url_or_missing_port_is_one_line_exit_2(url: str, needles: tuple[str, ...]) -> None:
    _one_line_error(tmeye("track", "--servo", url, "--frames", "3", "--fast"), *needles)


def test_silent_device_is_one_line_exit_2() -> None:
    master, slave = os.openpty()  # a port that opens but never answers
    try:
        path = os.ttyname(slave)
        _one_line_error(tmeye("track", "--servo", f"ascii:{path}?boot=0.5&timeout=0.1", "--frames", "3"),
                        "no hello", path)
    finally:
        os.close(master)
        os.close(slave)


def test_sim_servo_needs_the_simulated_rig(tmp_path: object) -> None:
    from pathlib import Path

    from tracker.geometry import save_rig
    from tracker.sim.rig import default_rig

    rig = Path(str(tmp_path)) / "rig.json"
    save_rig(default_rig(), rig)
    left, right = Path(str(tmp_path)) / "l.mp4", Path(str(tmp_path)) / "r.mp4"
    out = tmeye("track", "--source", "files", str(left), str(right), "--rig", str(rig), "--servo", "sim")
    assert out.returncode == 2 and len(out.stderr.strip().splitlines()) == 1
