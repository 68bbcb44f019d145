"""Closed loop through the simulator: the pipeline, IMM and aim controller drive the simulated gimbal."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tracker.aim import AimConfig, AimController
from tracker.closedloop import LoopConfig, ServoLoop, background_range, survey_grid
from tracker.closedloop_eval import closed_loop_imm, closed_loop_pipeline, run_loop
from tracker.closedloop_path import MANOEUVRE, Leg, LegPath
from tracker.frames import GimbalState
from tracker.sim.scenarios import SimRig, get_scenario


@pytest.fixture(scope="module")
def short_run() -> object:
    return run_loop("manoeuvre", seed=0, frames=80, predictive=True)


def test_short_manoeuvre_stays_centred_without_loss(short_run: object) -> None:
    rec = short_run
    assert rec.frames == 80  # type: ignore[attr-defined]
    assert rec.in_zone == rec.frames  # type: ignore[attr-defined]
    assert rec.losses == 0  # type: ignore[attr-defined]
    assert math.sqrt(float(np.mean(np.square(rec.offsets_pct)))) < 2.0  # type: ignore[attr-defined]
    assert rec.detection.detection_rate > 0.95  # type: ignore[attr-defined]


def test_the_mount_really_follows(short_run: object) -> None:
    """By 2.6 s the target is at azimuth +38°, beyond the half field of view (28°): the cameras panned."""
    samples = short_run.samples  # type: ignore[attr-defined]
    assert math.degrees(math.atan2(samples[-1].truth[0], samples[-1].truth[2])) > 35.0
    assert short_run.commands > 20  # type: ignore[attr-defined]


def test_manoeuvre_path_shape() -> None:
    assert MANOEUVRE.duration_s == pytest.approx(9.8)
    az = [math.degrees(math.atan2(p[0], p[2])) for p in (MANOEUVRE(t) for t in np.arange(0, 9.8, 0.05))]
    assert max(az) - min(az) > 56.0  # more than the horizontal field of view
    assert MANOEUVRE.turn_rate(1.5) == pytest.approx(math.radians(25.0))
    assert MANOEUVRE.turning(0.0, 0.9) is False and MANOEUVRE.turning(0.9, 1.1) is True


def test_leg_path_turns_a_quarter_circle() -> None:
    """1 s at 6 m/s then 3 s turning 30°/s: a quarter circle of radius v/ω."""
    p = LegPath((Leg(1.0, accel=6.0), Leg(3.0, turn_deg_s=30.0), Leg(0.0, accel=-1.0)), (0.0, 0.0), 0.0,
                lambda t: 0.0)
    radius = 6.0 / math.radians(30.0)
    start, end = p(1.0), p(4.0)
    assert end[0] - start[0] == pytest.approx(radius, abs=0.02)
    assert end[2] - start[2] == pytest.approx(radius, abs=0.02)


def test_survey_grid_and_background_range() -> None:
    grid = survey_grid((-36.0, 42.0), (-6.0, 3.0))
    pans = sorted({g.pan_deg for g in grid})
    assert {g.tilt_deg for g in grid} == {-1.5} and pans[0] == -36.0 and pans[-1] == 42.0
    assert max(np.diff(pans)) <= 28.0  # half the field of view: neighbouring views overlap by half
    pan_r, tilt_r = background_range((-10.0, 10.0), (-2.0, 2.0), (640, 480), 600.0)
    assert 0.0 < pan_r < 25.0 and 0.0 < tilt_r < 12.0
    assert background_range((-40.0, 40.0), (0.0, 0.0), (640, 480), 600.0)[0] > 60.0


class FaultyDriver:
    """A ServoDriver whose device stopped answering after the first command."""

    def __init__(self) -> None:
        self.fault: str | None = None
        self.commands: list[tuple[float, float]] = []

    def command(self, pan_deg: float, tilt_deg: float) -> None:
        self.commands.append((pan_deg, tilt_deg))
        self.fault = "no reply from servo board on /dev/ttyFAKE within 0.3 s"

    def read_position(self) -> GimbalState | None:
        return None

    def close(self) -> None:
        pass


def test_a_failing_driver_is_reported_and_not_hammered() -> None:
    scenario = get_scenario("manoeuvre")
    sim = SimRig(scenario, seed=0)
    pipe = closed_loop_pipeline(sim, scenario)
    drv = FaultyDriver()
    loop = ServoLoop(pipe, AimController(AimConfig(focal_px=pipe.rect.f)), closed_loop_imm(), drv,
                     LoopConfig(retry_interval_s=60.0))
    steps = [loop.step(sim.step(GimbalState()).frame) for _ in range(25)]
    assert len(drv.commands) == 1  # once faulted, commands wait for the retry interval
    faulted = [s for s in steps if s.fault is not None]
    assert faulted and all(s.servo_json()["fault"] == drv.fault for s in faulted)
    assert all(s.result.primary is not None for s in steps[2:])  # the tracker keeps tracking


def test_a_new_primary_target_is_followed_afresh() -> None:
    """When the primary target changes (the tracker handing the role on, or an operator's choice), the
    predictor starts again from the new target's first measurement instead of taking it as the old one's
    next (an initialisation: no innovation)."""
    scenario = get_scenario("manoeuvre")
    sim = SimRig(scenario, seed=0)
    pipe = closed_loop_pipeline(sim, scenario)
    loop = ServoLoop(pipe, AimController(AimConfig(focal_px=pipe.rect.f)), closed_loop_imm(), None)
    steps = [loop.step(sim.step(GimbalState()).frame) for _ in range(8)]
    assert steps[-1].result.primary_id == 1 and steps[-1].estimate is not None
    assert steps[-1].estimate.nis is not None  # updating track 1
    pipe.tracker.tracks.clear()  # the same object now begins track 2
    steps = [loop.step(sim.step(GimbalState()).frame) for _ in range(3)]
    assert [s.result.primary_id for s in steps] == [None, 2, 2]
    est = [s.estimate for s in steps]
    assert est[1] is not None and est[1].state is not None and est[1].nis is None  # begun again
    assert est[2] is not None and est[2].nis is not None
