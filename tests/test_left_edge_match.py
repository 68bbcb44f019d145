"""A region at the image's left edge whose disparity lies past what its search can reach
(tracker.region_match.RegionMatcher._narrow_match): the right camera does not see left columns x < d, so
the search on the region's last columns stops short of its disparity, and where the right image beside the
object looks like it a few pixels on (here drawn so: the object's texture, noisy, PERIOD px right of it)
the search takes a false peak inside its reach. The region's disparity is then not known that frame; where
the region is wide enough to reach its own disparity, it is found. A tracked object's match within 2 px of
its search's end is kept where a window of its last 4 columns, reaching 4 px further, agrees
(RegionMatcher._within_reach)."""

from __future__ import annotations

from dataclasses import replace

import cv2
import numpy as np

from tracker.frames import StereoFrame
from tracker.pipeline import Pipeline
from tracker.sim.scenarios import SimRig, get_scenario

D = 23.0  # the object's disparity (px)
PERIOD = 7  # the right image PERIOD px right of the object looks like it: a false peak at D - PERIOD
ROWS = (200, 320)  # its rows (rectified)


def _texture(seed: int = 3) -> np.ndarray:
    """A smooth random texture over the rectified image and 64 px more, (480, 704) float32 grey levels."""
    t = cv2.GaussianBlur(np.random.default_rng(seed).normal(0.0, 1.0, (480, 704)).astype(np.float32), (0, 0), 1.2)
    return (128.0 + 40.0 * t / t.std()).astype(np.float32)


def _pair(right_edge: float) -> tuple[Pipeline, StereoFrame, tuple[int, int, int, int], np.ndarray]:
    """The walk scene's empty pair learnt, then an object over the rectified columns left of `right_edge`
    (it goes on past the image's left edge) and ROWS, at disparity D, drawn into both raw images through
    the rectification: the pipeline, the frame, the region's box (raw left px) and its mask over the box."""
    sim = SimRig(get_scenario("walk"), seed=0)
    pipe = Pipeline(sim.rig)
    empty = sim.background()
    pipe.learn_background(empty)
    rect = pipe.verifier.rect
    tex = _texture()
    noise = np.random.default_rng(5).normal(0.0, 12.0, (480, 640)).astype(np.float32)
    images = []
    masks = []
    for cam, shifts in ((0, (0.0,)), (1, (D - PERIOD, D))):  # the right camera sees left column u at u - D
        raw = (empty.left if cam == 0 else empty.right).astype(np.float32)
        rc = rect.rect_of_raw[cam]
        for shift in shifts:  # the decoy first, then the object over it
            u, v = rc[..., 0] + np.float32(shift), rc[..., 1]
            inside = (u < right_edge) & (v >= ROWS[0]) & (v < ROWS[1])
            drawn = cv2.remap(tex, u + np.float32(32.0), v, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT)
            raw[inside] = drawn[inside] + (noise[inside] if shift != D and cam == 1 else 0.0)
        images.append(np.clip(raw, 0, 255).astype(np.uint8))
        masks.append(inside)
    ys, xs = np.nonzero(masks[0])
    box = (0, int(ys.min()), int(xs.max()) + 1, int(ys.max()) + 1)
    region = masks[0][box[1]:box[3], box[0]:box[2]]
    return pipe, replace(empty, left=images[0], right=images[1]), box, region


def test_a_region_whose_disparity_lies_past_the_edge_cut_search_is_not_given_a_false_one() -> None:
    for right_edge in (30.0, 32.0):  # the last 4 columns peak at the end of their reach, and inside it
        pipe, frame, box, region = _pair(right_edge)
        strips = pipe.verifier._strips(frame, box, region, None)
        assert strips is not None and strips.clipped and strips.d_hi < D  # the search cannot reach D
        near = strips.match(region, None, 0)
        assert near is not None and abs(near.disparity - (D - PERIOD)) < 1.0  # the false peak it would take
        far, _ = pipe.verifier._narrow_match(frame, box, region)
        assert far is not None and abs(far.disparity - D) < 0.5
        assert pipe.verifier._coarse_disparity(frame, box, region, None) is None


def test_a_tracked_match_near_its_reach_is_kept_where_the_last_columns_agree() -> None:
    pipe, frame, box, region = _pair(34.0)
    strips = pipe.verifier._strips(frame, box, region, D)
    assert strips is not None and strips.clipped and strips.d_hi - 2.0 < D  # within 2 px of the reach
    fine = pipe.verifier.match_object(frame, box, region, D, 4, tracked=True)
    assert fine is not None and abs(fine.disparity - D) < 0.2


def test_a_region_wide_enough_to_reach_its_disparity_is_matched_there() -> None:
    pipe, frame, box, region = _pair(60.0)
    d = pipe.verifier._coarse_disparity(frame, box, region, None)
    assert d is not None and abs(d - D) < 0.5


def test_a_track_stepping_in_whose_search_fails_about_its_prediction_is_searched_over_its_reach() -> None:
    # endless:body seed 1, frames 2469-2475: a walker stepping in at the left edge at 17.2 px, its track born
    # at 8.97 px while the edge cut its search short, failed to match about 12.16 px, and the one-camera
    # stage held that: 5 m too far. The region (cut by the edge, wide enough now) is searched over its reach
    pipe, frame, box, region = _pair(60.0)
    reach = pipe.verifier._strips(frame, box, region, None)
    assert reach is not None and reach.clipped and reach.d_hi - 2.0 > 30.0 > D  # cut short, D inside it
    for d0 in (10.0, D - PERIOD):  # predictions short of its disparity, where the search about them fails
        assert pipe.verifier._stepping_in(frame, box, region, d0)
        fine = pipe.verifier.match_object(frame, box, region, d0, 1, tracked=True)
        assert fine is not None and abs(fine.disparity - D) < 0.2
    # a prediction past the peak found is not moved back to it: a search cut short finds false peaks short of
    # the true one (endless:plate seed 1, frames 2632-2636: a board leaving at 18.4 px, so matched at 5.9 px)
    assert pipe.verifier._stepping_in(frame, box, region, 30.0)
    assert pipe.verifier.match_object(frame, box, region, 30.0, 1, tracked=True) is None
    # nor searched anew at all where the prediction lies past the reach less 2 px (a track leaving)
    assert not pipe.verifier._stepping_in(frame, box, region, reach.d_hi - 1.0)
    # the same region with its first columns taken off, so that it no longer reaches column 0: not searched
    # anew, as a track's is not away from the edge
    inside = region.copy()
    inside[:, :3] = False
    assert not pipe.verifier._stepping_in(frame, box, inside, 10.0)
    assert pipe.verifier.match_object(frame, box, inside, 10.0, 1, tracked=True) is None
    assert pipe.verifier.match_object(frame, box, region, 10.0, 1, tracked=False) is None  # not a track's
