"""A tracked object only the left camera sees (tracker.one_camera, issue 12): which of its pixels the right
camera cannot see, the held disparity's 1-σ, the track it continues, and the tracks that may be continued."""

from __future__ import annotations

import cv2
import numpy as np

from tracker.bgdepth import CorrespondenceMap
from tracker.geometry import Camera, StereoRig
from tracker.one_camera import OneCameraConfig, coast_sigma_px, hidden_from_right, nearest_prediction, seen_by_right
from tracker.pipeline import Pipeline
from tracker.rectify import Rectifier
from tracker.sim.scenarios import SimRig, get_scenario
from tracker.stereo import refine_region
from tracker.tracks import MultiTracker

W, H = 640, 480
CFG = OneCameraConfig()


def _ideal_rig() -> StereoRig:
    """Identical pinhole cameras 0.3 m apart, no distortion: rectified = raw, f·b = 180 px·m."""
    K = np.array([[600.0, 0.0, W / 2], [0.0, 600.0, H / 2], [0.0, 0.0, 1.0]])
    half = np.array([0.15, 0.0, 0.0])
    return StereoRig(Camera(K, np.zeros(5), (W, H), np.eye(3), -half),
                     Camera(K.copy(), np.zeros(5), (W, H), np.eye(3), half))


def _background(ext: tuple[int, int, int, int], d_bg: float, post: tuple[int, int, float] | None
                ) -> CorrespondenceMap:
    """A learnt background at disparity d_bg over box `ext`, with a post (its left-image columns x0..x1 and
    disparity) standing before it."""
    h, w = ext[3] - ext[1], ext[2] - ext[0]
    disp = np.full((h, w), d_bg, np.float32)
    if post is not None:
        disp[:, post[0] - ext[0]:post[1] - ext[0]] = post[2]
    zeros = np.zeros((h, w), np.float32)
    return CorrespondenceMap(zeros, zeros, np.ones((h, w), bool), disp, np.zeros((h, w), np.uint8))


def test_the_right_camera_cannot_see_what_a_nearer_post_covers_in_its_image() -> None:
    """A walker at d = 12 px left of a post at d = 25 px (columns 100-120 of the left image): the post's right
    image lies at columns 75-95, so the walker's columns 87-107 (87 - 12 = 75 ... ) are hidden; those left
    of 87 are seen, and so is all of it without the post."""
    rect = Rectifier(_ideal_rig())
    box = (60, 200, 100, 260)
    obj = np.ones((60, 40), bool)
    ext = (60, 200, 60 + 80, 260)
    hidden = hidden_from_right(rect, box, obj, 12.0, _background(ext, 5.0, (100, 120, 25.0)), ext, CFG)
    cols = np.flatnonzero(hidden.all(axis=0)) + box[0]
    assert cols.min() in (86, 87) and cols.max() == 99  # x - 12 within 0.75 px of a post column 75..94
    assert not hidden[:, :86 - box[0]].any()
    assert not hidden_from_right(rect, box, obj, 12.0, _background(ext, 5.0, None), ext, CFG).any()
    # a post no nearer than the walker (by depth_tol_px) hides nothing
    assert not hidden_from_right(rect, box, obj, 12.0, _background(ext, 5.0, (100, 120, 12.5)), ext, CFG).any()


def test_pixels_whose_right_image_falls_off_the_right_camera_are_hidden() -> None:
    """At the left border, columns x < d have x - d < 0: outside the right image."""
    rect = Rectifier(_ideal_rig())
    box = (0, 200, 40, 260)
    obj = np.ones((60, 40), bool)
    ext = (0, 200, 120, 260)
    hidden = hidden_from_right(rect, box, obj, 21.5, _background(ext, 5.0, None), ext, CFG)
    assert hidden[:, :21].all() and not hidden[:, 22:].any()
    only = obj.copy()
    only[:, :30] = False  # the region's own mask bounds what is hidden
    assert not hidden_from_right(rect, box, only, 21.5, _background(ext, 5.0, None), ext, CFG).any()


def test_a_held_disparity_grows_less_certain_as_fast_as_the_object_may_move_in_range() -> None:
    fb = 180.0
    # just after the stereo sighting: its own 1-σ with the floor
    assert np.isclose(coast_sigma_px(12.0, 0.1, 0.0, fb, CFG), np.hypot(0.1, CFG.sigma0_px))
    # 0.5 s later at 15 m (d = 12 px): 1.5 m/s · 0.5 s = 0.75 m of range, 12² · 0.75 / 180 = 0.6 px
    assert np.isclose(coast_sigma_px(12.0, 0.0, 0.5, fb, CFG), np.hypot(CFG.sigma0_px, 0.6))
    # nearer, the same time and pace shift the disparity more
    assert coast_sigma_px(24.0, 0.0, 0.5, fb, CFG) > 3.5 * coast_sigma_px(12.0, 0.0, 0.5, fb, CFG)


def test_the_prediction_continued_is_the_nearest_within_the_gate() -> None:
    coast = np.array([[70.8, 278.0, 10.9, 2, 0.03, 0.1], [200.0, 250.0, 20.0, 0, 0.05, 0.03]])
    assert nearest_prediction(coast, np.array([50.0, 276.0]), CFG) == 0  # 21 px away: a post hides the rest
    assert nearest_prediction(coast, np.array([180.0, 250.0]), CFG) == 1
    assert nearest_prediction(coast, np.array([400.0, 250.0]), CFG) is None
    assert nearest_prediction(coast[:0], np.array([50.0, 276.0]), CFG) is None


def _sight(mt: MultiTracker, t: float, x: float, d: float, alone: bool, sigma: float = 0.05) -> list[int]:
    return mt.update(t, np.array([[x, 250.0, d]]), np.array([sigma]), np.array([alone]))


def test_a_confirmed_track_may_be_continued_holding_its_recent_stereo_disparity() -> None:
    mt = MultiTracker()
    _sight(mt, 0.0, 100.0, 30.0, False)
    assert len(mt.coasting(0.033, 8)) == 0  # one hit: not confirmed
    # six more stereo sightings; the last, as the object passes behind a post, is off by 0.8 px
    for k, d in enumerate((12.0, 12.1, 11.9, 12.0, 12.0, 12.8), start=1):
        _sight(mt, 0.1 * k, 100.0 - 2.0 * k, d, False, sigma=0.05)
    row = mt.coasting(0.7, 8)
    assert row.shape == (1, 6)
    assert np.allclose(row[0, :2], [86.0, 250.0], atol=0.5)  # x, y predicted at about constant velocity
    t_mean = np.mean([0.2, 0.3, 0.4, 0.5, 0.6])  # the first two sightings (30 px, 12 px) fell out of the 5 kept
    assert np.allclose(row[0, 2:], [12.0, 0, np.std([12.1, 11.9, 12.0, 12.0, 12.8]), 0.7 - t_mean])
    assert _sight(mt, 0.7, 86.0, 12.0, True) == [1]  # a one-camera sighting continues track 1
    mt.update(0.8, np.zeros((0, 3)))  # then a miss
    row = mt.coasting(0.9, 8)
    assert np.allclose(row[0, 2:4], [12.0, 2])  # d still held; one sighting and one miss since the stereo one
    assert len(mt.coasting(0.9, 0)) == 0  # missed more often than allowed
    _sight(mt, 0.9, 82.0, 12.2, False)
    assert mt.coasting(1.0, 8)[0, 3] == 0  # a stereo sighting resets the count


def test_a_track_started_by_a_one_camera_sighting_needs_a_stereo_one() -> None:
    mt = MultiTracker()
    _sight(mt, 0.0, 100.0, 12.0, True)
    assert mt.tracks[0].stereo == []  # no borrowed disparity among its stereo sightings
    _sight(mt, 0.033, 100.0, 12.5, False)  # confirmed by a stereo sighting
    assert mt.tracks[0].confirmed and len(mt.coasting(0.066, 8)) == 1
    assert mt.coasting(0.066, 8)[0, 2] == 12.5
    mt2 = MultiTracker()
    _sight(mt2, 0.0, 100.0, 12.0, True)
    _sight(mt2, 0.033, 100.0, 12.0, True)
    assert not mt2.tracks[0].confirmed and len(mt2.coasting(0.066, 8)) == 0  # never a false target so


def test_the_updates_since_the_last_stereo_sighting_count_misses_between_one_camera_sightings() -> None:
    """A thin sliver seen every other frame: misses and one-camera sightings alike count towards max_frames."""
    mt = MultiTracker()
    _sight(mt, 0.0, 100.0, 12.0, False)
    _sight(mt, 0.033, 100.0, 12.0, False)
    for k in range(1, 21):
        t = 0.033 * (1 + k)
        if k % 2:
            mt.update(t, np.zeros((0, 3)))
        else:
            _sight(mt, t, 100.0, 12.0, True)
        assert mt.coasting(t + 0.033, 8)[0, 3] == k


def test_one_object_per_track_continued() -> None:
    """A track's prediction lying on an object found, or within the gate of a region already taken for it
    by one camera, is offered to no other region."""
    from tracker.results import Blob
    from tracker.temporal import _unclaimed

    coast = np.array([[50.0, 270.0, 12.0, 1, 0.05, 0.03], [300.0, 250.0, 20.0, 0, 0.05, 0.03]])
    mask = np.ones((20, 20), bool)
    one = Blob((30, 260, 50, 280), mask, 400, np.array([40.0, 270.0]), np.array([40.0, 270.0]), 12.0, 0.3,
               3.0, 0.0, 1.0, True)
    assert np.array_equal(_unclaimed(lambda: coast, [one], 40.0), coast[1:])
    stereo = Blob((290, 240, 310, 260), mask, 400, np.array([300.0, 250.0]), np.array([300.0, 250.0]), 20.0,
                  0.05, 3.0, 0.97)
    assert np.array_equal(_unclaimed(lambda: coast, [stereo], 40.0), coast[:1])
    far_stereo = Blob((30, 300, 50, 320), mask, 400, np.array([40.0, 310.0]), np.array([40.0, 310.0]), 12.0,
                      0.05, 3.0, 0.97)  # a stereo object 40 px below: claims nothing it does not hold
    assert np.array_equal(_unclaimed(lambda: coast, [far_stereo], 40.0), coast)


def _longest_run(rows: list[tuple[int, int, bool, float, float]]) -> int:
    run = best = 0
    for r in rows:
        run = run + 1 if r[2] else 0
        best = max(best, run)
    return best


def _behind_the_post(one_camera: OneCameraConfig | None) -> list[tuple[int, int, bool, float, float]]:
    """occlusion's plate passing behind the post at 9 m (12 m away, cameras still), frames 40-99: for each
    frame the target shows in both cameras (16 px or more), its detection's track id (0: missed), whether
    only the left camera saw it, its disparity error and 1-σ (px)."""
    sim = SimRig(get_scenario("occlusion"))
    pipe = Pipeline(sim.rig, one_camera=one_camera)
    pipe.learn_background(sim.background())
    out = []
    for i in range(100):
        sf = sim.step()
        res = pipe.step(sf.frame)
        tt = sf.truth.target(1)
        if i < 40 or tt is None or min(tt.area_left, tt.area_right) < 16:
            continue
        ids = sf.truth.ids_left
        on = [d for d in res.detections
              if np.mean(ids[d.blob.box[1]:d.blob.box[3], d.blob.box[0]:d.blob.box[2]][d.blob.mask] == 1) > 0.5]
        if not on:
            out.append((i, 0, False, 0.0, 0.0))
            continue
        _, _, d_true = pipe.rect.rig_to_rect(tt.rig[None, :])
        b = on[0].blob
        out.append((i, on[0].track_id, b.one_camera, b.disparity - float(d_true[0]), b.disparity_sigma))
    return out


def test_a_plate_passing_behind_a_post_keeps_its_track_while_only_the_left_camera_sees_it() -> None:
    rows = _behind_the_post(None)
    alone = [r for r in rows if r[2]]
    assert len(alone) >= 20  # frames 65-90: the right camera's view of it is the post's
    assert {r[1] for r in rows if r[1]} == {1}  # one track throughout, no new one after the post
    assert all(abs(r[3]) < 3.0 * r[4] for r in alone)  # the held disparity within 3σ of the truth
    assert all(r[1] for r in rows if r[0] <= 90)
    # without one-camera sightings the same frames are missed
    without = _behind_the_post(OneCameraConfig(max_frames=0))
    assert sum(1 for r in without if r[1] == 0) >= len(alone)
    assert not any(r[2] for r in without)
    # the tracker counts them as such: at most max_frames in a row after a stereo sighting
    assert _longest_run(rows) > 10 and _longest_run(_behind_the_post(OneCameraConfig(max_frames=10))) == 10


def _plate_left_of_post() -> tuple[np.ndarray, np.ndarray]:
    """A rectified pair of the ideal rig: a textured plate at d = 12 px (left columns 60-99) before a
    background at 5 px, left of a post at 25 px (columns 100-119). Each surface's texture is indexed by
    its left column; the right camera sees the nearest surface along x_r + d."""
    rng = np.random.default_rng(5)
    tex = [np.asarray(cv2.GaussianBlur(rng.uniform(0, 255, (H, W + 40)).astype(np.float32), (0, 0), 1.5))
           for _ in range(3)]
    surfaces = [((100, 120), 25.0, tex[2]), ((60, 100), 12.0, tex[1]), ((0, W + 40), 5.0, tex[0])]  # nearest first
    xs = np.arange(W)
    left, right = np.empty((H, W), np.float32), np.empty((H, W), np.float32)
    for img, shift in ((left, 0.0), (right, 1.0)):
        done = np.zeros(W, bool)
        for (x0, x1), d, t in surfaces:
            xl = xs + shift * d  # the left column a right pixel sees at this surface's disparity
            on = ~done & (xl >= x0) & (xl < x1)
            img[:, on] = t[:, np.round(xl[on]).astype(int)]
            done |= on
    return np.round(left).astype(np.uint8), np.round(right).astype(np.uint8)


def test_a_plate_is_matched_on_what_the_right_camera_sees_beside_a_nearer_post() -> None:
    """The post's right image lies at columns 75-94, so the plate's columns 87-99 are hidden from the right
    camera: matched with them, the plate scores 0.63 at 11.955 px; on the rest it scores 1 at 12 px."""
    left, right = _plate_left_of_post()
    rect = Rectifier(_ideal_rig())
    box = (60, 200, 100, 260)
    plate = np.ones((60, 40), bool)
    ext = (60, 200, 180, 260)
    seen = seen_by_right(rect, box, plate, 12.0, _background(ext, 5.0, (100, 120, 25.0)), ext, CFG)
    cols = np.flatnonzero(seen.all(axis=0)) + box[0]
    assert cols.min() == 60 and cols.max() in (85, 86) and not seen[:, 27:].any()
    whole = refine_region(left, right, plate, 60, 200, 12.0, min_score=0.0, robust=False)  # least squares
    part = refine_region(left, right, seen, 60, 200, 12.0, min_score=0.0)
    assert part is not None and abs(part.disparity - 12.0) < 0.02 and part.score > 0.99
    assert whole is not None and whole.score < 0.7 and abs(whole.disparity - 12.0) > 0.02  # 0.63, 11.955 px
    # where what the right camera sees is under half the region, the whole region is matched
    narrow = np.zeros((60, 40), bool)
    narrow[:, 20:] = True  # columns 80-99: 7 of 20 seen
    assert np.array_equal(seen_by_right(rect, box, narrow, 12.0, _background(ext, 5.0, (100, 120, 25.0)), ext,
                                        CFG), narrow)


def test_an_object_found_before_hides_a_tracked_one_from_the_right_camera_as_a_post_does() -> None:
    """The same plate before a background learnt without the post, the post found this frame as an object
    (a walker at 12 m behind a ball at 5 m in the right image: two-targets:body): the plate's columns the
    post's right image covers are left out as a learnt post's are, and none without it."""
    from tracker.frames import StereoFrame
    from tracker.results import Blob

    rng = np.random.default_rng(7)
    tex = np.asarray(cv2.GaussianBlur(rng.uniform(0, 255, (H, W + 40)).astype(np.float32), (0, 0), 1.5))
    xs = np.arange(W)
    empty = (np.round(tex[:, :W]).astype(np.uint8), np.round(tex[:, np.round(xs + 5.0).astype(int)]).astype(np.uint8))
    pipe = Pipeline(_ideal_rig())
    pipe.learn_background(StereoFrame(0, empty[0], empty[1], 0.0, 0.0))
    left, right = _plate_left_of_post()
    frame = StereoFrame(1, left, right, 0.1, 0.1)
    box, plate = (60, 200, 100, 260), np.ones((60, 40), bool)
    assert np.array_equal(pipe.verifier.seen_by_right(frame, box, plate, 12.0), plate)
    post = Blob((100, 200, 120, 260), np.ones((60, 20), bool), 1200, np.array([109.5, 229.5]),
                np.array([109.5, 229.5]), 25.0, 0.01, 5.0, 1.0)
    seen = pipe.verifier.seen_by_right(frame, box, plate, 12.0, [post])
    cols = np.flatnonzero(seen.all(axis=0)) + box[0]
    assert cols.min() == 60 and cols.max() in (85, 86) and not seen[:, 27:].any()
