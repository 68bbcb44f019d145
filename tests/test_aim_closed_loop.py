"""Closed loop without images: IMM predictor + AimController driving the SimulatedGimbal, against the
ReactiveController on the same turning target. Shows the integration pattern of the three libraries."""

from __future__ import annotations

import math

import numpy as np

from tracker.aim import AimConfig, AimController, AimInput, ReactiveController, aim_angles
from tracker.geometry import gimbal_rotation
from tracker.predict import IMMPredictor, Measurement, cartesian_to_spherical, stereo_sigmas
from tracker.servo import SimGimbalConfig, SimulatedGimbal

F64 = np.ndarray


def truth(t: float) -> F64:
    """A level circle of radius 6 m centred 12 m ahead, 7.5 m/s (ω = 1.25 rad/s), 1.5 m up."""
    w, r = 1.25, 6.0
    return np.array([r * math.sin(w * t), -1.5, 12.0 - r * math.cos(w * t)])


def pointing_errors(use_prediction: bool) -> list[float]:
    rng = np.random.default_rng(7)
    gimbal = SimulatedGimbal(SimGimbalConfig(latency_s=0.03, time_constant_s=0.06))
    cfg = AimConfig()
    ctrl = AimController(cfg) if use_prediction else ReactiveController(cfg)
    pred = IMMPredictor()
    errors = []
    for k in range(1, 150):
        t = k / 30.0
        g = gimbal.state_at(t)
        p = truth(t)
        d_cam = gimbal_rotation(g.pan_deg, g.tilt_deg).T @ p  # where the cameras see the target
        centroid = (cfg.focal_px * d_cam[0] / d_cam[2], cfg.focal_px * d_cam[1] / d_cam[2])
        inp = AimInput(t, gimbal=g, centroid_px=centroid)
        if use_prediction:
            sr, sa, se = stereo_sigmas(float(np.linalg.norm(p)), 600.0, 0.3)
            r, az, el = cartesian_to_spherical(p)
            z = Measurement(r + sr * rng.normal(), az + sa * rng.normal(), el + se * rng.normal(), sr, sa, se)
            est = pred.update(t, z)
            # lead = servo latency + time constant: where the target will be when the mount gets there
            inp = AimInput(t, g, pred.predict_at(t + 0.09), est.state, centroid)
        cmd = ctrl.step(inp)
        if cmd is not None:
            gimbal.command(cmd.pan_deg, cmd.tilt_deg)
        if t > 1.5:
            pan, tilt = aim_angles(p)
            errors.append(math.hypot((pan - g.pan_deg) * math.cos(math.radians(tilt)), tilt - g.tilt_deg))
    return errors


def test_predictive_aiming_points_closer_than_reactive() -> None:
    predictive, reactive = pointing_errors(True), pointing_errors(False)
    rms_p = math.sqrt(float(np.mean(np.square(predictive))))
    rms_r = math.sqrt(float(np.mean(np.square(reactive))))
    print(f"RMS pointing error: predictive {rms_p:.2f}°, reactive {rms_r:.2f}°")
    assert rms_p < 0.7 * rms_r
    assert rms_p < 2.5  # degrees; the deadband alone is 1.2°
