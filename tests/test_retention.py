"""The retention engine alone: age per kind, the quota, oldest unlocked first, never a locked or open one."""

from __future__ import annotations

from server.services.retention import DAY_S, Policy, SegmentInfo, locked, to_delete

NOW = 1_800_000_000.0


def seg(i: int, start: float, kind: str = "continuous", size: int = 100, open_: bool = False) -> SegmentInfo:
    return SegmentInfo(i, kind, start, None if open_ else start + 10.0, size)


def test_age_per_kind() -> None:
    segs = [seg(1, NOW - 8 * DAY_S), seg(2, NOW - 8 * DAY_S, "event"), seg(3, NOW - 31 * DAY_S, "event"),
            seg(4, NOW - 60)]
    policy = Policy({"continuous": 7, "event": 30})
    assert to_delete(segs, [], policy, NOW) == [3, 1]


def test_quota_deletes_oldest_unlocked_first_never_locked() -> None:
    segs = [seg(i, NOW - 1000 + 10 * i) for i in range(10)]  # 10 x 100 bytes, oldest id 0
    locks = [(NOW - 1000 + 5, NOW - 1000 + 12)]  # overlaps segments 0 and 1
    out = to_delete(segs, locks, Policy({"continuous": 7}, quota_bytes=550), NOW)
    assert out == [2, 3, 4, 5, 6]
    assert not {0, 1} & set(out)


def test_quota_unreachable_with_locks_keeps_them() -> None:
    segs = [seg(i, NOW - 100 + 10 * i) for i in range(3)]
    locks = [(NOW - 200, NOW)]
    assert to_delete(segs, locks, Policy({"continuous": 7}, quota_bytes=1), NOW) == []


def test_open_segment_is_never_deleted() -> None:
    segs = [seg(1, NOW - 9 * DAY_S, open_=True), seg(2, NOW - 50)]
    assert to_delete(segs, [], Policy({"continuous": 7}, quota_bytes=1), NOW) == [2]


def test_no_quota_no_age_deletes_nothing() -> None:
    segs = [seg(i, NOW - 100 * i) for i in range(5)]
    assert to_delete(segs, [], Policy({"continuous": 7}), NOW) == []


def test_locked_overlap_edges() -> None:
    s = seg(1, 100.0)  # 100..110
    assert locked(s, [(110.0, 120.0)]) and locked(s, [(90.0, 100.0)]) and not locked(s, [(110.5, 120.0)])
