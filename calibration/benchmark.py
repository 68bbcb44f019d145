"""Benchmark (not a test): joint bundle adjustment of 2 cameras x 30 views (the issue's speed line), and
the simulated scenario (the calibration procedure's VIEWS views) against the truth and OpenCV's
stereoCalibrate. Run: .venv/bin/python -m calibration.benchmark [seeds]"""

from __future__ import annotations

import json
import sys
import time

import numpy as np

from calibration.bundle import bundle_adjust
from calibration.initial import default_fixed, init_stereo
from calibration.scenario import PROC_BOARD, add_corner_noise, procedure_poses, render_views
from tracker.sim.rig import default_rig


def time_bundle_adjustment(views: int = 30, seed: int = 0, repeats: int = 3) -> dict[str, float]:
    """Seconds for the joint adjustment (intrinsics, distortion, 30 board poses of the procedure's
    17x12 board, extrinsics) from the per-camera start values; best of `repeats`."""
    rng = np.random.default_rng(seed)
    rig = default_rig()
    vs, truth = render_views(rig, procedure_poses(rng, views, rig), rng, PROC_BOARD)
    add_corner_noise(vs, truth, 0.1, rng)
    obj = np.broadcast_to(vs.obj, (vs.obs.shape[1], *vs.obj.shape)).copy()
    t0 = time.perf_counter()
    inp = init_stereo(obj, np.nan_to_num(vs.obs), vs.seen, vs.size, default_fixed())
    t_init = time.perf_counter() - t0
    best = min(bundle_adjust(inp).seconds for _ in range(repeats))
    return {"views": float(views), "init_s": t_init, "joint_bundle_adjustment_s": best}


def main() -> None:
    from calibration.scenario import run_calibration_scenario

    print(json.dumps(time_bundle_adjustment()))
    for seed in [int(s) for s in sys.argv[1:]] or [0]:
        r = run_calibration_scenario(seed=seed)
        keys = ("views", "corner_error_px", "focal_err_pct", "principal_err_px", "baseline_err_pct",
                "rotation_err_deg", "held_out_3d_error_mm", "bundle_adjustment_s", "stereo_rms_px",
                "rectified_row_error_rms_px", "best_model")
        out = {k: getattr(r, k) for k in keys}
        out["seed"] = seed
        out["opencv"] = r.opencv
        out["polynomial_held_out_3d_error_mm"] = r.models["polynomial"].held_out_3d_error_mm
        print(json.dumps(out))


if __name__ == "__main__":
    main()
