"""Device faults from the health figures of the moment (pure): which built-in fault sources are active,
each with a one-line message. Sources: camera (stalled or gone), frame_rate (under a floor), servo,
recording, disk (free space under a floor), database (errors)."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class FaultThresholds:
    """stall_s: a camera with no new frame for longer is stalled (s); fps_floor: frames per second below
    which frame_rate faults, measured over fps_window_s (s); disk_min_bytes: free space floor; first_frame_s:
    how long after the start the first frame may take (s)."""

    stall_s: float = 0.5
    first_frame_s: float = 5.0
    fps_floor: float = 10.0
    fps_window_s: float = 3.0
    disk_min_bytes: int = 500 * 1024 * 1024


@dataclass(frozen=True)
class Health:
    """now: wall time (s); runtime_state / runtime_error: the tracker runtime's; source_fault: the frame
    source's last read error; last_frame_at: wall time of the newest processed frame (None: none yet);
    up_s: seconds since the runtime started; frame_rate: frames processed per second over the window (None
    until the window is full); servo, recording, database: their one-line faults (None when healthy);
    disk_free_bytes: free space of the data directory (None: unknown)."""

    now: float
    runtime_state: str
    runtime_error: str | None = None
    source_fault: str | None = None
    last_frame_at: float | None = None
    up_s: float = 0.0
    frame_rate: float | None = None
    servo: str | None = None
    recording: str | None = None
    database: str | None = None
    disk_free_bytes: int | None = None


def device_faults(h: Health, th: FaultThresholds) -> dict[str, str]:
    """The active fault sources and their messages."""
    out: dict[str, str] = {}
    camera = _camera(h, th)
    if camera:
        out["camera"] = camera
    elif h.frame_rate is not None and h.frame_rate < th.fps_floor:
        out["frame_rate"] = f"{h.frame_rate:.1f} frames per second, under the floor of {th.fps_floor:g}"
    if h.servo:
        out["servo"] = h.servo
    if h.recording:
        out["recording"] = h.recording
    if h.database:
        out["database"] = h.database
    if h.disk_free_bytes is not None and h.disk_free_bytes < th.disk_min_bytes:
        out["disk"] = (f"{h.disk_free_bytes / 2**20:.0f} MiB free, under the floor of "
                       f"{th.disk_min_bytes / 2**20:.0f} MiB")
    return out


def _camera(h: Health, th: FaultThresholds) -> str | None:
    if h.runtime_state in ("failed", "ended", "stopped"):
        return f"the tracker {h.runtime_state}" + (f": {h.runtime_error}" if h.runtime_error else "")
    if h.source_fault:
        return f"camera gone: {h.source_fault}"
    if h.last_frame_at is None:
        return f"no frame {h.up_s:.1f} s after the start" if h.up_s > th.first_frame_s else None
    if h.now - h.last_frame_at > th.stall_s:
        return f"camera stalled: no frame for {h.now - h.last_frame_at:.1f} s"
    return None
