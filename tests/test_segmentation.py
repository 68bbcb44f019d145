"""The centroid's 1-σ from the outline's whole pixels and from a body's hull gap (tracker.segmentation)."""

from __future__ import annotations

import statistics

import numpy as np
import pytest

from tracker.extent_history import ExtentHistory
from tracker.segmentation import HeightHistory, edge_quantisation_px, hull_gap_px, outline_sigma_px


def _centroid(m: np.ndarray) -> np.ndarray:
    ys, xs = np.nonzero(m)
    return np.array([xs.mean(), ys.mean()])


def _sampled(shape: str, size: tuple[float, float], c: np.ndarray, turn: float = 0.0) -> np.ndarray:
    """A disc (radius size[0]) or board (width x height) centred at c (px), point-sampled at pixel centres."""
    yy, xx = np.mgrid[0:200, 0:200].astype(float)
    u, v = xx - c[0], yy - c[1]
    if shape == "disc":
        return np.asarray(u * u + v * v <= size[0] ** 2)
    ca, sa = np.cos(turn), np.sin(turn)
    return np.asarray((np.abs(u * ca + v * sa) <= size[0] / 2) & (np.abs(v * ca - u * sa) <= size[1] / 2))


@pytest.mark.parametrize(("shape", "size", "turn", "lo"), [("disc", (8.0, 0.0), 0.0, 0.7),
                                                            ("disc", (20.0, 0.0), 0.0, 0.7),
                                                            ("board", (30.5, 100.5), 0.0, 0.7),
                                                            ("board", (40.0, 120.0), 0.2, 0.25)])
def test_edge_quantisation_meets_point_sampled_outlines(shape: str, size: tuple[float, float], turn: float,
                                                        lo: float) -> None:
    # the outline at random sub-pixel positions: the centroid's scatter about the true centre is what the
    # term says (a turned board's staircase pins its sides down better than the term, which stays cautious)
    rng = np.random.default_rng(3)
    errs, terms = [], []
    for _ in range(200):
        c = np.array([100.0, 100.0]) + rng.random(2)
        m = _sampled(shape, size, c, turn)
        errs.append(_centroid(m) - c)
        terms.append(edge_quantisation_px(m))
    measured, term = np.sqrt(np.mean(np.square(errs), axis=0)), np.mean(terms, axis=0)
    assert np.all(lo * term < measured) and np.all(measured < 1.5 * term), (measured, term)


def test_a_board_seen_square_on_is_off_by_a_fifth_of_a_pixel_whatever_its_size() -> None:
    # its straight sides move as one: 1/√24 px along each axis, where independent edge pixels would give
    # 1/√(24 H) and less
    for n in (40, 160):
        m = np.zeros((n + 20, n + 20), bool)
        m[10:10 + n, 10:10 + n] = True
        sx, sy = edge_quantisation_px(m)
        assert abs(sx - 1 / np.sqrt(24)) < 0.01 and abs(sy - 1 / np.sqrt(24)) < 0.01
    ragged = np.zeros((80, 80), bool)  # a ragged side (row ends one column in or out) is a staircase
    rng = np.random.default_rng(2)
    for r in range(10, 70):
        ragged[r, 10 + int(rng.random() < 0.5):70 - int(rng.random() < 0.5)] = True
    assert edge_quantisation_px(ragged)[0] < 0.05
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


def test_an_upright_bodys_hull_gap_counts_along_y_only() -> None:
    # a walker 32 px wide and 110 px high, one arm held out (a notch between it and the torso, to the
    # right): for a person (tracker.solid_prior.SolidPrior.upright) the notches are the spaces between its limbs
    # and the gap's x term is left to the prior's upright_x_var (tracker.localize.with_gap_x); flat targets
    # (no prior) and a body lying on its side (110 px wide, 32 px high) keep it, in quadrature
    from tracker.localize import with_gap_x
    from tracker.solid_prior import SolidPrior

    walker = np.zeros((120, 50), bool)
    walker[5:115, 10:30] = True  # torso and legs
    walker[70:115, 17:23] = False  # between the legs
    walker[20:60, 38:42] = True  # the arm
    walker[20:24, 30:38] = True  # the shoulder
    _, (gx, gy) = outline_sigma_px(walker)
    assert gx > 0.1 and gy > 0.1
    assert with_gap_x(0.3, gx, SolidPrior(), 32.0, 110.0) == 0.3
    assert with_gap_x(0.3, gx, None, 32.0, 110.0) == pytest.approx(float(np.hypot(0.3, gx)))
    assert with_gap_x(0.3, gx, SolidPrior(), 110.0, 32.0) == pytest.approx(float(np.hypot(0.3, gx)))


def test_extent_history_bounds_a_cut_by_what_the_track_showed_whole() -> None:
    hist = ExtentHistory()
    kappa = (12.4, 12.4)  # kappa x the visible extent (tracker.visibility.extra_sigma_px): nothing known
    assert hist.bounded_sigma_px(1, (30.0, 30.0), 900.0, 15.0, kappa) == kappa  # no history yet
    for d in (15.5, 15.4, 15.3, 15.2):  # a square 30 px across at 15 px of disparity, seen whole, receding
        s = d / 15.0
        assert hist.bounded_sigma_px(1, (30.0 * s, 30.0 * s), 900.0 * s * s, d, (0.0, 0.0)) == (0.0, 0.0)
    # beside a nearer object, seen whole still at 15 px: only the extents' rounding (1/√6 px rms), halved
    sx, sy = hist.bounded_sigma_px(1, (30.0, 30.0), 900.0, 15.0, kappa, (False, False))
    assert sx == pytest.approx(0.5 / np.sqrt(6.0)) and sy == pytest.approx(0.5 / np.sqrt(6.0))
    # a strip 10 px wide hidden at one side: the centroid is 5 px off along x; y keeps kappa's 0, not cut
    sx, sy = hist.bounded_sigma_px(1, (20.0, 30.0), 600.0, 15.0, (8.0, 0.0), (False, True))
    assert sx == pytest.approx(0.5 * np.sqrt(100.0 + 1.0 / 6.0)) and sy == 0.0
    # a rail 6 px high across it: the extents whole, 180 px² hidden inside the outline, up to its share of
    # the seen area times half the extent (3.75 px) along either axis
    sx, sy = hist.bounded_sigma_px(1, (30.0, 30.0), 720.0, 15.0, kappa, (False, False))
    assert sy == pytest.approx(np.sqrt(1.0 / 24.0 + (15.0 * 180.0 / 720.0) ** 2)) and sx == pytest.approx(sy)
    # never more than kappa's term; cut frames add nothing to the history; another track has its own
    assert hist.bounded_sigma_px(1, (2.0, 30.0), 60.0, 15.0, (0.8, 0.0))[0] == 0.8
    assert hist.bounded_sigma_px(2, (20.0, 30.0), 600.0, 15.0, (8.0, 0.0)) == (8.0, 0.0)
    hist.keep_only([2])
    assert hist.bounded_sigma_px(1, (20.0, 30.0), 600.0, 15.0, (8.0, 0.0)) == (8.0, 0.0)


def test_extent_history_counts_a_strip_the_outline_took_in_beyond_the_target() -> None:
    # endless:plate, frames 1329-1331: a board at the image's edge drawn with a ghost strip beside it
    hist = ExtentHistory()
    for _ in range(5):  # a board 30 px across at 15 px of disparity, seen whole
        hist.bounded_sigma_px(1, (30.0, 30.0), 900.0, 15.0, (0.0, 0.0))
    # 12 px wider than it ever was, cut by the image's edge (not seen whole, not kept) yet no narrower than
    # the history, which bounded it to the rounding: the centroid lies up to 6 px off along x
    sx, sy = hist.bounded_sigma_px(1, (42.0, 30.0), 1260.0, 15.0, (16.8, 12.0), (False, True))
    assert sx == pytest.approx(0.5 * np.sqrt(144.0 + 1.0 / 6.0)) and sy == 0.0  # its height seen whole
    # a pixel wider is the outline's rounding (within twice the scatter and the rounding): nothing taken in
    sx, _ = hist.bounded_sigma_px(1, (31.0, 30.0), 930.0, 15.0, (12.4, 12.0), (False, False))
    assert sx == pytest.approx(0.5 / np.sqrt(6.0))


def test_extent_history_counts_a_strip_lost_where_no_cut_was_found() -> None:
    # endless:body seed 1, frames 2770-2772: a head over a hedge, 12-13 px wide by its history, drawn 7 px
    # wide with no cut found (eq. (9) lost a side against a background like it): x had no term at all
    hist = ExtentHistory()
    for _ in range(5):  # a board 30 px across at 15 px of disparity, seen whole
        assert hist.bounded_sigma_px(1, (30.0, 30.0), 900.0, 15.0, (0.0, 0.0)) == (0.0, 0.0)
    # a pixel narrower is the outline's rounding (within the slack): still nothing
    assert hist.bounded_sigma_px(1, (29.0, 30.0), 870.0, 15.0, (0.0, 0.0)) == (0.0, 0.0)
    # 10 px narrower, no side seen cut: a strip lost at a side not known, the centroid 5 px off either way
    sx, sy = hist.bounded_sigma_px(1, (20.0, 30.0), 600.0, 15.0, (0.0, 0.0))
    assert sx == pytest.approx(5.0) and sy == 0.0
    # not kept as the target's width: the next frame seen whole at 30 px is bounded as before
    assert hist.bounded_sigma_px(1, (30.0, 30.0), 900.0, 15.0, (0.0, 0.0)) == (0.0, 0.0)
    # a board's history is not upright: where a person is expected, a strip lost all the same
    sx, _ = hist.bounded_sigma_px(1, (20.0, 30.0), 600.0, 15.0, (0.0, 0.0), upright_aspect=2.0)
    assert sx == pytest.approx(5.0)
    # a walker's outline (history 10 x 30 px) narrows with its stride: its shape, which its own term holds
    for _ in range(5):
        hist.bounded_sigma_px(2, (10.0, 30.0), 300.0, 15.0, (0.0, 0.0))
    assert hist.bounded_sigma_px(2, (6.0, 30.0), 180.0, 15.0, (0.0, 0.0), upright_aspect=2.0) == (0.0, 0.0)
    sx, _ = hist.bounded_sigma_px(2, (6.0, 30.0), 180.0, 15.0, (0.0, 0.0))  # no person expected: a strip lost
    assert sx == pytest.approx(2.0)
    # its height does not change with its stride: 12 px shorter is a strip lost at its top or bottom
    # (endless:body seed 2, frames 1768-1775: a head and shoulders over a hedge not found below it)
    sx, sy = hist.bounded_sigma_px(2, (10.0, 18.0), 180.0, 15.0, (0.0, 0.0), upright_aspect=2.0)
    assert sx == 0.0 and sy == pytest.approx(6.0)


def test_extent_history_of_a_persons_fragment_bounds_no_cut() -> None:
    # endless:body seed 1, frames 2546-2595: a track born on a 16 px wide sliver of a walker beside a post
    person = (36.0, 13.8)  # SolidPrior.fragment_px where a person stands 60 px high: 0.6 and 0.23 of that
    hist = ExtentHistory()
    for _ in range(5):  # the sliver, 16 x 26 px, seen whole at 15 px of disparity
        hist.bounded_sigma_px(1, (16.0, 26.0), 416.0, 15.0, (0.0, 0.0))
    kappa = (6.4, 0.0)  # cut at the post now, 4 px of it hidden
    sliver = hist.bounded_sigma_px(1, (12.0, 26.0), 312.0, 15.0, kappa, (False, True))
    assert sliver[0] == pytest.approx(0.5 * np.sqrt(16.0 + 1.0 / 6.0))  # no person expected: bounded
    # a person expected: upright (over 1.5) and under 36 px high, a fragment's history, kappa's term stands
    assert hist.bounded_sigma_px(1, (12.0, 26.0), 312.0, 15.0, kappa, (False, True), None, 1.5, person) == kappa
    # the same history where a person stands 40 px high is a whole person's: it still bounds the cut
    whole = (24.0, 9.2)
    assert hist.bounded_sigma_px(1, (12.0, 26.0), 312.0, 15.0, kappa, (False, True), None, 1.5, whole) == sliver
    # its height never seen whole (cut throughout), its width kept: narrower than a person's shoulders
    cut = ExtentHistory()
    for _ in range(5):
        cut.bounded_sigma_px(1, (12.0, 26.0), 312.0, 15.0, (0.0, 9.0), (True, False))
    assert cut.bounded_sigma_px(1, (8.0, 26.0), 208.0, 15.0, (4.0, 9.0), (False, False), None, 1.5, person) \
        == (4.0, 9.0)
    assert cut.bounded_sigma_px(1, (8.0, 26.0), 208.0, 15.0, (4.0, 9.0), (False, False), None, 1.5, whole)[0] < 4.0
    # a ball's history (round, not upright) still bounds it where a person is expected
    ball = ExtentHistory()
    for _ in range(5):
        ball.bounded_sigma_px(1, (20.0, 20.0), 314.0, 15.0, (0.0, 0.0))
    sx, _ = ball.bounded_sigma_px(1, (16.0, 20.0), 251.0, 15.0, (6.4, 0.0), (False, True), None, 1.5, person)
    assert sx < 6.4


def test_extent_history_widens_by_how_much_the_whole_target_varied() -> None:
    # a robust scale (1.4826 x the median absolute deviation): one frame that took in a strip (a merge,
    # kept as whole) does not widen the bound for the next 15 frames, as a standard deviation did
    hist = ExtentHistory()
    for w in (40.0, 50.0, 40.0, 50.0):  # a walker's width with its stride, at disparity 10 px
        hist.bounded_sigma_px(1, (w, 100.0), 3000.0, 10.0, (0.0, 0.0))
    sx, _ = hist.bounded_sigma_px(1, (45.0, 100.0), 3000.0, 10.0, (18.0, 0.0), (False, True))
    assert sx == pytest.approx(0.5 * 1.4826 * 5.0)  # median 45, 1.4826 x its median deviation 5
    board = ExtentHistory()
    for h in (29.0,) * 6 + (35.0,) + (29.0,) * 2:  # occlusion:plate: one frame drawn 35 px high
        board.bounded_sigma_px(1, (29.0, h), 29.0 * h, 15.0, (0.0, 0.0))
    _, sy = board.bounded_sigma_px(1, (29.0, 29.0), 841.0, 15.0, (3.0, 11.0), (False, False))
    assert sy == pytest.approx(0.5 / np.sqrt(6.0))  # the rounding alone (a standard deviation: 1.9 px)


def test_extent_history_keeps_no_frame_whose_area_fell_short() -> None:
    hist = ExtentHistory()
    for _ in range(5):
        hist.bounded_sigma_px(1, (30.0, 30.0), 900.0, 15.0, (0.0, 0.0))
    for _ in range(20):  # a third of it behind a rail no side cut was found at: not taken as its size
        hist.bounded_sigma_px(1, (30.0, 30.0), 600.0, 15.0, (0.0, 0.0))
    _, sy = hist.bounded_sigma_px(1, (30.0, 30.0), 600.0, 15.0, (12.0, 12.0), (False, False))
    assert sy == pytest.approx(np.sqrt(1.0 / 24.0 + (15.0 * 300.0 / 600.0) ** 2))


def test_extent_history_keeps_each_axis_seen_whole_apart() -> None:
    """A board coming in past the image's left edge (its width never seen whole, its height always): a
    post's gap through it counted as a cut top is bounded by the height it showed, the width stays kappa's."""
    hist = ExtentHistory()
    for w in (10.0, 14.0, 18.0, 22.0):
        assert hist.bounded_sigma_px(1, (w, 29.0), 29.0 * w, 15.0, (11.2, 0.0), (False, True)) == (11.2, 0.0)
    sx, sy = hist.bounded_sigma_px(1, (24.0, 29.0), 29.0 * 24.0, 15.0, (12.0, 11.8), (False, False))
    assert sx == 12.0 and sy == pytest.approx(0.5 / np.sqrt(6.0))  # no area history: nothing inside known
    sx, sy = hist.bounded_sigma_px(1, (24.0, 21.0), 21.0 * 24.0, 15.0, (12.0, 11.8), (False, False))
    assert sy == pytest.approx(0.5 * np.sqrt(64.0 + 1.0 / 6.0))  # 8 px of its height hidden
    # the post cuts a side only and moves the centroid along y across it (kappa's skew), the height seen
    # whole: both its ends are seen, their rounding is the outline's edge term (not counted twice); with its
    # heights all alike (no scatter) and no area history, nothing bounds it but that: 0 (occlusion:plate's
    # board, 0.2 px so, was off by 0.01-0.03 px in elevation on such frames)
    assert hist.bounded_sigma_px(1, (24.0, 29.0), 29.0 * 24.0, 15.0, (12.0, 2.7), (False, True))[1] == 0.0


def test_a_strip_at_a_round_sides_rounding_moves_its_centroid_less_than_a_rectangles() -> None:
    # a strip δ wide at a side covers δ times the outline's outermost run there: half of δ for a board,
    # about an eighth for a disc of radius 15 px (its outer two columns 6 px long on average)
    import cv2

    from tracker.segmentation import outer_runs

    disc = np.zeros((33, 33), np.uint8)
    cv2.circle(disc, (16, 16), 15, 1, -1)
    board = np.ones((30, 20), bool)
    assert outer_runs(board) == (30.0, 20.0)
    ex, ey = outer_runs(disc.astype(bool))
    assert ex == ey and 5.0 <= ex <= 9.0
    assert outer_runs(disc.astype(bool), depth=1) == (1.0, 1.0)  # a rasterised disc's single-pixel tip
    assert outer_runs(np.zeros((4, 4), bool)) == (0.0, 0.0)
    area = float(disc.sum())
    hist = ExtentHistory()
    for w in (31.0, 32.0, 31.0, 32.0, 31.0):  # its width rounding to whole pixels as it moves
        hist.bounded_sigma_px(1, (w, 31.0), area, 15.0, (0.0, 0.0))
    kappa = (12.4, 0.0)  # a crosser beside it: a side flagged as cut, the width no shorter than it was
    rect_x, _ = hist.bounded_sigma_px(1, (31.0, 31.0), area, 15.0, kappa, (False, True))
    disc_x, _ = hist.bounded_sigma_px(1, (31.0, 31.0), area, 15.0, kappa, (False, True), (ex, ey))
    assert rect_x == pytest.approx(0.5 / np.sqrt(6.0))  # the rounding, at most half a pixel each end
    assert disc_x == pytest.approx(rect_x * ex * 31.0 / area)
    assert disc_x < 0.45 * rect_x
    # a strip hidden for sure (6 px short) moves it by half of that whatever the shape: kept conservative
    short_x, _ = hist.bounded_sigma_px(1, (25.0, 31.0), area - 150.0, 15.0, kappa, (False, True), (ex, ey))
    assert short_x > 3.0


def test_extent_history_remembers_a_track_seen_upright_whole() -> None:
    # a walker 40 x 100 px seen whole, then only its head and shoulders over a car (not kept: cut)
    hist = ExtentHistory(min_frames=3)
    assert not hist.seen_upright(1, 1.5)
    for _ in range(2):
        hist.bounded_sigma_px(1, (40.0, 100.0), 2500.0, 15.0, (0.0, 0.0))
    assert not hist.seen_upright(1, 1.5)  # two frames: too few
    hist.bounded_sigma_px(1, (40.0, 100.0), 2500.0, 15.0, (0.0, 0.0))
    hist.bounded_sigma_px(1, (38.0, 30.0), 900.0, 15.0, (0.0, 12.0), (True, False))
    assert hist.seen_upright(1, 1.5) and not hist.seen_upright(1, 3.0)
    for _ in range(3):  # a ball
        hist.bounded_sigma_px(2, (30.0, 30.0), 700.0, 15.0, (0.0, 0.0))
    assert not hist.seen_upright(2, 1.5)


def test_extent_history_measures_a_persons_stature_from_its_whole_frames() -> None:
    # h / d times the baseline: a walker 100 px high at 15 px of disparity with b = 0.3 m is 2.0 m tall
    hist = ExtentHistory(min_frames=3)
    assert hist.stature_m(1, 0.3, 15.0) is None
    for h, d in ((100.0, 15.0), (96.0, 14.4), (104.0, 15.6), (101.0, 15.0)):
        hist.bounded_sigma_px(1, (40.0, h), 2500.0, d, (0.0, 0.0))
    hist.bounded_sigma_px(1, (40.0, 30.0), 900.0, 15.0, (0.0, 12.0), (True, False))  # its top alone: not kept
    height, sigma = hist.stature_m(1, 0.3, 15.0)  # type: ignore[misc]
    assert height == pytest.approx(0.3 * statistics.median([100 / 15, 96 / 14.4, 104 / 15.6, 101 / 15]))
    # the four h / d values scatter by 1.4826 x their median deviation; at least the outline's rounding
    hd = [100 / 15, 96 / 14.4, 104 / 15.6, 101 / 15]
    mad = 1.4826 * statistics.median([abs(v - statistics.median(hd)) for v in hd])
    assert sigma == pytest.approx(0.3 * max(mad, 1.0 / (np.sqrt(6.0) * 15.0)))
    assert hist.stature_m(1, 0.3, 40.0)[1] == pytest.approx(0.3 * max(mad, 1.0 / (np.sqrt(6.0) * 40.0)))  # type: ignore[index]
    assert hist.stature_m(1, 0.3, 0.0) is None


def test_extent_history_lets_a_cut_fade_over_sightings_not_at_once() -> None:
    # endless:body with seed 2, frames 1988-1991: the cut not found in one frame of a walker going behind
    # a crate; what was hidden comes back over frames
    hist = ExtentHistory()
    CUT = (False, False)  # neither extent seen whole: no history to bound it by
    f = hist.fade
    assert hist.cut_sigma_px(1, (20.0, 30.0), 600.0, 15.0, (8.0, 4.0), CUT) == (8.0, 4.0)
    sx, sy = hist.cut_sigma_px(1, (20.0, 30.0), 600.0, 15.0, (0.1, 0.0), CUT)  # a fade, then another
    assert 0 < f < 1 and sx == pytest.approx(8.0 * f) and sy == pytest.approx(4.0 * f)
    sx, sy = hist.cut_sigma_px(1, (20.0, 30.0), 600.0, 15.0, (0.0, 0.0), CUT)
    assert sx == pytest.approx(8.0 * f * f) and sy == pytest.approx(4.0 * f * f)
    sx, sy = hist.cut_sigma_px(1, (20.0, 30.0), 600.0, 15.0, (6.0, 0.0), CUT)  # a larger cut at once
    assert sx == 6.0 and sy == pytest.approx(4.0 * f**3)
    assert hist.cut_sigma_px(2, (20.0, 30.0), 600.0, 15.0, (0.0, 0.0)) == (0.0, 0.0)  # another track its own
    hist.keep_only([2])
    assert hist.cut_sigma_px(1, (20.0, 30.0), 600.0, 15.0, (0.0, 0.0)) == (0.0, 0.0)  # ended: forgotten

