"""A solid target's unseen depth (tracker.solid_prior.SolidPrior): the centre is placed behind the seen face
along the left camera's line of sight (the ray of eq. 10's centroid) by ρ/2 times the smaller seen extent, and
the range's 1-σ grows by σ_ρ/2 times it; the angles about the origin (midway between the lenses) move only by that
shift's parallax; without a prior (flat targets) nothing changes."""

from __future__ import annotations

import math

import numpy as np
import pytest
from sim_helpers import run_frames

from tracker import partly_seen, pipeline
from tracker.localize import Localizer
from tracker.rectify import Rectifier
from tracker.segmentation import outline_sigma_px
from tracker.sim.rig import default_rig
from tracker.solid_prior import SolidPrior


def _pair(z_m: float, extent_px: tuple[float, float]):  # type: ignore[no-untyped-def]
    rect = Rectifier(default_rig())
    x, y = rect.rig.left.size[0] / 2.0 + 40.0, rect.rig.left.size[1] / 2.0 - 20.0
    d = rect.f * rect.rig.baseline / z_m
    args = (np.array([x, y]), d, 0.05, 400, None, (0.0, 0.0), extent_px)
    flat = Localizer(rect).locate(*args)
    prior = SolidPrior(0.5, 0.3, rim_sigma_px=0.0, upright_sigma=0.0, upright_ratio=0.5, upright_ratio_sigma=0.3,
                       upright_x_sigma=0.0, upright_swing_sigma=0.0, wide_ratio=0.5, wide_ratio_sigma=0.3,
                       upright_shift=0.0, upright_depth_m2=0.0)
    # upright and wide bodies' own terms apart (tested below)
    solid = Localizer(rect, solid=prior).locate(*args)
    return flat, solid, rect


def test_the_centre_lies_behind_the_face_by_half_the_assumed_depth() -> None:
    flat, solid, rect = _pair(10.0, (60.0, 165.0))  # a person 0.6 x 1.65 m at 10 m: extent 0.6 m
    e = 60.0 * float(flat.rig[2]) / rect.f
    c = rect.rig.left.c  # the centroid is measured in the left image: the centre stays on its ray
    moved = float(np.linalg.norm(solid.rig - c) - np.linalg.norm(flat.rig - c))
    assert math.isclose(moved, 0.25 * e, rel_tol=1e-9)
    u = (flat.rig - c) / np.linalg.norm(flat.rig - c)
    assert np.allclose(np.cross(solid.rig - flat.rig, u), 0.0, atol=1e-12)  # along the line of sight
    mid = 0.5 * (rect.rig.left.c + rect.rig.right.c)  # not along the ray from the midpoint of the lenses
    assert np.linalg.norm(np.cross(solid.rig - flat.rig, (flat.rig - mid) / np.linalg.norm(flat.rig - mid))) > 1e-4
    assert math.isclose(solid.sigma_r ** 2, flat.sigma_r ** 2 + (0.15 * e) ** 2, rel_tol=0.02)
    assert abs(solid.theta - flat.theta) < 1e-3 and abs(solid.phi - flat.phi) < 1e-3
    # the same lateral spread a little farther, and the depth's spread along the left ray seen about the
    # origin (midway between the lenses) by parallax: its share across the line of sight from there
    o = solid.rig / np.linalg.norm(solid.rig)
    across = 0.15 * e * float(np.linalg.norm(np.cross(u, o))) / float(np.linalg.norm(solid.rig))
    assert math.isclose(solid.sigma_theta ** 2, flat.sigma_theta ** 2 + across ** 2, rel_tol=0.1)


def test_a_solid_bodys_rim_widens_the_centroids_sigma_by_a_side_over_root_two() -> None:
    # each side of the outline off by rim_sigma_px (1-σ), independently: eq. (10)'s centroid off by half of
    # each side's shift, so by rim_sigma_px / √2 along x and y, as if that were seen-in-part's extra_px
    rect = Rectifier(default_rig())
    base = (np.array([380.0, 200.0]), 12.0, 0.05, 400, None)

    def loc(rim_px: float, extra: tuple[float, float]):  # type: ignore[no-untyped-def]
        prior = SolidPrior(rim_sigma_px=rim_px, upright_sigma=0.0)
        return Localizer(rect, solid=prior).locate(*base, extra, (60.0, 80.0))  # not upright

    rim = loc(0.5, (0.0, 0.0))
    s = 0.5 / math.sqrt(2.0)
    same = loc(0.0, (s, s))
    assert np.allclose(rim.world, same.world) and np.allclose(rim.cov_world, same.cov_world, rtol=1e-12, atol=0.0)
    sharp = loc(0.0, (0.0, 0.0))
    assert rim.sigma_theta > 1.5 * sharp.sigma_theta and rim.sigma_phi > 1.5 * sharp.sigma_phi
    assert math.isclose(rim.sigma_r, sharp.sigma_r, rel_tol=0.01)  # the range hardly moves with the centroid


def test_an_upright_bodys_elevation_sigma_is_at_least_a_share_of_its_height() -> None:
    # a person (height >= 1.5 x width): y's further 1-σ is max(upright_sigma * h, the seen-in-part extra_px);
    # a ball or a car side-on (not upright) keeps its own
    rect = Rectifier(default_rig())
    base = (np.array([380.0, 200.0]), 12.0, 0.05, 400, None)
    solid = SolidPrior(rim_sigma_px=0.0, upright_sigma=0.03)
    bare = SolidPrior(rim_sigma_px=0.0, upright_sigma=0.0)

    def loc(prior: SolidPrior, extra: tuple[float, float], extent: tuple[float, float]):  # type: ignore[no-untyped-def]
        return Localizer(rect, solid=prior).locate(*base, extra, extent)

    person = loc(solid, (0.0, 0.0), (40.0, 120.0))
    assert np.allclose(person.cov_world, loc(bare, (0.0, 3.6), (40.0, 120.0)).cov_world, rtol=1e-12, atol=0.0)
    assert person.sigma_phi > 5.0 * loc(bare, (0.0, 0.0), (40.0, 120.0)).sigma_phi
    hidden = loc(solid, (0.0, 10.0), (40.0, 120.0))  # its legs hidden: the larger term counts, not both
    assert np.allclose(hidden.cov_world, loc(bare, (0.0, 10.0), (40.0, 120.0)).cov_world, rtol=1e-12, atol=0.0)
    for extent in ((60.0, 60.0), (150.0, 55.0)):  # a ball, a car
        assert np.allclose(loc(solid, (0.0, 0.0), extent).cov_world, loc(bare, (0.0, 0.0), extent).cov_world,
                           rtol=1e-12, atol=0.0)


def test_an_upright_body_has_its_own_depth_prior() -> None:
    # a person (height >= 1.5 x width): ρ = upright_ratio ± upright_ratio_sigma of its seen width; a ball
    # (not upright) the general ρ ± σ_ρ
    rect = Rectifier(default_rig())
    d = rect.f * rect.rig.baseline / 10.0
    args = (np.array([360.0, 220.0]), d, 0.05, 400, None, (0.0, 0.0))
    prior = SolidPrior(0.5, 0.3, rim_sigma_px=0.0, upright_sigma=0.0, upright_ratio=0.36, upright_ratio_sigma=0.15,
                       upright_shift=0.0)
    _moved_by(rect, args, prior, (((60.0, 165.0), 0.36, 0.15), ((60.0, 60.0), 0.5, 0.3)))


def _moved_by(rect: Rectifier, args: tuple[np.ndarray, float, float, int, None, tuple[float, float]], prior: SolidPrior,
              cases: tuple[tuple[tuple[float, float], float, float], ...]) -> None:
    """For each (seen extent (w, h) px, ρ, σ_ρ): the centre lies ρ/2 · e behind the flat point along the left
    camera's ray and σ_r² grows by (σ_ρ/2 · e)², e the smaller extent in metres."""
    c = rect.rig.left.c
    for extent, ratio, sigma in cases:
        flat = Localizer(rect).locate(*args, extent)
        solid = Localizer(rect, solid=prior).locate(*args, extent)
        e = min(extent) * float(flat.rig[2]) / rect.f
        moved = float(np.linalg.norm(solid.rig - c) - np.linalg.norm(flat.rig - c))
        assert math.isclose(moved, 0.5 * ratio * e, rel_tol=1e-9), (extent, moved)
        assert math.isclose(solid.sigma_r ** 2, flat.sigma_r ** 2 + (0.5 * sigma * e) ** 2, rel_tol=0.02)


def test_an_upright_bodys_azimuth_sigma_is_a_share_of_its_height_in_place_of_the_rims() -> None:
    # along x a person's 1-σ is upright_x_sigma times its seen height, not the rim's term (rim_px, from the
    # rim's contrast while the cameras are still): as if that were seen-in-part's extra_px along x, the
    # rim's y term kept. While the cameras move (rim_px None: the outline warped, no rim contrast) the
    # fixed rim term counts along x as well.
    rect = Rectifier(default_rig())
    base = (np.array([380.0, 200.0]), 12.0, 0.05, 400, None)
    rim = 0.5 / math.sqrt(2.0)
    sharp = (rim, rim)

    def loc(prior: SolidPrior, extra: tuple[float, float], extent: tuple[float, float],  # type: ignore[no-untyped-def]
            rim_px: tuple[float, float] | None):
        return Localizer(rect, solid=prior).locate(*base, extra, extent, rim_px)

    prior = SolidPrior(upright_sigma=0.0, upright_x_sigma=0.005, upright_swing_sigma=0.0)
    bare = SolidPrior(rim_sigma_px=0.0, upright_sigma=0.0, upright_x_sigma=0.0, upright_swing_sigma=0.0)
    person = loc(prior, (0.0, 0.0), (40.0, 200.0), sharp)
    same = loc(bare, (1.0, rim), (40.0, 200.0), (0.0, 0.0))
    assert np.allclose(person.cov_world, same.cov_world, rtol=1e-12, atol=0.0)
    cut = loc(prior, (0.7, 0.0), (40.0, 200.0), sharp)  # both count
    same = loc(bare, (math.hypot(1.0, 0.7), rim), (40.0, 200.0), (0.0, 0.0))
    assert np.allclose(cut.cov_world, same.cov_world, rtol=1e-12, atol=0.0)
    moving = loc(prior, (0.0, 0.0), (40.0, 200.0), None)
    same = loc(bare, (math.hypot(1.0, rim), rim), (40.0, 200.0), (0.0, 0.0))
    assert np.allclose(moving.cov_world, same.cov_world, rtol=1e-12, atol=0.0)
    assert moving.sigma_theta > 1.02 * person.sigma_theta
    taller = loc(prior, (0.0, 0.0), (40.0, 400.0), sharp)
    assert taller.sigma_theta > 1.5 * person.sigma_theta
    ball = loc(prior, (0.0, 0.0), (60.0, 60.0), None)
    plain = loc(SolidPrior(rim_sigma_px=0.0, upright_sigma=0.0), (rim, rim), (60.0, 60.0), None)
    assert np.allclose(ball.cov_world, plain.cov_world, rtol=1e-12, atol=0.0)


def test_an_upright_bodys_azimuth_sigma_grows_with_the_share_of_its_swing_seen_across_the_image() -> None:
    # h (a² + b² s²)^½ along x: s = 1 walking across the line of sight, 0 towards it, s² = 1/2 unknown
    rect = Rectifier(default_rig())
    prior = SolidPrior(upright_sigma=0.0, upright_x_sigma=0.003, upright_swing_sigma=0.006)
    bare = SolidPrior(rim_sigma_px=0.0, upright_sigma=0.0, upright_x_sigma=0.0, upright_swing_sigma=0.0)
    base = (np.array([380.0, 200.0]), 12.0, 0.05, 400, None)
    h = 200.0
    rim = (0.2, 0.2)

    def loc(p: SolidPrior, extra_x: float, swing: float | None):  # type: ignore[no-untyped-def]
        return Localizer(rect, solid=p).locate(*base, (extra_x, 0.0), (40.0, h), rim, True, None, swing)

    for swing, s2 in ((1.0, 1.0), (0.0, 0.0), (0.5, 0.25), (None, 0.5)):
        same = loc(bare, h * math.sqrt(0.003**2 + 0.006**2 * s2), swing)  # its x terms as the extra term's
        assert np.allclose(loc(prior, 0.0, swing).cov_world, same.cov_world, rtol=1e-12, atol=0.0), swing
    assert loc(prior, 0.0, 1.0).sigma_theta > 1.5 * loc(prior, 0.0, 0.0).sigma_theta
    # standing still (gait m = 0) only upright_still_sigma remains; walking fully (m = 1) as above
    assert prior.upright_x_var(h, 0.0, 0.0) == pytest.approx((h * prior.upright_still_sigma) ** 2)
    assert prior.upright_x_var(h, 0.5, 1.0) == pytest.approx(prior.upright_x_var(h, 0.5))
    a0, a = prior.upright_still_sigma, prior.upright_x_sigma
    assert prior.upright_x_var(h, 0.0, 0.5) == pytest.approx(h * h * (a0**2 + 0.25 * (a**2 - a0**2)))


def test_a_standing_upright_bodys_elevation_sigma_is_the_still_share_of_its_height() -> None:
    # h (σ0² + (σ² - σ0²) √m)^½ about its shift along y: m = 0 standing, 1 (or unknown) walking
    prior = SolidPrior(upright_sigma=0.028, upright_still_y_sigma=0.0127)
    h = 150.0
    assert prior.upright_y_sigma(h, 0.0) == pytest.approx(h * 0.0127)
    assert prior.upright_y_sigma(h, 1.0) == pytest.approx(h * 0.028) == prior.upright_y_sigma(h)
    assert prior.upright_y_sigma(h, 0.25) == pytest.approx(h * math.sqrt(0.0127**2 + 0.5 * (0.028**2 - 0.0127**2)))
    assert SolidPrior(upright_sigma=0.0).upright_y_sigma(h, 0.0) == 0.0  # never more than the walking one
    # in the localisation: a person seen whole, not cut, standing has the smaller elevation 1-σ
    rect = Rectifier(default_rig())
    base = (np.array([380.0, 200.0]), 12.0, 0.05, 400, None, (0.0, 0.0), (40.0, h), (0.2, 0.2), True, None, 0.5)

    def sigma_phi(gait: float | None) -> float:
        return Localizer(rect, solid=prior).locate(*base, None, None, gait).sigma_phi

    assert sigma_phi(0.0) < 0.6 * sigma_phi(1.0) and sigma_phi(None) == pytest.approx(sigma_phi(1.0))


def test_an_outline_short_of_a_persons_stature_at_its_disparity_says_by_how_much() -> None:
    # height_m d / b - h: a walker entering at the image's side, 46 px of the 125 a 1.7 m person shows at
    # 22 px of disparity on a 0.3 m baseline (endless:body frame 1546)
    prior = SolidPrior(height_m=1.7)
    assert prior.short_of_stature_px(46.0, 22.0, 0.3) == pytest.approx(1.7 * 22.0 / 0.3 - 46.0)
    assert prior.short_of_stature_px(130.0, 22.0, 0.3) == 0.0  # seen whole: nothing short
    assert prior.short_of_stature_px(46.0, 22.0, 0.0) == 0.0


def test_a_persons_fragment_is_under_part_of_its_stature_high_or_under_its_shoulders_wide() -> None:
    # a person 1.7 m tall at 22 px of disparity on a 0.3 m baseline stands 124.7 px high
    prior = SolidPrior(height_m=1.7)
    part, shoulders = prior.fragment_px(22.0, 0.3) or (0.0, 0.0)
    assert part == pytest.approx(0.6 * 1.7 * 22.0 / 0.3) and shoulders == pytest.approx(0.23 * 1.7 * 22.0 / 0.3)
    assert prior.fragment_px(22.0, 0.0) is None  # no baseline: no stature


def test_a_person_seen_in_part_is_as_uncertain_as_its_depth_behind_what_is_seen() -> None:
    # an outline under part_share of a person's height at its disparity (its legs hidden): the centre's depth
    # behind the seen face has a 1-σ of at least part_depth_sigma_m (px at the face's depth: m d / b); seen
    # whole, behind_face_px's stands
    prior = SolidPrior()
    d, b = 22.0, 0.3
    whole = prior.behind_face_px(40.0, 120.0)
    assert prior.seen_in_part(whole, 120.0, d, b) == whole  # 120 of 125 px
    part = prior.seen_in_part(whole, 60.0, d, b)  # 60 of 125 px
    assert part == (whole[0], pytest.approx(prior.part_depth_sigma_m * d / b)) and part[1] > whole[1]
    assert prior.seen_in_part(whole, 60.0, d, 0.0) == whole
    # the localiser widens σ_r by it: about part_depth_sigma_m in metres
    rect = Rectifier(default_rig())
    dz = rect.f * rect.rig.baseline / 10.0
    args = (np.array([360.0, 220.0]), dz, 0.05, 3000, None, (0.0, 0.0))
    stature = 1.7 * dz / rect.rig.baseline
    seen = Localizer(rect, solid=prior).locate(*args, (0.3 * stature, stature))
    legs_hidden = Localizer(rect, solid=prior).locate(*args, (0.3 * stature, 0.5 * stature))
    assert seen.sigma_r < 0.05 < prior.part_depth_sigma_m * 0.95 < legs_hidden.sigma_r


def test_a_wide_body_has_its_own_depth_prior() -> None:
    # a vehicle side-on (width >= 2 x height): ρ = wide_ratio ± wide_ratio_sigma of its seen height (its
    # smaller extent); just under the aspect, the general ρ ± σ_ρ
    rect = Rectifier(default_rig())
    d = rect.f * rect.rig.baseline / 12.0
    args = (np.array([360.0, 260.0]), d, 0.05, 4000, None, (0.0, 0.0))
    prior = SolidPrior(0.5, 0.3, rim_sigma_px=0.0, wide_ratio=1.2, wide_ratio_sigma=0.25)
    _moved_by(rect, args, prior, (((150.0, 75.0), 1.2, 0.25), ((149.0, 75.0), 0.5, 0.3)))
    assert prior.depth_ratio(40.0, 60.0) == (prior.upright_ratio, prior.upright_ratio_sigma)  # a person
    assert prior.depth_ratio(60.0, 60.0) == (0.5, 0.3) and not prior.wide(0.0, 0.0)


def test_upright_is_a_height_of_at_least_one_and_a_half_widths() -> None:
    prior = SolidPrior()
    assert prior.upright(40.0, 60.0) and prior.upright(0.5, 1.0)
    assert not prior.upright(40.0, 59.9) and not prior.upright(60.0, 40.0) and not prior.upright(0.0, 0.0)


def test_the_smaller_extent_counts_and_no_extent_or_prior_changes_nothing() -> None:
    _, tall, _ = _pair(10.0, (60.0, 165.0))
    _, wide, _ = _pair(10.0, (165.0, 60.0))
    assert np.allclose(tall.rig, wide.rig) and math.isclose(tall.sigma_r, wide.sigma_r)
    rect = Rectifier(default_rig())
    args = (np.array([300.0, 200.0]), 12.0, 0.05, 400, None)
    a = Localizer(rect, solid=SolidPrior()).locate(*args)  # no extent given
    b = Localizer(rect).locate(*args, (0.0, 0.0), (60.0, 165.0))  # flat targets
    c = Localizer(rect).locate(*args)
    assert np.array_equal(a.rig, c.rig) and np.array_equal(b.rig, c.rig) and a.sigma_r == b.sigma_r == c.sigma_r


def test_the_runtime_chooses_the_prior_from_its_targets_setting() -> None:
    from tmeye.runtime.compose import solid_prior
    from tmeye.runtime.config import RuntimeConfig

    def prior(**kw: object) -> SolidPrior | None:
        return solid_prior(RuntimeConfig(**kw))  # type: ignore[arg-type]

    assert prior() is None  # the server's default: the simulator's endless scene of flat plates
    assert prior(scenario="walk:body") == SolidPrior()  # the simulator's solid bodies
    assert prior(source="files", inputs=("l.mp4", "r.mp4")) == SolidPrior()  # real cameras: solid
    assert prior(source="recording", inputs=("d",), start=0.0, end=1.0, scenario="") == SolidPrior()
    assert prior(source="recording", inputs=("d",), start=0.0, end=1.0, scenario="walk") is None
    assert prior(scenario="walk", targets="solid") == SolidPrior()
    assert prior(source="usb", inputs=("0", "1"), targets="flat") is None
    try:
        RuntimeConfig(targets="round")
    except ValueError as exc:
        assert "unknown targets 'round'" in str(exc)
    else:
        raise AssertionError("a bad targets setting was taken")


def test_the_server_refuses_an_unknown_targets_setting_in_one_line(tmp_path) -> None:  # type: ignore[no-untyped-def]
    import os
    import subprocess
    import sys

    env = dict(os.environ, TMEYE_TARGETS="round")
    p = subprocess.run([sys.executable, "-m", "tmeye", "serve", "--port", "0", "--data-dir", str(tmp_path / "d")],
                       capture_output=True, text=True, timeout=60, env=env)
    assert p.returncode != 0 and "unknown targets 'round'; use auto, solid or flat" in p.stderr, p.stderr
    assert len(p.stderr.strip().splitlines()) == 1, p.stderr
    assert not (tmp_path / "d" / "tmeye.db").exists()  # nothing made


def test_an_upright_bodys_centre_lies_above_its_silhouettes_centroid_unless_the_frame_cuts_it() -> None:
    # a person seen whole: the centroid moved up by upright_shift times its seen height before eq. (2); one
    # that meets the image's top or bottom edge (in_frame False), a ball, a car: not moved
    rect = Rectifier(default_rig())
    base = (np.array([380.0, 200.0]), 12.0, 0.05, 400, None, (0.0, 0.0))
    moved, still = SolidPrior(upright_shift=0.03), SolidPrior(upright_shift=0.0)
    person = Localizer(rect, solid=moved).locate(*base, (40.0, 120.0))
    up = Localizer(rect, solid=still).locate(np.array([380.0, 200.0 - 0.03 * 120.0]), *base[1:], (40.0, 120.0))
    assert np.allclose(person.rig, up.rig, rtol=0.0, atol=1e-12)
    unmoved = Localizer(rect, solid=still).locate(*base, (40.0, 120.0))
    assert person.phi > unmoved.phi + 1e-4
    assert person.measured_world is not None and unmoved.measured_world is not None  # as measured: not moved up
    assert np.allclose(person.measured_world, unmoved.world, rtol=0.0, atol=1e-12)
    for extent, in_frame in (((40.0, 120.0), False), ((60.0, 60.0), True), ((150.0, 55.0), True)):
        a = Localizer(rect, solid=moved).locate(*base, extent, None, in_frame)
        b = Localizer(rect, solid=still).locate(*base, extent, None, in_frame)
        assert np.allclose(a.rig, b.rig, rtol=0.0, atol=1e-12), extent


def test_a_person_whose_lower_part_is_hidden_is_placed_from_its_top() -> None:
    # an upright body with its top seen and its bottom hidden: its centre c H f / Z_c below the top (Z_c the
    # centre's depth, ρ/2 of the seen width behind the face); y's 1-σ the top's edge and the height's share,
    # not what is hidden (extra_px); a ball (not upright) keeps its own
    rect = Rectifier(default_rig())
    d = rect.f * rect.rig.baseline / 10.0  # the face at 10 m
    args = (np.array([360.0, 220.0]), d, 0.05, 4000, None)
    prior = SolidPrior(rim_sigma_px=0.0, height_sigma_m=0.0, centre_below_top_sigma=0.0)
    loc = Localizer(rect, solid=prior)
    person = loc.locate(*args, (0.0, 30.0), (60.0, 100.0), None, True, 150.0)
    z_c = 10.0 * (1.0 + 0.5 * prior.upright_ratio * 60.0 / rect.f)
    y_expected = 150.0 + prior.centre_below_top * prior.height_m * rect.f / z_c
    _, y, _ = rect.rig_to_rect(person.rig[None, :])
    assert math.isclose(float(y[0]), y_expected, abs_tol=1e-6)
    assert abs(y_expected - 220.0) > 5.0  # not the silhouette's centroid
    # what is hidden does not count: the same with no extra term, and a tight y
    same = loc.locate(*args, (0.0, 0.0), (60.0, 100.0), None, True, 150.0)
    assert np.allclose(person.cov_world, same.cov_world, rtol=1e-12, atol=0.0)
    assert person.sigma_phi < 0.2 * loc.locate(*args, (0.0, 30.0), (60.0, 100.0)).sigma_phi
    # the height's spread: c σ_H f / Z_c px along y
    spread = Localizer(rect, solid=SolidPrior(rim_sigma_px=0.0, centre_below_top_sigma=0.0))
    wide = spread.locate(*args, (0.0, 0.0), (60.0, 100.0), None, True, 150.0)
    s_px = prior.centre_below_top * 0.10 * rect.f / z_c
    assert math.isclose(wide.sigma_phi, s_px / rect.f, rel_tol=0.05)
    # a ball's top says nothing of its centre that way
    ball = loc.locate(*args, (0.0, 0.0), (60.0, 60.0), None, True, 150.0)
    assert math.isclose(float(rect.rig_to_rect(ball.rig[None, :])[1][0]), 220.0, abs_tol=1e-6)
    # but a person known as one (its track saw it whole), of whom only head and shoulders show, is: its
    # centre from its top, its depth prior a person's
    known = loc.locate(*args, (0.0, 0.0), (60.0, 60.0), None, True, 150.0, None, True)
    y_known = 150.0 + prior.centre_below_top * prior.height_m * rect.f / z_c
    assert math.isclose(float(rect.rig_to_rect(known.rig[None, :])[1][0]), y_known, abs_tol=1e-6)
    assert prior.depth_ratio(60.0, 60.0, upright=True) == (prior.upright_ratio, prior.upright_ratio_sigma)
    assert prior.depth_ratio(40.0, 100.0, upright=False) == (prior.ratio, prior.ratio_sigma)
    # the stature its track measured (1.60 ± 0.01 m) weighs in with the prior's 1.70 ± 0.10 m, past the
    # outline's own 2 cm (stature_sigma_m): inverse-variance weighted
    measured = spread.locate(*args, (0.0, 0.0), (60.0, 100.0), None, True, 150.0, None, None, (1.60, 0.01))
    w_m = 1.0 / (0.01**2 + prior.stature_sigma_m**2)
    h_c = (1.70 / 0.10**2 + 1.60 * w_m) / (1.0 / 0.10**2 + w_m)
    assert spread.solid is not None and (spread.solid.height_m, spread.solid.height_sigma_m) == (1.70, 0.10)
    y_m = 150.0 + prior.centre_below_top * h_c * rect.f / z_c
    assert math.isclose(float(rect.rig_to_rect(measured.rig[None, :])[1][0]), y_m, abs_tol=1e-6)
    assert measured.sigma_phi < wide.sigma_phi  # the measured stature narrows it
    # its depth prior on its seen width, not on its smaller extent (a head and shoulders 60 x 40 px)
    flat = Localizer(rect).locate(*args, (0.0, 0.0), (60.0, 40.0))
    squat = Localizer(rect, solid=SolidPrior(upright_shift=0.0)).locate(*args, (0.0, 0.0), (60.0, 40.0), None,
                                                                        True, None, None, True)
    e = 60.0 * float(flat.rig[2]) / rect.f
    c = rect.rig.left.c
    moved = float(np.linalg.norm(squat.rig - c) - np.linalg.norm(flat.rig - c))
    assert math.isclose(moved, 0.5 * prior.upright_ratio * e, rel_tol=1e-6)
    not_known = loc.locate(*args, (0.0, 0.0), (60.0, 100.0), None, True, 150.0, None, False)
    assert math.isclose(float(rect.rig_to_rect(not_known.rig[None, :])[1][0]), 220.0, abs_tol=1e-6)


def test_a_person_hidden_below_gets_no_move_along_x_for_its_hidden_part(monkeypatch) -> None:  # type: ignore[no-untyped-def]
    # foliage:body, frame 105: a walker behind the bush, its top seen. visibility.cuts finds its bottom cut
    # and a move of the centroid along x across it (the hidden part taken to go on beyond the bush's edge
    # away from the centroid); an upright body's hidden legs stand under what is seen, so none counts, but
    # for the pull of what shows of them past the bush (partly_seen.legs_aside_px, 0.07 px). A body the
    # prior does not take for upright keeps the move.
    found, pulls = [], []
    real, real_pull = partly_seen.cuts, partly_seen.legs_aside_px
    monkeypatch.setattr(partly_seen, "cuts", lambda *a, **k: found.append(real(*a, **k)) or found[-1])
    monkeypatch.setattr(partly_seen, "legs_aside_px", lambda *a: pulls.append(real_pull(*a)) or pulls[-1])
    pipe, sf, res = run_frames("foliage:body", 105)
    (det,) = res.detections
    found.clear()
    pulls.clear()
    terms = pipe._sigma_terms(sf.frame, det.blob, [det.blob])
    assert terms.hidden_below and found[-1].sides[3] and found[-1].skew[0] > 0.5
    assert len(pulls) == 1 and pulls[0] < 0.2
    assert terms.cut_px[0] == pytest.approx(pulls[0], abs=1e-12) and terms.cut_px[1] > 10.0
    pipe.localizer.solid = SolidPrior(upright_aspect=10.0)  # not upright: the move stands
    assert math.isclose(pipe._sigma_terms(sf.frame, det.blob, [det.blob]).cut_px[0], found[-1].skew[0],
                        rel_tol=1e-9)


def test_a_wide_bodys_outline_notches_are_its_shape_not_missed_pixels() -> None:
    # occlusion:body, frame 100: a car side-on, its cabin over its body. The convex hull's gap beside the
    # cabin is the car's own shape, not parts the segmentation missed: no hull-gap term along y. A body the
    # prior does not take for wide keeps it.
    pipe, sf, res = run_frames("occlusion:body", 100)
    (det,) = res.detections
    _, (_, gap_y) = outline_sigma_px(det.blob.mask)
    assert gap_y > 2.0
    edge_y = outline_sigma_px(det.blob.mask)[0][1]
    terms = pipe._sigma_terms(sf.frame, det.blob, [det.blob])
    assert math.isclose(terms.centroid_px[1], edge_y, rel_tol=1e-9)
    pipe.localizer.solid = SolidPrior(wide_aspect=10.0)  # not wide: the gap counts
    narrow = pipe._sigma_terms(sf.frame, det.blob, [det.blob])
    assert math.isclose(narrow.centroid_px[1], math.hypot(edge_y, gap_y), rel_tol=1e-9)


def test_a_round_body_is_placed_at_the_centre_of_a_sphere_behind_its_seen_face() -> None:
    # the matched disparity is the seen face's mean depth: over the disc a sphere of radius R is seen as,
    # the mean of its near surface's depth lies 2R/3 before the centre; the default ρ puts it there
    R = 1.0
    r = np.linspace(0.0, R, 200001)
    w = 2.0 * np.pi * r  # the disc's area element
    face_before_centre = float(np.trapezoid(np.sqrt(R * R - r * r) * w, r) / np.trapezoid(w, r))
    prior = SolidPrior()
    ratio, sigma = prior.depth_ratio(60.0, 60.0)  # seen as wide as high: neither upright nor wide
    assert math.isclose(0.5 * ratio * 2.0 * R, face_before_centre, rel_tol=1e-3)
    assert 0.0 < sigma < 0.1  # fitted to a sphere's ranges (tracker.round_face), not spanning other shapes


def test_an_upright_bodys_centre_lies_higher_above_its_silhouette_seen_from_the_side() -> None:
    # walking across the line of sight (s = 1) its striding legs spread its silhouette low: the volume centre
    # lies upright_shift_side of the seen height above the centroid; seen from the front (s = 0)
    # upright_shift_front; unknown heading: upright_shift
    prior = SolidPrior()
    assert prior.shift_up(None) == prior.upright_shift
    assert prior.shift_up(0.0) == prior.upright_shift_front < prior.upright_shift < prior.shift_up(1.0)
    assert prior.shift_up(1.0) == pytest.approx(prior.upright_shift_side)
    assert prior.shift_up(0.5) == pytest.approx(prior.upright_shift_front
                                                + 0.25 * (prior.upright_shift_side - prior.upright_shift_front))
    rect = Rectifier(default_rig())
    args = (np.array([380.0, 200.0]), 12.0, 0.05, 4000, None, (0.0, 0.0), (40.0, 200.0), None, True, None)
    ys = []
    for swing in (0.0, None, 1.0):
        loc = Localizer(rect, solid=SolidPrior(upright_ratio=0.0)).locate(*args, swing)
        ys.append(float(rect.rig_to_rect(loc.rig[None, :])[1][0]))
    assert ys[0] == pytest.approx(200.0 - prior.upright_shift_front * 200.0, abs=1e-6)
    assert ys[2] == pytest.approx(200.0 - prior.upright_shift_side * 200.0, abs=1e-6)
    assert ys[2] < ys[1] < ys[0]


def test_a_person_seen_side_on_has_its_centre_deeper_behind_its_face() -> None:
    # seen width plus depth along the line of sight ≈ g h: a narrow silhouette (a walker side-on, stride
    # closed) puts the centre κ (g h - w) behind the face, with half that as its 1-σ; a wide one keeps ρ/2 w
    prior = SolidPrior()
    g, k = prior.upright_girth, prior.upright_side_ratio
    side = k * (g * 160.0 - 20.0)
    assert prior.behind_face_px(20.0, 160.0) == pytest.approx((side, prior.upright_side_sigma * side))
    assert side > 0.5 * prior.upright_ratio * 20.0
    front = (0.5 * prior.upright_ratio * 70.0, 0.5 * prior.upright_ratio_sigma * 70.0)
    assert prior.behind_face_px(70.0, 160.0) == pytest.approx(front)
    ball = prior.behind_face_px(60.0, 50.0)  # not upright: ρ/2 of the smaller extent, no side term
    assert ball == pytest.approx((0.5 * prior.ratio * 50.0, 0.5 * prior.ratio_sigma * 50.0))
    assert prior.behind_face_px(20.0, 160.0, upright=False)[0] == pytest.approx(0.5 * prior.ratio * 20.0)
    # the localiser moves the face point that far along the left camera's ray, and widens σ_r by its 1-σ
    rect = Rectifier(default_rig())
    d = rect.f * rect.rig.baseline / 10.0
    args = (np.array([360.0, 220.0]), d, 0.05, 3000, None)
    flat = Localizer(rect).locate(*args, (0.0, 0.0), (20.0, 160.0))
    person = Localizer(rect, solid=SolidPrior(upright_shift=0.0, upright_shift_front=0.0, upright_shift_side=0.0,
                                              rim_sigma_px=0.0, upright_sigma=0.0)).locate(
        *args, (0.0, 0.0), (20.0, 160.0))
    c = rect.rig.left.c
    moved = float(np.linalg.norm(person.rig - c) - np.linalg.norm(flat.rig - c))
    assert math.isclose(moved, side * float(flat.rig[2]) / rect.f, rel_tol=1e-6)
    assert person.sigma_r > flat.sigma_r + 0.5 * prior.upright_side_sigma * side * float(flat.rig[2]) / rect.f


def _side_cut(x0: int) -> tuple[tuple[float, float], tuple[bool, bool]]:
    """tracker.partly_seen of a person's outline 16 x 60 px at disparity 22 px starting at column x0, before
    a far background (2 px) that hides nothing: (x, y) extra 1-σ and whether width and height were seen whole."""
    from tracker.bgdepth import CorrespondenceMap
    from tracker.results import Blob
    from tracker.visibility import padded

    pipe = pipeline.Pipeline(default_rig(), solid=SolidPrior())
    d, size = 22.0, pipe.rig.left.size
    box = (x0, 200, min(x0 + 16, size[0]), 260)
    mask = np.ones((box[3] - box[1], box[2] - box[0]), bool)
    b = Blob(box, mask, int(mask.sum()), np.zeros(2), np.zeros(2), d, 0.05, 2.0, 1.0)
    grown, gbox = padded(mask, box, size, left=2 + 22, below=2 + 60)
    shape = grown.shape
    cm = CorrespondenceMap(np.zeros(shape, np.float32), np.zeros(shape, np.float32), np.ones(shape, bool),
                           np.full(shape, 2.0, np.float32), np.zeros(shape, np.uint8))
    person = (pipe.localizer.solid, pipe.rect.b)
    _, cut, whole = partly_seen.partly_seen(b, [], True, (grown, gbox, cm), size, pipe.visibility, person)
    return cut, whole


def test_a_person_cut_at_a_side_of_the_image_holds_the_rest_of_its_stature_in_y() -> None:
    prior = SolidPrior()
    short = prior.short_of_stature_px(60.0, 22.0, default_rig().baseline)  # 1.7 m at 22 px: 125 px, 60 seen
    cut, whole = _side_cut(640 - 16)  # at the right border: the rest of the person is above or below what is seen
    assert not whole[0]
    assert cut[1] >= short / math.sqrt(12.0) - 1e-6 > 15.0
    # the same outline clear of every border: nothing hides its sides, but under part_share of a person's
    # stature with no cut found, the rest of the person may lie anywhere above or below (unseen_rest_px)
    inside, seen = _side_cut(300)
    assert inside == (0.0, pytest.approx(short / math.sqrt(12.0))) and seen == (True, False)


def test_a_person_seen_in_part_where_no_cut_was_found_may_be_anywhere_about_it() -> None:
    prior = SolidPrior()
    stature = 1.7 * 16.5 / 0.3  # 93.5 px at 16.5 px of disparity, baseline 0.3 m
    # endless:body seed 1 frame 2545: a walker behind a post, a sliver 9 x 34 px beside the post seen, the map
    # beside it far: no cut found, its azimuth error 1.27 deg (13 px) against a 1-σ of 0.009 deg
    x, y = prior.unseen_rest_px(9.0, 34.0, 16.5, 0.3, (False, False))
    assert x == pytest.approx((0.5 * stature - 9.0) / 12**0.5)
    assert y == pytest.approx((stature - 34.0) / 12**0.5)
    assert prior.unseen_rest_px(9.0, 34.0, 16.5, 0.3, (True, True)) == (None, None)  # the cuts' terms hold
    assert prior.unseen_rest_px(9.0, 60.0, 16.5, 0.3, (False, False)) == (None, None)  # 0.64 of the stature
    # a walker's upper body over what hides its legs, as wide as a person: its width is whole
    x, y = prior.unseen_rest_px(30.0, 50.0, 16.5, 0.3, (False, False))
    assert x is None and y == pytest.approx((stature - 50.0) / 12**0.5)
    # a fragment under 0.3 of the stature: its width says nothing either
    x, _ = prior.unseen_rest_px(16.0, 27.0, 16.5, 0.3, (False, True))
    assert x == pytest.approx((0.5 * stature - 16.0) / 12**0.5)
    assert prior.unseen_rest_px(9.0, 34.0, 16.5, 0.0, (False, False)) == (None, None)


def test_an_upright_bodys_depth_widens_its_x_sigma_by_k_f_over_z_squared() -> None:
    # a box-like cross-section's silhouette lies off its centre's direction by up to P z_r / Z² (rad): its
    # 1-σ in px is k f / Z², the same at any height seen, along x alone, for an upright body alone
    rect = Rectifier(default_rig())
    prior = SolidPrior()
    for z_m in (3.0, 10.0):
        d = rect.f * rect.rig.baseline / z_m
        assert prior.upright_depth_px(d, rect.rig.baseline, rect.f) == pytest.approx(0.017 * rect.f / z_m**2)
    assert prior.upright_depth_px(20.0, 0.0, rect.f) == 0.0
    centre = np.array([rect.rig.left.size[0] / 2.0, rect.rig.left.size[1] / 2.0])
    d = rect.f * rect.rig.baseline / 3.0
    args = (centre, d, 0.05, 4000, None, (0.0, 0.0))
    without = SolidPrior(upright_depth_m2=0.0)
    for extent, upright in (((60.0, 330.0), True), ((330.0, 200.0), False)):
        a = Localizer(rect, solid=prior).locate(*args, extent)
        b = Localizer(rect, solid=without).locate(*args, extent)
        # k f / Z² px at the face 3 m away is k / Z m across, seen from the origin at the centre's range
        grows = (a.sigma_theta**2 - b.sigma_theta**2) * float(np.linalg.norm(a.rig)) ** 2
        assert grows == pytest.approx((0.017 / 3.0) ** 2 if upright else 0.0, rel=0.02, abs=1e-12)
        assert a.sigma_phi == pytest.approx(b.sigma_phi, rel=1e-6)
