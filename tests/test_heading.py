"""tracker.heading: the share of a walker's limb swing seen across the image, from its track's positions."""

from __future__ import annotations

import numpy as np
import pytest

from tracker.heading import HeadingHistory

ORIGIN = np.zeros(3)


def _walk(h: HeadingHistory, start: np.ndarray, velocity: np.ndarray, frames: int, noise_m: float = 0.0,
          track: int = 1, first: int = 0, fps: float = 30.0) -> None:
    rng = np.random.default_rng(3)
    for k in range(frames):
        i = first + k
        p = start + velocity * (i / fps)
        los = p / np.linalg.norm(p)
        h.add(track, i, i / fps, p + los * rng.normal(0.0, noise_m))  # range noise: along the line of sight


def test_walking_across_the_line_of_sight_is_seen_whole_towards_it_not_at_all() -> None:
    across, towards = HeadingHistory(), HeadingHistory()
    start = np.array([0.0, 1.0, 12.0])  # 12 m ahead, y down: on the ground below the rig
    _walk(across, start, np.array([1.4, 0.0, 0.0]), 15, noise_m=0.1)
    _walk(towards, start, np.array([0.0, 0.0, -1.4]), 15, noise_m=0.1)
    assert across.swing_share(1, 15, ORIGIN) == pytest.approx(1.0, abs=0.02)
    assert towards.swing_share(1, 15, ORIGIN) == pytest.approx(0.0, abs=0.05)
    oblique = HeadingHistory()
    _walk(oblique, start, np.array([1.0, 0.0, 1.0]) * 1.4 / np.sqrt(2.0), 15)
    # at 45 degrees to the line of sight where it is (that turns as the walker moves across)
    p = start + np.array([1.0, 0.0, 1.0]) * 1.4 / np.sqrt(2.0) * 14 / 30.0
    u = np.array([p[0], p[2]]) / np.hypot(p[0], p[2])
    expected = abs(u[1] - u[0]) / np.sqrt(2.0)  # |v x u| / |v| with v along (1, 1)
    assert oblique.swing_share(1, 15, ORIGIN) == pytest.approx(expected, abs=1e-6)


def test_a_body_standing_still_swings_nothing_and_a_slow_one_less() -> None:
    still, slow = HeadingHistory(walk_mps=0.5), HeadingHistory(walk_mps=0.5)
    start = np.array([2.0, 1.0, 10.0])
    _walk(still, start, np.zeros(3), 15, noise_m=0.05)
    _walk(slow, np.array([0.0, 1.0, 10.0]), np.array([0.25, 0.0, 0.0]), 15)
    assert still.swing_share(1, 15, ORIGIN) < 0.05  # the range's noise lies along the line of sight
    assert slow.swing_share(1, 15, ORIGIN) == pytest.approx(0.5, abs=0.01)  # 0.25 m/s of 0.5


def test_no_share_without_enough_recent_positions() -> None:
    h = HeadingHistory(frames=15, min_frames=5, max_gap=3)
    start, v = np.array([0.0, 1.0, 12.0]), np.array([1.4, 0.0, 0.0])
    _walk(h, start, v, 4)
    assert h.swing_share(1, 4, ORIGIN) is None  # four positions, five needed
    _walk(h, start, v, 1, first=4)
    assert h.swing_share(1, 5, ORIGIN) is not None
    assert h.swing_share(1, 9, ORIGIN) is None  # the last one five frames old
    assert h.swing_share(2, 5, ORIGIN) is None  # another track
    _walk(h, start, v, 1, first=12)  # a gap over max_gap starts afresh
    assert h.swing_share(1, 13, ORIGIN) is None
    h.keep_only([2])
    assert h.swing_share(1, 13, ORIGIN) is None


def test_bad_settings_are_refused() -> None:
    with pytest.raises(ValueError, match="min_frames"):
        HeadingHistory(frames=3, min_frames=5)


def test_the_gait_share_is_the_speed_beyond_the_positions_scatter() -> None:
    # a walker standing at 10 m whose range scatters by 0.1 m: its fitted speed (about 0.2 m/s along the
    # line of sight) is what that scatter explains, so it hardly walks; at 1.4 m/s it walks fully; at
    # 0.25 m/s, half of the walking speed v_0
    still, walking, slow = HeadingHistory(), HeadingHistory(), HeadingHistory()
    _walk(still, np.array([0.5, 1.0, 10.0]), np.zeros(3), 15, noise_m=0.1)
    _walk(walking, np.array([0.0, 1.0, 12.0]), np.array([0.0, 0.0, -1.4]), 15, noise_m=0.1)
    _walk(slow, np.array([0.0, 1.0, 10.0]), np.array([0.25, 0.0, 0.0]), 15)
    fit = still._velocity(1, 15)
    assert fit is not None and float(np.hypot(*fit[0])) > 0.0  # the raw slope says it moves a little
    assert still.gait_share(1, 15) < min(0.1, float(np.hypot(*fit[0])) / 0.5)
    assert walking.gait_share(1, 15) == 1.0
    assert slow.gait_share(1, 15) == pytest.approx(0.5, abs=0.01)
    assert HeadingHistory().gait_share(1, 0) is None
