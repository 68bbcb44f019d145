"""The engine's view of one processed frame: targets from the frame's telemetry (every detection's track
id, x, y, z and r in metres, metric size from its disparity) and the primary target's closing speed, in
m/s, from the predictor's state (position p, velocity v with covariance P_v, world frame; o the origin
of r):

    −dr/dt = −u·v,  u = (p − o) / |p − o|,  σ = √(uᵀ P_v u).

The closing speed is unknown (None) unless the predictor was updated by this frame's detection (a
coasting predictor extrapolates a velocity no detection supports), the update was consistent with the
state (normalised innovation squared under NIS_GATE, the 99.9 % point of χ² with 3 degrees of freedom: a
wrong disparity that puts the target metres nearer for a frame is not a target running at 10 m/s) and
σ ≤ CLOSING_SIGMA_MAX_MPS (a track just started has σ of metres per second). The primary target's
position is the predictor's filtered one when it was updated by this frame (it smooths the single-frame
disparity outliers of a raw fix); the other targets' are their raw fixes."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from server.alarms.conditions import Snapshot, Target
from tracker.closedloop import LoopStep
from tracker.predict import PredictedState, TrackStatus

CLOSING_SIGMA_MAX_MPS = 0.5
NIS_GATE = 16.27  # χ²(3) at 0.999


def _tracking(step: LoopStep | None) -> PredictedState | None:
    est = None if step is None else step.estimate
    return None if est is None or est.status != TrackStatus.TRACKING else est.state


def closing_speed(step: LoopStep | None, origin: Sequence[float]) -> float | None:
    """−dr/dt (m/s, positive when approaching) of the predictor's state updated by this frame, None when
    there is none or its 1-σ is over CLOSING_SIGMA_MAX_MPS."""
    st = _tracking(step)
    est = None if step is None else step.estimate
    if st is None or (est is not None and est.nis is not None and est.nis > NIS_GATE):
        return None
    rel = np.asarray(st.position, float) - np.asarray(origin, float)
    r = float(np.linalg.norm(rel))
    if r < 1e-6:
        return None
    u = rel / r
    if st.velocity_covariance is not None and float(u @ st.velocity_covariance @ u) > CLOSING_SIGMA_MAX_MPS**2:
        return None
    return -float(u @ np.asarray(st.velocity, float))


def targets_of(telemetry: Mapping[str, Any], step: LoopStep | None = None,
               origin: Sequence[float] = (0.0, 0.0, 0.0)) -> tuple[Target, ...]:
    """The frame's tracked detections; the primary's position from the predictor when it tracks."""
    st = _tracking(step)
    primary = telemetry.get("track_id")
    out = []
    for d in telemetry.get("detections", ()):
        if d.get("track_id") is None:
            continue
        w, h = d.get("size_m") or (0.0, 0.0)
        x, y, z, r = float(d["x"]), float(d["y"]), float(d["z"]), float(d["r"])
        if st is not None and d["track_id"] == primary:
            x, y, z = (float(v) for v in st.position)
            r = float(np.linalg.norm(np.asarray(st.position, float) - np.asarray(origin, float)))
        out.append(Target(int(d["track_id"]), x, y, z, r, float(w), float(h)))
    return tuple(out)


def snapshot_from(t: float, frame: int, telemetry: Mapping[str, Any], step: LoopStep | None,
                  origin: Sequence[float], faults: Mapping[str, str] | None = None,
                  servo_mode: str | None = None) -> Snapshot:
    """The snapshot of a processed frame at time t (s)."""
    return Snapshot(t, frame, targets_of(telemetry, step, origin), telemetry.get("track_id"),
                    closing_speed(step, origin), dict(faults or {}), servo_mode)
