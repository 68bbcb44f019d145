"""Sanity checks of a rig read from a file: every field a finite number of the right shape, a 3x3 K with
positive focal lengths, orthonormal rotations, a baseline within plausible limits (metres), and the first
background pair against the rig (exchanged inputs or a reversed baseline give negative disparities).

Each failure is a `RigError` whose message is one line naming the field, e.g.
"field left.K: must be a 3x3 matrix, got 2x3"; `load_rig` prefixes the file name."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

F64 = NDArray[np.float64]

# Plausible baselines b = |c_right - c_left| in metres: below 1 cm nothing is resolved in depth, above 10 m
# the file is most likely in centimetres or millimetres. A caller may widen them (load_rig's argument).
BASELINE_LIMITS_M = (0.01, 10.0)
ROTATION_TOL = 1e-3  # largest |R Rᵀ - I| entry accepted for a rotation read from a file


class RigError(ValueError):
    """A rig field is malformed or implausible; the message names the field and is one line."""


def matrix_field(d: dict[str, Any], key: str, name: str, shape: tuple[int, ...], default: Any = None,
                 nan_ok: bool = False) -> F64:
    """Field `key` of `d` as a finite float64 array of exactly `shape`; RigError naming `name` otherwise.
    nan_ok: NaN entries are kept (a figure that could not be estimated); infinities are still refused."""
    if key not in d:
        if default is None:
            raise RigError(f"field {name}: missing")
        return np.asarray(default, dtype=np.float64)
    try:
        a = np.asarray(d[key], dtype=np.float64)
    except (TypeError, ValueError):
        raise RigError(f"field {name}: not an array of numbers") from None
    if a.shape != shape:
        got = "x".join(str(n) for n in a.shape) or "a scalar"
        raise RigError(f"field {name}: must be {'x'.join(str(n) for n in shape)}, got {got}")
    if nan_ok and np.any(np.isinf(a)):
        raise RigError(f"field {name}: holds an infinite number")
    if not nan_ok and not np.all(np.isfinite(a)):
        raise RigError(f"field {name}: holds a non-finite number (NaN or infinity)")
    return a


def check_rotation(R: F64, name: str) -> None:
    """R must be a proper rotation: R Rᵀ = I within ROTATION_TOL and det R = +1."""
    err = float(np.max(np.abs(R @ R.T - np.eye(3))))
    if err > ROTATION_TOL:
        raise RigError(f"field {name}: not an orthonormal rotation (|R Rᵀ - I| reaches {err:.3g})")
    if np.linalg.det(R) < 0:
        raise RigError(f"field {name}: a reflection (det = -1), not a rotation")


def camera_fields(d: object, side: str) -> dict[str, Any]:
    """The checked fields of one camera: K (3, 3) px, dist (5,), size (w, h) px, R_rc (3, 3), c (3,) m."""
    if not isinstance(d, dict):
        raise RigError(f"field {side}: missing or not an object")
    K = matrix_field(d, "K", f"{side}.K", (3, 3))
    fx, fy = float(K[0, 0]), float(K[1, 1])
    if not (fx > 0 and fy > 0):
        raise RigError(f"field {side}.K: focal lengths must be positive, got fx {fx:g}, fy {fy:g}")
    if not np.allclose(K[2], [0.0, 0.0, 1.0]) or K[1, 0] != 0.0:
        raise RigError(f"field {side}.K: not an upper-triangular intrinsic matrix with last row 0 0 1")
    dist = matrix_field(d, "dist", f"{side}.dist", (5,))
    size = d.get("size")
    if (not isinstance(size, list) or len(size) != 2
            or not all(isinstance(v, int) and not isinstance(v, bool) and v > 0 for v in size)):
        raise RigError(f"field {side}.size: must be two positive whole numbers [width, height], got {size!r}")
    R_rc = matrix_field(d, "R_rc", f"{side}.R_rc", (3, 3), np.eye(3))
    check_rotation(R_rc, f"{side}.R_rc")
    c = matrix_field(d, "c", f"{side}.c", (3,), np.zeros(3))
    return {"K": K, "dist": dist, "size": (int(size[0]), int(size[1])), "R_rc": R_rc, "c": c}


def check_baseline(R_left: F64, c_left: F64, c_right: F64,
                   limits_m: tuple[float, float] = BASELINE_LIMITS_M) -> None:
    """b = |c_right - c_left| must lie within limits_m (metres): a rig in cm or mm fails here. The right
    lens centre must lie on the left camera's +x side (R_left (c_right - c_left))ₓ > 0: a reversed
    baseline (the centres exchanged) fails here."""
    b = float(np.linalg.norm(c_right - c_left))
    lo, hi = limits_m
    if not lo <= b <= hi:
        hint = " (is the file in centimetres or millimetres? the rig's unit is the metre)" if b > hi else ""
        raise RigError(f"field right.c: baseline {b:.6g} m is outside {lo:g} to {hi:g} m{hint}")
    x = float((R_left @ (c_right - c_left))[0])
    if x <= 0:
        raise RigError(f"field right.c: the right camera lies {-x:.4g} m to the left of the left camera "
                       "(the baseline is reversed: are left and right exchanged?)")


def check_disparity_range(f_px: float, b_m: float, near_m: float, width_px: int) -> int:
    """Disparity search length for the background (px, a multiple of 16): d_max = f b / r_near, bounded
    by half the image width; RigError when the rig asks for more (units, or a nearest range too close)."""
    if not (math.isfinite(near_m) and near_m > 0):
        raise RigError(f"nearest range must be a positive number of metres, got {near_m!r}")
    d_max = f_px * b_m / near_m
    if d_max > width_px / 2:
        raise RigError(
            f"field right.c: baseline {b_m:.6g} m with f {f_px:.1f} px needs disparities up to {d_max:.0f} px at "
            f"the nearest range {near_m:g} m, more than {width_px // 2} px (half the image width; is the "
            "baseline in metres? otherwise raise the nearest range)")
    return int(16 * math.ceil(max(d_max, 1.0) / 16))


def check_disparity_sign(as_given: int, exchanged: int, min_points: int) -> None:
    """The first background pair must match with a positive rectified disparity x_l - x_r as given:
    `as_given` and `exchanged` count the confident matches of the pair as given and with left and right
    exchanged (a negative disparity as given). Far more of the latter: the inputs are exchanged."""
    if exchanged >= min_points and exchanged > 1.5 * as_given:
        raise RigError(
            f"the background's disparity is negative (it matches at {exchanged} points with the left and right "
            f"images exchanged, at {as_given} as given): the left and right inputs are exchanged, or the "
            "rig's cameras (field right.c) are")
