"""The engine's view of one processed frame: targets from the frame's telemetry (every detection's track
id, x, y, z and r in metres, metric size from its disparity) and the primary target's closing speed
−dr/dt = −(p − o)·v / |p − o| from the predictor's state (position p, velocity v, world frame; o the
origin of r), in m/s."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from server.alarms.conditions import Snapshot, Target
from tracker.closedloop import LoopStep


def closing_speed(step: LoopStep | None, origin: Sequence[float]) -> float | None:
    """−dr/dt (m/s, positive when approaching) of the predictor's current state, None without one."""
    est = None if step is None else step.estimate
    if est is None or est.state is None:
        return None
    rel = np.asarray(est.state.position, float) - np.asarray(origin, float)
    r = float(np.linalg.norm(rel))
    if r < 1e-6:
        return None
    return -float(rel @ np.asarray(est.state.velocity, float)) / r


def targets_of(telemetry: Mapping[str, Any]) -> tuple[Target, ...]:
    out = []
    for d in telemetry.get("detections", ()):
        if d.get("track_id") is None:
            continue
        w, h = d.get("size_m") or (0.0, 0.0)
        out.append(Target(int(d["track_id"]), float(d["x"]), float(d["y"]), float(d["z"]), float(d["r"]),
                          float(w), float(h)))
    return tuple(out)


def snapshot_from(t: float, frame: int, telemetry: Mapping[str, Any], step: LoopStep | None,
                  origin: Sequence[float], faults: Mapping[str, str] | None = None) -> Snapshot:
    """The snapshot of a processed frame at time t (s)."""
    return Snapshot(t, frame, targets_of(telemetry), telemetry.get("track_id"), closing_speed(step, origin),
                    dict(faults or {}))
