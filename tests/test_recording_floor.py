"""The free-disk floor on a real server: with a floor above the disk's free space, nothing is recorded,
/api/status carries `recording.fault` and a fault of kind recording, and tracking goes on."""

from __future__ import annotations

import time
from pathlib import Path

from server_helpers import start_server


def test_free_disk_floor_stops_recording_not_tracking(tmp_path: Path) -> None:
    s = start_server(tmp_path / "data", env={"TMEYE_MIN_FREE_MB": "1e12"})  # 1 EB: more than any disk has free
    try:
        with s.as_admin() as c:
            st = c.get("/api/status").json()
            time.sleep(3.0)
            st2 = c.get("/api/status").json()
            rec = st2["recording"]
            assert rec["state"] == "fault" and "below the floor" in rec["fault"], rec
            assert any(f["kind"] == "recording" and f["message"] == rec["fault"] for f in st2["faults"])
            assert st2["frame"] > st["frame"]  # the tracker goes on
            assert c.get("/api/recordings").json() == []
            assert not list((s.data_dir / "recordings").rglob("*.mp4"))
    finally:
        s.stop()
