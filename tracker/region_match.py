"""Matching a region of the left image against the right at full resolution: the disparity search about a
track's prediction or over the whole range (`match_object`), the parts of a verified blob
(`part_fits`), the right-key mask of eq. (9) at a disparity (`right_key_at`) and what the right camera sees
of a region (`seen_by_right`). The verifier (tracker.verify) builds on it."""

from __future__ import annotations

from dataclasses import replace

import cv2
import numpy as np
from numpy.typing import NDArray

from tracker.detect import Box, StereoSubtractor
from tracker.disparity_sigma import part_fits
from tracker.frames import StereoFrame
from tracker.masks import changed_part, key_mask, largest_component
from tracker.one_camera import OneCameraConfig, seen_by_right
from tracker.rectify import Rectifier
from tracker.regions import row_thirds
from tracker.results import Blob, PartFit
from tracker.stereo import RegionMatch
from tracker.strips import MATCH_HALF, MIN_SCORE, Strips, first_window, whole_outline
from tracker.visibility import with_objects

BoolA = NDArray[np.bool_]

_MATCH_HALF_SLANT = (12, 8)  # the same when the larger ones match nowhere (slanted faces, near)
_SEARCH_RADIUS = 4  # px about a disparity that refining from failed to match (RegionMatcher.search_radius)
_MIN_COLS = 8  # columns of a region near the image's left edge kept for the search (RegionMatcher._strips)
_EDGE_COLS = 4  # the fewer kept, over all its rows, to look past that search's reach (RegionMatcher._beyond_reach)
_ONE = OneCameraConfig()  # its depth_tol_px and cover_px: what a nearer background hides from the right camera


class RegionMatcher:
    """A region's disparity by matching its pixels in the rectified pair (the subtractor's rig and
    settings)."""

    def __init__(self, sub: StereoSubtractor, rect: Rectifier):
        self.sub = sub
        self.rect = rect
        self.cfg = sub.cfg

    def seen_by_right(self, frame: StereoFrame, box: Box, region: BoolA, d: float, found: list[Blob] | None = None
                      ) -> BoolA:
        """one_camera.seen_by_right: the region less what a nearer background hides from the right camera,
        and the objects found before it this frame (`found`; a nearer one hides it as the background does:
        two-targets:body, frames 142-165, a ball at 5 m covered a walker's arm at 12 m in the right image,
        and the walker's range was 0.2 to 0.6 m off)."""
        ext = (box[0], box[1], min(box[2] + self.sub.bg.num_disparities, frame.left.shape[1]), box[3])
        cm = self.sub.correspondence(0, frame.gimbal, ext)
        if found:
            disp, valid = with_objects(cm.disparity, cm.valid, ext, [(f.box, f.mask, f.disparity) for f in found])
            if disp is not None and valid is not None:
                cm = replace(cm, disparity=disp, valid=valid)
        return seen_by_right(self.rect, box, region, d, cm, ext, _ONE)

    def search_radius(self, d_hint: float | None) -> int:
        """How far (px) about a track's predicted disparity d the search goes when refining from it fails:
        as far as its disparity can move in a frame at max_speed_mps, Δd = d ΔZ / Z = d² v / (f b fps)
        (Z = f b / d), doubled, between 1 and 4 px; 4 about a new object's coarse disparity. A far target
        (26 m: d 7 px, Δd 0.1 px) so cannot take a stronger peak 2 to 4 px away (a hedge behind a head)."""
        if d_hint is None:
            return _SEARCH_RADIUS
        step = d_hint * d_hint * self.cfg.max_speed_mps / (self.rect.f * self.rect.b * self.cfg.fps)
        return int(min(max(np.ceil(2.0 * step), 1), _SEARCH_RADIUS))

    def match_object(self, frame: StereoFrame, box: Box, obj: BoolA, d0: float | None,
                     radius: int = _SEARCH_RADIUS, tracked: bool = False) -> RegionMatch | None:
        """The object's disparity from matching its own pixels (a search over the whole range first when
        no prior d0 is known). None without a match, or with one the image edge may have cut short (the
        right camera may not see it). A region whose depth varies (a walker's swinging limbs about its
        centroid) may match nowhere as one surface: then its top, middle and bottom thirds are tried; and a
        near object's slanted faces, whose disparity changes across the window by several pixels (a face at
        45° across 48 px at 3 m: about 5 px), match nowhere at one disparity: then windows half as wide.
        tracked: d0 is a track's prediction (or a body's found this frame), so a small region's whole
        outline may give the disparity where its core's match disagrees or fails (Strips.match). Near the
        image's left edge, where that fails for a region the edge cuts (`_stepping_in`), the region's coarse
        disparity is searched over its whole reach as a new object's is (`_coarse_disparity`), then refined
        as above (radius, tracked; d0 as the caller gives it: a track's prediction, or a part's, a
        neighbour's or a hidden part's disparity with tracked set, tracker.verify): a track born as it came in,
        its search cut short, may hold a false peak (endless:body seed 1, frames 2465-2475: a walker stepping
        in at 17.2 px, born at 8.97 px, held at 12.16 px by the one-camera stage in frames 2469-2475). Its
        peak is taken only past the prediction's search (a false peak of a search cut short lies short of
        the true one). Not where the edge does not cut it: a 10 px sliver of a person at 18 px, 58 px from
        the edge, so searched peaked at 57.6 px (frame 2518)."""
        fine = self._match_about(frame, box, obj, self._coarse_disparity(frame, box, obj, d0), radius, tracked)
        if fine is None and tracked and d0 is not None and self._stepping_in(frame, box, obj, d0):
            # a track born as it came in, its search cut short, may hold a false peak short of its disparity
            anew = self._match_about(frame, box, obj, self._coarse_disparity(frame, box, obj, None), radius,
                                     tracked)
            fine = anew if anew is not None and anew.disparity > d0 + radius else None
        return fine

    def _match_about(self, frame: StereoFrame, box: Box, obj: BoolA, d0: float | None, radius: int,
                     tracked: bool) -> RegionMatch | None:
        """`match_object`'s refining about a coarse disparity d0 (None: nothing to refine, None)."""
        if d0 is None:
            return None
        for half in (first_window(obj), _MATCH_HALF_SLANT):
            for part in row_thirds(obj):
                strips = self._strips(frame, box, part, d0, half)
                fine = None if strips is None else strips.match(part, d0, radius, tracked)
                if fine is not None and strips is not None:
                    return self._within_reach(frame, box, part, strips, fine)
        return None

    def _stepping_in(self, frame: StereoFrame, box: Box, region: BoolA, d0: float) -> bool:
        """Whether the region is cut by the image's left edge (it reaches column 0), a search of it over the
        whole range is cut short there, and d0 (px; `match_object`'s, mostly a track's prediction) lies inside
        that search's reach by 2 px (`_within_reach`'s margin): a track leaving past the edge, its disparity
        held beyond the shrinking reach, would find only false peaks there (endless:plate seed 1, frames
        2632-2636: a board at 18.4 px so matched at 5.9 and 10.7 px)."""
        if box[0] > 0 or not region[:, 0].any():
            return False
        strips = self._strips(frame, box, region, None)
        return strips is not None and strips.clipped and d0 <= strips.d_hi - 2.0

    def _within_reach(self, frame: StereoFrame, box: Box, region: BoolA, strips: Strips, fine: RegionMatch
                      ) -> RegionMatch | None:
        """A match near the image's left edge whose search the edge cut short (strips.clipped) and whose peak
        lies within 2 px of that search's end, where the true peak may lie past it: kept where the region's
        last columns (`_narrow_match`, a search reaching at least 2 px further) peak within 1 px of it, and
        not within 2 px of their own reach; else None. Their peak is not taken itself: 4 columns are too few
        to stand alone (occlusion:body with seed 1, frame 174: a car's end left of a post, 16 px, peaked at
        41.8 px there with a score of 0.88). endless:body with seed 2, frames 1963-1964: a walker stepping
        in at the left edge (20.6-20.7 px at its centre) matched at 21.3-21.4 px with a reach of 22-23 px,
        its last columns at 20.6-20.8 px with a reach of 26-27 px; refused for lying within 2 px of the
        reach, it was lost."""
        if not strips.clipped or fine.disparity <= strips.d_hi - 2.0:
            return fine
        far, reach = self._narrow_match(frame, box, region)
        if far is None or reach < strips.d_hi + 2 or far.disparity > reach - 2.0:
            return None
        return fine if abs(far.disparity - fine.disparity) <= 1.0 else None

    def match_part_or_whole(self, frame: StereoFrame, box: Box, part: BoolA | None, whole: BoolA, d0: float | None,
                            radius: int, tracked: bool) -> RegionMatch | None:
        """match_object on `part` of a region (the pixels the right camera sees, `seen_by_right`; None: no
        such part), and where that fails or there is none, on the whole region (the same search not twice)."""
        fine = None if part is None else self.match_object(frame, box, part, d0, radius, tracked)
        if fine is None and (part is None or not np.array_equal(part, whole)):
            fine = self.match_object(frame, box, whole, d0, radius, tracked)
        return fine

    def part_fits(self, frame: StereoFrame, blob: Blob) -> list[PartFit]:
        """The disparities (px), 1-σ (px) and pixel counts of the parts of a verified blob (tracker.
        disparity_sigma.part_fits: the window `match_object` uses first cut into a grid, each part refined
        from the blob's disparity on the same strips); the parts that do not match are left out. A person's
        are matched on the pixels of its outline that changed (_changed_part), any other's robustly."""
        strips = self._strips(frame, blob.box, blob.mask, blob.disparity, first_window(blob.mask))
        if strips is None:
            return []
        whole = whole_outline(blob.mask)
        seen = self._changed_part(frame, blob) if whole else blob.mask
        return part_fits(strips.left, strips.right, strips.core(seen), strips.off, blob.disparity, MIN_SCORE,
                         robust=not whole)

    def _changed_part(self, frame: StereoFrame, blob: Blob) -> BoolA:
        """masks.changed_part of a person's outline with the cameras still (its temporal background at this
        pose); the whole outline while they move."""
        model = self.sub.left_background(frame.gimbal)
        if model is None:
            return blob.mask
        x0, y0, x1, y1 = blob.box
        return changed_part(blob.mask, frame.left[y0:y1, x0:x1], model[0][y0:y1, x0:x1], blob.gain,
                            self.cfg.epsilon)

    def _coarse_disparity(self, frame: StereoFrame, box: Box, region: BoolA, d0: float | None) -> float | None:
        """d0 if known, else the region's disparity from a search over the whole range (None: no match).
        A new object whose depth varies (a walker's swinging legs) may match nowhere as one surface, as a
        tracked one may (match_object): then its top, middle and bottom thirds are searched in turn."""
        if d0 is not None:
            return d0
        for part in row_thirds(region):
            strips = self._strips(frame, box, part, None)
            coarse = None if strips is None else strips.match(part, None, 0)
            if strips is None or coarse is None:
                continue
            if not strips.clipped:
                return coarse.disparity
            far, reach = self._narrow_match(frame, box, part)
            beyond = far is not None and reach > strips.d_hi and far.disparity > strips.d_hi + 1.0
            return None if beyond else coarse.disparity  # the peak inside the reach may be a false one
        return None

    def _narrow_match(self, frame: StereoFrame, box: Box, region: BoolA) -> tuple[RegionMatch | None, int]:
        """A region near the image's left edge, whose search the edge cut short (the right camera does not see
        left columns x < d, so a window of the region's right part reaches no further than its own columns
        less 3), matched on a window of its last _EDGE_COLS columns and all its rows, whose search reaches
        _MIN_COLS - _EDGE_COLS px further: its peak (None: none; within 2 px of that reach, the true peak may
        lie further still) and the reach (px; 0: no such window). Where it peaks past the first search's
        reach, the first search's peak may be a false one, and the region's disparity is not known this
        frame (`_coarse_disparity`). endless:body with seed 2, frames 1959-1973: a walker stepping in at
        the left edge, 32-44 px of it seen and 21 px of disparity, matched at 13.6-15.2 px on its last 8
        columns (the search reached 18 px), a range 4.6-5.3 m too far with a 1-σ of 0.2-0.4 m. A region
        whose disparity lies further still is not told from one matched right: as a region comes in at
        the edge it widens, and its disparity passes through those few pixels first."""
        narrow = self._strips(frame, box, region, None, (MATCH_HALF[0], 1 << 16), min_cols=_EDGE_COLS)
        if narrow is None:
            return None, 0
        far = narrow.match(region, None, 0)
        return far, narrow.d_hi

    def _strips(self, frame: StereoFrame, box: Box, region: BoolA, d_hint: float | None,
                half: tuple[int, int] = MATCH_HALF, min_cols: int = _MIN_COLS) -> Strips | None:
        """Rectified left/right strips around a region's rows, wide enough for the disparity search; the
        window matched is the region's central 2 half[0] x 2 half[1] px at most, and near the image's left
        edge its last min_cols columns at least."""
        rect, cfg = self.rect, self.cfg
        x0, y0, x1, y1 = box
        bx, by, bw, bh = cv2.boundingRect(region.view(np.uint8))
        if bw * bh < 8:
            return None
        # the region's box in rectified coordinates: its corners and edge midpoints (the lens bends edges)
        gx = np.array([bx, bx + bw // 2, bx + bw - 1] * 3)
        gy = np.repeat([by, by + bh // 2, by + bh - 1], 3)
        rc = rect.rect_of_raw[0][y0 + gy, x0 + gx]
        w, h = rect.rig.left.size
        rx0, ry0 = int(np.floor(rc[:, 0].min())), max(int(np.floor(rc[:, 1].min())), 0)
        rx1, ry1 = int(np.ceil(rc[:, 0].max())) + 1, min(int(np.ceil(rc[:, 1].max())) + 1, h)
        # a large object is matched on a central window only (`half`; a person on its whole outline,
        # first_window): its disparity is then already far more precise than its range needs (the range
        # error grows as z², the object shrinks as 1/z)
        cx, cy = (rx0 + rx1) // 2, (ry0 + ry1) // 2
        rx0, rx1 = max(rx0, cx - half[0]), min(rx1, cx + half[0])
        ry0, ry1 = max(ry0, cy - half[1]), min(ry1, cy + half[1])
        d_hi = cfg.max_disparity if d_hint is None else int(np.ceil(d_hint)) + 8
        # near the left edge the search range runs out of image: keep at least min_cols columns of the
        # region (its right part) and search as far as the image allows
        rx0 = max(rx0, min(d_hi + 3, rx1 - min_cols))
        clipped = rx0 - 3 < d_hi
        d_hi = min(d_hi, rx0 - 3)
        rx1 = min(rx1, w - 2)  # at the right edge, match on the part inside the image
        if d_hi < 3 or rx1 - rx0 < 4 or ry1 <= ry0:
            return None
        sx0 = rx0 - d_hi - 2
        box_r = (sx0, ry0, rx1 + 2, ry1)
        return Strips(rect, (x0, y0), (rx0, ry0, rx1, ry1), rect.rectify(frame.left, 0, box_r),
                       rect.rectify(frame.right, 1, box_r), rx0 - sx0, d_hi, clipped)

    def right_key_at(self, frame: StereoFrame, box: Box, d: float) -> BoolA:
        """The right-key mask of eq. (9), sampled at the left box's pixels shifted by disparity d."""
        rect = self.rect
        x0, y0, x1, y1 = box
        ur, vr = rect.right_at(box, d)
        w, h = rect.rig.right.size
        bx0, by0 = max(int(np.floor(ur.min())) - 1, 0), max(int(np.floor(vr.min())) - 1, 0)
        bx1, by1 = min(int(np.ceil(ur.max())) + 2, w), min(int(np.ceil(vr.max())) + 2, h)
        if bx0 >= bx1 or by0 >= by1:
            return np.zeros((y1 - y0, x1 - x0), bool)
        rbox = (bx0, by0, bx1, by1)
        cm = self.sub.correspondence(1, frame.gimbal, rbox)
        floor = cm.floor
        m_right = largest_component(key_mask(frame.right[by0:by1, bx0:bx1], frame.left, cm.map_x, cm.map_y,
                                     cm.valid, self.cfg.epsilon, floor), close=True, every=True).astype(np.float32)
        sampled = cv2.remap(m_right, (ur - bx0).astype(np.float32), (vr - by0).astype(np.float32),
                            cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT, borderValue=0.0)
        return np.asarray(sampled >= 0.5)
