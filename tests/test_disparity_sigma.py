"""The disparity's 1-σ from the scatter of its parts (tracker.disparity_sigma, issue 12 item 1)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from tracker.disparity_sigma import (
    COLUMNS,
    FEW_PARTS_FACTOR,
    FEW_PARTS_PERSON_PX,
    MIN_PARTS,
    PRIOR_DOF,
    PRIOR_SHARE,
    ROWS,
    SPREAD_RATE,
    SPREAD_SHARE,
    PartSpread,
    blob_sigma,
    on_surface,
    part_fits,
    parts_sigma,
    scatter_sigma,
    surface_mean,
)
from tracker.results import Blob, PartFit
from tracker.stereo import refine_region


def test_the_sigma_is_the_standard_error_of_the_parts_mean() -> None:
    d = [10.0, 10.2, 9.8, 10.1, 9.9, 10.0, 10.3, 9.7]
    assert np.isclose(scatter_sigma(d), np.std(d, ddof=1) / np.sqrt(8))
    assert scatter_sigma(d[:MIN_PARTS - 1]) == 0.0
    assert scatter_sigma([12.0] * 8) == 0.0
    assert np.isclose(scatter_sigma(d, [0.02] * 8), scatter_sigma(d))  # equal weights: s / √n


def test_the_whole_fit_leans_on_its_best_textured_parts_and_is_as_uncertain_as_their_weights_say() -> None:
    """The whole region's fit is about the information-weighted mean of its parts (w_i ∝ 1 / σ_i²): with two
    parts of eight of half the others' σ (four times their information), those two hold 8/14 of the weight
    and the mean's standard error is s √Σ w², 1.25 times s / √8."""
    d = [10.0, 10.2, 9.8, 10.1, 9.9, 10.0, 10.3, 9.7]
    sig = [0.01, 0.01] + [0.02] * 6
    w = np.array([1 / 0.01**2] * 2 + [1 / 0.02**2] * 6)
    w /= w.sum()
    s = np.std(d, ddof=1)
    assert np.isclose(scatter_sigma(d, sig), s * np.sqrt(np.sum(w * w)))
    assert np.isclose(scatter_sigma(d, sig) / scatter_sigma(d), np.sqrt(8 * np.sum(w * w)))
    assert parts_sigma(d, 0.01, sig) == scatter_sigma(d, sig)


def _disparities(left: np.ndarray, right: np.ndarray, core: np.ndarray, off: int, d: float, min_score: float
                 ) -> list[float]:
    """The parts' disparities of part_fits (their own 1-σ left out)."""
    return [p.d for p in part_fits(left, right, core, off, d, min_score)]


def _pair(slope: float) -> tuple[np.ndarray, np.ndarray]:
    """A textured surface whose disparity is 10 px + slope px per column (a surface turned from the axis)."""
    rng = np.random.default_rng(3)
    tex = np.repeat(np.repeat(rng.uniform(30, 220, (64, 64)), 3, axis=0), 3, axis=1)[:120, :]
    xs = np.arange(160, dtype=float)
    left = np.zeros((120, 160))
    right = np.zeros((120, 160))
    for y in range(120):
        left[y] = np.interp(xs, np.arange(192), tex[y])
        right[y] = np.interp(xs + 10.0 + slope * (xs - 80.0), np.arange(192), tex[y])
    return left.clip(0, 255).astype(np.uint8), right.clip(0, 255).astype(np.uint8)


def test_each_part_is_refined_as_refine_region_refines_it_alone() -> None:
    left, right = _pair(0.02)  # 0.02 px a column: the parts' disparities differ
    core = np.ones((40, 48), np.uint8)  # rows 40..80, columns 56..104 of the images
    ours = _disparities(left[40:80], right[40:80], core, 56, 10.0, 0.8)
    alone = []
    for r in range(ROWS):
        for c in range(COLUMNS):
            fit = refine_region(left, right, np.ones((40 // ROWS, 48 // COLUMNS), np.uint8), 56 + c * 48 // COLUMNS,
                                40 + r * 40 // ROWS, 10.0, min_score=0.8, robust=False)
            assert fit is not None
            alone.append(fit.disparity)
    assert np.allclose(ours, alone, atol=0.005)


def test_the_parts_of_a_slanted_surface_disagree_and_of_a_flat_one_agree() -> None:
    def parts(slope: float) -> list[float]:
        left, right = _pair(slope)
        return _disparities(left[40:80], right[40:80], np.ones((40, 48), np.uint8), 56, 10.0, 0.8)
    flat, slanted = parts(0.0), parts(0.02)
    assert len(flat) == len(slanted) == COLUMNS * ROWS
    assert np.allclose(flat, 10.0, atol=0.02)
    assert scatter_sigma(flat) < 0.01 and scatter_sigma(slanted) > 5 * scatter_sigma(flat)
    assert scatter_sigma(slanted) > 0.05


def test_parts_without_texture_or_pixels_are_left_out() -> None:
    left, right = _pair(0.0)
    core = np.ones((40, 48), np.uint8)
    core[:, :12] = 0  # the first column of parts has no pixels
    flat = left[40:80].copy()
    flat[:20] = 128  # the top row of parts has no texture
    assert len(_disparities(flat, right[40:80], core, 56, 10.0, 0.8)) == COLUMNS - 1
    assert _disparities(left[40:80], right[40:80], core, 2, 10.0, 0.8) == []  # the strip ends


def test_too_few_parts_stand_for_twice_the_matchers_sigma_and_the_phase_term_is_in_every_range_sigma() -> None:
    many = [10.0, 10.1, 9.9, 10.05, 9.95, 10.0]
    assert parts_sigma(many, 0.01) == scatter_sigma(many)
    assert parts_sigma(many[:MIN_PARTS - 1], 0.01) == FEW_PARTS_FACTOR * 0.01 == 0.02
    from tracker.localize import MATCH_FLOOR_PX, PHASE_SIGMA_PX, Localizer
    from tracker.rectify import Rectifier
    from tracker.sim.rig import default_rig

    rect = Rectifier(default_rig())
    for s_d in (0.0, 0.05):
        loc = Localizer(rect).locate(np.array([320.0, 240.0]), 10.0, s_d, 10_000, None)
        z = rect.f * rect.rig.baseline / 10.0  # σ_Z = Z² / (f b) σ_d, σ_d = √(s_d² + 0.012² + 0.010²)
        expected = z * z / (rect.f * rect.rig.baseline) * float(np.sqrt(s_d**2 + PHASE_SIGMA_PX**2
                                                                        + MATCH_FLOOR_PX**2))
        assert abs(loc.sigma_r - expected) < 0.05 * expected


def test_robust_parts_leave_out_what_the_cameras_see_differently() -> None:
    """A flat surface at 10 px, a dark gap 2 px wide seen by the right camera alone in its second column of
    parts: refined plainly, that column's parts are pulled off; robust (the pixels the model does not fit at
    10 px left out, tracker.stereo.residual_outliers), every part is within 0.02 px of 10 px."""
    left, right = _pair(0.0)
    right = right.copy()
    right[40:80, 56 + 18 - 10 : 56 + 20 - 10] = 10  # left columns 74-75 (parts' column 1) at d = 10
    core = np.ones((40, 48), np.uint8)
    plain = [p.d for p in part_fits(left[40:80], right[40:80], core, 56, 10.0, 0.5)]
    robust = [p.d for p in part_fits(left[40:80], right[40:80], core, 56, 10.0, 0.5, robust=True)]
    assert len(robust) == COLUMNS * ROWS
    assert np.allclose(robust, 10.0, atol=0.02)
    assert max(abs(d - 10.0) for d in plain) > 0.05


def _two_depths(contrast_right: float) -> tuple[np.ndarray, np.ndarray]:
    """A surface whose left half (columns under 80 of the left image) lies at a disparity of 10 px and right
    half at 10.6 px (a walker's arm before its torso), the right half's texture `contrast_right` times as
    contrasted as the left's: the left and right images (120, 160) uint8."""
    rng = np.random.default_rng(5)
    u = np.arange(0, 192, 0.25)  # surface points, by the left image's column they are seen at
    tex = np.array([np.interp(u, np.arange(192), row) for row in
                    np.repeat(np.repeat(rng.uniform(-90, 90, (64, 64)), 3, axis=0), 3, axis=1)[:120]])
    tex[:, u >= 80] *= contrast_right
    xs = np.arange(160, dtype=float)
    d = np.where(u >= 80, 10.6, 10.0)
    left = np.array([np.interp(xs, u, row) for row in tex]) + 128
    right = np.array([np.interp(xs, u - d, row) for row in tex]) + 128  # point u is seen at u - d on the right
    return left.clip(0, 255).astype(np.uint8), right.clip(0, 255).astype(np.uint8)


def test_a_persons_disparity_is_its_parts_mean_by_pixels_not_its_best_textured_parts() -> None:
    """Half the region at 10 px, half at 10.6 px, the nearer half's texture half as contrasted: the one fit
    over the whole region lies near 10.1 px (the gradients weigh it), the seen surface's mean point at
    10.3 px; surface_mean, the parts' mean weighted by their pixel counts, finds it."""
    left, right = _two_depths(0.5)
    core = np.ones((40, 48), np.uint8)  # rows 40..80, columns 56..104: half each side of column 80
    whole = refine_region(left, right, core, 56, 40, 10.0, min_score=0.5)
    assert whole is not None and abs(whole.disparity - 10.3) > 0.15
    fits = part_fits(left[40:80], right[40:80], core, 56, whole.disparity, 0.5)
    assert len(fits) == COLUMNS * ROWS and {f.pixels for f in fits} == {240}
    mean = surface_mean(fits)
    assert mean is not None and abs(mean[0] - 10.3) < 0.03
    # its 1-σ: the standard error of an equally weighted mean (equal pixel counts), s / √n, s the parts'
    # spread pooled with the prior's
    n = len(fits)
    spread = np.var([f.d for f in fits], ddof=1)
    var = (PRIOR_DOF * (PRIOR_SHARE * mean[0]) ** 2 + (n - 1) * spread) / (PRIOR_DOF + n - 1)
    assert np.isclose(mean[1], np.sqrt(var / n))
    assert surface_mean(fits[:MIN_PARTS - 1]) is None  # too few parts to tell: none


def test_on_surface_moves_a_persons_disparity_and_keeps_its_parts() -> None:
    left, right = _two_depths(0.5)
    fits = part_fits(left[40:80], right[40:80], np.ones((40, 48), np.uint8), 56, 10.0, 0.5)

    def blob(w: int, h: int, one_camera: bool = False) -> Blob:
        return Blob((0, 0, w, h), np.ones((h, w), bool), w * h, np.zeros(2), np.zeros(2), 10.0, 0.01, 5.0, 0.9,
                    one_camera=one_camera)

    person = blob(40, 100)  # upright: a person's outline
    moved = on_surface(person, lambda: fits)
    mean = surface_mean(fits)
    assert mean is not None and moved.disparity == mean[0] and moved.parts == tuple(fits)
    assert moved.disparity_sigma == person.disparity_sigma  # the matcher's own σ stays the matcher's
    few = on_surface(person, lambda: fits[:MIN_PARTS - 1])  # too few to tell: its disparity stays, its parts kept
    assert few.disparity == person.disparity and few.parts == tuple(fits[:MIN_PARTS - 1])

    def never() -> list[PartFit]:
        raise AssertionError("parts matched again")

    assert blob_sigma(moved, never) == mean[1]  # its 1-σ: its parts' mean's, from the parts it keeps
    # too few to tell, a person's: at least FEW_PARTS_PERSON_PX (twice the matcher's would be 0.02 px), not
    # matched again; a ball with too few: twice the matcher's
    assert blob_sigma(few, never) == FEW_PARTS_PERSON_PX > FEW_PARTS_FACTOR * 0.01
    none = on_surface(person, lambda: [])  # none of its parts matched: not matched again either
    assert none.parts == () and blob_sigma(none, never) == FEW_PARTS_PERSON_PX
    few_ball = replace(blob(80, 80), parts=tuple(fits[:MIN_PARTS - 1]))
    assert blob_sigma(few_ball, never) == FEW_PARTS_FACTOR * 0.01

    for other in (blob(80, 80), blob(40, 100, one_camera=True)):  # a ball; a person seen by one camera
        assert on_surface(other, never) is other
    ball = blob(80, 80)
    assert blob_sigma(ball, lambda: fits) == parts_sigma([f.d for f in fits], 0.01, [f.sigma for f in fits])


def test_the_surface_mean_weighs_each_part_by_its_pixels() -> None:
    """Parts of unequal size (a walker's legs cut by the ground, its head small): each counts by its pixels,
    and the mean's 1-σ is the standard error of that weighted mean, s √Σ w², w_i = n_i / Σ n_i."""
    d = [10.0, 10.2, 9.8, 10.1, 9.9, 10.0, 10.3, 9.7]
    n = [400, 400, 100, 100, 400, 400, 50, 50]
    mean = surface_mean([PartFit(di, 0.01, ni) for di, ni in zip(d, n, strict=True)])
    w = np.array(n) / sum(n)
    assert mean is not None and np.isclose(mean[0], float(w @ d)) and not np.isclose(mean[0], np.mean(d))
    var = (PRIOR_DOF * (PRIOR_SHARE * mean[0]) ** 2 + 7 * np.var(d, ddof=1)) / (PRIOR_DOF + 7)
    assert np.isclose(mean[1], np.sqrt(var * np.sum(w * w)))


def test_a_persons_parts_that_happen_to_agree_keep_the_priors_spread() -> None:
    """Eight parts that agree to a hundredth of a pixel at 20 px: their own spread would give the mean a
    1-σ of 0.004 px; pooled with the prior's (PRIOR_SHARE · d̄ worth ν0 = PRIOR_DOF parts) it keeps at
    least √(ν0 / (ν0 + 7)) of the prior's, and parts that disagree widely keep √(7 / (ν0 + 7)) of theirs."""
    agree = [PartFit(20.0 + 0.01 * (i % 2), 0.01, 100) for i in range(8)]
    mean = surface_mean(agree)
    assert mean is not None
    prior_only = PRIOR_SHARE * mean[0] / np.sqrt(8)
    assert np.sqrt(PRIOR_DOF / (PRIOR_DOF + 7)) * prior_only < mean[1] < prior_only
    wide = [PartFit(20.0 + (1.0 if i % 2 else -1.0), 0.01, 100) for i in range(8)]
    wide_mean = surface_mean(wide)
    own = np.std([f.d for f in wide], ddof=1) / np.sqrt(8)
    assert wide_mean is not None and np.sqrt(7 / (PRIOR_DOF + 7)) * own < wide_mean[1] < own
    assert scatter_sigma([f.d for f in agree]) < 0.005  # the parts' own, as scatter_sigma gives without a prior


def _parts(d: float, spread: float) -> tuple[PartFit, ...]:
    """Eight equal parts about d (px) whose sample deviation is `spread` (px)."""
    offsets = np.array([-1.0, 1.0] * 4)
    offsets *= spread / np.std(offsets, ddof=1)
    return tuple(PartFit(d + o, 0.01, 100) for o in offsets)


def test_a_tracks_parts_spread_sets_its_prior() -> None:
    """A track not yet seen takes PRIOR_SHARE · d; one whose parts spread by 2 % of d frame after frame comes
    to SPREAD_SHARE of that; a flat board's, whose parts agree, narrows towards none; too few parts tell
    nothing; an ended track is forgotten."""
    spread = PartSpread()
    assert spread.prior(None, 20.0) == spread.prior(1, 20.0) == (PRIOR_SHARE * 20.0, PRIOR_DOF)
    for _ in range(1200):  # 40 s at 30 frames a second
        spread.add(1, _parts(20.0, 0.4), 20.0)  # 2 % of d
        spread.add(2, _parts(10.0, 0.001), 10.0)  # a board's parts
        spread.add(3, _parts(10.0, 0.4)[:MIN_PARTS - 1], 10.0)
    s0, nu0 = spread.prior(1, 30.0)
    assert nu0 == PRIOR_DOF and np.isclose(s0, SPREAD_SHARE * 0.02 * 30.0, rtol=0.01)
    assert spread.prior(2, 10.0)[0] < 0.01 * PRIOR_SHARE * 10.0
    assert spread.prior(3, 10.0) == (PRIOR_SHARE * 10.0, PRIOR_DOF)
    first = PartSpread()
    first.add(1, _parts(20.0, 0.4), 20.0)  # one frame moves it by SPREAD_RATE of the way
    m0 = PRIOR_SHARE / SPREAD_SHARE
    assert np.isclose(first.prior(1, 1.0)[0], SPREAD_SHARE * (m0 + SPREAD_RATE * (0.02 - m0)))
    spread.keep_only([2])
    assert spread.prior(1, 20.0) == (PRIOR_SHARE * 20.0, PRIOR_DOF) and spread.prior(2, 10.0)[0] < 0.01


def test_a_persons_1_sigma_takes_its_tracks_prior() -> None:
    parts = _parts(20.0, 0.001)
    person = replace(Blob((0, 0, 40, 100), np.ones((100, 40), bool), 4000, np.zeros(2), np.zeros(2), 20.0, 0.01,
                          5.0, 0.9), parts=parts)

    def never() -> list[PartFit]:
        raise AssertionError("parts matched again")

    tight, default = (0.002, PRIOR_DOF), surface_mean(list(parts))
    got = surface_mean(list(parts), tight)
    assert default is not None and got is not None
    assert blob_sigma(person, never, tight) == got[1] < 0.1 * default[1] == 0.1 * blob_sigma(person, never)
