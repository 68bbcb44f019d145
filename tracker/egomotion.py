"""The image motion the mount's own turning causes, taken out of the tracks' image states.

The multi-target tracker (tracker.tracks) predicts each object at constant velocity in image pixels and
disparity. While the mount slews, most of an object's image motion is the cameras turning: a target the
servo turns towards sweeps across the image at tens of pixels a frame and stops when the mount stops.
Extrapolated, that velocity carries the prediction past the object, out of the association gate, and the
track breaks. So the tracker is given the left camera's pixels as they would be seen at the home pose
(pan = tilt = 0): for a pure rotation of the camera about its centre, pixel x_g at gimbal pose g maps to

    x_h ~ H_g x_g,   H_g = K R_rc R_world_rig(home)ᵀ R_world_rig(g) R_rcᵀ K⁻¹   (3 x 3, homogeneous),

K and R_rc the left camera's intrinsics and rotation in the rig frame (tracker.geometry.Camera), and its
predictions are taken back with H_g⁻¹ to the frame's pose. A static point keeps its home pixel however the
mount turns; an object's tracked velocity is its own. Disparity is left as it is (a rotation of the rig
about its pivot does not change a target's depth along the rig's axis by more than the pivot's offset).
Lens distortion and the cameras' offset from the pivot are left out: at the simulated rig's distortion
and 5 cm offset they move a target beyond 3 m by well under the 40 px gate. At the home pose, or with no
mount, H is the identity: the tracker sees raw pixels, as before.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from tracker.frames import GimbalState
from tracker.geometry import Camera, gimbal_rotation

F64 = NDArray[np.float64]


class PoseCompensation:
    """Maps (x, y, disparity) rows between the left camera's raw pixels at a gimbal pose and at home."""

    def __init__(self, left: Camera):
        self.K = np.asarray(left.K, np.float64)
        self.K_inv = np.linalg.inv(self.K)
        self.R_rc = np.asarray(left.R_rc, np.float64)
        self.R_home_t = gimbal_rotation(0.0, 0.0).T
        self._cached: tuple[tuple[float, float], F64, F64] | None = None

    def _homographies(self, gimbal: GimbalState | None) -> tuple[F64, F64] | None:
        """(H_g, H_g⁻¹), or None at home or without a mount (the identity)."""
        if gimbal is None or (gimbal.pan_deg == 0.0 and gimbal.tilt_deg == 0.0):
            return None
        pose = (gimbal.pan_deg, gimbal.tilt_deg)
        if self._cached is None or self._cached[0] != pose:
            H = self.K @ self.R_rc @ self.R_home_t @ gimbal_rotation(*pose) @ self.R_rc.T @ self.K_inv
            self._cached = (pose, H, np.linalg.inv(H))
        return self._cached[1], self._cached[2]

    def to_home(self, points: F64, gimbal: GimbalState | None) -> F64:
        """(N, 3) x, y (raw left px at `gimbal`), disparity -> x, y as seen at home, disparity."""
        hs = self._homographies(gimbal)
        return points if hs is None else _apply(hs[0], points)

    def from_home(self, points: F64, gimbal: GimbalState | None) -> F64:
        """The inverse of `to_home` at the same pose."""
        hs = self._homographies(gimbal)
        return points if hs is None else _apply(hs[1], points)


def _apply(H: F64, points: F64) -> F64:
    """x, y of (N, 3) rows through the homography H (disparity kept); points behind the camera (w <= 0,
    beyond 90° of turning) keep their coordinates."""
    out = np.array(points, np.float64, copy=True).reshape(-1, 3)
    if not len(out):
        return out
    p = np.column_stack([out[:, 0], out[:, 1], np.ones(len(out))]) @ H.T
    ok = p[:, 2] > 1e-9
    out[ok, 0] = p[ok, 0] / p[ok, 2]
    out[ok, 1] = p[ok, 1] / p[ok, 2]
    return out
