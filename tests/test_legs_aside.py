"""A person whose legs a nearer thing hides but for a leg seen past its edge (tracker.partly_seen.legs_aside_px,
tracker.visibility.Cuts.hidden_from): the hidden legs stand under what is seen above, so the leg seen beside
the occluder pulls the centroid to its side, and the centroid's x 1-σ holds that pull. On the endless scene
a crate before a walker at 7.4 m left one leg in view and the azimuth 0.57° off with a 1-σ of 0.06°."""

from __future__ import annotations

import numpy as np
import pytest
from sim_helpers import run_frames

import tracker.partly_seen as partly_seen
from tracker.evaluation import _on
from tracker.partly_seen import legs_aside_px
from tracker.visibility import VisibilityConfig, cuts

CFG = VisibilityConfig()
SIZE = (640, 480)


def _walker(legs: str) -> np.ndarray:
    """A 60 x 120 mask: a torso 20 px wide (rows 10-69, columns 20-39) over legs (rows 70-109): 'both' (columns
    22-27 and 32-37), 'right' (32-37 alone) or 'none'."""
    m = np.zeros((120, 60), bool)
    m[10:70, 20:40] = True
    if legs in ("both", "left"):
        m[70:110, 22:28] = True
    if legs in ("both", "right"):
        m[70:110, 32:38] = True
    return m


def test_a_leg_seen_beside_an_occluder_pulls_the_centroid_by_its_share_and_offset() -> None:
    m = _walker("right")
    n_up, n_low = 60 * 20, 40 * 6
    expected = n_low * abs(34.5 - 29.5) / (n_up + n_low)  # the leg's mean column 34.5, the torso's 29.5
    assert legs_aside_px(m, 70) == pytest.approx(expected)
    assert legs_aside_px(_walker("both"), 70) == pytest.approx(0.0)  # both legs: under the torso
    assert legs_aside_px(_walker("none"), 70) == 0.0  # nothing seen below
    assert legs_aside_px(m, 0) == 0.0  # nothing seen above


def test_an_occluder_across_the_legs_is_found_and_the_ground_beside_the_feet_is_not() -> None:
    m = _walker("right")
    d = 25.0
    bg = np.full(m.shape, 15.0, np.float32)  # the wall far behind
    bg[70:, :31] = d + 5.0  # a crate 5 px nearer hides the legs left of column 31
    valid = np.ones(m.shape, bool)
    found = cuts(m, (200, 200, 260, 320), SIZE, d, bg, valid, CFG)
    assert found.hidden_from is not None and 68 <= found.hidden_from <= 72
    bg = np.full(m.shape, 15.0, np.float32)
    bg[100:, :] = d + 1.2  # the ground beside the feet, a little nearer than the body's disparity
    assert cuts(_walker("both"), (200, 200, 260, 320), SIZE, d, bg, valid, CFG).hidden_from is None


@pytest.mark.parametrize("with_term", [True, False])
def test_the_walker_behind_the_crate_on_the_endless_scene(with_term: bool, monkeypatch: pytest.MonkeyPatch) -> None:
    # frame 305: the crate hides the walker's legs but for one past its right edge
    if not with_term:
        monkeypatch.setattr(partly_seen, "legs_aside_px", lambda mask, hidden_from: 0.0)
    _, sf, res = run_frames("endless:body", 306)
    tt = sf.truth.target(1)
    assert tt is not None
    det = next(d for d in res.detections if _on(d, tt, sf.truth.ids_left))
    truth = np.arctan2(tt.world[0], tt.world[2])
    z = (det.loc.theta - truth) / det.loc.sigma_theta
    assert abs(np.degrees(det.loc.theta - truth)) > 0.3  # the centroid is pulled to the leg either way
    assert (abs(z) < 2.0) if with_term else (abs(z) > 5.0)


def test_an_occluder_above_the_centroid_or_at_the_top_is_no_occluder_across_the_legs() -> None:
    valid = np.ones((120, 60), bool)
    for rows in (slice(0, 40), slice(0, 12)):  # beside the torso; over the head
        bg = np.full((120, 60), 15.0, np.float32)
        bg[rows, :] = 30.0
        assert cuts(_walker("right"), (200, 200, 260, 320), SIZE, 25.0, bg, valid, CFG).hidden_from is None
