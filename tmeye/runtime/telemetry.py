"""One frame's telemetry as a JSON-ready mapping: the fields of `tmeye track --json` (angles in degrees,
lengths in metres, times in seconds), and for the server the capture time, the servo state and every
detection (for the console's overlay)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from tracker.frames import StereoFrame
from tracker.results import Detection, FrameResult


def _r(v: float, nd: int = 4) -> float:
    return round(float(v), nd)


def primary_fields(det: Detection) -> dict[str, Any]:
    """x, y, z (m, gimbal-base frame), r (m), θ, φ (deg) and their 1-σ, of a detection's localisation."""
    loc = det.loc
    return {"x": _r(loc.world[0]), "y": _r(loc.world[1]), "z": _r(loc.world[2]), "r": _r(loc.r),
            "theta_deg": _r(math.degrees(loc.theta)), "phi_deg": _r(math.degrees(loc.phi)),
            "sigma_r": _r(loc.sigma_r), "sigma_theta_deg": _r(math.degrees(loc.sigma_theta), 5),
            "sigma_phi_deg": _r(math.degrees(loc.sigma_phi), 5)}


def metric_size(det: Detection, focal_px: float) -> tuple[float, float]:
    """(width, height) in metres of a detection: its mask's extent in pixels times depth z over f."""
    m = det.blob.mask
    cols, rows = np.flatnonzero(m.any(axis=0)), np.flatnonzero(m.any(axis=1))
    if cols.size == 0:
        return 0.0, 0.0
    z = float(det.loc.rig[2])
    return (float(cols[-1] - cols[0] + 1) * z / focal_px, float(rows[-1] - rows[0] + 1) * z / focal_px)


def detection_json(det: Detection, focal_px: float) -> dict[str, Any]:
    """A detection for the overlay: track id, left-image box (x0, y0, x1, y1 px), centroid (raw px),
    area (px), disparity (px), metric size (m) and its 3-D position."""
    b = det.blob
    w, h = metric_size(det, focal_px)
    out: dict[str, Any] = {"track_id": det.track_id, "box": [int(v) for v in b.box],
                           "centroid": [_r(b.centroid_raw[0], 2), _r(b.centroid_raw[1], 2)],
                           "area_px": int(b.area), "disparity_px": _r(b.disparity, 3),
                           "size_m": [_r(w, 3), _r(h, 3)]}
    out.update(primary_fields(det))
    return out


def telemetry(res: FrameResult, frame: StereoFrame, fps: float, frame_no: int | None = None) -> dict[str, Any]:
    """The `tmeye track --json` line of a frame: frame, t, offset_s, detected, track_id, objects, fps,
    step_ms and, with a primary target, x, y, z, r, theta_deg, phi_deg and their sigmas."""
    out: dict[str, Any] = {"frame": frame.index if frame_no is None else frame_no, "t": round(frame.t, 6),
                           "offset_s": round(frame.offset_s, 6), "detected": res.primary is not None,
                           "track_id": res.primary_id, "objects": len(res.detections), "fps": round(fps, 1),
                           "step_ms": round(sum(res.stage_ms.values()), 3)}
    if res.primary is not None:
        out.update(primary_fields(res.primary))
    return out
