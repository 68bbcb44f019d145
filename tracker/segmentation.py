"""How far off the centroid of eq. (10) may lie because the outline itself is imperfect (issue 12 item 1).

Three terms, from the mask and the track's recent masks alone (no truth), each a 1-σ in px along x and y
(y only for the last), added in quadrature to the centroid's other terms (tracker.pipeline):

`edge_quantisation_px`: an outline is a set of whole pixels. Each row's run of mask pixels ends at a whole
pixel where the true outline crosses the row somewhere within it, unknown and evenly spread over it as the
target moves by fractions of a pixel: that end is off by 1/√12 px rms, and it moves the centroid along x
by (its offset) x (its position - the centroid) / the area; likewise each column's run ends for y. Where
the outline is slanted or curved, it crosses each column of pixels within a few rows (the staircase of
its image) and the ends' errors change from row to row: they are independent. Where it runs straight along
a column (a board's upright side, seen square on), the ends of all its rows there lie at one unknown
offset: they move together, and the centroid with them, by n times as much for a run of n rows. A run
counts as straight when it is longer than a curved outline's can be: the outline of a disc of radius R
(px) stays within one column for about 2√R rows where it turns, a straight side for its whole length, so
runs of at least 2√(2 E) rows (E: the outline's extent along them) are taken as straight, unless they are
steps of a slanted side's staircase (the next steps carry on one column over, to either side). So, over the
runs k of row ends in one column (n_k rows, at x_k) and of column ends in one row (at y_k),

    σ_cx² = Σ_k w_k (x_k - c_x)² / (12 A²),   w_k = n_k² for a straight run, n_k otherwise   (px², A in px)

and σ_cy² the same with the column ends. For a W x H px plate seen square on that is 1/√24 = 0.20 px along
each axis whatever its size; for a disc of radius R about 1/√(24 R) (0.035 px at R = 20). Checked against
point-sampled outlines at 300 random sub-pixel positions each: discs of radius 8, 20 and 50 px scatter by
0.049, 0.034 and 0.022 px (the term: 0.049, 0.033, 0.021), boards of 30 x 100 and 80 x 240 px by 0.27 to
0.30 px (their two sides alike offset when the width is a whole number of pixels: 1/√12 = 0.29; 0.20 with
the sides independent), the same boards turned by 3 to 34 degrees by 0.010 to 0.024 px (the term: 0.018 to
0.040). The earlier term took every edge pixel as independent, 0.014 to 0.05 px for those boards: the
endless scene's boards, standing still for seconds at one sub-pixel offset, were 26.6 times their
azimuth 1-σ² off on average.

`hull_gap_px`: a solid, textured, shaded body (a person, a vehicle) is not segmented whole: faces turned
from the light, a texture like the background, the gap at the neck leave parts of it out (about 17 % of a
person's silhouette in the simulated scenes), and what is left out lies in notches of the outline. The
pixels inside the mask's convex hull but not in the mask (the hull gap, n_g px) are each either background
seen through a concave outline (between the legs) or the target missed; which, one frame cannot tell. If a
share u of them is the target, the centroid moves by u n_g / (A + u n_g) times their offset from it; with u
unknown and evenly spread over [0, 1] (rms 1/√3), and the gap's pixels at their rms distance from the
centroid along each axis,

    σ_gx = κ s √(mean_gap (x - c_x)²),   s = n_g / (A + n_g),   κ = 1/√3.

A convex outline (a plate, a sphere seen whole) has no gap and no such term; a merged or badly cut mask, a
large one. The pixels a body loses beyond the hull (a head past the neck's gap) are not in it.

`HeightHistory`: a piece lost or gained at the top or bottom shows as a change of the outline's height that
the target's change of range does not explain (see the class). The first two cost about 0.15 ms a target
together and go through tracker.schedule.SigmaSchedule; the third, a few µs, is worked out every frame.
"""

from __future__ import annotations

import math
import statistics

import cv2
import numpy as np
from numpy.typing import NDArray

BoolA = NDArray[np.bool_]
_CROSS = cv2.getStructuringElement(cv2.MORPH_CROSS, (3, 3))
EDGE_PX = 1.0 / np.sqrt(12.0)  # rms error (px) of where the true outline crosses an end pixel
KAPPA = 1.0 / np.sqrt(3.0)  # rms of the unknown share of the hull gap that is the target


def edge_quantisation_px(mask: BoolA) -> tuple[float, float]:
    """The centroid's 1-σ (px, x and y) from the whole-pixel outline: EDGE_PX times the root of the
    weighted sums of the squared distances of the runs of its rows' (columns') end pixels from its
    centroid (straight runs move as one; see the module's docstring), over its area. mask: (h, w) bool,
    any origin. (0, 0) for an empty mask."""
    return outline_sigma_px(mask)[0]


def hull_gap_px(mask: BoolA, kappa: float = KAPPA) -> tuple[float, float]:
    """The centroid's 1-σ (px, x and y) from the mask's hull gap (the pixels of its convex hull, drawn
    through its outline's pixel centres, that are not in it, the hull's own 1-px rim left out): kappa x
    the gap's share of mask and gap x the gap pixels' rms distance from the mask's centroid along each
    axis. mask: (h, w) bool, any origin. (0, 0) for an empty or convex mask."""
    return outline_sigma_px(mask, kappa)[1]


def outline_sigma_px(mask: BoolA, kappa: float = KAPPA) -> tuple[tuple[float, float], tuple[float, float]]:
    """`edge_quantisation_px` and `hull_gap_px` of a mask at once: ((x, y), (x, y)) in px. The mask and its
    hull gap are summed along the columns and rows in one pass (cv2.reduce over the two as channels), their
    centroids and spreads taken from those sums; the runs of the outline's row and column ends are found as
    connected components. About 0.2 ms for a walker's 100 x 45 px mask in the pipeline."""
    bx, by, bw, bh = cv2.boundingRect(mask.view(np.uint8))
    if bw == 0:
        return (0.0, 0.0), (0.0, 0.0)
    m8 = np.ascontiguousarray(mask.view(np.uint8)[by:by + bh, bx:bx + bw])  # the work scales with the box
    contours, _ = cv2.findContours(m8, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
    filled = np.zeros_like(m8)
    cv2.fillConvexPoly(filled, cv2.convexHull(np.concatenate(contours)), 1)
    # the hull's own rim left out: a digitised convex outline (a disc) differs from its hull's there
    gap = cv2.subtract(cv2.erode(filled, _CROSS, borderType=cv2.BORDER_CONSTANT, borderValue=0), m8)
    two = cv2.merge([m8, gap])
    cols = cv2.reduce(two, 0, cv2.REDUCE_SUM, dtype=cv2.CV_64F).reshape(-1, 2)  # (w, 2): Σ per column
    rows = cv2.reduce(two, 1, cv2.REDUCE_SUM, dtype=cv2.CV_64F).reshape(-1, 2)  # (h, 2)
    x, y = np.arange(bw, dtype=np.float64), np.arange(bh, dtype=np.float64)
    n, sx, sy, sxx, syy = cols.sum(axis=0), x @ cols, y @ rows, (x * x) @ cols, (y * y) @ rows
    cx, cy = sx[0] / n[0], sy[0] / n[0]
    ex, ey = _end_runs(m8, cx, cy)
    edge_px = (float(EDGE_PX * np.sqrt(ex) / n[0]), float(EDGE_PX * np.sqrt(ey) / n[0]))
    if n[1] == 0:
        return edge_px, (0.0, 0.0)
    # Σ (x - cx)², Σ (y - cy)² of the gap's pixels about the mask's centroid
    vx = max(sxx[1] - 2.0 * cx * sx[1] + cx * cx * n[1], 0.0)
    vy = max(syy[1] - 2.0 * cy * sy[1] + cy * cy * n[1], 0.0)
    share = kappa * n[1] / (n[0] + n[1])
    return edge_px, (float(share * np.sqrt(vx / n[1])), float(share * np.sqrt(vy / n[1])))


def _end_runs(m8: NDArray[np.uint8], cx: float, cy: float) -> tuple[float, float]:
    """Σ_k w_k (x_k - c_x)² over the runs k of the rows' end pixels that lie in one column, and Σ_k w_k
    (y_k - c_y)² over those of the columns' end pixels in one row (px²; see the module's docstring): w_k the
    run's length n_k, or n_k² where it is straight. Two left ends (or two right ends) are never side by
    side in a row, so the runs are the 4-connected components of each side's end pixels; likewise for the
    top and bottom ends."""
    bh, bw = m8.shape
    pad = cv2.copyMakeBorder(m8, 1, 1, 1, 1, cv2.BORDER_CONSTANT, value=0)
    inner = pad[1:-1, 1:-1]
    sums = []
    for axis, c, sides in ((0, cx, (pad[1:-1, :-2], pad[1:-1, 2:])),  # left and right ends: runs down a column
                           (1, cy, (pad[:-2, 1:-1], pad[2:, 1:-1]))):  # top and bottom ends: along a row
        v = 0.0
        for outside in sides:
            ends = cv2.copyMakeBorder(cv2.subtract(inner, outside), 1, 1, 1, 1, cv2.BORDER_CONSTANT, value=0)
            e = np.ascontiguousarray(ends if axis == 0 else ends.T, np.uint8)  # runs down the columns of e
            _, _, stats, centres = cv2.connectedComponentsWithStats(e, connectivity=4)
            k = stats[1:, cv2.CC_STAT_HEIGHT].astype(np.float64)
            d = centres[1:, 0] - (c + 1.0)  # the border of one pixel
            straight = _straight(e, np.asarray(stats[1:], np.int32), extent=bh if axis == 0 else bw)
            v += float(np.where(straight, k * k, k) @ (d * d))
        sums.append(v)
    return sums[0], sums[1]


def _straight(e: NDArray[np.uint8], stats: NDArray[np.int32], extent: int) -> NDArray[np.bool_]:
    """Which runs down the columns of e (end pixels, a zero border around them; stats of their
    components) are straight: at least 2√(2 E) long (E = `extent`, the outline's extent along them: a
    curved outline turns within about 2√R of its radius R) and not a step of a slanted outline's staircase
    (whose neighbouring steps, one column to one side beyond its top and to the other side beyond its
    bottom, carry on the slant)."""
    x, top, n = stats[:, cv2.CC_STAT_LEFT], stats[:, cv2.CC_STAT_TOP], stats[:, cv2.CC_STAT_HEIGHT]
    above = e[top - 1, x + 1].astype(np.int8) - e[top - 1, x - 1].astype(np.int8)  # +1: the step above is right
    below = e[top + n, x + 1].astype(np.int8) - e[top + n, x - 1].astype(np.int8)
    return np.asarray((n >= 2.0 * np.sqrt(2.0 * extent)) & ~((above != 0) & (above == -below)))


class HeightHistory:
    """The outline's height per track over its last `frames` frames, to tell a piece of the target lost or
    gained at its top or bottom (a head past the neck's gap, feet against the ground, another object
    merged) from the target's own change of size.

    A target's image height scales with its disparity (h / d is its height in metres over f b) and, for a
    walker, hardly changes with its gait (its legs and arms swing across the line of sight: they change
    the outline's width by a fifth within a stride, symmetrically about its centre, but not its height).
    So where the height differs from the median of the last frames' h / d times this frame's d by more
    than the pixel the outline's ends may round to, the difference is a piece lost or gained at one end:
    it moves the centroid by about half of it, the 1-σ added along y. Cheap (a median of at most
    `frames` numbers): worked out every frame, not through the SigmaSchedule."""

    def __init__(self, frames: int = 15, min_frames: int = 3, max_gap: int = 3, round_px: float = 1.0):
        self.frames = frames
        self.min_frames = min_frames
        self.max_gap = max_gap
        self.round_px = round_px
        self._kept: dict[int, tuple[int, list[float]]] = {}  # track id -> (last frame index, h / d values)

    def sigma_px(self, track_id: int, index: int, height_px: float, disparity: float) -> float:
        """The centroid's further 1-σ along y (px) for the track's outline of height_px at frame `index`
        with disparity `disparity` (px), and the height kept for the next frames. 0 until the track has
        min_frames heights from frames at most max_gap apart."""
        if disparity <= 0:
            return 0.0
        last, seen = self._kept.get(track_id, (index, []))
        if index - last > self.max_gap or index < last:
            seen = []
        out = 0.0
        if len(seen) >= self.min_frames:
            expected = statistics.median(seen) * disparity  # a few µs on 15 floats, unlike np.median
            out = 0.5 * max(abs(height_px - expected) - self.round_px, 0.0)
        seen = (seen + [height_px / disparity])[-self.frames:]
        self._kept[track_id] = (index, seen)
        return out

    def keep_only(self, track_ids: list[int]) -> None:
        """Forget the heights of tracks not in track_ids (ended)."""
        live = set(track_ids)
        self._kept = {i: v for i, v in self._kept.items() if i in live}


def outer_runs(mask: BoolA, depth: int = 2) -> tuple[float, float]:
    """The outline's outermost runs (px): the mean count of mask pixels over its first `depth` columns,
    or its last (the larger), and the same over its rows. A strip δ (a pixel or less) wide hidden at a side
    covers about δ times that run: it moves the centroid by δ run (extent / 2) / area, half of δ for a
    rectangle, about an eighth for a disc of radius 15 px (its outer columns 1 and 11 px long: a cap δ
    deep covers about (4/3) √(2 R δ) δ px², 3.2 px² at δ = 0.57, 7.4 px² at δ = 1). Over two columns, not
    the first alone: a rasterised disc often ends in a single pixel. On two-targets:plate (a disc beside a
    nearer crosser, its width's history scattering by 0.57 px with its rounding) azimuth within 1σ 0.762
    -> 0.746, NEES 0.722 -> 0.756 (over one column 0.742, over three 0.754: at the band's edge)."""
    cols, rows = np.flatnonzero(mask.any(axis=0)), np.flatnonzero(mask.any(axis=1))
    if cols.size == 0:
        return 0.0, 0.0
    m = mask[rows[0]:rows[-1] + 1, cols[0]:cols[-1] + 1]
    k = min(depth, m.shape[1]), min(depth, m.shape[0])
    x = max(np.count_nonzero(m[:, :k[0]]), np.count_nonzero(m[:, m.shape[1] - k[0]:])) / k[0]
    y = max(np.count_nonzero(m[:k[1]]), np.count_nonzero(m[m.shape[0] - k[1]:])) / k[1]
    return float(x), float(y)


class ExtentHistory:
    """A track's seen width and height over its disparity (w / d, h / d: its size in metres over f b), each
    from the frames where that axis was seen whole (no side along it cut, tracker.visibility.cuts, and
    nothing lost against the ground along y), and its area over d² from the frames seen whole, to tell how
    much of it the sides cut now hide.

    A cut side's 1-σ, kappa times the visible extent (tracker.visibility.extra_sigma_px), and the
    centroid's move across it (`cuts`' skew, likewise kappa's) suppose nothing is known of how far the
    target goes on behind what cuts it. Of a target seen whole a few frames before, it is. Its extent then,
    scaled by this frame's disparity, less the extent seen now, is what is hidden along that axis: the
    centroid lies half of that from the whole target's (exactly for a rectangle, less for a round shape).
    The area hidden beyond what those strips account for (their length times the other extent) lies
    within the outline (a rail across a board: the extents stay whole): it moves the centroid by up to its
    share of the seen area times half the extent. Each is as uncertain as the history's own scatter (its
    robust scale (`_stats`) scaled by d, d²: a walker's width changes with its stride), at least the
    extents' rounding where an end along that axis is cut (each end of the outline rounds by up to half a
    pixel, evenly: 1/√6 px rms; a board's kept extents scatter by that rounding alone, which is not counted
    twice). Along an axis seen whole (both ends seen, kappa's term there only the centroid's move across a
    cut side) that rounding is the outline's edge term's (`edge_quantisation_px`), not counted again. That 1-σ,
    never more than kappa's, stands for kappa's along an axis with a history. two-targets:plate, frames
    102-180: a disc beside a nearer crosser, seen whole, had kappa x its 31 px width, 12.4 px, along x and
    y, and a move across its cut top of 9.9 px along x, where its centroid was off by under 0.01 px; on
    occlusion:plate a board coming in past the image's left edge and then behind posts, its height seen
    whole throughout, had up to 12.5 px along y for errors of 0.01 px. A frame whose extent or area falls
    short of the history's by more than twice its scatter and the rounding is not kept (a board sinking
    behind a hedge, the cut not found in every frame); the history is kept while the track lives (a long
    cut must not wear it out), and used from `min_frames` frames.

    An extent that exceeds the history's by more than twice its scatter and the rounding says the outline
    took in a strip that is not the target's (a ghost, a neighbour's part), on a side not known: the
    centroid lies half of that off, as across a hidden strip. endless:plate, frames 1329-1331: a board 35 px
    wide by its history, at the image's left edge, was drawn 51 to 62 px wide; its width counted as seen
    whole bounded its x 1-σ to 0.25 px, for azimuth errors of 0.70 to 1.03° (13 to 15 σ, a fifth of the
    scenario's azimuth NEES); with the excess, 0.8 to 1.7 σ."""

    def __init__(self, frames: int = 15, min_frames: int = 3, round_px: float = 1.0, fade: float = 0.35,
                 lost_share: float = 0.1):
        self.frames = frames
        self.lost_share = lost_share
        self.min_frames = min_frames
        self.round_px = round_px
        self.fade = fade
        # track id -> the w / d, h / d and A / d² values kept
        self._kept: dict[int, tuple[list[float], list[float], list[float]]] = {}
        self._last: dict[int, tuple[float, float]] = {}  # track id -> the cut 1-σ (px, x and y) last given

    def cut_sigma_px(self, track_id: int, extent_px: tuple[float, float], area_px: float, disparity: float,
                     cut_px: tuple[float, float], seen_whole: tuple[bool, bool] = (True, True),
                     edge_px: tuple[float, float] | None = None, upright_aspect: float | None = None
                     ) -> tuple[float, float]:
        """`bounded_sigma_px`, at least `fade` times what the track's last sighting was given: the cut is
        not found in every frame (endless:body with seed 2, frames 1988-1991: a walker going behind a crate
        had an x term of 20.7, 2.9, 0.07 and 7.1 px; at 1990 its azimuth 1-σ was 0.016° for an error of
        0.50°), and what was hidden comes back into view over frames, not at once. fade 0.35 against 0.5:
        `eval --all` seed 0 kept its 120 lines met (118 with 0.5: two 1-σ lines one frame over their band's
        top as what was hidden came back), endless:body's azimuth NEES 1.40 -> 1.31 (1.28)."""
        got = self.bounded_sigma_px(track_id, extent_px, area_px, disparity, cut_px, seen_whole, edge_px,
                                    upright_aspect)
        last = self._last.get(track_id, (0.0, 0.0))
        out = (max(got[0], self.fade * last[0]), max(got[1], self.fade * last[1]))
        self._last[track_id] = out
        return out

    def bounded_sigma_px(self, track_id: int, extent_px: tuple[float, float], area_px: float, disparity: float,
                         cut_px: tuple[float, float], seen_whole: tuple[bool, bool] = (True, True),
                         edge_px: tuple[float, float] | None = None, upright_aspect: float | None = None
                         ) -> tuple[float, float]:
        """The cut sides' 1-σ (px, x and y) for a track's outline of extent_px (width, height, px) and
        area_px (px²) at disparity d (px), given kappa's (cut_px; (0, 0): seen whole) and whether its
        width and height were seen whole (kept for later frames). edge_px: the outline's outermost runs
        (`outer_runs`), for how far the history's scatter moves the centroid (None: a rectangle's, half of
        it): what varies from frame to frame is the outline's outermost part (a board's rounded side, a
        walker's limb reaching out), whose area is the scatter times that run. A strip hidden for sure
        (`off`) counts at half its width whatever the shape. upright_aspect: a SolidPrior's
        (None: no person expected); a track whose history stands at least that many times as high as wide
        (`seen_upright`, from the same medians) is a person, whose outline narrows from frame to frame with
        its stride and its arms, so an axis seen whole and short of the history is its shape, not a strip
        lost (`_lost_unseen`)."""
        if disparity <= 0 or area_px <= 0:
            return cut_px
        kept = self._kept.setdefault(track_id, ([], [], []))
        scale = (disparity, disparity, disparity * disparity)
        now = (extent_px[0], extent_px[1], area_px)
        stats = [self._stats(v, k) for v, k in zip(scale, kept, strict=True)]
        for a, whole in enumerate((seen_whole[0], seen_whole[1], cut_px == (0.0, 0.0))):
            st = stats[a]
            if whole and (st is None or now[a] >= st[0] - self._slack(st[1], a)):
                kept[a].append(now[a] / scale[a])
                del kept[a][:-self.frames]
        expected = [now[a] if st is None else st[0] for a, st in enumerate(stats[:2])]
        short = [max(e - n, 0.0) for e, n in zip(expected, now[:2], strict=True)]
        cut_px = self._lost_unseen(cut_px, seen_whole, short, stats, upright_aspect)
        if cut_px == (0.0, 0.0):  # nothing cut: nothing to bound
            return cut_px
        strips = short[0] * expected[1] + short[1] * expected[0]  # the area the extents' shortfalls hide
        inside = 0.0 if stats[2] is None else max(stats[2][0] - area_px - strips, 0.0)
        spread_a = 0.0 if stats[2] is None else stats[2][1]
        out = []
        for a, kappa in enumerate(cut_px):
            st = stats[a]
            if kappa <= 0.0 or st is None:
                out.append(kappa)
                continue
            over = now[a] - expected[a]  # a strip taken in that is not the target's, past the slack
            off = max(short[a], over if over > self._slack(st[1], a) else 0.0)  # hidden, or taken in
            floor = 0.0 if seen_whole[a] else self.round_px**2 / 6.0  # both ends seen: the edge term's
            g = 0.5 if edge_px is None else min(0.5, 0.5 * edge_px[a] * expected[a] / area_px)
            var = 0.25 * off**2 + g * g * max(st[1] ** 2, floor)
            var += (0.5 * expected[a] / area_px) ** 2 * (inside**2 + spread_a**2)
            out.append(min(kappa, float(np.sqrt(var))))
        return out[0], out[1]

    def _lost_unseen(self, cut_px: tuple[float, float], seen_whole: tuple[bool, bool], short: list[float],
                     stats: list[tuple[float, float] | None], upright_aspect: float | None
                     ) -> tuple[float, float]:
        """kappa's terms (cut_px), unbounded (inf, for `bounded_sigma_px` to bound) along an axis where no cut
        was found (seen whole, no term) but the extent falls short of the history's by more than the slack
        and `lost_share` of it: a strip lost at a side not known, eq. (9) and the temporal model missing it
        against a background like it, not something seen to hide it. endless:body with seed 1, frames
        2770-2772: a head and shoulders over a hedge at 28 m, 12-13 px wide by its history, drawn 7 px wide;
        its x term 0 (no cut), its azimuth 1-σ 0.006-0.029° for errors of 0.18-0.23° (z -34 to -6: a fifth
        of the scenario's azimuth NEES). lost_share: a ball at 2 m is drawn 2-3 % narrower than its
        history's w / d says, seen whole (approach:body seed 0, frames 286-299: with the slack alone its
        azimuth 1-σ went 0.017 -> 0.58° for errors of 0.05°). Not for a walker (its history upright by
        upright_aspect, as `seen_upright` tells from the same medians): a stride's narrowing took walk:body's
        azimuth within 1σ 0.72 -> 0.80 (seed 0), its upright term (tracker.solid_prior) already holding it."""
        out = list(cut_px)
        for a in range(2):
            st = stats[a]
            if out[a] == 0.0 and seen_whole[a] and st is not None and \
                    short[a] > max(self._slack(st[1], a), self.lost_share * st[0]):
                out[a] = math.inf
        w, h = stats[0], stats[1]
        if out != list(cut_px) and upright_aspect is not None and w is not None and h is not None and \
                h[0] >= upright_aspect * w[0]:  # a person: its stride, not a strip lost
            return cut_px
        return out[0], out[1]

    def seen_upright(self, track_id: int, aspect: float) -> bool:
        """Whether the track, seen whole (its kept widths and heights), stood at least `aspect` times as high
        as wide: a person, though only its top shows now."""
        kept = self._kept.get(track_id)
        if kept is None or min(len(kept[0]), len(kept[1])) < self.min_frames:
            return False
        return statistics.median(kept[1]) >= aspect * statistics.median(kept[0])

    def stature_m(self, track_id: int, baseline_m: float, disparity: float) -> tuple[float, float] | None:
        """The height (m) of the track seen whole, b times the median of its kept h / d, and its 1-σ: b times
        their robust scale, at least the outline's rounding at this disparity (1/√6 px); None with too few
        heights kept. A person's stature from its own frames, for placing it from its top when its lower
        part is hidden (tracker.localize.Localizer._below_top)."""
        kept = self._kept.get(track_id)
        st = None if kept is None or disparity <= 0 else self._stats(1.0, kept[1])
        if st is None:
            return None
        return baseline_m * st[0], baseline_m * max(st[1], 1.0 / (math.sqrt(6.0) * disparity))

    def _slack(self, spread: float, axis: int) -> float:
        """How far a value may stray from the history's median and still be the whole target's: twice the
        history's scatter `spread`, and the rounding for an extent (axis 0, 1; not the area, axis 2). A frame
        short by more is not kept; an extent over by more took in a strip that is not the target's."""
        return 2.0 * spread + (self.round_px if axis < 2 else 0.0)

    def _stats(self, scale: float, kept: list[float]) -> tuple[float, float] | None:
        """The median and a robust scale (1.4826 times the median absolute deviation: a standard deviation
        for Gaussian values) of the kept values, times scale; None with too few. A frame kept whole that
        took in a strip (occlusion:plate: one frame drawn 35 px high among 29s) made the standard deviation
        1.5 px for the next 15 frames, and the bound on a post's cut 0.75 px for errors of 0.01-0.03 px.
        Plain Python on at most `frames` floats: every frame, for every target, a few µs (numpy's
        median and std took 65 µs a call, as HeightHistory found)."""
        n = len(kept)
        if n < self.min_frames:
            return None
        med = statistics.median(kept)
        return med * scale, 1.4826 * statistics.median([abs(v - med) for v in kept]) * scale

    def keep_only(self, track_ids: list[int]) -> None:
        """Forget the extents of tracks not in track_ids (ended)."""
        live = set(track_ids)
        self._kept = {i: v for i, v in self._kept.items() if i in live}
        self._last = {i: v for i, v in self._last.items() if i in live}
