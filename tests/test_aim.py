"""AimController and ReactiveController: aiming, limits, deadband, loss/home, manual, centroid correction."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tracker.aim import (
    AimConfig,
    AimController,
    AimInput,
    AimMode,
    ReactiveController,
    ServoCommand,
    aim_angles,
    centroid_direction,
)
from tracker.frames import GimbalState
from tracker.geometry import gimbal_rotation
from tracker.predict import PredictedState

DT = 1.0 / 30.0


def state_at(p: list[float], t: float = 0.0) -> PredictedState:
    return PredictedState(t, np.array(p, dtype=float), np.zeros(3), np.eye(3) * 0.01)


def run(ctrl: AimController | ReactiveController, inputs: list[AimInput]) -> list[ServoCommand | None]:
    return [ctrl.step(i) for i in inputs]


def test_aim_angles_point_the_optical_axis_at_the_target() -> None:
    p = np.array([3.0, -2.0, 8.0])  # right of and above the mount
    pan, tilt = aim_angles(p)
    assert pan > 0.0 and tilt > 0.0
    assert aim_angles(np.array([0.0, 0.0, 1.0])) == (0.0, 0.0)
    assert aim_angles(np.array([1.0, 0.0, 0.0]))[0] == pytest.approx(90.0)  # pan + turns +z to +x
    # a centroid offset seen from a tilted mount maps back to the exact world direction
    g = GimbalState(20.0, 30.0)
    d = gimbal_rotation(g.pan_deg, g.tilt_deg) @ np.array([0.1, -0.05, 1.0])
    assert np.allclose(centroid_direction(g, 60.0, -30.0, 600.0), aim_angles(d))


def test_converges_on_a_predicted_target_within_rate_and_acceleration_limits() -> None:
    cfg = AimConfig(max_rate_deg_s=90.0, max_accel_deg_s2=400.0)
    ctrl = AimController(cfg)
    target = state_at([4.0, -1.0, 6.0])
    cmds = [c for c in run(ctrl, [AimInput(k * DT, predicted=target) for k in range(60)]) if c is not None]
    goal = aim_angles(target.position)
    assert cmds[-1].pan_deg == pytest.approx(goal[0]) and cmds[-1].tilt_deg == pytest.approx(goal[1])
    assert all(c.reason == "track" for c in cmds)
    pans = np.array([0.0] + [c.pan_deg for c in cmds])
    ts = np.array([0.0] + [c.t for c in cmds])
    rate = np.diff(pans) / np.diff(ts)
    assert np.max(np.abs(rate)) <= 90.0 + 1e-9
    assert np.max(np.abs(np.diff(rate) / np.diff(ts)[1:])) <= 400.0 * 1.001 + 1e-9


def test_mechanical_limits_are_always_clamped() -> None:
    ctrl = AimController(AimConfig(max_rate_deg_s=1000.0, max_accel_deg_s2=1e5))
    behind_and_below = state_at([0.5, 30.0, -5.0])  # pan ~ 174°, tilt ~ -80°
    cmds = [c for c in run(ctrl, [AimInput(k * DT, predicted=behind_and_below) for k in range(90)]) if c]
    assert max(c.pan_deg for c in cmds) == 170.0 and min(c.tilt_deg for c in cmds) == -30.0
    ctrl.set_manual(-400.0, 400.0)
    cmds = [c for c in run(ctrl, [AimInput(3 + k * DT) for k in range(120)]) if c]
    assert cmds[-1].pan_deg == -170.0 and cmds[-1].tilt_deg == 80.0


def test_deadband_spares_the_motors() -> None:
    cfg = AimConfig()  # 2 % of 640 px at f = 600 px: 1.22°
    assert cfg.deadband_deg == pytest.approx(math.degrees(math.atan(12.8 / 600.0)))
    ctrl = AimController(cfg)
    near = state_at([math.tan(math.radians(1.0)) * 10.0, 0.0, 10.0])  # 1° off: inside
    assert run(ctrl, [AimInput(k * DT, predicted=near) for k in range(30)]) == [None] * 30
    far = state_at([math.tan(math.radians(2.0)) * 10.0, 0.0, 10.0])  # 2° off: moves, all the way
    cmds = [c for c in run(ctrl, [AimInput(1 + k * DT, predicted=far) for k in range(30)]) if c]
    assert cmds and cmds[-1].pan_deg == pytest.approx(2.0)
    jitter = state_at([math.tan(math.radians(2.5)) * 10.0, 0.0, 10.0])  # 0.5° from the new setpoint
    assert run(ctrl, [AimInput(2 + k * DT, predicted=jitter) for k in range(30)]) == [None] * 30


def test_holds_then_returns_home_after_the_loss_timeout() -> None:
    cfg = AimConfig(loss_timeout_s=1.0, home_pan_deg=5.0, home_tilt_deg=10.0)
    ctrl = AimController(cfg)
    target = state_at([5.0, 0.0, 5.0])
    run(ctrl, [AimInput(k * DT, predicted=target) for k in range(60)])  # tracking until t ≈ 2 s
    assert ctrl.setpoint.pan_deg == pytest.approx(45.0)
    lost = run(ctrl, [AimInput(2.0 + k * DT) for k in range(1, 90)])
    t_first = min(c.t for c in lost if c is not None)
    assert t_first > 2.96  # held until the timeout ...
    assert all(c.reason == "home" for c in lost if c is not None)
    assert ctrl.setpoint == GimbalState(5.0, 10.0)  # ... then went home


def test_the_loss_timeout_counts_from_the_last_measurement_not_from_the_predictions_end() -> None:
    """Live, a predictor coasts 1 s after its target's last measurement, and the mount went home 1.5 s
    after that, 2.5 s after the target was last seen, against a loss timeout of 1.5 s."""
    cfg = AimConfig(loss_timeout_s=1.5, home_pan_deg=5.0, home_tilt_deg=10.0)
    ctrl = AimController(cfg)
    target = state_at([5.0, 0.0, 5.0])
    run(ctrl, [AimInput(k * DT, predicted=target) for k in range(60)])  # measured until t ≈ 2 s
    coast = [AimInput(2.0 + k * DT, predicted=target, coasting_s=k * DT) for k in range(1, 30)]  # to 2.97 s
    assert all(c is None for c in run(ctrl, coast))  # following the prediction
    lost = run(ctrl, [AimInput(3.0 + k * DT) for k in range(0, 60)])  # the prediction has run out
    t_first = min(c.t for c in lost if c is not None)
    assert 3.5 < t_first < 3.5 + 2 * DT  # 1.5 s after the last measurement at about 2 s
    assert all(c.reason == "home" for c in lost if c is not None)
    ctrl2 = AimController(cfg)  # a prediction that outlasts the timeout: home all the same
    run(ctrl2, [AimInput(k * DT, predicted=target) for k in range(60)])
    long = run(ctrl2, [AimInput(2.0 + k * DT, predicted=target, coasting_s=k * DT) for k in range(1, 90)])
    assert min(c.t for c in long if c is not None) > 3.5 and ctrl2.setpoint == GimbalState(5.0, 10.0)


def test_manual_mode_overrides_until_resumed() -> None:
    ctrl = AimController()
    target = state_at([-3.0, 0.0, 5.0])
    ctrl.set_manual(30.0, 5.0)
    assert ctrl.mode is AimMode.MANUAL
    cmds = [c for c in run(ctrl, [AimInput(k * DT, predicted=target) for k in range(60)]) if c]
    assert {c.reason for c in cmds} == {"manual"} and ctrl.setpoint == GimbalState(30.0, 5.0)
    ctrl.resume_auto()
    assert ctrl.mode is AimMode.AUTO
    cmds = [c for c in run(ctrl, [AimInput(2 + k * DT, predicted=target) for k in range(60)]) if c]
    assert cmds[-1].reason == "track"
    assert ctrl.setpoint.pan_deg == pytest.approx(aim_angles(target.position)[0])


def test_centroid_corrects_a_pointing_bias() -> None:
    """The 3-D estimate says 10° but the cameras, pointing at 10°, see the target 1° to the right: the
    correction converges to +1° (low-passed) and the goal to 11°."""
    cfg = AimConfig(correction_tau_s=0.2, deadband_frac=0.0)
    ctrl = AimController(cfg)
    est = state_at([math.sin(math.radians(10.0)) * 10, 0.0, math.cos(math.radians(10.0)) * 10])
    du = cfg.focal_px * math.tan(math.radians(1.0))
    inputs = [
        AimInput(k * DT, gimbal=GimbalState(10.0, 0.0), predicted=est, current=est, centroid_px=(du, 0.0))
        for k in range(60)
    ]
    run(ctrl, inputs)
    assert ctrl.bias_deg[0] == pytest.approx(1.0, abs=0.01) and ctrl.bias_deg[1] == pytest.approx(
        0.0, abs=1e-6
    )
    assert ctrl.setpoint.pan_deg == pytest.approx(11.0, abs=0.01)
    no_3d = AimController(cfg)
    cmds = [c for c in run(no_3d, [AimInput(k * DT, centroid_px=(-100.0, 0.0)) for k in range(30)]) if c]
    assert cmds[-1].reason == "centroid" and cmds[-1].pan_deg < 0.0


def test_reactive_controller_follows_the_centroid_only() -> None:
    ctrl = ReactiveController(AimConfig(reactive_gain=0.5))
    target_dir = np.array([math.sin(math.radians(15.0)), 0.0, math.cos(math.radians(15.0))])
    assert (
        run(ctrl, [AimInput(k * DT, predicted=state_at(list(target_dir))) for k in range(10)]) == [None] * 10
    )
    for k in range(10, 100):  # the camera sees the target where it really is relative to the setpoint
        g = ctrl.setpoint
        d_cam = gimbal_rotation(g.pan_deg, g.tilt_deg).T @ target_dir
        c = ctrl.step(AimInput(k * DT, gimbal=g, centroid_px=(600.0 * d_cam[0] / d_cam[2], 0.0)))
        assert c is None or c.reason == "reactive"
    assert ctrl.setpoint.pan_deg == pytest.approx(15.0, abs=AimConfig().deadband_deg)


def test_time_must_not_go_backwards() -> None:
    ctrl = AimController()
    ctrl.step(AimInput(1.0))
    with pytest.raises(ValueError):
        ctrl.step(AimInput(0.5))


def test_gimbal_rotation_points_the_optical_axis_where_aim_angles_aims() -> None:
    p = np.array([3.0, -2.0, 8.0])
    pan, tilt = aim_angles(p)
    axis = gimbal_rotation(pan, tilt) @ np.array([0.0, 0.0, 1.0])
    assert np.allclose(axis, p / np.linalg.norm(p))
