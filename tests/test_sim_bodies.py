"""Solid bodies in the simulator (tracker.sim.bodies, scenarios `NAME:body`; issue 12 item 2)."""

from __future__ import annotations

from dataclasses import replace

import cv2
import numpy as np
import pytest

from tracker.evaluation import survey_poses, target_prior
from tracker.frames import GimbalState
from tracker.geometry import gimbal_rotation
from tracker.pipeline import Pipeline
from tracker.rectify import Rectifier
from tracker.sim.bodies import SPHERE_R_M, Body, BodyObject, Part, body_texture
from tracker.sim.render import SimRenderer
from tracker.sim.rig import default_rig
from tracker.sim.scenarios import SimRig, get_scenario
from tracker.sim.scene import CAMERA_HEIGHT_M, MovingObject, Surface, smooth_texture


def _still(p: tuple[float, float, float]) -> BodyObject:
    def path(t: float) -> np.ndarray:
        return np.array(p)
    return BodyObject(1, "sphere", path, body_texture(np.random.default_rng(1), "sphere"))


def _render(static: list[Surface], body: BodyObject) -> tuple[SimRenderer, np.ndarray]:
    rig = default_rig()
    r = SimRenderer(rig, static, seed=0)
    _, ids = r.render(0, 0.0, GimbalState(), [body.surface(0.0, np.eye(3))], 1.0, noisy=False)
    return r, ids[0]


def _wall(z: float) -> Surface:
    ex, ey, _ = np.eye(3)
    return Surface("wall", np.array([0.0, 0.0, z]), ex, ey, 30.0, 20.0,
                   smooth_texture(np.random.default_rng(0), (100, 100), 2.0, 30, 120), 0.6)


def test_body_name_is_opt_in_and_the_default_is_unchanged() -> None:
    plain, body = get_scenario("walk"), get_scenario("walk:body")
    assert not plain.bodies and body.bodies and body.name == "walk:body" and body.paths == plain.paths
    assert all(isinstance(o, MovingObject) for o in SimRig(plain).objects)
    assert all(isinstance(o, BodyObject) and o.kind == "person" for o in SimRig(body).objects)
    assert [o.kind for o in SimRig(get_scenario("occlusion:body")).objects] == ["vehicle"]  # type: ignore[union-attr]
    with pytest.raises(ValueError, match="unknown scenario 'nope:body'"):
        get_scenario("nope:body")


def test_box_ray_cast_distance_and_normal() -> None:
    box = Part("box", np.array([0.0, 0.0, 5.0]), np.eye(3), np.array([1.0, 0.5, 1.0]))
    w = np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [0.6, 0.0, 0.8]])
    dist, hit, n, _ = box.intersect(np.zeros(3), w)
    assert hit.tolist() == [True, False, False]  # the third passes x = 3 m by the time it is at z = 4 m
    assert dist[0] == pytest.approx(4.0) and n[0] == pytest.approx([0.0, 0.0, -1.0])
    turned = Part("box", box.centre, np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]]), box.half)
    dist, hit, n, _ = turned.intersect(np.array([3.0, 0.2, 5.3]), np.array([[-1.0, 0.0, 0.0]]))
    assert hit[0] and dist[0] == pytest.approx(2.0) and n[0] == pytest.approx([1.0, 0.0, 0.0])


def test_sphere_pixels_centre_on_its_projected_centre() -> None:
    body = _still((0.0, 0.0, 8.0))
    r, ids = _render([_wall(30.0)], body)
    v, u = np.nonzero(ids == 1)
    centre = r.rig.left.project(body.trajectory(0.0)[None, :])[0]
    assert np.hypot(u.mean() - centre[0], v.mean() - centre[1]) < 0.3
    disc = np.pi * (600.0 * SPHERE_R_M / 8.0) ** 2
    assert u.size == pytest.approx(disc, rel=0.06)
    assert body.near_depth_m(0.0, np.zeros(3)) == pytest.approx(SPHERE_R_M)


def test_bodies_are_hidden_by_nearer_scene_geometry() -> None:
    ex, ey, _ = np.eye(3)
    post = Surface("post", np.array([-0.15, 0.0, 5.0]), ex, ey, 0.05, 2.0,  # centred on the left camera's axis
                   smooth_texture(np.random.default_rng(2), (80, 8), 1.5, 20, 110), 0.0125)
    body = _still((-0.15, 0.0, 8.0))
    r, ids = _render([_wall(30.0), post], body)
    cx = r.rig.left.project(np.array([[-0.15, 0.0, 5.0]]))[0][0]
    cols = np.nonzero((ids == 1).any(axis=0))[0]
    half_post = 600.0 * 0.05 / 5.0
    assert cols.size > 0
    assert not np.any(np.abs(cols - cx) < half_post - 1.0)  # no body pixel where the post is
    assert np.any(cols < cx - half_post) and np.any(cols > cx + half_post)  # seen on both sides
    _, behind = _render([_wall(7.0)], body)  # a wall in front of it: nothing of it is seen
    assert not np.any(behind == 1)


def test_person_stands_on_the_ground_and_its_truth_is_its_volume_centroid() -> None:
    sim = SimRig(get_scenario("walk:body"))
    person = sim.objects[0]
    assert isinstance(person, BodyObject)
    for t in (0.0, 1.3, 4.0):
        parts = person.parts(t)
        feet = max(float(q.corners()[:, 1].max()) for q in parts)
        assert feet == pytest.approx(CAMERA_HEIGHT_M, abs=0.05)
        vol = np.array([q.volume for q in parts])
        c = person.trajectory(t)
        assert c == pytest.approx(vol @ np.array([q.centre for q in parts]) / vol.sum())
        assert CAMERA_HEIGHT_M - 1.2 < c[1] < CAMERA_HEIGHT_M - 0.6  # between knees and chest
    sf = sim.step()
    tt = sf.truth.target(1)
    assert tt is not None and tt.area_left > 1000 and 0.0 < tt.near_depth_m < 0.6


def test_a_walker_near_the_cameras_is_matched_and_kept() -> None:
    # a walker at 3 m: its box's centre lies between its swinging legs, where no single disparity
    # matches; the verifier then matches the region's row thirds (tracker.verify)
    from tracker.evaluation import survey_poses
    from tracker.pipeline import Pipeline
    from tracker.sim.scenarios import SCENARIOS, _walk

    def late(t: float) -> np.ndarray:
        return _walk(t + 9.0)

    sc = replace(SCENARIOS["walk"], name="walk-late:body", paths=((1, late),), bodies=True, frames=30)
    sim = SimRig(sc)
    pipe = Pipeline(sim.rig)
    for g in survey_poses(sc):
        pipe.learn_background(sim.background(g))
    recall = []
    for _ in range(sc.frames):
        sf = sim.step()
        truth = sf.truth.ids_left == 1
        fg = pipe.step(sf.frame).foreground_mask(truth.shape)
        recall.append((fg & truth).sum() / truth.sum())
    seen = " ".join(f"{r:.2f}" for r in recall)
    assert np.mean(recall[3:]) > 0.7 and min(recall[3:]) > 0.2, seen  # before: 8 frames lost (recall 0)


def test_surface_truth_is_the_mean_of_the_seen_surface() -> None:
    # a ball at 8 m seen head-on: the seen cap's mean point lies on the line of sight to the centre,
    # between R/2 and R nearer (a hemisphere's surface centroid is R/2 from its centre; the cap seen from
    # 8 m is slightly less than a hemisphere, and perspective weights its near part more per pixel)
    body = _still((0.0, 0.0, 8.0))
    r, ids = _render([_wall(30.0)], body)
    s = r.surface_mean(0, ids, 1, r.depth_window(0))
    assert s is not None
    c_left = r.rig.left.c
    towards = (body.trajectory(0.0) - c_left) / np.linalg.norm(body.trajectory(0.0) - c_left)
    along = float((body.trajectory(0.0) - s) @ towards)
    across = np.linalg.norm((body.trajectory(0.0) - s) - along * towards)
    assert SPHERE_R_M / 2 < along < SPHERE_R_M and across < 0.01
    assert r.surface_mean(0, ids, 2, r.depth_window(0)) is None
    # in a body scenario the truth carries it (world frame), near the volume centroid; plates do not
    tt = SimRig(get_scenario("walk:body")).step().truth.target(1)
    assert tt is not None and tt.surface_world is not None
    assert 0.05 < np.linalg.norm(tt.surface_world - tt.world) < 0.6
    plate = SimRig(get_scenario("walk")).step().truth.target(1)
    assert plate is not None and plate.surface_world is None


def test_truth_read_frames_later_equals_truth_read_at_once() -> None:
    """A frame's truth is worked out when first read (SimFrame.truth): from that frame's render, not the
    renderer's state at the time of reading."""
    late, now = SimRig(get_scenario("walk:body"), seed=0), SimRig(get_scenario("walk:body"), seed=0)
    frames = [late.step() for _ in range(8)]
    for f, eager in zip(frames, [now.step().truth for _ in range(8)], strict=True):
        for a, b in zip(f.truth.targets, eager.targets, strict=True):
            assert a.area_left == b.area_left and a.area_right == b.area_right
            assert (a.surface_world is None) == (b.surface_world is None)
            if a.surface_world is not None and b.surface_world is not None:
                assert np.allclose(a.surface_world, b.surface_world)


def test_the_silhouette_point_lies_on_the_ray_eq_10_measures_on_the_true_silhouette() -> None:
    # the point the tracker measures: eq. (10)'s area-weighted centroid of the body's left pixels in
    # rectified coordinates (tracker.rectify.Rectifier.area_moments), turned back into the left camera
    sim = SimRig(get_scenario("walk:body"))
    for _ in range(3):
        sf = sim.step()
    tr = sf.truth
    tt = tr.target(1)
    assert tt is not None and tt.silhouette_world is not None and tt.surface_world is not None
    rect = Rectifier(sim.rig)
    sx, sy, sa, _ = cv2.mean(rect.area_moments, mask=(tr.ids_left == 1).view(np.uint8))
    v = rect.R1.T @ np.array([(sx / sa - rect.cx) / rect.f, (sy / sa - rect.cy) / rect.f, 1.0])
    R_wr = gimbal_rotation(tr.gimbal.pan_deg, tr.gimbal.tilt_deg)
    c = R_wr @ sim.rig.left.c
    X = sim.rig.left.R_rc @ (R_wr.T @ (tt.silhouette_world - c))
    assert np.allclose(X[:2] / X[2], v[:2] / v[2], atol=0.1 / rect.f)  # within 0.1 px
    # the surface mean is off that ray by more, at about the same distance
    S = sim.rig.left.R_rc @ (R_wr.T @ (tt.surface_world - c))
    assert np.linalg.norm(S[:2] / S[2] - v[:2] / v[2]) > 0.3 / rect.f
    assert abs(np.linalg.norm(X) - np.linalg.norm(S)) < 0.05
    plate = SimRig(get_scenario("walk")).step().truth.target(1)
    assert plate is not None and plate.silhouette_world is None


def _walk_body_at(frames: tuple[int, ...]) -> dict[int, tuple[np.ndarray, list[np.ndarray]]]:
    """walk:body run through the pipeline: the true left silhouette of the walker and each detection's
    pixels (full image) at each of the frames."""
    sc = get_scenario("walk:body")
    sim = SimRig(sc, seed=0)
    pipe = Pipeline(sim.rig, None, solid=target_prior(sc))
    for g in survey_poses(sc):
        pipe.learn_background(sim.background(g))
    out = {}
    for i in range(max(frames) + 1):
        sf = sim.step()
        res = pipe.step(sf.frame)
        if i in frames:
            truth = sf.truth.ids_left == 1
            masks = []
            for d in res.detections:
                m = np.zeros_like(truth)
                m[d.blob.box[1]:d.blob.box[3], d.blob.box[0]:d.blob.box[2]] = d.blob.mask
                masks.append(m)
            out[i] = truth, masks
    return out


def test_a_near_walker_is_outlined_without_the_ghost_beside_it_and_with_its_head() -> None:
    """A walker at 3 m (walk:body frames 6 and 24). Frame 24: a second region of its box, beside the
    torso, must take its temporal gain from the background, not from the torso (which made g 1.28 and
    joined a ghost of 5,400 px, 27 % of the outline): under 5 % of the outline lies off the true
    silhouette (2.4 %: ground between the legs, at their depth). Frame 6: the head,
    past the neck's gap and under a tenth of the body, is verified as a part of it (it was dropped as too
    small for a second object): the walker is one detection, and most of the head's pixels are in it."""
    seen = _walk_body_at((6, 24))
    truth, masks = seen[24]
    fg = np.logical_or.reduce(masks)
    assert np.count_nonzero(fg & truth) > 0.8 * np.count_nonzero(truth)
    assert np.count_nonzero(fg & ~truth) < 0.05 * np.count_nonzero(fg)
    truth, masks = seen[6]
    assert len(masks) == 1
    rows = np.flatnonzero(truth.any(axis=1))
    head = np.zeros_like(truth)
    head[rows[0]:rows[0] + 30] = truth[rows[0]:rows[0] + 30]  # the top 30 rows of 280: the head
    assert np.count_nonzero(masks[0] & head) > 0.8 * np.count_nonzero(head)


def _edge_row(x_edge: float, samples: int) -> tuple[np.ndarray, np.ndarray, float]:
    """An even grey box whose left side stands at x = x_edge (m), its front 8 m ahead, before an even wall at
    30 m: the left camera's middle row, its ids, and the front edge's true column (px)."""
    rig = default_rig()
    ex, ey, _ = np.eye(3)
    wall = Surface("wall", np.array([0.0, 0.0, 30.0]), ex, ey, 40.0, 30.0, np.full((64, 64), 60, np.uint8), 0.6)
    r = SimRenderer(rig, [wall], seed=0, edge_samples=samples)
    front, half = 8.0, np.array([0.5, 0.5, 0.2])
    part = Part("box", np.array([x_edge + half[0], 0.0, front + half[2]]), np.eye(3), half)
    body = Body("box", 1, (part,), np.full((256, 256), 200.0, np.float32))
    frame, ids = r.render(0, 0.0, GimbalState(), [body], 1.0, noisy=False)
    v = rig.left.size[1] // 2
    u_edge = float(rig.left.project(np.array([[x_edge, rig.left.c[1], front]]))[0][0])
    return frame.left[v].astype(float), ids[0][v], u_edge


@pytest.mark.parametrize("frac", [0.1, 0.3, 0.5, 0.7, 0.9])
def test_a_body_edge_is_drawn_as_much_of_each_pixel_as_it_covers(frac: float) -> None:
    """With edge_samples, a pixel an edge crosses takes the mean over the pixel, as a camera integrates
    light: the edge's column read back from the grey levels (the box's share of each pixel summed) is
    where it projects, within half the spacing of 8 rays a side (1/16 px) and a grey level's rounding;
    drawn at the pixels' centres alone it is off by up to half a pixel. The truth (ids) stays the
    centres'."""
    rig = default_rig()
    cam, want = rig.left, 299.5 + frac  # pixel 300 spans columns 299.5-300.5, left of the lens: the side is hidden
    x_edge = float(cam.c[0])
    for _ in range(4):  # the side's x that projects at `want` on the middle row (Newton; the lens distorts)
        u0, u1 = (float(cam.project(np.array([[x, cam.c[1], 8.0]]))[0][0]) for x in (x_edge, x_edge + 1e-3))
        x_edge += (want - u0) * 1e-3 / (u1 - u0)
    errs = {}
    for samples in (1, 8):
        row, ids, u_edge = _edge_row(x_edge, samples)
        wall, box = row[270], row[330]
        share = np.clip((row[290:311] - wall) / (box - wall), 0.0, 1.0)  # the box's share of columns 290-310
        errs[samples] = (310.5 - share.sum()) - u_edge
        assert u_edge == pytest.approx(want, abs=0.01)
        if samples == 1:
            ids1 = ids
        else:
            np.testing.assert_array_equal(ids, ids1)
    assert abs(errs[8]) <= 1.0 / 16.0 + 0.01
    assert abs(errs[1]) == pytest.approx(min(frac, 1.0 - frac), abs=0.05)


def _angle(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.arccos(np.clip(a @ b / (np.linalg.norm(a) * np.linalg.norm(b)), -1.0, 1.0)))


def test_the_seen_surface_of_a_face_square_to_the_lens_lies_on_its_silhouettes_ray_wherever_it_is() -> None:
    # a face at one depth in the image's corner, where the lens distorts most: the mean of its points weighs
    # each pixel by its area in the undistorted plane, as eq. (10) does, so it lies on the ray of the
    # silhouette's centroid; weighing each raw pixel alike put it 0.048 deg off that ray
    renderer = SimRig(get_scenario("walk:body")).renderer
    view = renderer.views[0]
    x0, y0, x1, y1 = 520, 380, 630, 470
    ids = np.zeros(view.ray_len.shape, np.uint8)
    ids[y0:y1, x0:x1] = 7
    window = ((x0, y0, x1, y1), (5.0 * view.ray_len[y0:y1, x0:x1]).astype(np.float32))  # Z = 5 m
    mean = renderer.surface_mean(0, ids, 7, window)
    ray = renderer.surface_mean(0, ids, 7, window, on_mean_ray=True)
    assert mean is not None and ray is not None
    c = view.cam.c
    assert _angle(mean - c, ray - c) < 1e-6
    raw = (view.rays[y0:y1, x0:x1].reshape(-1, 3) * window[1].reshape(-1, 1)).mean(axis=0)
    assert _angle(raw, ray - c) > np.radians(0.02)


@pytest.mark.drawn_statures
def test_people_are_drawn_with_peoples_statures_and_built_to_them() -> None:
    from tracker.sim.bodies import PERSON_STATURE_M, draw_stature

    rng = np.random.default_rng(5)
    drawn = np.array([draw_stature(rng) for _ in range(4000)])
    assert drawn.mean() == pytest.approx(1.695, abs=0.01) and drawn.std() == pytest.approx(0.095, abs=0.01)
    z = (drawn - drawn.mean()) / drawn.std()
    assert np.mean(z**4) - 3.0 < -0.2  # two peaks, a woman's and a man's: flatter than one normal (-0.43)

    def still(t: float) -> np.ndarray:
        return np.array([0.0, 0.0, 6.0])

    tex = body_texture(np.random.default_rng(1), "person")
    for stature in (1.55, PERSON_STATURE_M, 1.90):
        parts = BodyObject(1, "person", still, tex, stature_m=stature).parts(0.0)
        top = min(float(q.centre[1] - q.half[0]) if q.kind == "sphere" else float(q.corners()[:, 1].min())
                  for q in parts)
        feet = max(float(q.corners()[:, 1].max()) for q in parts)
        assert feet == pytest.approx(CAMERA_HEIGHT_M, abs=0.03)  # on the ground whatever its height
        assert CAMERA_HEIGHT_M - top == pytest.approx(stature)  # its head's top the stature above the ground
    with pytest.raises(ValueError, match="stature must lie in 0.5-2.5 m, got 3.0"):
        BodyObject(1, "person", still, tex, stature_m=3.0)
    statures = {SimRig(get_scenario(f"{name}:body"), seed=0).objects[0].stature_m  # type: ignore[union-attr]
                for name in ("walk", "foliage", "pan")}
    assert len(statures) == 3  # each scene its own person
