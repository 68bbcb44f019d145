"""The centroid's 1-σ from the outline's whole pixels and from a body's hull gap (tracker.segmentation)."""

from __future__ import annotations

import numpy as np

from tracker.segmentation import HeightHistory, edge_quantisation_px, hull_gap_px


def _centroid(m: np.ndarray) -> np.ndarray:
    ys, xs = np.nonzero(m)
    return np.array([xs.mean(), ys.mean()])


def test_edge_quantisation_meets_randomly_covered_edges() -> None:
    # a 40 x 60 px plate whose edge pixels are each in or out by their unknown coverage (texture and
    # background vary along the edge): the centroid's scatter over many frames is what the term says
    rng = np.random.default_rng(1)
    h, w = 60, 40
    errs = []
    for _ in range(400):
        m = np.zeros((h + 4, w + 4), bool)
        left = 2 + (rng.random(h) < 0.5)  # each row's end pixel in with probability 1/2 (coverage ~ U[0, 1])
        right = 2 + w - (rng.random(h) < 0.5)
        for r in range(h):
            m[2 + r, left[r]:right[r]] = True
        errs.append(_centroid(m)[0] - (2 + w / 2 - 0.5))
        sx, _ = edge_quantisation_px(m)
    measured = float(np.sqrt(np.mean(np.square(errs))))
    assert 0.6 * sx < measured < 1.6 * sx  # Bernoulli ends: 1/4 px² a row end against the model's 1/12 ... 1/4


def test_edge_quantisation_falls_with_size_and_is_zero_when_empty() -> None:
    small, large = np.zeros((60, 60), bool), np.zeros((240, 240), bool)
    small[10:50, 10:50] = True
    large[20:180, 20:180] = True
    s, big = edge_quantisation_px(small), edge_quantisation_px(large)
    assert abs(s[0] - 1 / np.sqrt(24 * 40)) < 0.3 / np.sqrt(24 * 40)  # about 1 / √(24 H) for a square
    assert big[0] < 0.6 * s[0] and big[1] < 0.6 * s[1]
    assert edge_quantisation_px(np.zeros((10, 10), bool)) == (0.0, 0.0)


def test_a_convex_mask_has_no_hull_gap() -> None:
    m = np.zeros((80, 60), bool)
    m[10:70, 10:50] = True
    assert hull_gap_px(m) == (0.0, 0.0)
    yy, xx = np.mgrid[:80, :80]
    disc = (xx - 40) ** 2 + (yy - 40) ** 2 <= 30**2
    assert max(hull_gap_px(disc)) < 0.05


def test_hull_gap_covers_a_missed_part_of_unknown_size() -> None:
    # a body 40 x 100 px whose lower middle (a notch 14 px wide, 40 px high) the segmentation may have
    # missed in part: for shares u of it evenly spread over [0, 1], the centroid's error about the truth
    # (u of the notch filled from the top) is within the term's 1-σ on rms
    seen = np.zeros((110, 50), bool)
    seen[5:105, 5:45] = True
    seen[65:105, 18:32] = False
    sx, sy = hull_gap_px(seen)
    assert sx < 0.5 * sy  # the notch lies well below the centre, and is narrow
    errs = []
    for u in np.linspace(0.0, 1.0, 41):
        truth = seen.copy()
        truth[65:65 + int(round(40 * u)), 18:32] = True
        errs.append(_centroid(seen)[1] - _centroid(truth)[1])
    rms = float(np.sqrt(np.mean(np.square(errs))))
    assert 0.5 * sy < rms < 1.5 * sy
    deeper = seen.copy()
    deeper[45:105, 18:32] = False
    assert hull_gap_px(deeper)[1] > sy


def test_height_history_is_quiet_while_a_target_only_comes_nearer() -> None:
    hist = HeightHistory()
    # a target 100 px tall at disparity 20 px coming nearer: its height grows with its disparity, rounded
    out = [hist.sigma_px(1, i, float(round(5.0 * (20.0 + 0.2 * i))), 20.0 + 0.2 * i) for i in range(30)]
    assert max(out) == 0.0


def test_height_history_takes_half_of_a_piece_lost_or_gained() -> None:
    hist = HeightHistory()
    for i in range(10):
        assert hist.sigma_px(1, i, 100.0, 20.0) == 0.0
    assert abs(hist.sigma_px(1, 10, 88.0, 20.0) - 0.5 * (12.0 - 1.0)) < 1e-9  # a head of 12 px lost
    assert abs(hist.sigma_px(1, 11, 110.0, 20.0) - 0.5 * (10.0 - 1.0)) < 1e-9  # something merged on top
    assert hist.sigma_px(2, 11, 60.0, 20.0) == 0.0  # another track has its own history
    # after a gap of more than max_gap frames the old heights no longer count, nor for an ended track
    assert hist.sigma_px(1, 20, 50.0, 20.0) == 0.0
    hist.keep_only([2])
    assert hist.sigma_px(1, 21, 10.0, 20.0) == 0.0
