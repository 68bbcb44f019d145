"""Temporal candidates (tracker.temporal): a target too near its background for the stereo residual is
found while the cameras are still; light steps, foliage and shadows raise no target."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from tracker.frames import StereoFrame
from tracker.pipeline import Pipeline
from tracker.results import Blob
from tracker.sim.scenarios import SimRig, get_scenario, near_wall_scenario
from tracker.temporal import TemporalConfig, texture_corr, without_duplicates


def _run(sim: SimRig, pipe: Pipeline, frames: int) -> tuple[int, int, list[float]]:
    """Frames with the target visible, frames it was detected in, and range errors (m)."""
    visible = found = 0
    errors: list[float] = []
    for _ in range(frames):
        sf = sim.step()
        res = pipe.step(sf.frame)
        tt = sf.truth.target(1)
        if tt is None or min(tt.area_left, tt.area_right) < 200:
            continue
        visible += 1
        ids = sf.truth.ids_left
        on = [d for d in res.detections
              if np.mean(ids[d.blob.box[1]:d.blob.box[3], d.blob.box[0]:d.blob.box[2]][d.blob.mask] == 1) > 0.5]
        if on:
            found += 1
            errors.append(on[0].loc.r - float(np.linalg.norm(tt.world)))
    return visible, found, errors


def _near_wall(gap: float, temporal: TemporalConfig | None = None) -> tuple[SimRig, Pipeline]:
    sim = SimRig(near_wall_scenario(gap, frames=110, enter_s=2.6))
    pipe = Pipeline(sim.rig, temporal=temporal)
    pipe.learn_background(sim.background())
    return sim, pipe


def test_a_person_02_m_before_a_wall_at_7_m_is_found_and_ranged() -> None:
    sim, pipe = _near_wall(0.2)
    visible, found, errors = _run(sim, pipe, 110)
    assert visible >= 25
    assert found >= visible - 1  # the first sighting may be taken by the track's confirmation
    assert np.sqrt(np.mean(np.square(errors))) < 0.03  # range (m) of the target itself, not of the wall


def test_without_temporal_candidates_the_stereo_residual_misses_it() -> None:
    sim, pipe = _near_wall(0.2, TemporalConfig(min_area_px=10**7))  # no temporal region is large enough
    visible, found, _ = _run(sim, pipe, 110)
    assert visible >= 25 and found == 0


def _empty_wall(light: bool, foliage: bool = False) -> tuple[SimRig, Pipeline]:
    sc = replace(near_wall_scenario(0.1, light=light), paths=(), foliage=foliage)
    sim = SimRig(sc)
    pipe = Pipeline(sim.rig)
    pipe.learn_background(sim.background())
    return sim, pipe


def test_light_steps_and_a_swaying_bush_raise_no_target() -> None:
    sim, pipe = _empty_wall(light=True, foliage=True)
    for _ in range(300):  # steps of +30 %, -40 %, ramps and a step back (tracker.sim.scenarios)
        assert pipe.step(sim.step().frame).detections == ()


def test_a_shadow_on_the_wall_raises_no_target() -> None:
    sim, pipe = _empty_wall(light=False)
    for _ in range(90):
        pipe.step(sim.step().frame)
    for _ in range(20):  # a shadow 60 % as bright falls across the wall in both cameras
        f = sim.step().frame
        left, right = f.left.copy(), f.right.copy()
        for img, x0 in ((left, 200), (right, 175)):
            img[150:330, x0:x0 + 160] = (img[150:330, x0:x0 + 160] * 0.6).astype(np.uint8)
        res = pipe.step(StereoFrame(f.index, left, right, f.t_left, f.t_right, f.gimbal))
        assert res.detections == ()


def test_a_change_only_the_left_camera_sees_raises_no_target() -> None:
    """A patch of the wall's own texture shown in the left image only (a reflection one camera sees) is
    unlike the temporal background and matches the right image at a disparity far clear of the wall (its
    source, 100 px away): the right camera's eq. (9) shows nothing there, so it is not an object."""
    sim, pipe = _empty_wall(light=False)
    for _ in range(90):
        pipe.step(sim.step().frame)
    for _ in range(10):
        f = sim.step().frame
        left = f.left.copy()
        left[200:236, 400:436] = left[200:236, 300:336]
        res = pipe.step(StereoFrame(f.index, left, f.right, f.t_left, f.t_right, f.gimbal))
        assert res.detections == ()


def test_texture_correlation_tells_relit_background_from_a_new_surface() -> None:
    rng = np.random.default_rng(1)
    bg = rng.uniform(30, 170, (40, 40)).astype(np.float32)
    mask = np.ones((40, 40), bool)
    assert texture_corr((bg * 0.6).astype(np.uint8), bg, mask) > 0.99
    other = rng.uniform(30, 170, (40, 40)).astype(np.uint8)
    assert abs(texture_corr(other, bg, mask)) < 0.2


def test_existing_scenario_walk_keeps_its_figures() -> None:
    sim = SimRig(get_scenario("walk"))
    pipe = Pipeline(sim.rig)
    pipe.learn_background(sim.background())
    visible, found, errors = _run(sim, pipe, 60)
    assert found >= visible - 1 and max(abs(e) for e in errors) < 0.2


def _blob(box: tuple[int, int, int, int], mask: np.ndarray) -> Blob:
    c = np.zeros(2)
    return Blob(box, mask, int(mask.sum()), c, c, 10.0, 0.1, 9.0, 1.0)


def test_a_blob_mostly_inside_a_larger_one_is_the_same_object() -> None:
    big = _blob((0, 0, 40, 80), np.ones((80, 40), bool))
    inside = _blob((25, 20, 45, 40), np.ones((20, 20), bool))  # 300 of its 400 pixels are big's
    apart = _blob((100, 0, 120, 20), np.ones((20, 20), bool))
    edge = _blob((35, 0, 55, 20), np.ones((20, 20), bool))  # 100 of them are
    assert [b.box for b in without_duplicates([inside, big, apart, edge])] == [big.box, apart.box, edge.box]
    half = _blob((30, 20, 50, 40), np.ones((20, 20), bool))  # exactly half: kept
    assert len(without_duplicates([big, half])) == 2


def test_a_person_05_m_before_a_wall_is_one_object_where_it_turns() -> None:
    # the stereo stages see parts of it and verify them again from overlapping boxes: one detection
    sc = near_wall_scenario(0.5, frames=135)
    sim = SimRig(sc)
    pipe = Pipeline(sim.rig)
    pipe.learn_background(sim.background())
    counts = []
    for _ in range(sc.frames):
        sf = sim.step()
        res = pipe.step(sf.frame)
        ids = sf.truth.ids_left
        counts.append(sum(
            np.mean(ids[d.blob.box[1]:d.blob.box[3], d.blob.box[0]:d.blob.box[2]][d.blob.mask] == 1) > 0.5
            for d in res.detections))
    assert sum(c > 0 for c in counts) >= 40  # it enters 3 s in and turns 4.5 s in
    assert max(counts) == 1
