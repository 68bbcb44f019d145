"""The endless simulated scene (`endless`): people come and go for ever, deterministic for a seed; finite
scenarios stay finite and can be looped with SimRig.rewind()."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tracker.closedloop import survey_grid
from tracker.closedloop_eval import mount_range
from tracker.sim import endless
from tracker.sim.endless import EndlessScene
from tracker.sim.scenarios import SCENARIOS, SimRig, get_scenario
from tracker.sim.scene import CAMERA_HEIGHT_M

DT = 0.1  # s, sampling step of the scene-level checks


def _samples(scene: EndlessScene, until_s: float) -> list[tuple[float, int, np.ndarray]]:
    """(t, target id, centre) of every object present, every DT seconds up to until_s."""
    return [(t, o.target_id, o.trajectory(t)) for t in np.arange(0.0, until_s, DT) for o in scene.present(t)]


def test_endless_is_a_scenario_and_the_others_are_finite() -> None:
    sc = get_scenario("endless")
    assert sc.endless and sc.foliage and sc.frames > 0  # frames: the length of bounded runs (eval, bench)
    assert not any(s.endless for name, s in SCENARIOS.items() if name != "endless")


def test_the_rig_is_never_exhausted_and_people_appear() -> None:
    sim = SimRig(get_scenario("endless"), seed=2)
    seen = 0
    for i in range(600):  # 20 s, gimbal still (the scenario's schedule)
        assert not sim.exhausted
        frame = sim.read()
        assert frame is not None and frame.index == i and frame.t == pytest.approx(i / 30.0)
        assert sim.last_truth is not None
        seen += bool(np.any(sim.last_truth.ids_left == 1))
    assert seen > 100


def test_deterministic_for_a_seed() -> None:
    a, b, c = (SimRig(get_scenario("endless"), seed=s) for s in (3, 3, 4))
    for _ in range(150):
        fa, fb, fc = a.step(), b.step(), c.step()
    assert np.array_equal(fa.frame.left, fb.frame.left) and np.array_equal(fa.frame.right, fb.frame.right)
    assert np.array_equal(fa.truth.ids_left, fb.truth.ids_left)
    assert not np.array_equal(fa.frame.left, fc.frame.left)
    # the scene itself, whatever order its times are asked in
    forward, backward = EndlessScene(7), EndlessScene(7)
    times = np.arange(0.0, 300.0, 0.7)
    ahead = [[(o.target_id, tuple(o.trajectory(t))) for o in forward.present(t)] for t in times]
    behind = [[(o.target_id, tuple(o.trajectory(t))) for o in backward.present(t)] for t in times[::-1]]
    assert ahead == behind[::-1]
    assert [forward.gain(t) for t in times] == [backward.gain(t) for t in times]


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_people_come_and_go_within_bounded_times(seed: int) -> None:
    scene = EndlessScene(seed)
    episodes = scene.episodes_until(1800.0)
    assert episodes[0].start <= endless.GAP_S[1]
    for ep, nxt in zip(episodes, episodes[1:], strict=False):
        assert ep.actors[0].target_id == 1 and all(a.target_id == 2 for a in ep.actors[1:])
        assert 5.0 < ep.end - ep.start < 120.0  # the last of them has left within two minutes
        assert endless.GAP_S[0] <= nxt.start - ep.end <= endless.GAP_S[1]  # the next comes within seconds
        assert not scene.present(0.5 * (ep.end + nxt.start))  # nobody between episodes
    assert any(len(ep.actors) > 1 for ep in episodes)  # now and then a second object
    kinds = {a.half_h_m is None for ep in episodes for a in ep.actors[1:]}
    assert kinds == {True, False}  # the plate and second people both occur


@pytest.mark.parametrize("seed", [0, 5])
def test_ranges_directions_and_walking(seed: int) -> None:
    scene = EndlessScene(seed)
    samples = _samples(scene, 900.0)
    people = [(t, p) for t, tid, p in samples if tid == 1]
    pts = np.array([p for _, p in people])
    ground = np.hypot(pts[:, 0], pts[:, 2])
    assert ground.min() >= 3.0 and np.linalg.norm(pts, axis=1).max() <= 30.0
    az = np.degrees(np.arctan2(pts[:, 0], pts[:, 2]))
    assert np.abs(az).max() <= endless.EDGE_AZ_DEG + 1e-9 and np.abs(az).max() > 35.0
    assert np.allclose(pts[:, 1], CAMERA_HEIGHT_M - endless.PERSON_HALF_H_M)  # standing on the ground
    # walking speed at most 1.8 m/s, and people stop (for a second or more) and walk on
    speeds = np.array([np.hypot(*(p1 - p0)[[0, 2]]) / DT for (t0, p0), (t1, p1) in
                       zip(people, people[1:], strict=False)
                       if abs(t1 - t0 - DT) < 1e-6])
    assert speeds.max() <= endless.SPEED_M_S[1] + 1e-6 and speeds.max() > 1.0
    still = speeds < 1e-9
    runs = np.diff(np.flatnonzero(np.diff(np.r_[0, still.astype(int), 0])))[::2]  # lengths of still runs
    assert (runs >= round(1.0 / DT)).sum() >= 10
    # every object's direction is inside the mount range the closed loop surveys
    (p0, p1), (t0, t1) = mount_range(get_scenario("endless"))
    for _, _, p in samples:
        assert p0 <= math.degrees(math.atan2(p[0], p[2])) <= p1
        assert t0 <= -math.degrees(math.atan2(p[1], math.hypot(p[0], p[2]))) <= t1


def test_light_ramps_and_steps() -> None:
    gain = EndlessScene(0).gain
    g = np.array([gain(t) for t in np.arange(0.0, 900.0, 1 / 30)])
    assert g.min() >= 0.65 - 1e-9 and g.max() <= 1.35 + 1e-9 and g.max() - g.min() > 0.3
    jumps = np.abs(np.diff(g)) / g[:-1]
    assert ((jumps > 0.15) & (jumps < 0.31)).sum() >= 5  # steps of ±20-30 %
    assert (jumps > 0.31).sum() == 0
    assert ((jumps > 1e-4) & (jumps < 0.01)).sum() > 300  # slow ramps


def test_person_truth_is_an_upright_board() -> None:
    sim = SimRig(get_scenario("endless"), seed=2, noise_sigma=0.0)
    checked = 0
    for _ in range(600):
        sf = sim.step()
        tt = sf.truth.target(1)
        if tt is None or tt.centroid_left is None:
            continue
        v, u = np.nonzero(sf.truth.ids_left == 1)
        inside = u.min() > 2 and u.max() < 637 and v.min() > 2 and v.max() < 477
        # fully in view, not hidden by the bush, the post or the hedge (its area is what 0.5 x 1.7 m covers)
        if not inside or np.any(sf.truth.ids_left == 2) or tt.visible_fraction < 0.95:
            continue
        w, h = u.max() - u.min() + 1, v.max() - v.min() + 1
        assert h / w == pytest.approx(1.7 / 0.5, rel=0.15)
        checked += 1
    assert checked > 50


def test_finite_scenarios_stay_finite_and_rewind_loops_them() -> None:
    sim = SimRig(get_scenario("walk"), seed=1)
    first = [sim.step().truth for _ in range(300)]
    assert sim.exhausted and sim.read() is None
    sim.rewind()
    assert not sim.exhausted and sim.scene_t == 0.0
    again = sim.step()
    assert again.frame.index == 300 and again.frame.t == pytest.approx(10.0)  # time keeps counting
    assert again.truth.t == pytest.approx(10.0)
    tt0, tt1 = first[0].target(1), again.truth.target(1)
    assert tt0 is not None and tt1 is not None and np.array_equal(tt0.world, tt1.world)  # the scene restarts
    for _ in range(299):
        assert sim.read() is not None
    assert sim.exhausted and sim.read() is None


def test_mount_range_of_the_endless_scene_is_fixed_and_surveyed_in_two_rows() -> None:
    pan, tilt = mount_range(get_scenario("endless"))
    assert pan == (-40.0, 40.0)
    assert tilt[0] <= -16.0 and 4.0 <= tilt[1] <= 8.0
    poses = survey_grid(pan, tilt)
    assert len({g.tilt_deg for g in poses}) == 2 and {g.pan_deg for g in poses} >= {-40.0, 40.0}


def test_eval_runs_a_bounded_number_of_frames() -> None:
    from tracker.evaluation import run_scenario

    report = run_scenario("endless", frames=20, seed=0)
    assert report.frames == 20 and report.false_target_frames == 0
