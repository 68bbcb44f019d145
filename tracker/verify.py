"""Full-resolution verification of a candidate and its centroid (paper eq. 9 both ways, eq. 10).

Occlusion shadows: with the left image as key, an object also shows up where the right camera sees it at
the background disparity, a "ghost" displaced by (d_object - d_background). With the right image as key the
ghost falls on the other side. Warping the right-key mask into the left image at the object's disparity
and intersecting it with the left-key mask keeps the object and removes both ghosts (for convex objects
exactly; Ivanov, Bobick and Liu's verification by warping in both directions).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

import cv2
import numpy as np
from numpy.typing import NDArray

from tracker.bgdepth import CorrespondenceMap
from tracker.bottom_edge import feet_at_ground_depth
from tracker.detect import Box, StereoSubtractor
from tracker.frames import StereoFrame
from tracker.growth import at_own_depth, grow_tracked, without_uncovered
from tracker.masks import (
    NEAR,
    change,
    changed_holes_filled,
    found_pixels,
    frame_gain,
    key_mask,
    largest_component,
    seen_changed,
    strict_limit,
    taken_pixels,
    temporal_outline,
    with_head,
)
from tracker.rectify import Rectifier
from tracker.region_match import RegionMatcher
from tracker.regions import (
    at_left_border,
    background_disparity,
    beyond_occluder_hints,
    border_hints,
    changed_at_depth,
    hints_around,
    in_front,
    mask_centroid,
    median_behind,
    nearest_hint,
)
from tracker.results import Blob
from tracker.rim import RimConfig
from tracker.rim_recovery import DEFAULT_RIM, RimRecovery
from tracker.split import hidden_between, join, own_pixels, rival_gap, same_body

U8 = NDArray[np.uint8]
F64 = NDArray[np.float64]
F32 = NDArray[np.float32]
BoolA = NDArray[np.bool_]


_PART_TRIES = 2  # regions of a box verified as parts of a body found before (tracker.split.same_body)


_REACH_PX = 4  # a track's predicted centroid in a gap of the key mask's region (an arm's, a crack) still names it
# how far outside a region's rectangle a track predicted about it still counts (hints_around): a walker's
# predicted centroid lies below a region of its upper body (endless:body frame 465: 4.3 px below), or beside
# its occlusion shadow, all the left key shows of a walker before a wall at its own depth (frame 1329: 7.7 px)
_AROUND_MARGIN_PX = 8
_AROUND_PX = 1.0  # a track predicted within a region's rectangle this near its match (px) names it (_seen_through)


def _part_of(found: list[Blob], region: BoolA, area: int, min_part_px: int) -> Blob | None:
    """The object found before of which a region too small to be a second object lies where a part of
    its body would (split.same_body at the object's own disparity), or None (or when under min_part_px)."""
    if area < min_part_px:
        return None
    return next((f for f in found if same_body(f.mask, f.disparity, region, f.disparity)), None)


class Verifier(RegionMatcher):
    """Turns candidate boxes into verified Blobs (or nothing); its regions' disparities are matched as
    tracker.region_match does."""

    def __init__(self, sub: StereoSubtractor, rect: Rectifier, rim: RimConfig | None = DEFAULT_RIM):
        """rim: how the outline's rim is recovered by stereo, the cameras still or moving (None: it is
        not)."""
        super().__init__(sub, rect)
        self.rim = None if rim is None else RimRecovery(rim, rect, sub.cfg.epsilon)

    def verify_all(self, frame: StereoFrame, box: Box, hints: F64 | None = None, max_objects: int = 3,
                   may_search: Callable[[], bool] | None = None) -> list[Blob]:
        """Verify a candidate box, which may hold several objects (one passing in front of another):
        the largest first, then what is left once its pixels are taken out.
        hints: (N, 3) predicted (x, y, disparity) of tracks in raw left pixels (narrows the search).
        may_search: asked before a region that holds no hint is searched as a new object; False leaves
        it out this frame (tracker.schedule: the frame's time budget). None: always searched."""
        cfg = self.cfg
        x0, y0, x1, y1 = box
        cm = self.sub.correspondence(0, frame.gimbal, box)
        m_raw = key_mask(frame.left[y0:y1, x0:x1], frame.right, cm.map_x, cm.map_y, cm.valid,
                          cfg.epsilon, np.maximum(self.sub.floor_at(box), cm.floor))
        found: list[Blob] = []
        free = np.ones(m_raw.shape, bool)  # pixels no object found so far explains
        min_area, min_part = cfg.min_area_px, 4 * cfg.min_area_px
        tries, part_tries = max_objects, _PART_TRIES  # regions verified as objects, and as parts of one
        while tries > 0 and len(found) < max_objects:
            if int(np.count_nonzero(m_raw)) < (min(min_area, min_part) if found else min_area):
                break
            # where the object overlaps its own ghost, Γ and Θ both show the object and may agree: holes
            m_left = largest_component(m_raw, close=True)
            n_left = int(np.count_nonzero(m_left))
            # a second object in the box must be substantial (min_area), but a part of a body found before
            # (a head past the neck's gap) only has to be a part: it is verified at the body's disparity
            part_of = _part_of(found, m_left, n_left, min_part) if n_left < min_area and part_tries else None
            if n_left < min_area and part_of is None:
                break
            if part_of is None:
                tries -= 1
            else:
                part_tries -= 1
            hint = part_of.disparity if part_of is not None else nearest_hint(hints, m_left, box, _REACH_PX)
            around = hints_around(hints, m_left, box, _AROUND_MARGIN_PX)
            if hint is None and len(around) == 1 and at_left_border(m_left, box, around[0]):
                hint = around[0]  # one track predicted past the region's edge (a car split by a post)
            new_later = hint is None and may_search is not None and not may_search()
            got = None if new_later or self._too_small_to_be_new(n_left, hint) else self._verify_region(
                frame, box, cm, m_left, hint, free, around, found, m_raw & ~m_left)
            if got is None and hint is not None and at_left_border(m_left, box, hint):
                got, m_left = self._every_region_at_border(frame, box, cm, (m_raw, m_left), hint, free, around,
                                                           found)
            if got is None and hint is None and not new_later:  # no track's, and not found (or too small) anew
                beyond = border_hints(hints, m_left, box) or beyond_occluder_hints(
                    hints, m_left, box, cm, cfg.min_depth_gap, cfg.min_disparity_gap_px)
                got = next((g for d in beyond if (g := self._verify_region(
                    frame, box, cm, m_left, d, free, around, found)) is not None), None)
                got = None if got is None else (replace(got[0], part_only=True), got[1])
            if got is not None and hint is None and part_of is None:  # found anew: a track's object after all?
                got, m_left = self._as_tracked(frame, box, cm, (got, m_left), hints, free, found)
            hidden = None  # or a part of an object found before, a nearer background hiding what lies between
            if got is None and hint is None and not new_later:
                got, hidden = self._hidden_part(frame, box, cm, m_left, free, around, found)
            if got is None:
                m_raw = m_raw & ~m_left  # not an object: try what else the box holds
                continue
            blob, changed = got
            k = hidden if hidden is not None else next(
                (k for k, f in enumerate(found) if same_body(f.mask, f.disparity, blob.mask, blob.disparity)), None)
            if k is None and part_of is not None:  # admitted as a part, but not at the body's depth
                m_raw = m_raw & ~m_left
                continue
            if k is not None:  # a part of a body found before: one object, with the disparity and match of
                first = found.pop(k)  # the part verified first
                blob = join(first, blob, self.rect.area_moments, lead=first)
            found.append(blob)
            # a second object in the same box must be substantial: not the rim left around the first
            min_area = max(min_area, 4 * cfg.min_area_px, blob.area // 10)
            taken = taken_pixels(blob.mask, blob.disparity - blob.bg_disparity, changed)
            m_raw, free = m_raw & ~taken, free & ~taken
        return found

    def _every_region_at_border(self, frame: StereoFrame, box: Box, cm: CorrespondenceMap,
                                masks: tuple[BoolA, BoolA], d: float, free: BoolA, around: list[float],
                                found: list[Blob]) -> tuple[tuple[Blob, BoolA | None] | None, BoolA]:
        """A tracked object's region at the left border (`regions.at_left_border` at its track's disparity d)
        that failed verification, verified again as every region of the box's left-key mask at once (masks: that
        mask and the region). The right camera sees none of the object left of x = d, so the mask there
        falls apart into regions and the largest may hold too little the right camera sees to be matched:
        endless:body frame 484, a walker leaving at the left border, its mask in regions of 1,166, 727 and
        187 px; the largest (x 0-37) failed, and the temporal stage found the legs alone as a new track,
        its centroid 37 px from the truth's. Returns the verification (None: failed again) and the region
        it was made on."""
        m_raw, region = masks
        every = largest_component(m_raw, close=True, every=True)
        if int(np.count_nonzero(every)) <= int(np.count_nonzero(region)):
            return None, region
        got = self._verify_region(frame, box, cm, every, d, free, around, found)
        return got, (region if got is None else every)

    def _as_tracked(self, frame: StereoFrame, box: Box, cm: CorrespondenceMap,
                    first: tuple[tuple[Blob, BoolA | None], BoolA], hints: F64 | None, free: BoolA,
                    found: list[Blob]) -> tuple[tuple[Blob, BoolA | None], BoolA]:
        """A region no track names, verified as a new object (first: that verification and the region), whose
        object a track is predicted on (its predicted centroid on the object's outline or within _REACH_PX of
        it, at a disparity within rival_gap of the object's), verified again at that track's disparity over the
        region and the outline together: what is done for a tracked object alone then applies
        (`_tracked_outline`: the outline drawn over both keys' regions and grown into the changed pixels
        about it). Kept where it covers more. endless:body frame 222: the left key's region is a walker's arm
        and side (1,067 px), its track predicted beside it, not on it; verified anew the outline held 3,457
        px, as the track's 4,384 of the walker's 4,437 (the centroid 2.2 -> 1.5 px from the truth's). Returns
        the verification kept and the region it was made on."""
        got, region = first
        blob = got[0]
        d = nearest_hint(hints, blob.mask, box, _REACH_PX)
        if d is None or abs(d - blob.disparity) >= rival_gap(blob.disparity):
            return got, region
        joined = region | blob.mask
        around = hints_around(hints, joined, box, _AROUND_MARGIN_PX)
        again = self._verify_region(frame, box, cm, joined, d, free, around, found)
        if again is None or again[0].area <= blob.area:
            return got, region
        return again, joined

    def _hidden_part(self, frame: StereoFrame, box: Box, cm: CorrespondenceMap, region: BoolA, free: BoolA,
                     around: list[float], found: list[Blob]) -> tuple[tuple[Blob, BoolA | None] | None, int | None]:
        """A region no track names and not found anew, verified at the disparity of an object found before in
        the box where a nearer background hides what lies between them (split.hidden_between): a walker's
        leg beside a box that hides the rest of its legs, too slanted and too thin to be matched as an
        object of its own (endless:body frame 274, 390 px matched at 26.7 px with a score of 0.87 against
        the walker's 25.6 px). Returns the verification and the index in `found` of the object it is a part
        of; (None, None) where there is none, or the region does not match at that object's depth."""
        cfg = self.cfg
        for k, f in enumerate(found):
            if f.box != box or not hidden_between(f.mask, f.disparity, region, (cm.disparity, cm.valid),
                                                  cfg.min_depth_gap, cfg.min_disparity_gap_px):
                continue
            got = self._verify_region(frame, box, cm, region, f.disparity, free, around, found)
            if got is not None and abs(got[0].disparity - f.disparity) < rival_gap(f.disparity):
                return got, k
        return None, None

    def _too_small_to_be_new(self, area: int, hint: float | None) -> bool:
        """While the cameras move, a region no track is predicted in must cover moving_min_cells · stride²
        pixels to be verified as a new object: the rule the candidate stage applies to whole boxes (a moving
        view leaves small residuals at the background's edges), applied to each region of a box."""
        cfg = self.cfg
        return self.sub.moving and hint is None and area < cfg.moving_min_cells * cfg.stride * cfg.stride

    def _verify_region(self, frame: StereoFrame, box: Box, cm: CorrespondenceMap, m_left: BoolA,
                       d_hint: float | None, free: BoolA, around: list[float] | None = None,
                       found: list[Blob] | None = None, rest: BoolA | None = None
                       ) -> tuple[Blob, BoolA | None] | None:
        """Verify one connected region of the left-key mask inside a box. Returns the blob and, with the
        cameras still, the box's pixels unlike the temporal background (|Γ - g B| > ε + 3 g D).
        around: the predicted disparities of the tracks about the region (regions.hints_around); with more
        than one, a tracked object's outline keeps only its pixels that match best at its own (tracker.split).
        found: the objects found before in the box (they stay out of the outline's gain). rest: the box's
        other left-key pixels, where a head past the neck's gap may lie (_outline_stereo)."""
        cfg = self.cfg
        around = around or []
        x0, y0, x1, y1 = box
        gain, changed, matched, inferred = 1.0, None, None, False
        model = self.sub.left_background(frame.gimbal)
        if model is not None and d_hint is not None:  # a tracked object, cameras still
            obj, matched, gain, changed = self._tracked_outline(frame, box, cm, model, m_left, d_hint, free,
                                                                around, found)
            matched, d0 = self.seen_by_right(frame, box, seen_changed(matched, changed, m_left), d_hint, found), d_hint
        else:
            # a new object, or the cameras move: verification by warping in both directions
            stereo = self._outline_stereo(frame, box, cm, m_left, d_hint, rest)
            if stereo is None:
                return None
            obj, either, d0, inferred = stereo
            if model is not None:  # cameras still: the temporal model draws the exact outline
                obj, gain, changed = self._temporal_outline(frame, box, model, obj, either & free, found)
        radius, tracked = self.search_radius(d_hint), d_hint is not None
        fine = self.match_part_or_whole(frame, box, matched, obj, d0, radius, tracked)
        if fine is None:
            return None
        if self.rim is not None and model is not None and changed is not None:  # cameras still (the model
            # drew the outline, so `changed` is known): the rim eq. (9) and the model missed
            obj = self.rim.recover(frame, box, cm, obj, fine.disparity, free & ~changed, gain, model)
        elif self.rim is not None and model is None:  # cameras moving: where eq. (9) could not tell
            obj = self.rim.recover(frame, box, cm, obj, fine.disparity, free)
        if changed is not None:  # the holes the rim's growth closed where the model saw change
            obj = changed_holes_filled(obj, changed)
        if not obj.any():
            return None
        m8 = obj.view(np.uint8)
        area, c_box = mask_centroid(m8)
        c_raw = c_box + (x0, y0)  # eq. (10), c(i, j) = the object mask
        d_bg = background_disparity(cm, obj, c_raw - (x0, y0))
        # in front of the background behind its centre, or else of the median behind all its pixels: the map
        # may be wrong behind the centre alone (SGBM carries a post's disparity into a smooth ground; endless:
        # body, elevation 0.744 -> 0.630 deg); a misregistered background patch lies at its own by both
        gap, gap_px = cfg.min_depth_gap, cfg.min_disparity_gap_px
        behind = median_behind(cm, obj)
        if not (in_front(fine.disparity, d_bg, gap, gap_px) or in_front(fine.disparity, behind, gap, gap_px)):
            far = self._seen_through(cm, obj, fine.disparity, min(d_bg, behind), d_hint, around)
            if far is not None and in_front(fine.disparity, far, gap, gap_px):
                d_bg = far
            elif d_hint is None or not changed_at_depth((obj, changed), fine.disparity - min(d_bg, behind)):
                return None  # not in front of the background, untracked or unchanged: a misregistered patch
        # eq. (10) in rectified coordinates, pixels weighted by their area: Σ a x / Σ a, Σ a y / Σ a
        sx, sy, sa, _ = cv2.mean(self.rect.area_moments[y0:y1, x0:x1], mask=m8)
        return Blob(box, obj, area, c_raw, np.array([sx / sa, sy / sa]), fine.disparity, fine.sigma, d_bg,
                    fine.score, gain, bottom_inferred=inferred), changed

    def _seen_through(self, cm: CorrespondenceMap, obj: BoolA, d: float, d_bg: float, d_hint: float | None,
                      around: list[float]) -> float | None:
        """The background's disparity about a tracked object (d_hint: its track's prediction) where the map
        puts the background behind it nearer than the object itself by min_disparity_gap_px (0.5 px) or
        more: the object is seen there by both cameras, so nothing nearer stands before it and
        the map is wrong (semi-global matching carries a post's disparity into the band left of it the
        right camera cannot see). Then the farthest known background about it: the 10th percentile of the
        map's disparity over the box's known pixels outside the object. None otherwise. The whole
        depth-gap test turned round (d_bg >= d (1 + min_depth_gap) + gap_px) left a walker beside a box
        matched at 27.5 px before a map of 29.1 px refused (endless:body frame 465, 4.2° off; against it,
        `tmeye eval --all`: endless:body's elevation RMSE against the seen surface 0.396 -> 0.339°,
        occlusion:body's azimuth 0.187 -> 0.182°, the other angles within 0.0003°). A region no track
        is predicted on is a tracked object's too where one is predicted about it (`around`: within its
        bounding rectangle) within _AROUND_PX of its match: endless:body frame 464, a walker beside a box
        whose predicted centroid fell in a gap of its region; refused there, its upper part alone was kept,
        38 px above the truth's centroid."""
        tracked = d_hint is not None or any(abs(h - d) < _AROUND_PX for h in around)
        if not tracked or not in_front(d_bg, d, 0.0, self.cfg.min_disparity_gap_px):
            return None
        beyond = cm.disparity[~obj & cm.valid]
        return float(np.percentile(beyond, 10)) if beyond.size else None

    def _tracked_outline(self, frame: StereoFrame, box: Box, cm: CorrespondenceMap, model: tuple[F32, F32],
                         m_left: BoolA, d_hint: float, free: BoolA, around: list[float], found: list[Blob] | None
                         ) -> tuple[BoolA, BoolA, float, BoolA]:
        """A tracked object's outline with the cameras still, the part of it its disparity is matched on, the
        outline's gain and the box's changed pixels. The temporal model draws the part inside the left-key
        region (object and shadow), at the strict threshold (moving background there stays out); the
        outline is drawn inside the right key's region as well: where the object overlaps its own ghost in
        the left key, a smooth face compared with itself passes eq. (9) (walk:body against the seen
        surface: azimuth RMSE 0.113 -> 0.092°, elevation 0.406 -> 0.324°; matching the disparity over the
        whole outline instead made endless:body's range RMSE 0.616 -> 0.639 m and lost a far head over a
        hedge in 49 frames). The outline is the part and what the right key's region adds to it: through
        the right key's pixels, a region the left key alone sees (where a walker stood while the background
        was learnt: the temporal model still holds it) joined the outline and made it a false target."""
        at_depth = self.at_depth(frame, box, cm, model, d_hint)  # left out of the outlines' gain, and grown into
        matched = self._temporal_outline(frame, box, model, None, m_left & free, found, at_depth)[0]
        m_right = self.right_key_at(frame, box, d_hint)
        wide, gain, changed = self._temporal_outline(frame, box, model, None, (m_left | m_right) & free, found,
                                                     at_depth)
        if matched.any():  # what the right key adds to it (joined through it, a ghost the left key alone
            wide = with_head(matched | (wide & m_right))  # sees would be taken in)
        wide = grow_tracked(self.rect, frame, box, cm, model[0], wide, changed & free, d_hint, self.cfg.epsilon,
                            self.cfg.min_area_px, at_depth)
        if len(around) > 1:  # other tracks predicted about the region: keep the pixels at this one's d
            matched = own_pixels(self.rect, frame, box, matched, d_hint, around, self.cfg.min_area_px)
            wide = own_pixels(self.rect, frame, box, wide, d_hint, around, self.cfg.min_area_px)
        return wide, matched, gain, changed

    def at_depth(self, frame: StereoFrame, box: Box, cm: CorrespondenceMap, model: tuple[F32, F32], d: float
                 ) -> BoolA | None:
        """growth.at_own_depth over the box (the background's map at the body's depth d, px) where the pixel
        changed at the frame's global gain (masks.frame_gain, as tracker.temporal takes it): most likely a
        part of the body eq. (9) missed. The outline's own gain is taken on a ring about the region, so
        these pixels are left out of that ring: at endless:plate frame 1319 a plate's lower part before a
        post at its depth raised the ring's gain until the whole box changed, and the plate's outline took
        in 3,387 px of background about it (a false target at frame 1320). Parts whose edge is the model's
        rather than the frame's are left out (growth.without_uncovered: where a walker stood while the
        background was learnt, start-up). None without a global gain."""
        bg, dev = model
        g = frame_gain(frame.left, bg, self.cfg.stride)
        if g is None:
            return None
        x0, y0, x1, y1 = box
        key, b = frame.left[y0:y1, x0:x1], bg[y0:y1, x0:x1]
        changed = change(key, b, g) > strict_limit(dev[y0:y1, x0:x1], g, self.cfg.epsilon)
        at = at_own_depth(cm, d, self.cfg.min_depth_gap, self.cfg.min_disparity_gap_px) & changed
        return without_uncovered(at, key, b * np.float32(g))  # the edges of g B against Γ's

    def _temporal_outline(self, frame: StereoFrame, box: Box, model: tuple[F32, F32], core: BoolA | None,
                          region: BoolA, found: list[Blob] | None, left_out: BoolA | None = None
                          ) -> tuple[BoolA, float, BoolA]:
        """masks.temporal_outline of an object inside `region` of the box (core: none, or the pixels both
        keys agree are the object); the objects `found` before in the box and the pixels `left_out` are
        not taken for its ring's gain."""
        x0, y0, x1, y1 = box
        bg, dev = model
        taken = found_pixels([f.mask for f in found or []])
        if left_out is not None:
            taken = left_out if taken is None else taken | left_out
        return temporal_outline(frame.left[y0:y1, x0:x1], bg[y0:y1, x0:x1], dev[y0:y1, x0:x1],
                                np.zeros_like(region) if core is None else core, region, self.cfg.epsilon, taken)

    def _outline_stereo(self, frame: StereoFrame, box: Box, cm: CorrespondenceMap, m_left: BoolA,
                        d_hint: float | None, rest: BoolA | None = None) -> tuple[BoolA, BoolA, float, bool] | None:
        """The left-key mask intersected with the right-key mask warped at the object's disparity: the
        occlusion shadows of both keys drop out (verification by warping in both directions). While the
        cameras move (no temporal model to draw the outline after), a head past the neck's gap is kept
        (with_head, over the box's other left-key pixels `rest` as well where the right key sees them at
        this disparity, where that keeps the same body) and the feet eq. (9) cannot see against the ground
        are filled (feet_at_ground_depth).
        Returns that mask, the union of the two masks, the disparity used (the track's prediction, or for a
        new object a search over the whole range) and whether the feet were filled (Blob.bottom_inferred)."""
        d_hint = self._coarse_disparity(frame, box, m_left, d_hint)
        if d_hint is None:
            return None
        m_right = self.right_key_at(frame, box, d_hint)
        both = m_left & m_right
        if self.sub.left_background(frame.gimbal) is None:  # the cameras move
            head = with_head(both if rest is None else both | (rest & m_right))  # the head, or more of the
            if rest is not None and not head[largest_component(both)].all():  # body; not another thing
                head = with_head(both)
            feet = feet_at_ground_depth(head, m_left | m_right, cm.disparity, cm.valid, d_hint)
            inferred = feet is not head
            obj = with_head(feet) if inferred else head
        else:
            obj, inferred = largest_component(both), False
        if int(np.count_nonzero(obj)) < self.cfg.min_area_px:
            return None
        # the rest of the object: where the right key sees it at this disparity, or next to the solid
        near = cv2.dilate(obj.astype(np.uint8), NEAR) > 0
        return obj, m_right | (m_left & near), d_hint, inferred
