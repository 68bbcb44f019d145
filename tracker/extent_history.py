"""A track's extents seen whole, for how much of it a cut hides now (issue 12 item 1; see ExtentHistory).

The centroid's terms for the outline itself (edge quantisation, the hull gap, a piece lost at the top or
bottom) are tracker.segmentation's; a side cut by the image's edge or a nearer object is
tracker.visibility's kappa term, which this history bounds where the track was seen whole before.
"""

from __future__ import annotations

import math
import statistics
from collections.abc import Sequence

import numpy as np


def _upright(stats: Sequence[tuple[float, float] | None], aspect: float | None) -> bool:
    """Whether a history's width and height medians (stats[0], stats[1]: (median, scale) or None with too
    few kept) stand at least `aspect` times as high as wide (a SolidPrior's upright_aspect; None: no person
    expected): a person's."""
    w, h = stats[0], stats[1]
    return aspect is not None and w is not None and h is not None and h[0] >= aspect * w[0]


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
    twice). Along an axis seen whole (both ends seen, kappa's term there only the centroid's move across a cut
    side) that rounding is the outline's edge term's (tracker.segmentation.edge_quantisation_px), not counted
    again. That 1-σ, never more than kappa's, stands for kappa's along an axis with a history.
    two-targets:plate, frames 102-180: a disc beside a nearer crosser, seen whole, had kappa x its 31 px
    width, 12.4 px, along x and y, and a move across its cut top of 9.9 px along x, where its centroid was off
    by under 0.01 px; on occlusion:plate a board coming in past the image's left edge and then behind posts,
    its height seen whole throughout, had up to 12.5 px along y for errors of 0.01 px. A frame whose extent or
    area falls short of the history's by more than twice its scatter and the rounding is not kept (a board
    sinking behind a hedge, the cut not found in every frame); the history is kept while the track lives (a
    long cut must not wear it out), and used from `min_frames` frames.

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
                     edge_px: tuple[float, float] | None = None, upright_aspect: float | None = None,
                     fragment_px: tuple[float, float] | None = None) -> tuple[float, float]:
        """`bounded_sigma_px`, at least `fade` times what the track's last sighting was given: the cut is
        not found in every frame (endless:body with seed 2, frames 1988-1991: a walker going behind a crate
        had an x term of 20.7, 2.9, 0.07 and 7.1 px; at 1990 its azimuth 1-σ was 0.016° for an error of
        0.50°), and what was hidden comes back into view over frames, not at once. fade 0.35 against 0.5:
        `eval --all` seed 0 kept its 120 lines met (118 with 0.5: two 1-σ lines one frame over their band's
        top as what was hidden came back), endless:body's azimuth NEES 1.40 -> 1.31 (1.28)."""
        got = self.bounded_sigma_px(track_id, extent_px, area_px, disparity, cut_px, seen_whole, edge_px,
                                    upright_aspect, fragment_px)
        last = self._last.get(track_id, (0.0, 0.0))
        out = (max(got[0], self.fade * last[0]), max(got[1], self.fade * last[1]))
        self._last[track_id] = out
        return out

    def bounded_sigma_px(self, track_id: int, extent_px: tuple[float, float], area_px: float, disparity: float,
                         cut_px: tuple[float, float], seen_whole: tuple[bool, bool] = (True, True),
                         edge_px: tuple[float, float] | None = None, upright_aspect: float | None = None,
                         fragment_px: tuple[float, float] | None = None) -> tuple[float, float]:
        """The cut sides' 1-σ (px, x and y) for a track's outline of extent_px (width, height, px) and
        area_px (px²) at disparity d (px), given kappa's (cut_px; (0, 0): seen whole) and whether its
        width and height were seen whole (kept for later frames). edge_px: the outline's outermost runs
        (tracker.segmentation.outer_runs), for how far the history's scatter moves the centroid (None: a
        rectangle's, half of it): what varies from frame to frame is the outline's outermost part (a board's
        rounded side, a walker's limb reaching out), whose area is the scatter times that run. A strip hidden
        for sure (`off`) counts at half its width whatever the shape. upright_aspect: a SolidPrior's (None: no
        person expected); a track whose history stands at least that many times as high as wide
        (`seen_upright`, from the same medians) is a person, whose outline narrows from frame to frame with
        its stride and its arms, so its width seen whole and short of the history is its shape, not a strip
        lost (`_lost_unseen`; its height short of it is one). fragment_px: the height and the width (px)
        under which a person's outline at this disparity is a fragment (SolidPrior.fragment_px; None: no
        person expected): a history of a fragment bounds nothing (`_fragment`)."""
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
        if self._fragment(stats, upright_aspect, fragment_px):
            return cut_px
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
        azimuth 1-σ went 0.017 -> 0.58° for errors of 0.05°). Not across a walker (its history upright by
        upright_aspect, as `seen_upright` tells from the same medians): a stride's narrowing took walk:body's
        azimuth within 1σ 0.72 -> 0.80 (seed 0), its upright term (tracker.solid_prior) already holding it.
        Along its height, yes: a walker's height hardly changes with its gait (segmentation.HeightHistory).
        endless:body with seed 2 (people of people's statures), frames 1768-1775: a person's head and
        shoulders over a hedge at 24 m, drawn 17 px high and, the hedge not found below it, taken as seen
        whole; its elevation 1-σ faded to 0.023° for errors of 1.0° (z 42), now 1.48° (z 0.7)."""
        out = list(cut_px)
        person = _upright(stats, upright_aspect)
        for a in range(2):
            st = stats[a]
            if out[a] == 0.0 and seen_whole[a] and st is not None and not (person and a == 0) and \
                    short[a] > max(self._slack(st[1], a), self.lost_share * st[0]):
                out[a] = math.inf
        return out[0], out[1]

    @staticmethod
    def _fragment(stats: list[tuple[float, float] | None], upright_aspect: float | None,
                  fragment_px: tuple[float, float] | None) -> bool:
        """Whether the history's medians (stats, px at this disparity) are a person's fragment's, not the
        whole target's (fragment_px: SolidPrior.fragment_px, the height and width under which they are;
        None: no person expected): upright (at least upright_aspect times as high as wide) and short of the
        height, or, its height never seen whole, narrower than the width. What a cut hides is not known from
        them, nor a strip lost where no cut was found from its narrowing (a person's piece narrows with its
        stride as the whole does: `_lost_unseen`'s rule for an upright history). endless:body with seed 1,
        frames 2546-2595: a track born on a 16 px wide sliver of a walker beside a post (a person's shoulders
        21 px there), its height never seen whole, had its x 1-σ bounded by the sliver's width to 0.017° (z up
        to 99) once a closing as in an empty plane let the sliver through."""
        w, h = stats[0], stats[1]
        if upright_aspect is None or fragment_px is None or w is None:
            return False
        if h is None:
            return w[0] < fragment_px[1]
        return _upright(stats, upright_aspect) and h[0] < fragment_px[0]

    def seen_upright(self, track_id: int, aspect: float) -> bool:
        """Whether the track, seen whole (its kept widths and heights), stood at least `aspect` times as high
        as wide: a person, though only its top shows now."""
        kept = self._kept.get(track_id)
        return kept is not None and _upright([self._stats(1.0, k, spread=False) for k in kept[:2]], aspect)

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

    def _stats(self, scale: float, kept: list[float], spread: bool = True) -> tuple[float, float] | None:
        """The median and a robust scale (1.4826 times the median absolute deviation: a standard deviation
        for Gaussian values; 0 unless `spread`) of the kept values, times scale; None with too few. A frame
        kept whole that took in a strip (occlusion:plate: one frame drawn 35 px high among 29s) made the
        standard deviation 1.5 px for the next 15 frames, and the bound on a post's cut 0.75 px for errors
        of 0.01-0.03 px. Plain Python on at most `frames` floats: every frame, for every target, a few µs
        (numpy's median and std took 65 µs a call, as HeightHistory found)."""
        n = len(kept)
        if n < self.min_frames:
            return None
        med = statistics.median(kept)
        if not spread:
            return med * scale, 0.0
        return med * scale, 1.4826 * statistics.median([abs(v - med) for v in kept]) * scale

    def keep_only(self, track_ids: list[int]) -> None:
        """Forget the extents of tracks not in track_ids (ended)."""
        live = set(track_ids)
        self._kept = {i: v for i, v in self._kept.items() if i in live}
        self._last = {i: v for i, v in self._last.items() if i in live}
