"""Click to point: the mount angles that bring what is seen at a pixel to the centre of that camera's
image, through the calibrated camera (its lens, its offset from the pivot) and the distance along the
pixel's ray (the detection under it, else the learnt background, else a default)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from tmeye.runtime.servo import ServoRequestError
from tracker.aim import point_angles
from tracker.frames import GimbalState

if TYPE_CHECKING:
    from tmeye.runtime.compose import Composition
    from tmeye.runtime.events import FrameEvent

DEFAULT_POINT_DISTANCE_M = 20.0


def pixel_angles(comp: Composition, latest: FrameEvent | None, camera: str, u: float, v: float
                 ) -> tuple[float, float]:
    """(pan, tilt) in degrees for raw pixel (u, v) of `camera` ("left" or "right") in the latest frame."""
    cam = comp.pipeline.rig.left if camera == "left" else comp.pipeline.rig.right
    w, h = cam.size
    if not (0 <= u < w and 0 <= v < h):
        raise ServoRequestError(f"pixel ({u:g}, {v:g}) is outside the {w}x{h} image")
    g = (latest.frame.gimbal if latest is not None else None) or GimbalState()
    return point_angles(cam, u, v, distance_along(comp, latest, camera, u, v, g), g)


def distance_along(comp: Composition, latest: FrameEvent | None, camera: str, u: float, v: float,
                   g: GimbalState) -> float:
    """Distance (m) from the lens centre along the pixel's ray to what it sees."""
    key = 0 if camera == "left" else 1
    cam = comp.pipeline.rig.left if key == 0 else comp.pipeline.rig.right
    if latest is not None and key == 0:
        for det in latest.result.detections:
            x0, y0, x1, y1 = det.blob.box
            if x0 <= u < x1 and y0 <= v < y1:
                return float(np.linalg.norm(det.loc.rig - cam.c))
    iu, iv = int(u), int(v)
    cm = comp.pipeline.bg.correspondence(key, g, 1, box=(iu, iv, iu + 1, iv + 1), with_floor=False)
    if cm.valid.size and bool(cm.valid.flat[0]) and float(cm.disparity.flat[0]) > 0:
        rect = comp.pipeline.rect
        d = cam.rays_rig(np.array([u], float), np.array([v], float))[0]
        return float(rect.f * rect.b / float(cm.disparity.flat[0]) / max(float(d[2]), 0.1))
    return DEFAULT_POINT_DISTANCE_M
