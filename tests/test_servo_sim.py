"""SimulatedGimbal: latency, rate limit, first-order lag, backlash, limits, determinism."""

from __future__ import annotations

import math

import pytest

from tracker.servo import SimGimbalConfig, SimulatedGimbal, open_servo
from tracker.servo.base import AxisLimits


def test_latency_then_rate_limited_slew_then_first_order_settling() -> None:
    cfg = SimGimbalConfig(time_constant_s=0.05, max_rate_deg_s=200.0, latency_s=0.04, backlash_deg=0.0)
    g = SimulatedGimbal(cfg)
    g.command(90.0, -20.0)
    assert g.state_at(0.039).pan_deg == 0.0  # nothing happens before the latency
    a, b = g.state_at(0.10).pan_deg, g.state_at(0.20).pan_deg
    assert b - a == pytest.approx(200.0 * 0.10)  # slewing at the rate limit
    # saturation ends when the error is rate·τ = 10°: at t = 0.04 + 80/200 = 0.44 s; then e^(-t/τ)
    assert g.state_at(0.44).pan_deg == pytest.approx(80.0)
    assert g.state_at(0.49).pan_deg == pytest.approx(90.0 - 10.0 * math.exp(-1.0))
    assert g.state_at(2.0).pan_deg == pytest.approx(90.0) and g.state_at(2.0).tilt_deg == pytest.approx(-20.0)


def test_integration_is_exact_whatever_the_step() -> None:
    cfg = SimGimbalConfig(backlash_deg=0.5)
    fine, coarse = SimulatedGimbal(cfg), SimulatedGimbal(cfg)
    for g in (fine, coarse):
        g.command(30.0, 10.0)
        g.advance(0.1)
        g.command(-5.0, 12.0)
    for k in range(1, 401):
        fine.advance(0.1 + k * 0.001)
    a, b = fine.state_at(0.5), coarse.state_at(0.5)
    assert a.pan_deg == pytest.approx(b.pan_deg, abs=1e-9) and a.tilt_deg == pytest.approx(
        b.tilt_deg, abs=1e-9
    )


def test_backlash_hides_small_reversals() -> None:
    cfg = SimGimbalConfig(time_constant_s=0.02, latency_s=0.0, backlash_deg=1.0)
    g = SimulatedGimbal(cfg)
    g.command(10.0, 0.0)
    assert g.state_at(1.0).pan_deg == pytest.approx(9.5)  # the load trails the motor by half the play
    g.command(9.6, 0.0)
    assert g.state_at(2.0).pan_deg == pytest.approx(9.5)  # reversal inside the play: the load stays
    g.command(8.0, 0.0)
    assert g.state_at(3.0).pan_deg == pytest.approx(8.5)


def test_limits_determinism_and_clock() -> None:
    cfg = SimGimbalConfig(pan_limits=AxisLimits(-90.0, 90.0), tilt_limits=AxisLimits(-10.0, 45.0))
    runs = []
    for _ in range(2):
        g = SimulatedGimbal(cfg)
        g.command(500.0, -500.0)
        runs.append([g.state_at(k * 0.05) for k in range(60)])
        assert g.target.pan_deg == 90.0 and g.target.tilt_deg == -10.0
        assert g.read_position() == runs[-1][-1] and g.fault is None
        with pytest.raises(ValueError):
            g.advance(1.0)
    assert runs[0] == runs[1]
    assert runs[0][-1].pan_deg == pytest.approx(90.0, abs=0.2)


def test_open_servo_sim_options() -> None:
    g = open_servo("sim?latency=0.1&tau=0.2&rate=50&backlash=0")
    assert isinstance(g, SimulatedGimbal)
    assert g.config == SimGimbalConfig(
        time_constant_s=0.2, max_rate_deg_s=50.0, latency_s=0.1, backlash_deg=0.0
    )
