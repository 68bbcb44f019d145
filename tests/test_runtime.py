"""The runtime shared by `tmeye track` and `tmeye serve`: drop-oldest publishing that never blocks the
worker, pacing with skipped frames counted, operator servo control, live tuning and rig switching."""

from __future__ import annotations

import threading
import time

import pytest

from tmeye.runtime import Hub, Runtime, RuntimeConfig, ServoMode, ServoRequestError, TrackerTuning
from tmeye.runtime.compose import ComposeError
from tmeye.runtime.servo import ServoControl
from tracker.aim import AimController
from tracker.sim.scenarios import get_scenario


def test_a_full_subscription_drops_its_oldest_and_counts() -> None:
    hub: Hub[int] = Hub()
    slow = hub.subscribe(maxsize=3, name="slow")
    fast = hub.subscribe(maxsize=100, name="fast")
    for i in range(10):
        hub.publish(i)
    assert slow.drain() == [7, 8, 9] and slow.dropped == 7
    assert fast.drain() == list(range(10)) and fast.dropped == 0
    assert {s["name"]: s["dropped"] for s in hub.stats()} == {"slow": 7, "fast": 0}


def test_a_blocking_consumer_never_stalls_the_publisher() -> None:
    hub: Hub[int] = Hub()
    release = threading.Event()
    hub.subscribe(maxsize=2, notify=lambda: None, name="never-read")
    hub.subscribe(maxsize=2, notify=lambda: release.wait(0) or None, name="notify-ok")
    bad = hub.subscribe(maxsize=2, name="raises")
    bad.notify = lambda: (_ for _ in ()).throw(RuntimeError("loop closed"))
    t0 = time.perf_counter()
    for i in range(1000):
        hub.publish(i)
    assert time.perf_counter() - t0 < 5.0  # nothing waited (a generous bound: this is no benchmark)
    assert all(s["queued"] == 2 for s in hub.stats())


def test_subscriptions_made_first_are_notified_before_the_others_in_their_own_order() -> None:
    hub: Hub[int] = Hub()
    woken: list[str] = []
    for name, first in (("encoder", False), ("ws-1", True), ("writer", False), ("ws-2", True)):
        hub.subscribe(maxsize=2, notify=lambda n=name: woken.append(n), name=name, first=first)
    hub.publish(1)
    assert woken == ["ws-1", "ws-2", "encoder", "writer"]
    hub.unsubscribe(next(s for s in hub._subs if s.name == "ws-1"))
    woken.clear()
    hub.subscribe(maxsize=2, notify=lambda: woken.append("ws-3"), name="ws-3", first=True)
    hub.publish(2)
    assert woken == ["ws-2", "ws-3", "encoder", "writer"]


def test_subscription_get_ends_when_closed() -> None:
    hub: Hub[int] = Hub()
    sub = hub.subscribe(maxsize=4)
    hub.publish(1)
    hub.close()
    assert sub.get(0.1) == 1 and sub.get(0.1) is None and sub.closed


def test_a_finite_scenario_repeats_with_time_increasing() -> None:
    n = get_scenario("walk").frames
    rt = Runtime(RuntimeConfig(scenario="walk", servo=None, realtime=False, max_frames=n + 5, loop_source=True))
    sub = rt.hub.subscribe(maxsize=n + 10)
    rt.start()
    rt.join(120)
    evs = sub.drain()
    rt.stop()
    assert [e.frame_no for e in evs] == list(range(n + 5))  # the second pass goes on counting
    ts = [e.frame.t for e in evs]
    assert all(b > a for a, b in zip(ts, ts[1:], strict=False))
    assert rt.comp is not None and rt.comp.sim is not None
    assert rt.comp.sim.scene_t == pytest.approx(5 / get_scenario("walk").fps)  # the scene started again
    assert all(e.telemetry["objects"] >= 1 for e in evs[n + 1:])  # and the target is seen at its start


def test_runtime_runs_publishes_and_stops() -> None:
    rt = Runtime(RuntimeConfig(scenario="walk", servo=None, realtime=False, max_frames=20, loop_source=False))
    sub = rt.hub.subscribe(maxsize=100)
    rt.start()
    rt.join(60)
    evs = sub.drain()
    assert [e.frame_no for e in evs] == list(range(20)) and rt.state == "ended"
    assert sum(e.telemetry["detected"] for e in evs) >= 15
    assert sub.closed
    rt.stop()


def test_realtime_skips_frames_it_cannot_process_in_time() -> None:
    rt = Runtime(RuntimeConfig(scenario="walk", servo=None, realtime=True, loop_source=True))
    rt.start()
    assert rt.comp is not None
    slow = rt.comp.pipeline.step

    def step_slowly(frame):  # type: ignore[no-untyped-def]
        time.sleep(0.1)  # three frame periods
        return slow(frame)
    rt.comp.pipeline.step = step_slowly  # type: ignore[method-assign]
    sub = rt.hub.subscribe(maxsize=100)
    time.sleep(1.5)
    rt.stop()
    frames = [e.frame_no for e in sub.drain()][1:]  # the first may have started before the slow step
    gaps = [b - a for a, b in zip(frames, frames[1:], strict=False)]
    assert gaps and min(gaps) >= 3 and rt.skipped >= 2 * len(gaps)  # newest frame next, never a backlog
    assert rt.status()["skipped_frames"] == rt.skipped


def _closed_loop() -> Runtime:
    rt = Runtime(RuntimeConfig(scenario="walk", servo="sim", realtime=True, loop_source=True))
    rt.start()
    return rt


def _wait_angles(rt: Runtime, pan: float, tilt: float, timeout: float = 5.0) -> tuple[float, float]:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        ev = rt.latest
        if ev is not None and ev.servo is not None and abs(ev.servo.pan_deg - pan) < 0.5 \
                and abs(ev.servo.tilt_deg - tilt) < 0.5:
            return ev.servo.pan_deg, ev.servo.tilt_deg
        time.sleep(0.05)
    ev = rt.latest
    raise AssertionError(f"mount at {ev.servo if ev else None}, wanted {pan}, {tilt}")


def test_servo_modes_goto_and_jog() -> None:
    rt = _closed_loop()
    try:
        rt.servo_goto(15.0, 4.0).result(2)
        assert rt.servo is not None and rt.servo.mode is ServoMode.MANUAL
        _wait_angles(rt, 15.0, 4.0)
        with pytest.raises(ServoRequestError, match="outside the mount's range"):
            rt.servo_goto(15.0, 85.0).result(2)
        rt.servo_jog(10.0, 0.0, 1.0).result(2)
        _wait_angles(rt, 25.0, 4.0)
        rt.servo_mode(ServoMode.HOME).result(2)
        _wait_angles(rt, 0.0, 0.0)
        rt.servo_mode(ServoMode.AUTO).result(2)
        assert rt.servo.mode is ServoMode.AUTO and rt.servo.goal is None
    finally:
        rt.stop()


def test_a_jog_moves_rate_times_duration_and_repeated_jogs_keep_moving() -> None:
    dt = 1 / 30
    sc = ServoControl(AimController())
    sc.goto(0.0, 0.0)
    sc.jog(12.0, -6.0, 0.5)
    for k in range(1, 40):
        sc.tick(k * dt, dt)
    assert sc.goal == pytest.approx((6.0, -3.0))  # 12 and -6 deg/s for 0.5 s
    # a client repeating a short jog every frame (a gamepad polled each animation frame) moves at the rate
    sc.goto(0.0, 0.0)
    for k in range(40, 70):
        sc.jog(20.0, 0.0, 0.6)
        sc.tick(k * dt, dt)
    assert sc.goal is not None and sc.goal[0] == pytest.approx(20.0)  # 30 frames at 20 deg/s


def test_the_verify_and_sigma_budgets_apply_in_real_time_only() -> None:
    for realtime, want, want_sigma in ((True, 4.0, 3.0), (False, None, None)):
        rt = Runtime(RuntimeConfig(scenario="walk", servo=None, realtime=realtime, max_frames=2,
                                   verify_budget_ms=4.0, sigma_budget_ms=3.0))
        rt.start()
        try:
            assert rt.comp is not None and rt.comp.pipeline.schedule.budget_ms == want
            assert rt.comp.pipeline.sigma_schedule.budget_ms == want_sigma
        finally:
            rt.stop()
        assert rt.status()["deferred_boxes"] == rt.deferred_boxes >= 0
        assert rt.status()["reused_sigma"] >= 0


def test_in_real_time_the_worker_gives_the_pipeline_the_time_between_frames() -> None:
    for realtime in (True, False):
        rt = Runtime(RuntimeConfig(scenario="walk", servo=None, realtime=realtime, loop_source=True,
                                   max_frames=None if realtime else 40, verify_budget_ms=2.0, sigma_budget_ms=3.0))
        rt.start()
        try:
            assert rt.comp is not None
            pipe = rt.comp.pipeline
            deadline = time.monotonic() + 20.0
            while pipe.sigma_schedule.refreshed < 10 and rt.running and time.monotonic() < deadline:
                time.sleep(0.1)
            if not realtime:
                rt.join(20.0)  # 40 frames as fast as they go
            assert pipe.schedule.later is realtime
            # the walker tracked, its 1-σ terms worked out between frames in real time only
            assert (pipe.sigma_schedule.refreshed >= 10) is realtime
        finally:
            rt.stop()


def test_tuning_applies_from_the_next_frame_and_rejects_bad_fields() -> None:
    rt = Runtime(RuntimeConfig(scenario="walk", servo=None, realtime=True))
    rt.start()
    try:
        assert TrackerTuning().track_config().primary_hold_s == TrackerTuning().aim.loss_timeout_s == 1.5
        new = rt.tuning.updated({"detector": {"epsilon": 20}, "tracks": {"gate_px": 30.0},
                                 "aim": {"loss_timeout_s": 4.0}})
        rt.set_tuning(new).result(2)
        assert rt.comp is not None
        assert rt.comp.pipeline.subtractor.cfg.epsilon == 20 and rt.comp.pipeline.tracker.cfg.gate_px == 30.0
        # the primary target is given up when the aim gives it up
        assert rt.comp.pipeline.tracker.cfg.primary_hold_s == 4.0
        with pytest.raises(ValueError, match="primary_hold_s"):
            TrackerTuning().updated({"tracks": {"primary_hold_s": 2.0}})  # not a setting of its own
        with pytest.raises(ValueError, match="stride"):
            TrackerTuning().updated({"detector": {"stride": 2}})
        with pytest.raises(ValueError, match="unknown tracker settings section"):
            TrackerTuning().updated({"lens": {}})
    finally:
        rt.stop()


def test_rig_switch_keeps_frames_increasing() -> None:
    rt = Runtime(RuntimeConfig(scenario="walk", servo=None, realtime=True))
    rt.start()
    try:
        assert rt.comp is not None
        sub = rt.hub.subscribe(maxsize=1000)
        rig = rt.comp.rig
        rt.switch_rig(rig).result(60)
        time.sleep(0.5)
        evs = sub.drain()
        assert any(e.generation == 1 for e in evs) and evs[0].generation == 0
        frames = [e.frame_no for e in evs]
        assert all(b > a for a, b in zip(frames, frames[1:], strict=False))
    finally:
        rt.stop()


def test_bad_configuration_is_a_one_line_error() -> None:
    with pytest.raises(ComposeError, match="unknown scenario"):
        Runtime(RuntimeConfig(scenario="nope", servo=None)).start()
    with pytest.raises(ComposeError, match="needs a rig file"):
        Runtime(RuntimeConfig(source="files", inputs=("a.mp4", "b.mp4"), servo=None)).start()
    with pytest.raises(ValueError, match="two inputs"):
        RuntimeConfig(source="usb", inputs=("0",))


def test_a_failing_source_is_a_fault_not_a_dead_worker() -> None:
    rt = Runtime(RuntimeConfig(scenario="walk", servo=None, realtime=True))
    rt.start()
    try:
        assert rt.comp is not None
        good = rt.comp.source.read
        rt.comp.source.read = lambda: (_ for _ in ()).throw(OSError("camera unplugged"))  # type: ignore[method-assign]
        deadline = time.monotonic() + 5
        while not rt.status()["faults"] and time.monotonic() < deadline:
            time.sleep(0.05)
        assert rt.status()["faults"] == [{"kind": "source", "message": "OSError: camera unplugged"}]
        rt.comp.source.read = good  # type: ignore[method-assign]
        n = rt.frames
        deadline = time.monotonic() + 5
        while rt.frames <= n + 5 and time.monotonic() < deadline:
            time.sleep(0.05)
        assert rt.running and rt.frames > n + 5 and rt.status()["faults"] == []
    finally:
        rt.stop()


def _settle(rt: Runtime, seconds: float = 3.0) -> None:
    """Until the mount's angles stop changing (simulated gimbal)."""
    last = None
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        time.sleep(0.3)
        ev = rt.latest
        now = None if ev is None or ev.servo is None else (round(ev.servo.pan_deg, 3), round(ev.servo.tilt_deg, 3))
        if now is not None and now == last:
            return
        last = now


@pytest.mark.parametrize(("camera", "u", "v"), [("left", 560.0, 120.0), ("right", 90.0, 400.0)])
def test_click_to_point_centres_the_scene_point(camera: str, u: float, v: float) -> None:
    import numpy as np

    from tracker.geometry import gimbal_rotation

    rt = _closed_loop()
    try:
        rt.servo_mode(ServoMode.HOLD).result(2)
        _settle(rt)
        assert rt.comp is not None and rt.latest is not None and rt.comp.sim is not None
        g = rt.latest.frame.gimbal
        assert g is not None
        k = 0 if camera == "left" else 1
        cam = (rt.comp.rig.left, rt.comp.rig.right)[k]
        depth = rt.comp.sim.renderer.static_depth(g)[k]
        dist = float(depth[int(v), int(u)])  # the true distance along that pixel's ray
        d = cam.rays_rig(np.array([u]), np.array([v]))[0]
        X = gimbal_rotation(g.pan_deg, g.tilt_deg) @ (cam.c + dist * d)
        rt.servo_point(camera, u, v).result(2)
        _settle(rt)
        g2 = rt.latest.frame.gimbal
        assert g2 is not None
        px = cam.project((gimbal_rotation(g2.pan_deg, g2.tilt_deg).T @ X)[None, :])[0]
        off = float(np.hypot(*(px - cam.K[:2, 2])))
        assert off <= 0.01 * cam.size[0], (camera, px, off)
    finally:
        rt.stop()
