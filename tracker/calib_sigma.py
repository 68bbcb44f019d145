"""The calibration's own uncertainty, as it moves a localisation (issue 12 item 1).

A rig file written by `tmeye calibrate` keeps, under "calibration", the one-sigma of the bundle
adjustment's parameters (paper eq. 5-8): the intrinsics of each camera, the stereo translation T and the
Euler angles (δ, φ, γ) of eq. (6). Three of their effects on r, θ, φ are first-order and large:

- scale: z = f b / d (eq. 2) scales with f and b, and x, y with z, so a relative error ε of f·b moves
  the point X to (1 + ε) X: σ_ε² = (σ_b / b)² + ((σ_fx / fx)²_left + (σ_fx / fx)²_right) / 2, with
  σ_b = |T̂ · σ_T| (T̂ the baseline's direction; units cancel);
- disparity offset: errors of the relative yaw and of the principal points shift the right image
  sideways, every disparity by the same amount; the calibration writes its σ ("disparity_offset_std_px",
  px at the left camera's fx), propagated through the adjustment's joint covariance. The marginal σ of
  the yaw is no substitute: the yaw and the right principal point move the image alike, and the
  adjustment knows their sum far better than either (on the simulated rig, 15 board pairs: f σ_φ gave
  0.32 px where the disparity's actual error was about 0.025 px). Older rig files without the figure get
  no disparity term;
- principal point: the left camera's (σ_cx, σ_cy) px move the centroid's rays, and with them θ and φ.

A rig without the section (a simulated rig, another tool's file) has none of these: `CalibrationSigma()`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from tracker.rigcheck import RigError, matrix_field


@dataclass(frozen=True)
class CalibrationSigma:
    """scale_rel: σ of f·b as a fraction; disparity_px: σ of the disparity offset (px at the left camera's
    fx); principal_px: the left camera's (σ_cx, σ_cy) (px)."""

    scale_rel: float = 0.0
    disparity_px: float = 0.0
    principal_px: tuple[float, float] = (0.0, 0.0)

    @staticmethod
    def from_section(cal: object) -> CalibrationSigma:
        """From a rig file's "calibration" object; RigError naming calibration.FIELD when one is malformed.
        Fields absent from it, and σ the calibration could not estimate (NaN), count as not modelled (0)."""
        if not isinstance(cal, dict):
            raise RigError("field calibration: must be an object")
        T = matrix_field(cal, "T", "calibration.T", (3,), [0.0, 0.0, 0.0])
        T_std = _sigmas(cal, "T_std", (3,))
        d_std = float(_sigmas(cal, "disparity_offset_std_px", ()))
        b = float(np.linalg.norm(T))
        sigma_b_rel = abs(float(T @ T_std)) / (b * b) if b > 0 else 0.0
        f_rel = [_focal_rel(cal, side) for side in ("left", "right")]
        cx, cy = _std(cal, "left", "cx"), _std(cal, "left", "cy")
        scale = math.sqrt(sigma_b_rel**2 + (f_rel[0] ** 2 + f_rel[1] ** 2) / 2.0)
        return CalibrationSigma(scale, d_std, (cx, cy))


def _sigmas(d: dict[str, Any], key: str, shape: tuple[int, ...], where: str = "calibration") -> NDArray[np.float64]:
    """Field `key` of `d`: standard deviations of `shape`, each a number >= 0 or NaN (not estimated: 0
    here); zeros when absent. RigError naming WHERE.KEY otherwise."""
    name = f"{where}.{key}"
    if isinstance(d.get(key), (bool, str, dict)):
        raise RigError(f"field {name}: not a number or an array of numbers")
    a = matrix_field(d, key, name, shape, np.zeros(shape), nan_ok=True)
    if np.any(a[~np.isnan(a)] < 0):
        raise RigError(f"field {name}: must be numbers >= 0 (NaN: not estimated)")
    return np.nan_to_num(a, nan=0.0)


def _std(cal: dict[str, Any], side: str, name: str) -> float:
    """calibration.intrinsics_std.SIDE.NAME (px; 0 when absent or not estimated)."""
    block = cal.get("intrinsics_std", {})
    sub = block.get(side, {}) if isinstance(block, dict) else None
    if not isinstance(sub, dict):
        raise RigError(f"field calibration.intrinsics_std.{side}: must be an object")
    return float(_sigmas(sub, name, (), f"calibration.intrinsics_std.{side}"))


def _focal_rel(cal: dict[str, Any], side: str) -> float:
    """σ_fx / fx of one camera, fx from its own K (calibration.K_SIDE)."""
    s = _std(cal, side, "fx")
    if s == 0.0:
        return 0.0
    f = float(matrix_field(cal, f"K_{side}", f"calibration.K_{side}", (3, 3))[0, 0])
    if not f > 0:
        raise RigError(f"field calibration.K_{side}: focal length must be positive, got {f}")
    return s / f
