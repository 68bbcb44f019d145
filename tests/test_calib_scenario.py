"""Simulated truth (issue 3): calibrate the rendered views of the calibration procedure (60 views, see
calibration.scenario) with 0.1 px corner noise and compare with the true rig (acceptance: focal within
0.05 %, baseline within 0.1 %, rotation within 0.02°) and with OpenCV's stereoCalibrate on the same
corners."""

from __future__ import annotations

import pytest

from calibration.scenario import CalibrationScenarioResult, run_calibration_scenario


@pytest.fixture(scope="module")
def result() -> CalibrationScenarioResult:
    return run_calibration_scenario(seed=0, views=60, corner_noise_px=0.1)


def test_corner_noise_is_as_asked(result: CalibrationScenarioResult) -> None:
    assert result.corner_error_px == pytest.approx(0.1, abs=0.002)  # 2-D RMS, detector error included
    assert result.detector_error_px < 0.1


def test_against_truth(result: CalibrationScenarioResult) -> None:
    assert result.views_used == 60
    assert result.focal_err_pct < 0.05
    assert result.baseline_err_pct < 0.1
    assert result.rotation_err_deg < 0.02
    assert result.principal_err_px < 0.5
    assert result.held_out_3d_error_mm < 1.0
    assert set(result.models) == {"pinhole", "polynomial"}
    assert result.models["polynomial"].held_out_3d_error_mm < 2.0


def test_at_least_as_good_as_opencv(result: CalibrationScenarioResult) -> None:
    cv = result.opencv
    assert result.stereo_rms_px <= cv["stereo_rms_px"] * 1.0001
    assert result.rectified_row_error_rms_px <= cv["rectified_row_error_rms_px"] * 1.01


def test_to_json_has_the_figures(result: CalibrationScenarioResult) -> None:
    d = result.to_json()
    for k in ("focal_err_pct", "principal_err_px", "baseline_err_pct", "rotation_err_deg",
              "held_out_3d_error_mm", "models", "opencv"):
        assert k in d
    assert set(d["models"]["pinhole"]) >= {"focal_err_pct", "held_out_3d_error_mm"}  # type: ignore[index]


def test_rotation_error_is_the_angle_of_r_est_r_true_transposed() -> None:
    import numpy as np

    from calibration.scenario import _rotation_angle_deg
    from tracker.geometry import euler_to_matrix

    R_true = euler_to_matrix(0.2, -0.1, 0.3)
    R_est = euler_to_matrix(0.0, np.radians(0.015), 0.0) @ R_true  # 0.015° off, about y
    assert _rotation_angle_deg(R_est, R_true) == pytest.approx(0.015, abs=1e-6)
    assert _rotation_angle_deg(R_true, R_est) == pytest.approx(0.015, abs=1e-6)
