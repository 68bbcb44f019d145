"""A replay: the one runtime (tmeye.runtime) run over recorded frames (source "recording"), as fast as it can,
each frame's result compared with the live telemetry recorded for the same frame (`Agreement`). Used by
`tmeye track --source recording` and the server's replay jobs (server/services/replays.py); call from a
worker thread, never an event loop."""

from __future__ import annotations

import math
import threading
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from tmeye.runtime import FrameEvent, Runtime, RuntimeConfig, TrackerTuning
from tmeye.runtime.recording import CLOCK_HZ, RecordingSource
from tracker.geometry import StereoRig


@dataclass
class Agreement:
    """Live against replayed detections, frame by frame: the same number of objects, the same answer to
    "is the primary target detected", and |r_live - r_replay| (m) where both detected it."""

    frames: int = 0
    same_count: int = 0
    same_detected: int = 0
    range_diffs: list[float] = field(default_factory=list)

    def add(self, live: dict[str, Any], replay: dict[str, Any]) -> None:
        self.frames += 1
        self.same_count += int(live.get("objects", 0) == replay.get("objects", 0))
        self.same_detected += int(bool(live.get("detected")) == bool(replay.get("detected")))
        if live.get("detected") and replay.get("detected"):
            self.range_diffs.append(abs(float(live["r"]) - float(replay["r"])))

    def summary(self) -> dict[str, Any]:
        n, d = self.frames, np.asarray(self.range_diffs)
        return {"frames": n, "same_count": round(self.same_count / n, 4) if n else None,
                "same_detected": round(self.same_detected / n, 4) if n else None, "both_detected": int(d.size),
                "range_diff_median_m": round(float(np.median(d)), 4) if d.size else None,
                "range_diff_p95_m": round(float(np.percentile(d, 95)), 4) if d.size else None}


def replay_config(data_dir: str, start: float, end: float, scenario: str, seed: int = 0,
                  targets: str = "auto") -> RuntimeConfig:
    """The runtime of a replay: the recordings of start..end, unpaced, no servo; `scenario` "" for a
    recording of real cameras (background: the first recorded pair); `targets` as RuntimeConfig's."""
    if not (math.isfinite(start) and math.isfinite(end)):
        raise ValueError("start and end must be finite Unix times")
    return RuntimeConfig(source="recording", inputs=(data_dir,), start=start, end=end, scenario=scenario, seed=seed,
                         servo=None, realtime=False, loop_source=False, targets=targets)


def run_replay(cfg: RuntimeConfig, tuning: TrackerTuning | None, rig: StereoRig | None,
               on_frame: Callable[[FrameEvent, float], None], stop: threading.Event | None = None) -> Agreement:
    """Compose (ComposeError on a bad range, rig or scene) and run; `on_frame(event, progress 0..1)` per frame
    in order. RuntimeError when the runtime failed or a frame was lost."""
    rt = Runtime(cfg, tuning)
    sub = rt.hub.subscribe(maxsize=1_000_000, name="replay")  # nothing may be dropped (telemetry only is read)
    rt.start(rig)
    assert rt.comp is not None and isinstance(rt.comp.source, RecordingSource)
    src = rt.comp.source
    agree = Agreement()
    try:
        while not (stop is not None and stop.is_set()):
            ev = sub.get(timeout=0.5)
            if ev is None:
                if sub.closed:
                    break
                continue
            live = src.telemetry.get(round(ev.captured_at * CLOCK_HZ))
            if live is not None:
                agree.add(live.data, ev.telemetry)
            on_frame(ev, min(src.read_pairs / max(src.total, 1), 1.0))
    finally:
        rt.stop()
    if stop is not None and stop.is_set():
        raise RuntimeError("the replay was stopped")
    if rt.error:
        raise RuntimeError(rt.error)
    if sub.dropped or rt.frame_errors:
        raise RuntimeError(f"{sub.dropped + rt.frame_errors} frames of the replay were lost")
    return agree
