"""The per-frame pipeline: detection (eq. 9), centroid (eq. 10), matching and triangulation (eq. 1-2),
identities, and the primary target's r, θ, φ.

`Pipeline.step(frame) -> FrameResult` is pure computation on its own state: call it from one worker
thread (the server runs it that way); results are immutable dataclasses that can be handed to other
threads and published to many subscribers.
"""

from __future__ import annotations

import time
from dataclasses import replace
from functools import cache, partial

import cv2
import numpy as np
from numpy.typing import NDArray

from tracker.bgdepth import BackgroundDepth, CorrespondenceMap
from tracker.bglearn import LearntBackground, Sighting, StreamLearnConfig, StreamLearner, changed_box
from tracker.detect import Box, DetectorConfig, StereoSubtractor
from tracker.disparity_sigma import PartSpread, blob_sigma, on_surface
from tracker.egomotion import PoseCompensation
from tracker.extent_history import ExtentHistory
from tracker.frames import StereoFrame
from tracker.geometry import StereoRig
from tracker.heading import HeadingHistory
from tracker.localize import Localization, Localizer, with_gap_x
from tracker.one_camera import OneCameraConfig
from tracker.outline import OutlineConfig, warped_outline_sigma_px
from tracker.partly_seen import partly_seen, speck_rest
from tracker.rectify import Rectifier
from tracker.regions import hints_inside
from tracker.results import Blob, Detection, FrameResult
from tracker.rim_contrast import (
    RimContrastConfig,
    faint_shares,
    faint_shares_of,
    grown_shift_y,
    rim_shift_px,
    rim_sigma_px,
    stereo_residual,
)
from tracker.round_face import matched_factor
from tracker.schedule import SigmaSchedule, SigmaTerms, VerifySchedule
from tracker.segmentation import HeightHistory, outer_runs, outline_sigma_px
from tracker.solid_prior import SolidPrior
from tracker.split import join_occluded, join_parts
from tracker.strips import whole_outline
from tracker.temporal import TemporalConfig, TemporalDetector, without_duplicates
from tracker.top_history import TopHistory, top_world_y_m
from tracker.tracks import MultiTracker, TrackerConfig
from tracker.verify import Verifier
from tracker.visibility import (
    VisibilityConfig,
    object_and_shadow,
    padded,
)

F64 = NDArray[np.float64]
BoolA = NDArray[np.bool_]
STAGES = ("candidates", "verify", "localize", "track")


class Pipeline:
    """Composes the stages for one rig. Learn the background first (`learn_background`)."""

    def __init__(self, rig: StereoRig, detector: DetectorConfig | None = None,
                 tracker: TrackerConfig | None = None, origin: F64 | None = None,
                 temporal: TemporalConfig | None = None, verify_budget_ms: float | None = None,
                 sigma_budget_ms: float | None = None, solid: SolidPrior | None = None,
                 between_frames: bool = False, one_camera: OneCameraConfig | None = None):
        """verify_budget_ms: in real time, candidate boxes that hold no track's prediction, and regions
        beside a tracked object that hold none, are verified only while the frame's step is younger than
        this (ms); the others wait for the next frame (tracker.schedule.VerifySchedule; None: all are
        verified, as offline evaluation needs for repeatable results). sigma_budget_ms: in real time, a
        tracked target's costly 1-σ terms are worked out afresh only when they would end within this many
        ms of the step's start, else taken from a recent frame (tracker.schedule.SigmaSchedule; None:
        every frame). solid: what is known of solid targets' unseen depth (tracker.solid_prior.SolidPrior;
        None: flat targets, the range is the seen face's). between_frames: the caller calls
        `between_frames` after each step, so the searches the budget leaves out wait for it. one_camera: when
        a tracked object only the left camera sees is taken at its track's disparity (tracker.one_camera)."""
        self.rig = rig
        self.rect = Rectifier(rig)
        self.bg = BackgroundDepth(self.rect, near_m=(detector or DetectorConfig()).near_m)
        self.subtractor = StereoSubtractor(self.bg, detector)
        self.verifier = Verifier(self.subtractor, self.rect)
        self.temporal = TemporalDetector(self.subtractor, self.verifier, temporal, one_camera)
        # no centroid σ of its own: the outline's is worked out in _centroid_extra
        self.localizer = Localizer(self.rect, origin, centroid_sigma_px=None, solid=solid)
        self.tracker = MultiTracker(tracker)
        self.ego = PoseCompensation(rig.left)
        self.schedule = VerifySchedule(verify_budget_ms, later=between_frames)
        self.sigma_schedule = SigmaSchedule(sigma_budget_ms)
        self.heights = HeightHistory()
        self.extents = ExtentHistory()
        self.headings = HeadingHistory()
        self.tops = TopHistory()
        self.spread = PartSpread()  # each track's parts' spread: a person's disparity 1-σ's prior
        self.visibility, self.outline, self.rim_contrast = VisibilityConfig(), OutlineConfig(), RimContrastConfig()
        self._last_gain = 1.0
        # the last frame, its objects, their track ids, its tracks' hints and all it was verified with
        self._done: tuple[StereoFrame, list[Blob], list[int], F64, F64] | None = None
        # new objects found between frames: the index of the frame they are for, (N, 3) x, y, d seen at home
        self._found: tuple[int, F64] | None = None
        self._search_ms = 5.0  # what a search between frames costs (a running mean)
        self.learner: StreamLearner | None = None

    def learn_background(self, frame: StereoFrame) -> int:
        """Learn the background's geometry from an empty-scene pair (any gimbal pose): again from the pair
        with the cameras' exposures matched where they differ (tracker.exposure; eq. (9)'s floors would
        hold the difference)."""
        return self._learn(frame)[0]

    def _learn(self, frame: StereoFrame) -> tuple[int, StereoFrame]:
        """Learn from the pair matched by its images' mean greys, then by its background's correspondence
        (tracker.exposure); again where the two disagree. Returns the points learnt and the matched pair."""
        ex = self.subtractor.exposure
        guess = ex.guessed(frame.left, frame.right)
        n = self.bg.learn(replace(frame, right=ex.balanced(frame.right, guess)) if guess.applied else frame)
        self.subtractor.reset_maps()
        matched = self.subtractor.balanced(frame)
        if abs(ex.last.k / guess.k - 1.0) > ex.cfg.dead_band:
            n = self.bg.learn(matched)
            self.subtractor.reset_maps()
        self.subtractor.prime(matched)
        return n, matched

    def learn_background_from_stream(self, first: StereoFrame, config: StreamLearnConfig | None = None) -> int:
        """Start from the first pair as the background, then learn it again from the stream's robust
        statistics while the cameras stay at its pose (tracker.bglearn): objects in view at start-up
        need not leave first. Returns the number of background points learnt from `first`."""
        n, matched = self._learn(first)
        self.learner = StreamLearner(matched, config)
        return n

    def _relearn(self, frame: StereoFrame, learnt: LearntBackground) -> None:
        """Take a background pair learnt from the stream: the temporal model becomes its left image and
        deviation; where it differs from the pair the geometry came from (an object stood there), the
        geometry and floors are learnt again inside the bounding box of those pixels."""
        assert self.learner is not None
        pose = self.subtractor.pose_of(frame.gimbal)
        self.subtractor.left_bg[pose] = (learnt.left.astype(np.float32), learnt.left_dev)
        self.subtractor.left_learnt[pose][:] = learnt.samples  # D comes from the samples
        box = changed_box(self.learner.reference_left, learnt.left, self.subtractor.cfg.epsilon,
                          self.subtractor.cfg.min_area_px)
        self.learner.reference(learnt.left, learnt.right)
        if box is None:
            return
        pair = StereoFrame(frame.index, learnt.left, learnt.right, frame.t_left, frame.t_right, frame.gimbal)
        self.bg.relearn(pair, box)
        self.subtractor.reset_maps()
        self.subtractor.restart_floor()

    def step(self, frame: StereoFrame) -> FrameResult:
        ms: dict[str, float] = {}
        self._done = None  # a frame that raises leaves nothing for between_frames
        t0 = time.perf_counter()
        frame = self.subtractor.balanced(frame)  # the right camera's exposure matched to the left's
        cands = self.subtractor.step(frame)
        t1 = time.perf_counter()
        hints = self.ego.from_home(self.tracker.predictions(frame.t), frame.gimbal)  # at this frame's pose
        # a track receding fast may be predicted past infinity (disparity <= 0): that narrows no search
        hints = hints[np.isfinite(hints).all(axis=1) & (hints[:, 2] > 0)]
        seek = self._with_found(hints, frame)  # and the new objects found between frames
        boxes = cands.worth_verifying(self.subtractor.cfg.moving_min_cells, seek)
        blobs, deferred = self.schedule.run(boxes, seek, lambda box, may_search: self.verifier.verify_all(
            frame, box, seek, may_search=may_search), t0)
        blobs = join_parts(without_duplicates(blobs), self.rect.area_moments)  # one object again, or a part
        # cameras still: objects too near their background, tracked ones the right camera cannot see
        blobs = self.temporal.detect(frame, blobs, hints, cache(partial(self._coasting, frame)))
        blobs = join_occluded(blobs, lambda box: self._background_disparity(frame, box),  # one body, two sides
                              self.subtractor.cfg.min_depth_gap, self.rect.area_moments)
        blobs = [b for b in blobs if not b.part_only]  # a piece at the border the rest was not found for
        blobs = [on_surface(b, partial(self.verifier.part_fits, frame, b)) for b in blobs]  # a person's: its parts'
        t2 = time.perf_counter()
        obs = np.array([[b.centroid_raw[0], b.centroid_raw[1], b.disparity] for b in blobs]).reshape(-1, 3)
        # from centroids and disparities alone (not their σ), as seen at home: the mount's turning taken out
        sigma_d, alone = np.array([b.disparity_sigma for b in blobs]), np.array([b.one_camera for b in blobs], bool)
        ids = self.tracker.update(frame.t, self.ego.to_home(obs, frame.gimbal), sigma_d, alone)
        for kept in (self.sigma_schedule, self.heights, self.extents, self.headings, self.tops, self.spread):
            kept.keep_only([tr.track_id for tr in self.tracker.tracks])
        for blob, i in zip(blobs, ids, strict=True):
            self.spread.add(i, blob.parts, blob.disparity)
        t_ids = time.perf_counter()
        locs = [self._locate(frame, b, blobs, i, t0) for b, i in zip(blobs, ids, strict=True)]
        self._done = (frame, blobs, ids, hints, seek)  # for `between_frames`
        t3 = time.perf_counter()
        masks = [(b.box, b.mask) for b in blobs]
        self.subtractor.update_floor(self.subtractor.foreground_low(masks))
        gain = self.temporal.gain or (max(blobs, key=lambda b: b.area).gain if blobs else self._last_gain)
        self._last_gain = gain
        self.subtractor.update_left_background(frame, masks, gain)
        if self.learner is not None:
            seen = [Sighting(b.box, b.mask, b.disparity) for b in blobs]
            learnt = self.learner.observe(frame, gain, not cands.moving, seen)
            if learnt is not None:
                self._relearn(frame, learnt)
        t4 = time.perf_counter()
        for name, a, b in zip(STAGES, (t0, t1, t_ids, t3), (t1, t2, t3, t4), strict=True):
            ms[name] = (b - a) * 1e3
        ms["track"] += (t_ids - t2) * 1e3
        dets = tuple(Detection(b, loc, i) for b, loc, i in zip(blobs, locs, ids, strict=True))
        pid = self.tracker.primary_id
        primary = next((d for d in dets if d.track_id == pid), None)
        return FrameResult(frame.index, frame.t, dets, pid, primary, ms, deferred)

    def _coasting(self, frame: StereoFrame) -> F64:
        """MultiTracker.coasting at this frame's time and pose (x, y through the mount's turning), for the
        temporal stage, which asks for it only where a region matches nowhere (tracker.one_camera)."""
        coast = self.tracker.coasting(frame.t, self.temporal.one_cfg.max_missed)
        coast[:, :3] = self.ego.from_home(coast[:, :3], frame.gimbal)
        return coast[np.isfinite(coast).all(axis=1) & (coast[:, 2] > 0)]

    def _background_disparity(self, frame: StereoFrame, box: Box) -> tuple[NDArray[np.float32], NDArray[np.bool_]]:
        """The learnt background's rectified disparity (px) over a box of the left image, and where known."""
        cm = self.subtractor.correspondence(0, frame.gimbal, box)
        return cm.disparity, cm.valid

    def _locate(self, frame: StereoFrame, b: Blob, blobs: list[Blob], track_id: int, start: float) -> Localization:
        """eq. (1-2) for a blob, with its 1-σ: the matcher's, the costlier terms (SigmaTerms) and, every
        frame, a piece lost or gained at the outline's top or bottom (tracker.segmentation.HeightHistory)."""
        terms = self.sigma_schedule.terms(track_id, frame.index, start,
                                          lambda: self._sigma_terms(frame, b, blobs, track_id))
        _, _, w, h = cv2.boundingRect(b.mask.view(np.uint8))
        jump = self.heights.sigma_px(track_id, frame.index, float(h), b.disparity)
        solid = self.localizer.solid  # a person's outline narrows with its stride: its shape, not a strip lost
        kx, ky = self.extents.cut_sigma_px(track_id, (float(w), float(h)), float(b.area), b.disparity, terms.cut_px,
                                           terms.seen_whole, outer_runs(b.mask),
                                           None if solid is None else solid.upright_aspect,
                                           None if solid is None else solid.fragment_px(b.disparity, self.rect.b))
        cx = with_gap_x(float(np.hypot(terms.centroid_px[0], kx)), terms.gap_x_px, self.localizer.solid, w, h)
        cy = float(np.hypot(terms.centroid_px[1], ky))
        in_frame = b.box[1] > 0 and b.box[3] < self.rig.left.size[1]  # its box reaches neither top nor bottom
        fuse = b.bottom_inferred and not terms.hidden_below  # its feet inferred: from its top and its centroid
        top_seen = in_frame or (terms.hidden_below and b.box[1] > 0)  # its bottom past the image's edge
        top = self._top_px(b) if (terms.hidden_below or fuse) and top_seen else None  # seen over what hides it
        swing, gait = self.headings.shares(track_id, frame.index, self.localizer.origin)
        top_sigma = 0.0 if top is None or solid is None or terms.seen_whole[0] else \
            solid.top_sigma_px(float(w), b.disparity, self.rect.b)
        if b.box[1] > 0:  # its top seen: a piece lost there moves a centre found from it halfway up
            y_top = top_world_y_m(self.rect, frame.gimbal, float(b.centroid_rect[0]), self._top_px(b), b.disparity)
            off = self.tops.offset_px(track_id, y_top, b.disparity, self.rect.b)
            if top is not None and off != 0.0:
                top, top_sigma = top - off / 2.0, float(np.hypot(top_sigma, off / 2.0))
        centre = (b.centroid_rect + self.rect.shift_to_rect(b.centroid_raw, terms.rim_shift_px)  # faint bands undone
                  + self._perspective_px(b, (float(w), float(h)), terms))
        loc = self.localizer.locate(centre, b.disparity, max(b.disparity_sigma, terms.disparity_px),
                                    b.area, frame.gimbal, (cx, float(np.hypot(cy, jump))), (float(w), float(h)),
                                    terms.rim_px, in_frame, top, swing, True if terms.known_person else None,
                                    None if top is None else self.extents.stature_m(track_id, self.rect.b, b.disparity),
                                    gait, self.subtractor.left_background(frame.gimbal) is None, fuse,
                                    self._matched(b, track_id, (float(w), float(h))), top_sigma)
        self.headings.add(track_id, frame.index, frame.t, loc.world)
        return loc

    def _matched(self, b: Blob, track_id: int, extent_px: tuple[float, float]) -> float:
        """A round body's centre's depth behind the face its matched pixels measure over its SolidPrior's
        (tracker.round_face.matched_factor); 1 for a wide body (SolidPrior.behind_face_px does not scale
        it), for an outline matched whole (a person's) and for a piece of a track seen upright whole before
        (a person's part, not a ball). extent_px: the outline's (w, h), px."""
        solid = self.localizer.solid
        if (solid is None or solid.wide(*extent_px) or whole_outline(b.mask)
                or self.extents.seen_upright(track_id, solid.upright_aspect)):
            return 1.0
        return matched_factor(b.mask, self.rect.f, solid.ratio)

    def _perspective_px(self, b: Blob, extent_px: tuple[float, float], terms: SigmaTerms) -> F64:
        """How far (px, x and y) a solid body's centre's direction lies from eq. (10)'s centroid by perspective:
        to its direction centroid (Rectifier.direction_centroid) along x for a body seen whole across, along
        y too for a round one seen whole (neither upright nor wide; an upright body's rows each lie at about
        one depth, so its y is a plane figure's), and not at all for a wide one (a vehicle's long flat sides
        are not mirrored about the ray) or without a SolidPrior (a board). A side cut by the image's edge or
        a nearer object is not mirrored either. walk:body's walkers at 3 m lay up to 0.1° outwards before."""
        solid = self.localizer.solid
        if solid is None or solid.wide(*extent_px) or not terms.seen_whole[0]:
            return np.zeros(2)
        shift = self.rect.direction_centroid(b.box, b.mask) - b.centroid_rect
        if terms.known_person or solid.upright(*extent_px) or not terms.seen_whole[1]:
            shift[1] = 0.0
        return shift

    def _top_px(self, b: Blob) -> float:
        """The rectified y (px) of a blob's outline's top: the upper edge of its highest row's pixels."""
        rows = np.flatnonzero(b.mask.any(axis=1))
        cols = np.flatnonzero(b.mask[rows[0]])
        x, y = int(b.box[0] + cols[cols.size // 2]), int(b.box[1] + rows[0])
        return float(self.rect.rect_of_raw[0][y, x, 1]) - 0.5

    def _sigma_terms(self, frame: StereoFrame, b: Blob, blobs: list[Blob], track_id: int | None = None
                     ) -> SigmaTerms:
        """The blob's SigmaTerms (track_id: its track, which may know it as a person); one correspondence map."""
        mask, box = padded(b.mask, b.box, self.rig.left.size, left=2 + int(np.ceil(max(b.disparity, 0.0))),
                           below=2 + b.box[3] - b.box[1])
        cm = self.subtractor.correspondence(0, frame.gimbal, box)
        extra, gap_x, hidden_below, cut, whole, known = self._centroid_extra(frame, b, blobs, track_id, (mask, box, cm))
        x0, y0 = box[0], box[1]  # the blob's box within the ring's
        rim, shift = self._rim_px(frame, b, cm.crop((b.box[0] - x0, b.box[1] - y0, b.box[2] - x0, b.box[3] - y0)),
                                  known)
        s_d = blob_sigma(b, partial(self.verifier.part_fits, frame, b), self.spread.prior(track_id, b.disparity))
        return SigmaTerms(s_d, extra, gap_x, rim, hidden_below, cut, whole, known, shift)

    def _rim_px(self, frame: StereoFrame, b: Blob, cm: CorrespondenceMap, person: bool = False
                ) -> tuple[tuple[float, float] | None, tuple[float, float]]:
        """A solid body's outline's 1-σ (px, x and y) from its rim's contrast against the temporal model or,
        the cameras moving, the stereo pair's (tracker.rim_contrast); None without a SolidPrior, or for an
        upright body (or `person`, known as one) while the cameras move (its outline warped: the
        SolidPrior's fixed rim term). cm: the background's correspondences over the blob's box. Second: the
        true silhouette's centroid's offset from the outline's (px, x and y; rim_contrast.rim_shift_px), where
        a curved rim loses a band on its faint sides: along x but for a wide body (a vehicle's flat faces),
        along y but for a wide one (a person's faint bottom is its lower legs over the ground, a band of its
        own: rim_contrast.RimContrastConfig.person_band_still_y; the 1-σ along y stays the full side's for
        a person, whose head and feet tracker.segmentation's terms describe); (0, 0) where there is no 1-σ."""
        if self.localizer.solid is None:
            return None, (0.0, 0.0)
        upright, wide = self._seen_as(b)
        person |= upright
        model = self.subtractor.left_background(frame.gimbal)
        if model is None and person:
            return None, (0.0, 0.0)
        gain = self.temporal.gain or b.gain
        if model is None:
            res, tested = stereo_residual(frame.left, frame.right, b.box, b.mask, b.disparity, cm, self.rect)
            shares = faint_shares_of(b.mask, res, tested, self.rim_contrast)
        else:
            shares = faint_shares(b.mask, b.box, frame.left, model[0], gain, self.rim_contrast)
        corrected = (not wide, not (wide or person))  # a curved rim's band (rim_contrast.rim_shift_px)
        undone = (not wide, not wide)  # and a person's faint bottom, its legs over the ground
        shift = rim_shift_px(shares, b.mask, self.rim_contrast, undone, model is not None, person)
        if model is not None and corrected[1]:  # a round body, still: its faint rows beyond the outline,
            # measured, where they move it further than the band expected (rim_contrast.grown_shift_y)
            grown = grown_shift_y(b.mask, b.box, frame.left, model, gain, self.subtractor.cfg.epsilon,
                                  self.rim_contrast)
            shift = (shift[0], grown if abs(grown) > abs(shift[1]) else shift[1])
        return rim_sigma_px(shares, self.rim_contrast, corrected, model is None), shift

    def between_frames(self, deadline: float) -> None:
        """In real time, after a frame's results are out and before the next frame is due (`deadline`,
        time.perf_counter seconds): the searches for new objects the frame's budget left out
        (VerifySchedule `later`), whose finds the next frame verifies as it does tracked objects, from
        their position and disparity; then the tracked targets' costly 1-σ terms of the frame, for the
        next frame to use (tracker.schedule.SigmaSchedule.refresh)."""
        done, self._done = self._done, None
        if done is None:
            return
        frame, blobs, ids, hints, seek = done
        found = []
        later = self.schedule.take_later()
        for k, box in enumerate(later):
            if time.perf_counter() + self._search_ms * 1e-3 > deadline:
                self._search_ms *= 0.7  # a cost once high is not held against every later window
                self.schedule.not_made(later[k:])
                break
            t = time.perf_counter()
            new = [b for b in self.verifier.verify_all(frame, box, seek)
                   if not (b.part_only or _explained(b, hints, blobs))]
            self._search_ms += 0.2 * ((time.perf_counter() - t) * 1e3 - self._search_ms)
            self.schedule.searched_later(box, bool(new))
            found += [[b.centroid_raw[0], b.centroid_raw[1], b.disparity] for b in new]
        if found:  # for the next frame only
            self._found = (frame.index + 1, self.ego.to_home(np.array(found, np.float64), frame.gimbal))
        for b, i in zip(blobs, ids, strict=True):
            self.sigma_schedule.refresh(i, frame.index, deadline, partial(self._sigma_terms, frame, b, blobs, i))

    def _with_found(self, hints: F64, frame: StereoFrame) -> F64:
        """The hints and the new objects found between the frame before and this one, at this frame's
        pose (not after frames skipped, a source fault or a rewind: where they were says little then)."""
        found, self._found = self._found, None
        if found is None or found[0] != frame.index:
            return hints
        return np.vstack([hints, self.ego.from_home(found[1], frame.gimbal)])

    def _centroid_extra(self, frame: StereoFrame, b: Blob, blobs: list[Blob], track_id: int | None,
                        ring: tuple[BoolA, Box, CorrespondenceMap]
                        ) -> tuple[tuple[float, float], float, bool, tuple[float, float], tuple[bool, bool], bool]:
        """The centroid's further 1-σ (px, x and y): where its outline is drawn by warping (no temporal
        model at this pose: the cameras move; tracker.outline), the outline's whole pixels and the parts of
        a body its segmentation may have missed in the notches of its outline (tracker.segmentation); in
        quadrature, all being independent. Returned apart: the hull gap's x term (SigmaTerms.gap_x_px;
        `with_gap_x`), whether a nearer background hides the blob's bottom while its top is seen
        (SigmaTerms.hidden_below), and what may be hidden where the target is seen in part
        (SigmaTerms.cut_px and seen_whole, tracker.partly_seen). A wide body (SolidPrior.wide: a car side-on)
        has no hull-gap term along y: the gap beside its cabin, over its body, is its shape, not pixels
        the segmentation missed (occlusion:body, frames 50-174: 2.3 to 3.0 px along y, medians, for
        elevation errors of 0.32 to 1.56 px rms; 100 % of those frames within 1σ). Last: whether its track
        knows it as a person its outline no longer shows as one (SigmaTerms.known_person). Its terms here
        stay an outline's that is not upright: the upright x term scales with the seen height, 12 px of
        head and shoulders on endless:body, and with these terms dropped for it azimuth NEES went 0.95 ->
        3.02 there."""
        others = [e for o in blobs if o is not b for e in object_and_shadow(o.box, o.mask, o.disparity, o.bg_disparity)]
        upright, wide = self._seen_as(b)
        hidden_below, cut, whole = partly_seen(b, others, upright, ring, self.rig.left.size, self.visibility,
                                               (self.localizer.solid, self.rect.b), self._level_from(b, track_id))
        solid = self.localizer.solid  # a person whose top alone shows now: its track showed it whole
        known = hidden_below and not upright and solid is not None and track_id is not None and \
            self.extents.seen_upright(track_id, solid.upright_aspect)
        if solid is not None and not (upright or known):  # a speck: a piece of a body, its rest unseen
            cut, whole = speck_rest(b, solid, self.rect.b, cut, whole)
        edge, (gap_x, gap_y) = outline_sigma_px(b.mask)
        px, py = 0.0, 0.0
        # a car's cabin over its body, the space between a person's legs: their shape; a person's x: its
        # SolidPrior term, fitted to errors that hold the edge term
        terms = [(0.0 if upright else edge[0], edge[1]), (0.0, 0.0 if wide or upright else gap_y)]
        if self.subtractor.left_background(frame.gimbal) is None:
            terms.append(warped_outline_sigma_px(b.mask, self.outline))
        for ox, oy in terms:
            px, py = float(np.hypot(px, ox)), float(np.hypot(py, oy))
        return (px, py), gap_x, hidden_below, cut, whole, known

    def _level_from(self, b: Blob, track_id: int | None) -> float | None:
        """The disparity (px) a background is judged level with the blob from (tracker.visibility.cuts): its
        track's held disparity (MultiTracker.held_disparity) where farther than its own, else None."""
        held = self.tracker.held_disparity(track_id)
        return held if held is not None and held < b.disparity else None

    def _seen_as(self, b: Blob) -> tuple[bool, bool]:
        """Whether the blob is an upright body and whether a wide one, by the SolidPrior (its outline's
        width and height)."""
        solid = self.localizer.solid
        if solid is None:
            return False, False
        _, _, w, h = cv2.boundingRect(b.mask.view(np.uint8))
        return solid.upright(float(w), float(h)), solid.wide(float(w), float(h))


def _explained(b: Blob, hints: F64, blobs: list[Blob]) -> bool:
    """Whether a blob found between frames is an object known already: a hint lies on it, or its centroid
    lies on an object the frame found."""
    centroid = b.centroid_raw[None, :]
    return bool(hints_inside(hints, b.mask, b.box)) or any(hints_inside(centroid, o.mask, o.box) for o in blobs)
