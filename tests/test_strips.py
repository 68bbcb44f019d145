"""A small region's disparity stands only where its whole outline agrees (tracker.strips.outline_agrees);
where it does not, the whole region, outline included, gives it (tracker.strips.whole_match)."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest

from tracker import strips as st
from tracker.geometry import Camera, StereoRig
from tracker.rectify import Rectifier
from tracker.stereo import RegionMatch, match_region

FIXTURE = Path(__file__).parent / "fixtures" / "far_head_strips.npz"
TRUE_D = 6.56  # the head's rectified disparity in that frame (the simulator's truth)
W, H = 640, 480


def _ideal_rig() -> StereoRig:
    """No distortion, parallel cameras 0.3 m apart: the rectified image is the raw one."""
    K = np.array([[600.0, 0.0, W / 2], [0.0, 600.0, H / 2], [0.0, 0.0, 1.0]])
    half = np.array([0.15, 0.0, 0.0])
    return StereoRig(Camera(K, np.zeros(5), (W, H), np.eye(3), -half),
                     Camera(K.copy(), np.zeros(5), (W, H), np.eye(3), half))


def _texture(seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    t = cv2.GaussianBlur(rng.uniform(0, 255, (H, W + 64)).astype(np.float32), (0, 0), 1.5)
    return np.asarray(cv2.normalize(t, None, 40, 220, cv2.NORM_MINMAX), np.float32)


def _far_head() -> dict[str, np.ndarray]:
    """The rectified strips (13 x 34 px) the verifier matched a far walker's head and shoulders on, 27 m
    away over a hedge (endless:body frame 872, the fine match from the coarse 6.04 px, 4 px either side):
    left, right, the region's shrunk core and its whole mask over the window (13 x 15 px, from column
    `off`), d_hi. Written by running the pipeline on the scenario to that frame and saving Strips.match's
    arguments."""
    with np.load(FIXTURE) as z:
        return {k: z[k] for k in z.files}


def test_a_far_heads_smooth_inside_matches_far_off_and_its_outline_says_so() -> None:
    h = _far_head()
    off, d_hi = int(h["off"]), int(h["d_hi"])
    core_fit = match_region(h["left"], h["right"], h["core"], off, 0, d_hi, float(h["d0"]), search_radius=4,
                            min_score=st.MIN_SCORE)
    assert core_fit is not None and core_fit.disparity > TRUE_D + 2.0  # the core alone: 2.3 px too near
    assert 2 * int(h["core"].sum()) < int(h["whole"].sum())  # a small region: the check applies
    assert not st.outline_agrees(h["left"], h["right"], h["whole"], off, core_fit.disparity)
    assert st.outline_agrees(h["left"], h["right"], h["whole"], off, TRUE_D)
    # at its true disparity the whole region is within 0.05 of its best: a score read one pixel off is not
    assert st.outline_agrees(h["left"], h["right"], h["whole"], off, TRUE_D, tol=0.05)


def _strips_over(h: dict[str, np.ndarray], monkeypatch: pytest.MonkeyPatch) -> tuple[st.Strips, np.ndarray]:
    """The fixture's strips as a Strips on an undistorted rig, its region's core and whole mask those the
    pipeline had (the lens's rectification shrank the core further than the identity's would)."""
    n = h["whole"].shape[1]
    rows, off = h["left"].shape[0], int(h["off"])
    x0, y0 = 200, 100
    strips = st.Strips(Rectifier(_ideal_rig()), (x0, y0), (x0, y0, x0 + n, y0 + rows), h["left"], h["right"],
                       off, int(h["d_hi"]))
    monkeypatch.setattr(st.Strips, "_core_and_whole", lambda self, region: (h["core"], h["whole"]))
    return strips, h["whole"].astype(bool)


def test_where_its_outline_disagrees_a_small_tracked_region_takes_the_whole_regions_own_match(
        monkeypatch: pytest.MonkeyPatch) -> None:
    h = _far_head()
    strips, region = _strips_over(h, monkeypatch)
    d0 = float(h["d0"])
    fit = strips.match(region, d0, 4, whole_ok=True)  # the core's 8.9 px disagrees: the whole region's best
    assert fit is not None and abs(fit.disparity - TRUE_D) < 0.3 and fit.score >= st.WHOLE_MIN_SCORE
    assert strips.match(region, d0, 4) is None  # a new object's: none (a shadow's edge on a wall took it)
    threshold = st.WHOLE_MIN_SCORE
    monkeypatch.setattr(st, "WHOLE_MIN_SCORE", fit.score + 0.05)  # scoring under the threshold: none
    assert strips.match(region, d0, 4, whole_ok=True) is None
    monkeypatch.setattr(st, "WHOLE_MIN_SCORE", threshold)
    monkeypatch.setattr(st, "_peak_match", lambda *a, **k: None)  # without whole_match's peak: no match at all
    assert strips.match(region, d0, 4, whole_ok=True) is None
    monkeypatch.setattr(st, "_agrees", lambda *a, **k: True)  # without outline_agrees' check: the core's match
    fit = strips.match(region, d0, 4, whole_ok=True)
    assert fit is not None and fit.disparity > TRUE_D + 2.0


def test_a_whole_regions_peak_is_as_uncertain_as_its_distance_from_the_tracks_prediction(
        monkeypatch: pytest.MonkeyPatch) -> None:
    # the peak and the prediction disagree and neither is known right (a sliver beside a post takes the
    # post's edge; a coasting prediction drifts): the 1-σ is widened by half their distance
    h = _far_head()
    strips, region = _strips_over(h, monkeypatch)
    d0 = float(h["d0"])
    core_fit = match_region(h["left"], h["right"], h["core"], int(h["off"]), 0, int(h["d_hi"]), d0,
                            search_radius=4, min_score=st.MIN_SCORE)
    assert core_fit is not None
    raw = st.whole_match(h["left"], h["right"], h["whole"], int(h["off"]), core_fit.disparity)
    fit = strips.match(region, d0, 4, whole_ok=True)
    assert raw is not None and fit is not None and fit.disparity == raw.disparity
    assert fit.sigma == pytest.approx(float(np.hypot(raw.sigma, 0.5 * abs(raw.disparity - d0))))
    assert fit.sigma > raw.sigma
    far = st.disputed(RegionMatch(14.0, 0.1, 0.7, 1.0), 11.0)  # seed 2's sliver: 3 px from its prediction
    assert far.sigma == pytest.approx(float(np.hypot(0.1, 1.5))) and far.disparity == 14.0 and far.score == 0.7
    assert st.disputed(RegionMatch(11.0, 0.1, 0.7, 1.0), 11.0).sigma == pytest.approx(0.1)


def _periodic_bar(period: int, d: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Strips (12 x 44 px) of a bar 4 px high at disparity d over a background at 2 px, the bar's texture
    repeating every `period` columns, and the mask of the 14 px of its length seen in the window (columns
    20 to 40); the bar goes on beyond them, so that its texture, not its ends, says where it matches."""
    rows, cols, off, n = 12, 44, 20, 20
    yy, xx = np.mgrid[0:rows, 0:cols]
    phase = np.random.default_rng(3).uniform(0, 2 * np.pi, (rows, 1))
    background = _texture(5)

    def view(shift_bar: int, shift_bg: int) -> np.ndarray:
        out = background[yy + 50, xx + 50 + shift_bg].copy()
        on = (yy >= 4) & (yy < 8)
        bar = 128 + 90 * np.sin(2 * np.pi * (xx + shift_bar) / period + phase)
        out[on] = bar[on]
        return np.asarray(out.clip(0, 255), np.uint8)

    on = (yy >= 4) & (yy < 8) & (xx >= off + 3) & (xx < off + 17)
    return view(0, 0), view(d, 2), on[:, off:off + n].astype(np.uint8)


def test_the_whole_region_gives_no_disparity_where_it_matches_as_well_elsewhere() -> None:
    # a bar whose texture repeats every 3 px matches at 3, 6 and 9 px alike: no peak stands out
    left, right, whole = _periodic_bar(3, 6)
    assert st.whole_match(left, right, whole, 20, 6.0) is None
    # the same bar with a texture that does not repeat within the span: its own disparity
    left, right, whole = _periodic_bar(23, 6)
    fit = st.whole_match(left, right, whole, 20, 5.0)
    assert fit is not None and abs(fit.disparity - 6.0) < 0.2
    # about 11 px the span is 7 to 15 px: its best lies at its end, no peak within it
    assert st.whole_match(left, right, whole, 20, 11.0) is None


def test_a_small_textured_region_whose_outline_agrees_keeps_its_match() -> None:
    # a textured bar 14 x 4 px at disparity 6 over a background at 2: its shrunk core keeps 12 x 2 px of 56
    left_tex, bar = _texture(8), _texture(9)
    rows, cols, off, n = 12, 44, 20, 20  # the window: strip columns off .. off + n; the bar from off + 3
    yy, xx = np.mgrid[0:rows, 0:cols]
    x_bar = off + 3
    on = (yy >= 4) & (yy < 8) & (xx >= x_bar) & (xx < x_bar + 14)

    def view(shift_bar: int, shift_bg: int) -> np.ndarray:
        out = left_tex[yy + 50, xx + 50 + shift_bg].copy()
        on_r = (yy >= 4) & (yy < 8) & (xx + shift_bar >= x_bar) & (xx + shift_bar < x_bar + 14)
        out[on_r] = bar[yy + 50, xx + 50 + shift_bar][on_r]
        return np.asarray(out.clip(0, 255), np.uint8)

    left, right = view(0, 0), view(6, 2)
    strips = st.Strips(Rectifier(_ideal_rig()), (300, 200), (300, 200, 300 + n, 200 + rows), left, right, off, 12)
    region = on[:, off:off + n]
    core = strips.core(region)
    assert 2 * int(core.sum()) < int(region.sum())
    fit = strips.match(region, None, 0)
    assert fit is not None and abs(fit.disparity - 6.0) < 0.2
