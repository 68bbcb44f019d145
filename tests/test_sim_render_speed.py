"""The static scene seen from a moving gimbal (tracker.sim.static_cast, the path every frame of `pan`,
`manoeuvre` and the servo loop takes) equals the exact per-pixel ray cast: image, depth and what is hit.
Behaviour only; its speed is `tmeye bench --scenario pan` (render_ms_median)."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.typing import NDArray

from tracker.frames import GimbalState
from tracker.geometry import gimbal_rotation
from tracker.sim import cast, render
from tracker.sim.rig import default_rig
from tracker.sim.scenarios import SimRig, get_scenario
from tracker.sim.scene import Surface, smooth_texture

U8 = NDArray[np.uint8]
F32 = NDArray[np.float32]


def _exact(renderer: render.SimRenderer, surfaces: list[Surface], g: GimbalState) -> list[tuple[U8, F32]]:
    """Per camera: the reference image (uint8) and depth (m, inf where nothing is hit)."""
    R = gimbal_rotation(g.pan_deg, g.tilt_deg)
    out: list[tuple[U8, F32]] = []
    for view in renderer.views:
        w, h = view.cam.size
        img, depth = np.zeros((h, w), np.uint8), np.full((h, w), np.inf, np.float32)
        for s in surfaces:
            cast.cast_surface_exact(view, R, s, 0.0, img, depth, None)
        out.append((img, depth))
    return out


def _assert_matches(renderer: render.SimRenderer, surfaces: list[Surface], g: GimbalState, edge: float = 1e-5) -> None:
    """Equal up to the rounding of bilinear texture lookups (by 1 grey level, rarely), but for a fraction
    `edge` of pixels whose centre is on an edge to within rounding (the reference's rays are float32: 1e-5,
    a few pixels; one wrong cell of the fast path is 16); 1e-4 where cast_plane_fast casts a disc."""
    imgs, _ = renderer._static(g)
    depths = renderer.static_depth(g)
    for (ref, ref_depth), img, depth in zip(_exact(renderer, surfaces, g), imgs, depths, strict=True):
        diff = np.abs(ref.astype(int) - img.astype(int))
        assert (diff > 1).mean() <= edge  # no pixel sees another surface or texel
        assert (diff > 0).mean() < 0.005
        hit = np.isfinite(ref_depth)
        assert (hit != np.isfinite(depth)).mean() <= edge
        both = hit & np.isfinite(depth)
        assert (np.abs(depth[both] - ref_depth[both]) > 1e-4 * ref_depth[both]).mean() <= edge


@pytest.mark.parametrize("seed", [0, 1])
def test_moving_gimbal_render_equals_the_exact_ray_cast(seed: int) -> None:
    sim = SimRig(get_scenario("pan"), seed=seed, noise_sigma=0.0)
    rng = np.random.default_rng(seed)
    for _ in range(3):
        g = GimbalState(float(rng.uniform(-40.0, 40.0)), float(rng.uniform(-10.0, 10.0)))
        _assert_matches(sim.renderer, sim.renderer.static, g)


def test_successive_poses_of_a_slew_render_like_fresh_ones() -> None:
    # a closed-loop slew: every frame a new pose, each rendered on its own (no state carried over)
    sim = SimRig(get_scenario("manoeuvre"), noise_sigma=0.0)
    poses = [GimbalState(-19.0 + 0.9 * i, 0.2 * i) for i in range(6)]
    frames = [sim.renderer._static(g)[0] for g in poses]
    fresh = SimRig(get_scenario("manoeuvre"), noise_sigma=0.0).renderer
    for g, imgs in zip(poses[::-1], frames[::-1], strict=True):
        for a, b in zip(fresh._static(g)[0], imgs, strict=True):
            assert np.array_equal(a, b)
    _assert_matches(sim.renderer, sim.renderer.static, poses[-1])


def _awkward() -> list[Surface]:
    """Planes crossing each other at an angle, a post thinner than a pixel, a floor reaching behind the
    cameras, sky where nothing is hit, and a disc (cast per pixel by cast_plane_fast)."""
    rng = np.random.default_rng(5)
    ex, ey, ez = np.eye(3)
    tilt = np.array([np.cos(0.5), 0.0, np.sin(0.5)])
    surfaces = [
        Surface("a", np.array([0.0, -1.0, 20.0]), ex, ey, 6.0, 3.0, smooth_texture(rng, (60, 120), 2.0, 30, 200), 0.1),
        Surface("b", np.array([1.0, -1.0, 20.0]), tilt, ey, 5.0, 2.0, smooth_texture(rng, (40, 100), 2.0, 40, 220),
                0.1),
        Surface("thin", np.array([-3.0, 0.0, 30.0]), ex, ey, 0.02, 3.0, smooth_texture(rng, (60, 4), 1.0, 90, 250),
                0.01),
        Surface("floor", np.array([0.0, 1.5, 5.0]), ex, ez, 20.0, 9.0, smooth_texture(rng, (90, 200), 3.0, 20, 120),
                0.2),
        Surface("disc", np.array([2.0, 0.5, 8.0]), ex, ey, 0.5, 0.5, smooth_texture(rng, (32, 32), 2.0, 150, 250),
                1.0 / 32, shape="disc"),
    ]
    return surfaces


@pytest.mark.parametrize("disc", [False, True])
def test_awkward_scenes_equal_the_exact_ray_cast(disc: bool) -> None:
    surfaces = _awkward()[:None if disc else -1]
    renderer = render.SimRenderer(default_rig(), surfaces, seed=0, noise_sigma=0.0)
    for g in (GimbalState(0.0, 0.0), GimbalState(17.3, -4.1), GimbalState(-31.0, 8.0)):
        _assert_matches(renderer, surfaces, g, edge=1e-4 if disc else 1e-5)
    assert not np.isfinite(renderer.static_depth(GimbalState(0.0, 8.0))[0]).all()  # some sky in view


def test_row_bands_are_each_done_once_by_either_thread_and_errors_reach_wait() -> None:
    from concurrent.futures import ThreadPoolExecutor

    done: list[tuple[int, int]] = []
    bands = render._Bands(100, lambda r0, r1: done.append((r0, r1)))
    with ThreadPoolExecutor(1) as pool:
        pool.submit(bands.run)
        bands.run()
        bands.wait()
    assert sorted(done) == [(r, min(r + render._Bands.BAND, 100)) for r in range(0, 100, render._Bands.BAND)]

    def fail(r0: int, r1: int) -> None:
        if r0 > 0:
            raise ValueError("band failed")

    bad = render._Bands(100, fail)
    bad.run()
    with pytest.raises(ValueError, match="band failed"):
        bad.wait()


def test_segments_hidden_from_every_camera_centre_are_dropped_and_no_others() -> None:
    from tracker.sim import static_cast

    ex, ey = np.eye(3)[0], np.eye(3)[1]
    tex = np.full((4, 4), 100, np.uint8)
    hedge = Surface("hedge", np.array([0.0, 0.9, 24.0]), ex, ey, 40.0, 0.6, tex, 1.0)
    foot = (np.array([-60.0, 1.5, 60.0]), np.array([60.0, 1.5, 60.0]))  # a wall's foot behind it
    assert static_cast._hidden(*foot, hedge, 0.15)
    assert not static_cast._hidden(*foot, hedge, 1.0)  # a camera 1 m up sees over the hedge
    narrow = Surface("narrow", hedge.P0, ex, ey, 20.0, 0.6, tex, 1.0)
    assert not static_cast._hidden(*foot, narrow, 0.15)  # its ends are seen beside it
    assert not static_cast._hidden(foot[0], foot[1] - [0.0, 0.0, 50.0], hedge, 0.15)  # one end in front of it
    # the pan scene: the wall's foot is dropped, the hedge's top and the facade's edges are kept
    scene = SimRig(get_scenario("pan")).renderer._scene
    kept = {tuple(np.round(s, 1).ravel()) for s in scene._planes.segments}
    assert (-60.0, 1.5, 60.0, 60.0, 1.5, 60.0) not in kept and (60.0, 1.5, 60.0, -60.0, 1.5, 60.0) not in kept
    assert (-40.0, 0.3, 24.0, 40.0, 0.3, 24.0) in kept and (5.5, -6.5, 22.0, 12.5, -6.5, 22.0) in kept
