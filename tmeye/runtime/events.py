"""What the runtime (tmeye.runtime.worker) publishes for each frame: the mount's state and the frame's
event with its telemetry."""

from __future__ import annotations

import json
from dataclasses import dataclass
from functools import cached_property
from typing import Any

from tracker.closedloop import LoopStep
from tracker.frames import StereoFrame
from tracker.results import FrameResult


@dataclass(frozen=True)
class ServoState:
    """The mount at a frame: mode, angles (deg) at capture, the operator's goal (deg), the fault and the
    command sent this frame ({pan_deg, tilt_deg, reason} or None)."""

    mode: str
    pan_deg: float
    tilt_deg: float
    goal: tuple[float, float] | None
    fault: str | None
    command: dict[str, Any] | None = None

    def as_dict(self) -> dict[str, Any]:
        return {"mode": self.mode, "pan_deg": round(self.pan_deg, 4), "tilt_deg": round(self.tilt_deg, 4),
                "goal": None if self.goal is None else {"pan_deg": self.goal[0], "tilt_deg": self.goal[1]},
                "command": self.command, "fault": self.fault}


@dataclass(frozen=True)
class FrameEvent:
    """What the worker publishes per frame. frame_no: strictly increasing over the runtime's life (gaps
    are skipped frames); captured_at / done_at: Unix time (s) of the capture and of the end of the
    processing; telemetry: the JSON message of the frame."""

    frame_no: int
    frame: StereoFrame
    result: FrameResult
    step: LoopStep | None
    servo: ServoState | None
    captured_at: float
    done_at: float
    telemetry: dict[str, Any]
    generation: int = 0  # incremented when a new pipeline (rig) is swapped in: track ids restart

    @cached_property
    def telemetry_json(self) -> str:
        """The telemetry as JSON text, made once however many clients send it."""
        return json.dumps(self.telemetry, separators=(",", ":"))
