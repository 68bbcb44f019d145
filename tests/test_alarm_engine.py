"""The alarm engine alone: conditions in metres, delays, the ISA-18.2 lifecycle, shelving, flood."""

from __future__ import annotations

import pytest

from server.alarms.conditions import (
    Approach,
    Lost,
    RangeBelow,
    Size,
    Snapshot,
    Target,
    Zone,
    condition_from_dict,
    condition_to_dict,
)
from server.alarms.engine import AlarmEngine, AlarmStateError, Rule

BOX = Zone("box", x_min=-1, x_max=1, z_min=5, z_max=8)


def at(t: float, *targets: Target, frame: int | None = 0, primary: int | None = None,
       closing: float | None = None, faults: dict[str, str] | None = None, servo_mode: str | None = None) -> Snapshot:
    return Snapshot(t, frame, tuple(targets), primary, closing, faults or {}, servo_mode)


def person(x: float = 0.0, z: float = 6.0, tid: int = 1, w: float = 0.5, h: float = 1.7) -> Target:
    return Target(tid, x, 0.5, z, (x * x + z * z) ** 0.5, w, h)


def engine(cond: object, on: float = 0.0, off: float = 0.0, **kw: object) -> AlarmEngine:
    return AlarmEngine([Rule("rule:1", "r", "high", cond, on, off)], builtin=False, **kw)  # type: ignore[arg-type]


def kinds(trs: list[object]) -> list[str]:
    return [t.kind for t in trs]  # type: ignore[attr-defined]


def run(e: AlarmEngine, frames: list[Snapshot]) -> list[tuple[float, str]]:
    return [(tr.t, tr.kind) for s in frames for tr in e.step(s)]


def test_zone_activates_on_the_confirming_frame_and_clears_after_the_off_delay() -> None:
    e = engine(BOX, off=0.5)
    dt = 1 / 30
    inside = [at(k * dt, person(z=6.0), frame=k) for k in range(10)]
    outside = [at((10 + k) * dt, person(z=9.0), frame=10 + k) for k in range(30)]
    got = run(e, inside + outside)
    assert got[0] == (pytest.approx(dt), "activated")  # the second frame confirms the track
    assert got[1][1] == "cleared" and got[1][0] == pytest.approx(10 * dt + 0.5, abs=dt)
    assert e.points["rule:1"].state == "rtn_unack"


def test_cylinder_dwell_and_off_delay_hold_back_chatter() -> None:
    e = engine(Zone("cylinder", center_x=0, center_z=10, radius=2, dwell_s=0.2), off=1.0)
    snaps = []
    for k in range(90):  # 3 s at 30 fps; the target steps out for 0.3 s in the middle
        out = 45 <= k < 54
        snaps.append(at(k / 30, person(x=3.0 if out else 0.5, z=10), frame=k))
    got = run(e, snaps)
    assert kinds_of(got) == ["activated"]
    assert got[0][0] == pytest.approx(7 / 30, abs=1e-6)  # confirmed at frame 1, then 0.2 s of dwell


def kinds_of(got: list[tuple[float, str]]) -> list[str]:
    return [k for _, k in got]


def test_on_delay() -> None:
    e = engine(RangeBelow(5.0), on=0.5)
    got = run(e, [at(k / 10, person(z=4.0), frame=k) for k in range(10)])
    assert got == [(pytest.approx(0.6), "activated")]  # raw from 0.1 (confirmed), held 0.5 s


def test_approach_needs_speed_for_a_time_and_lost_and_size() -> None:
    e = engine(Approach(2.0, for_s=0.5))
    snaps = [at(k / 10, person(), frame=k, primary=1, closing=3.0 if k >= 3 else 1.0) for k in range(12)]
    assert run(e, snaps) == [(pytest.approx(0.8), "activated")]
    e = engine(Lost(1.0))
    snaps = [at(k / 10, person(), frame=k, primary=1) for k in range(5)]
    snaps += [at(k / 10, frame=k) for k in range(5, 30)]
    assert run(e, snaps) == [(pytest.approx(1.5), "activated")]  # last seen at 0.4 s
    e = engine(Size(0.3, 1.0, 1.2, 2.2))
    assert kinds(e.step(at(0, person(w=3, h=1.5))) + e.step(at(0.1, person(w=3, h=1.5)))) == []
    assert kinds(e.step(at(0.2, person(tid=2))) + e.step(at(0.3, person(tid=2)))) == ["activated"]


def test_a_single_frame_detection_raises_nothing_and_ticks_hold_the_value() -> None:
    e = engine(BOX)
    assert e.step(at(0, person(tid=7))) == []
    assert e.step(at(0.1, person(tid=8, z=20))) == []
    assert e.step(at(0.2, person(tid=8))) == []  # inside in one frame of the track so far
    assert kinds(e.step(at(0.3, person(tid=8)))) == ["activated"]
    assert e.step(at(5.0, frame=None)) == []  # no frame: still active
    assert e.points["rule:1"].active


def test_one_frame_whose_position_is_off_raises_nothing() -> None:
    """A confirmed track measured inside the zone in one frame only (a disparity outlier near the zone's
    far face) raises nothing; two frames in a row do."""
    e = engine(BOX)
    frames = [person(z=8.6), person(z=8.5), person(z=7.9), person(z=8.5), person(z=8.4)]
    assert [kinds(e.step(at(0.1 * i, p))) for i, p in enumerate(frames)] == [[]] * 5
    assert e.step(at(0.5, person(z=7.8))) == []
    assert kinds(e.step(at(0.6, person(z=7.7)))) == ["activated"]


def test_lifecycle_ack_then_clear_and_clear_before_ack() -> None:
    e = engine(RangeBelow(5.0))
    e.step(at(0, person(z=4)))
    a = e.step(at(0.1, person(z=4)))[0]
    assert (a.state_from, a.state_to, a.opened, a.target_id) == ("normal", "unack", True, 1)
    ack = e.ack("rule:1", 0.2, "op", "seen it")[0]
    assert (ack.state_to, ack.user, ack.comment, ack.occurrence) == ("ack", "op", "seen it", a.occurrence)
    with pytest.raises(AlarmStateError):
        e.ack("rule:1", 0.3, "op")
    c = e.step(at(0.4, person(z=9)))[0]
    assert (c.kind, c.state_to) == ("cleared", "normal")
    # a second occurrence, cleared before acknowledgement, re-alarms, then is acknowledged
    assert e.step(at(0.9, person(z=4))) == []  # a condition counts from its second frame in a row
    b = e.step(at(1.0, person(z=4)))[0]
    assert b.opened and b.occurrence != a.occurrence
    assert e.step(at(1.2, person(z=9)))[0].state_to == "rtn_unack"
    assert e.step(at(1.25, person(z=4))) == []
    again = e.step(at(1.3, person(z=4)))[0]
    assert (again.state_from, again.state_to, again.opened, again.occurrence) == ("rtn_unack", "unack", False,
                                                                                  b.occurrence)
    e.step(at(1.4, person(z=9)))
    done = e.ack("rule:1", 1.5, "op")[0]
    assert (done.state_from, done.state_to) == ("rtn_unack", "normal")
    assert e.points["rule:1"].occurrence is None


def test_timed_shelving_with_a_reason_unshelve_and_expiry() -> None:
    e = engine(RangeBelow(5.0), max_shelve_s=3600)
    e.step(at(0, person(z=4)))
    e.step(at(0.1, person(z=4)))
    with pytest.raises(AlarmStateError):
        e.shelve("rule:1", 0.2, "op", 61, "too long")
    with pytest.raises(AlarmStateError):
        e.shelve("rule:1", 0.2, "op", 5, " ")
    s = e.shelve("rule:1", 0.2, "op", 1, "maintenance")[0]
    assert s.state_to == "shelved" and e.points["rule:1"].shelved_until == pytest.approx(60.2)
    assert e.step(at(30, person(z=4))) == []  # shelved: nothing raised
    u = e.step(at(60.3, person(z=4)))
    assert [(x.kind, x.state_to, x.comment) for x in u] == [("unshelved", "unack", "shelving expired")]
    e.shelve("rule:1", 61, "op", 1, "again")
    e.step(at(62, person(z=9)))  # clears while shelved
    u = e.unshelve("rule:1", 63, "op")[0]
    assert (u.state_to, u.user) == ("normal", "op") and e.points["rule:1"].occurrence is None


def test_out_of_service_and_back() -> None:
    rule = Rule("rule:1", "r", "low", RangeBelow(5.0))
    e = AlarmEngine([rule], builtin=False)
    e.step(at(0, person(z=4)))
    e.step(at(0.1, person(z=4)))
    t = e.set_rule(Rule("rule:1", "r", "low", RangeBelow(5.0), out_of_service=True), 0.2, "admin")
    assert [(x.kind, x.state_to, x.user) for x in t] == [("out_of_service", "out_of_service", "admin")]
    assert e.step(at(0.3, person(z=4))) == []
    t = e.set_rule(rule, 0.4, "admin")
    assert kinds(t) == ["in_service"]
    assert kinds(e.step(at(0.5, person(z=4)))) == ["activated"]


def test_device_faults_are_built_in() -> None:
    e = AlarmEngine()
    tr = e.step(at(0, frame=None, faults={"servo": "Maestro port /dev/x lost"}))
    assert [(x.rule, x.priority, x.message) for x in tr] == [("fault:servo", "high", "Maestro port /dev/x lost")]
    assert kinds(e.step(at(0.5, frame=None))) == ["cleared"]


def test_flood_above_ten_new_alarms_in_ten_minutes_ends_below_five() -> None:
    e = engine(RangeBelow(5.0))
    t, events = 0.0, []
    for _ in range(11):  # eleven activations 20 s apart
        for z in (4, 4, 9):
            events += e.step(at(t, person(z=z)))
            t += 1.0
        e.ack("rule:1", t, "op") if e.points["rule:1"].state != "normal" else None
        t += 17.0
    assert "flood" in kinds(events) and e.flood
    for k in range(60):
        events += e.step(at(t + 10.0 * k, frame=None))
    assert kinds(events).count("flood_end") == 1 and not e.flood
    end = next(x for x in events if x.kind == "flood_end")
    assert end.t >= 20 * 6 + 600 - 20  # the seventh activation has left the window


def test_condition_json_round_trip_and_errors() -> None:
    d = {"kind": "zone", "shape": "box", "x_min": -1, "x_max": 1, "z_min": 5, "z_max": 8, "dwell_s": 2}
    assert condition_to_dict(condition_from_dict(d)) == {**{k: float(v) for k, v in d.items() if k not in
                                                            ("kind", "shape")}, "kind": "zone", "shape": "box"}
    for bad, msg in [({"kind": "zone", "x_min": 2, "x_max": 1, "z_min": 0, "z_max": 1}, "x_min"),
                     ({"kind": "range_below"}, "distance_m is required"),
                     ({"kind": "range_below", "distance_m": -1}, "at least 0"),
                     ({"kind": "zone", "shape": "sphere"}, "box or cylinder"),
                     ({"kind": "teleport"}, "kind must be")]:
        with pytest.raises(ValueError, match=msg):
            condition_from_dict(bad)


def test_device_faults_from_health() -> None:
    from server.alarms.faults import FaultThresholds, Health, device_faults

    th = FaultThresholds(stall_s=0.5, fps_floor=10.0, disk_min_bytes=100)
    ok = Health(now=100.0, runtime_state="running", last_frame_at=99.9, up_s=50, frame_rate=30.0,
                disk_free_bytes=1000)
    assert device_faults(ok, th) == {}
    stalled = device_faults(Health(now=100.0, runtime_state="running", last_frame_at=99.2, up_s=50,
                                   frame_rate=3.0), th)
    assert set(stalled) == {"camera"} and "no frame for 0.8 s" in stalled["camera"]
    assert "gone: OSError" in device_faults(Health(100.0, "running", source_fault="OSError: x", up_s=9), th)["camera"]
    assert "ended" in device_faults(Health(100.0, "ended", up_s=9), th)["camera"]
    slow = device_faults(Health(100.0, "running", last_frame_at=100.0, up_s=9, frame_rate=7.5, servo="lost",
                                recording="disk full", database="locked", disk_free_bytes=10), th)
    assert set(slow) == {"frame_rate", "servo", "recording", "database", "disk"}
    assert device_faults(Health(100.0, "running", up_s=2.0), th) == {}  # the first frame may take a while
    assert "no frame 6.0 s after the start" in device_faults(Health(100.0, "running", up_s=6.0), th)["camera"]


def test_a_detection_gap_inside_the_zone_holds_and_a_new_id_nearby_ends_the_hold() -> None:
    e = engine(BOX, off=0.5)
    dt = 1 / 30
    snaps = [at(k * dt, person(z=6.0), frame=k) for k in range(10)]
    snaps += [at(k * dt, frame=k) for k in range(10, 55)]  # 1.5 s without a detection: still inside
    snaps += [at(k * dt, person(z=6.1, tid=5), frame=k) for k in range(55, 60)]
    assert kinds_of(run(e, snaps)) == ["activated"]
    e = engine(BOX, off=0.5)
    snaps = [at(k * dt, person(z=6.0), frame=k) for k in range(10)]
    snaps += [at(k * dt, person(x=1.05, tid=2), frame=k) for k in range(10, 40)]  # taken up as 2, outside
    got = run(e, snaps)
    assert kinds_of(got) == ["activated", "cleared"]
    assert got[1][0] == pytest.approx(10 * dt + 0.5, abs=dt)  # cleared after the off-delay, not the 2 s hold
    e = engine(BOX)
    snaps = [at(k * dt, person(z=6.0), frame=k) for k in range(10)] + [at(k * dt, frame=k) for k in range(10, 80)]
    got = run(e, snaps)
    assert kinds_of(got) == ["activated", "cleared"] and got[1][0] == pytest.approx(9 * dt + 2.0, abs=2 * dt)


def test_approach_deadband_and_unknown_speed() -> None:
    e = engine(Approach(1.0, for_s=0.0, deadband_mps=0.3), off=0.0)
    speeds = [1.2, 0.9, 0.8, 0.75, None, None, 0.9, 0.6, 0.6]
    got = run(e, [at(k / 10, person(), frame=k, primary=1, closing=v) for k, v in enumerate(speeds)])
    assert got == [(0.0, "activated"), (pytest.approx(0.7), "cleared")]  # under 0.7 m/s only at 0.7 s
    e = engine(Approach(1.0, for_s=0.3))  # one wild sample, then the speed unknown: for_s does not pass
    speeds = [0.2, 9.0, None, None, None, None, None, 0.2]
    assert run(e, [at(k / 10, person(), frame=k, primary=1, closing=v) for k, v in enumerate(speeds)]) == []
    with pytest.raises(ValueError, match="deadband_mps"):
        condition_from_dict({"kind": "approach", "speed_mps": 0.5, "deadband_mps": 0.6})


def test_one_shot_shelving_lasts_until_the_alarm_clears() -> None:
    e = engine(RangeBelow(5.0), off=0.5, max_shelve_s=3600)
    e.step(at(0, person(z=4)))
    e.step(at(0.1, person(z=4)))
    with pytest.raises(AlarmStateError, match="not both"):
        e.shelve("rule:1", 0.2, "op", 5, "x", one_shot=True)
    s = e.shelve("rule:1", 0.2, "op", None, "checking the gate", one_shot=True)[0]
    assert (s.state_to, s.one_shot, s.until) == ("shelved", True, pytest.approx(3600.2))
    assert e.step(at(10.0, person(z=4))) == [] and e.step(at(10.2, person(z=9))) == []  # off-delay not yet over
    u = e.step(at(10.8, person(z=9)))
    assert [(x.kind, x.state_to, x.comment) for x in u] == [("unshelved", "normal",
                                                            "one-shot shelving ended: the alarm cleared")]
    assert e.points["rule:1"].occurrence is None
    assert e.step(at(10.9, person(z=4))) == []
    b = e.step(at(11.0, person(z=4)))  # the next activation is annunciated again
    assert [(x.kind, x.opened) for x in b] == [("activated", True)]
    e.step(at(11.1, person(z=9)))
    e.step(at(11.7, person(z=9)))  # cleared, unacknowledged: one-shot shelving has nothing to wait for
    with pytest.raises(AlarmStateError, match="has cleared"):
        e.shelve("rule:1", 11.8, "op", None, "x", one_shot=True)


def test_a_lost_rule_is_suppressed_by_design_while_the_mount_is_not_in_auto() -> None:
    e = engine(Lost(1.0))
    snaps = [at(k / 10, person(), frame=k, primary=1) for k in range(5)]
    snaps += [at(k / 10, frame=k) for k in range(5, 20)]  # lost from 0.5 s: active at 1.5 s
    got = [tr for s in snaps for tr in e.step(s)]
    assert [x.kind for x in got] == ["activated"]
    manual = [at(k / 10, frame=k, servo_mode="manual") for k in range(20, 60)]
    got = [tr for s in manual for tr in e.step(s)]
    assert [(x.kind, x.state_to, x.occurrence is not None) for x in got] == [("suppressed", "suppressed", True)]
    assert "manual mode" in (got[0].message or "") and e.points["rule:1"].state == "suppressed"
    with pytest.raises(AlarmStateError):
        e.shelve("rule:1", 6.0, "op", 5, "x")
    auto = [at(k / 10, frame=k, servo_mode="auto") for k in range(60, 90)]
    got = [(tr.t, tr.kind) for s in auto for tr in e.step(s)]
    assert got == [(6.0, "unsuppressed"), (pytest.approx(7.1), "activated")]  # the lost clock started afresh
    e2 = engine(Zone("box", x_min=-1, x_max=1, z_min=5, z_max=8))
    assert [x.kind for s in (at(0, person(), servo_mode="manual"), at(0.1, person(), servo_mode="manual"))
            for x in e2.step(s)] == ["activated"]  # other rules are not suppressed


def test_flood_per_logged_in_operator() -> None:
    e = engine(RangeBelow(5.0))
    e.set_operators({"olga": 0.0, "oscar": 150.0})
    t, events = 0.0, []
    for _ in range(12):  # twelve activations 20 s apart from 0 to 220 s
        for z in (4, 4, 9):
            events += e.step(at(t, person(z=z)))
            t += 1.0
        e.ack("rule:1", t, "op") if e.points["rule:1"].state != "normal" else None
        t += 17.0
    floods = [(x.kind, x.user) for x in events if x.kind.startswith("flood")]
    assert floods == [("flood", "olga")]  # oscar logged in at 150 s: 4 of the 12 were annunciated to him
    assert e.flooded("olga") and not e.flooded("oscar") and e.recent_count("oscar") == 4
    e.set_operators({"oscar": 150.0})  # olga logged out: she is out of flood, silently
    assert not e.flood and e.step(at(t, frame=None)) == []
