"""A track's outline's top in the world (tracker.top_history; issue 12 item 1)."""

from __future__ import annotations

import pytest

from tracker.frames import GimbalState
from tracker.geometry import gimbal_rotation
from tracker.rectify import Rectifier
from tracker.sim.rig import default_rig
from tracker.top_history import TopHistory, top_world_y_m


def test_a_top_that_sinks_is_a_piece_lost_and_not_kept() -> None:
    tops = TopHistory()
    d, b = 10.0, 0.3  # 33.3 px a metre at this disparity
    for k in range(3):  # too few to judge: nothing moved, each kept
        assert tops.offset_px(1, -0.20 + 0.005 * (k % 2), d, b) == 0.0
    for k in range(6):  # a head bobbing by a centimetre stays within the slack
        assert tops.offset_px(1, -0.20 + 0.01 * (k % 3 - 1), d, b) == 0.0
    assert tops.offset_px(1, 0.10, d, b) == pytest.approx(0.30 * d / b, abs=0.4)  # head and shoulders lost
    for _ in range(12):  # the lowered tops are not kept: still judged against the head's
        assert tops.offset_px(1, 0.10, d, b) > 9.0
    assert tops.offset_px(1, -0.20, d, b) == 0.0
    assert tops.offset_px(2, 0.10, d, b) == 0.0  # each track its own history
    tops.keep_only([2])
    assert tops.offset_px(1, 0.10, d, b) == 0.0  # forgotten: a fresh history


def test_a_top_that_rises_is_kept_a_track_born_on_a_headless_outline() -> None:
    tops = TopHistory()
    for _ in range(6):  # born on a person whose head was not yet in its outline
        assert tops.offset_px(1, 0.05, 10.0, 0.3) == 0.0
    for _ in range(8):  # its head now seen, higher: kept, nothing moved
        assert tops.offset_px(1, -0.20, 10.0, 0.3) == 0.0
    assert tops.offset_px(1, 0.05, 10.0, 0.3) > 7.0  # the history now the head's: a top lowered again is lost


def test_top_world_height_does_not_change_as_the_mount_pans() -> None:
    rect = Rectifier(default_rig())
    y0 = top_world_y_m(rect, GimbalState(), 320.0, 200.0, 12.0)
    y1 = top_world_y_m(rect, GimbalState(pan_deg=25.0), 320.0, 200.0, 12.0)
    assert y1 == pytest.approx(y0, abs=1e-9)
    assert top_world_y_m(rect, None, 320.0, 200.0, 12.0) == pytest.approx(y0)
    assert top_world_y_m(rect, GimbalState(), 320.0, 180.0, 12.0) < y0  # higher in the image: higher up (y down)
    # tilted by 10°, the same world point is seen elsewhere in the image and has the same world y
    X_w = gimbal_rotation(0.0, 0.0) @ rect.rect_to_rig(320.0, 200.0, 12.0)
    tilted = GimbalState(tilt_deg=10.0)
    x, y, d = rect.rig_to_rect((gimbal_rotation(0.0, 10.0).T @ X_w)[None, :])
    assert abs(float(y[0]) - 200.0) > 20.0
    assert top_world_y_m(rect, tilted, float(x[0]), float(y[0]), float(d[0])) == pytest.approx(float(X_w[1]), abs=1e-9)


def test_a_top_without_depth_is_neither_judged_nor_kept() -> None:
    tops = TopHistory()
    for _ in range(5):
        tops.offset_px(1, -0.2, 10.0, 0.3)
    assert tops.offset_px(1, float("inf"), 10.0, 0.3) == 0.0 and tops.offset_px(1, 0.3, 0.0, 0.3) == 0.0
    assert tops.offset_px(1, 0.1, 10.0, 0.3) > 9.0  # the history still the head's
