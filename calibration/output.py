"""Calibration outputs: the JSON summary, the rig file for the tracker, and the PNG report."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
from numpy.typing import NDArray

from calibration.bundle import INTR_NAMES
from calibration.stereo import StereoCalibration
from tracker.geometry import save_rig

U8 = NDArray[np.uint8]


def summary(cal: StereoCalibration, model: str = "pinhole") -> dict[str, object]:
    """Every calibration figure as JSON-ready values (lengths in the square's unit, angles in degrees)."""
    ba, rig = cal.ba, cal.rig
    vr = ba.view_rms
    views_rms = {n: [None if np.isnan(x) else float(x) for x in vr[:, v]] for v, n in enumerate(cal.names)}
    out: dict[str, object] = {
        "model": model,
        "board": {"cols": cal.board.cols, "rows": cal.board.rows, "square": cal.board.square},
        "image_size": list(cal.size),
        "rms_px": ba.rms,
        "stereo_rms_px": cal.stereo_rms_px,
        "per_view_rms_px": views_rms,
        "baseline": rig.baseline,
        "euler_deg": [float(np.degrees(a)) for a in ba.euler],
        "euler_std_deg": np.degrees(ba.std_euler).tolist(),
        "euler_recentred": ba.recentred,
        "R": ba.R.tolist(),
        "T": ba.T.tolist(),
        "T_std": ba.std_T.tolist(),
        "disparity_offset_std_px": ba.disparity_std_px,
        "K_left": rig.left.K.tolist(),
        "K_right": rig.right.K.tolist(),
        "dist_left": rig.left.dist.tolist(),
        "dist_right": rig.right.dist.tolist(),
        "intrinsics_std": {side: dict(zip(INTR_NAMES, ba.std_intr[c].tolist(), strict=True))
                           for c, side in enumerate(("left", "right"))},
        "rectified_row_error_mean_px": cal.rect.row_error_mean_px,
        "rectified_row_error_rms_px": cal.rect.row_error_rms_px,
        "coverage": {"left": cal.coverage[0], "right": cal.coverage[1]},
        "views_used": len(cal.names),
        "views_rejected": [{"view": s.name, "reason": s.reason} for s in cal.rejected],
        "images_skipped": [{"image": s.name, "reason": s.reason} for s in cal.skipped],
        "bundle_adjustment_s": ba.seconds,
    }
    if model == "polynomial":
        if cal.polynomial is None:
            raise ValueError(f"polynomial model unavailable: {cal.polynomial_error}")
        out["polynomial"] = {"left": cal.polynomial[0].to_dict(), "right": cal.polynomial[1].to_dict()}
    return out


def write_rig(cal: StereoCalibration, path: str | Path, model: str = "pinhole") -> None:
    """The rig file the tracker loads: Brown-Conrady cameras (tracker.geometry.Camera) placed from
    x_r = R x_l + T with the origin midway between the lens centres; the figures under "calibration"."""
    extra = summary(cal, model)
    extra.pop("per_view_rms_px")
    extra["per_view_rms_px"] = {n: [float(x) for x in np.nan_to_num(cal.ba.view_rms[:, v])]
                                for v, n in enumerate(cal.names)}
    save_rig(cal.rig, path, extra)


def report_image(cal: StereoCalibration, width: int = 1200) -> U8:
    """BGR report (H, width, 3): per-view RMS bars (left blue, right red, threshold line) on top, the
    corner residuals (scaled) of both cameras drawn over the image area below."""
    bars = _bar_panel(cal, width, 260)
    half = width // 2
    w, h = cal.size
    ph = int(round(h * half / w))
    panels = [_residual_panel(cal, c, half, ph) for c in range(2)]
    return np.vstack([bars, np.hstack(panels)])


def _bar_panel(cal: StereoCalibration, width: int, height: int) -> U8:
    img = np.full((height, width, 3), 255, np.uint8)
    vr = np.nan_to_num(cal.ba.view_rms)
    V = vr.shape[1]
    top = max(float(vr.max()), 1e-6) * 1.15
    x0, y0, y1 = 50, 30, height - 30
    step = (width - x0 - 10) / max(V, 1)
    for v in range(V):
        for c, color in enumerate(((200, 80, 0), (0, 0, 200))):
            x = int(x0 + v * step + c * step / 2)
            top_y = int(y1 - (y1 - y0) * vr[c, v] / top)
            cv2.rectangle(img, (x + 1, top_y), (int(x + step / 2) - 1, y1), color, -1)
    cv2.line(img, (x0, y1), (width - 10, y1), (0, 0, 0), 1)
    ry = int(y1 - (y1 - y0) * cal.ba.rms / top)
    cv2.line(img, (x0, ry), (width - 10, ry), (0, 150, 0), 1)
    text = f"per-view RMS px (left blue, right red); overall {cal.ba.rms:.3f} px (green); top {top:.3f}"
    cv2.putText(img, text, (x0, 20), cv2.FONT_HERSHEY_SIMPLEX, 0.5, (0, 0, 0), 1, cv2.LINE_AA)
    return img


def _residual_panel(cal: StereoCalibration, cam: int, pw: int, ph: int) -> U8:
    img = np.full((ph, pw, 3), 245, np.uint8)
    s = pw / cal.size[0]
    res = cal.ba.residuals[cam]
    seen = ~np.isnan(res[:, 0, 0])
    scale = 20.0 / max(float(np.nanmax(np.linalg.norm(res[seen], axis=-1))), 1e-9)
    obs = cal.observed[cam]
    for v in np.flatnonzero(seen):
        for p, r in zip(obs[v], res[v], strict=True):
            a = (int(p[0] * s), int(p[1] * s))
            b = (int(p[0] * s + r[0] * scale), int(p[1] * s + r[1] * scale))
            cv2.line(img, a, b, (0, 0, 220), 1, cv2.LINE_AA)
            cv2.circle(img, a, 1, (120, 120, 120), -1)
    side = ("left", "right")[cam]
    label = f"{side}: residuals x{scale:.0f}, coverage {100 * cal.coverage[cam]:.0f}%"
    cv2.putText(img, label, (8, 18), cv2.FONT_HERSHEY_SIMPLEX, 0.5, (0, 0, 0), 1, cv2.LINE_AA)
    return img


def write_report(cal: StereoCalibration, path: str | Path) -> None:
    """Write the PNG report; OSError if it cannot be written."""
    if not cv2.imwrite(str(path), report_image(cal)):
        raise OSError(f"cannot write report {path}")
