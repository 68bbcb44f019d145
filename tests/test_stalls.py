"""The runtime's stall log: the longest interval between published frames over a window, in fixed memory."""

from __future__ import annotations

import pytest

from tmeye.runtime.stalls import StallLog


def test_longest_interval_in_the_window() -> None:
    log = StallLog(seconds=60)
    assert log.longest_ms(10, 100.0) is None
    t = 100.0
    for _ in range(90):  # 3 s at 30 fps
        log.frame(t)
        t += 1 / 30
    log.frame(t + 0.25)  # one stall of 0.25 + 1/30 s
    t += 0.25 + 1 / 30
    for _ in range(30):
        t += 1 / 30
        log.frame(t)
    assert log.longest_ms(5, t) == pytest.approx(283.3, abs=0.2)
    later = t + 20.0  # the stall leaves the window; the interval still open now counts
    assert log.longest_ms(5, later) == pytest.approx(20_000.0, abs=1.0)
    log.pause()
    assert log.longest_ms(5, later) is None  # nothing in the window, nothing open


def test_memory_is_fixed_and_old_seconds_are_overwritten() -> None:
    log = StallLog(seconds=10)
    log.frame(0.0)
    log.frame(2.0)  # a 2 s gap in second 2
    t = 2.0
    for _ in range(30 * 20):  # 20 s of steady frames: the ring of 10 s wraps twice
        t += 1 / 30
        log.frame(t)
    assert log.longest_ms(9, t) == pytest.approx(33.3, abs=0.2)
    assert log._gap.shape == (10,)
