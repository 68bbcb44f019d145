"""Tests of tracker.stereo: exact synthetic sub-pixel shifts, rejection cases, argument errors and the
Middlebury ground-truth acceptance (median |disparity error| <= 0.25 px on textured points)."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest

from tracker.frames import FrameError
from tracker.point_match import match_point, match_window
from tracker.stereo import RegionMatch, match_region, refine_region

DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data"
STEREO_GT = DATA / "stereo-gt"
PAIRS = ["barn2", "bull", "poster", "sawtooth", "venus"]  # disp2.png scale factor 8 (datasets.xml)


def smooth_texture(shape: tuple[int, int], sigma: float, seed: int, shift: float = 0.0) -> np.ndarray:
    """Gaussian-filtered white noise (periodic, float), translated by `shift` px along x with an exact
    Fourier phase shift: the result at u is the unshifted texture at u + shift."""
    rng = np.random.default_rng(seed)
    H, W = shape
    F = np.fft.fft2(rng.standard_normal(shape))
    fy, fx = np.fft.fftfreq(H)[:, None], np.fft.fftfreq(W)[None, :]
    F *= np.exp(-2.0 * (np.pi * sigma) ** 2 * (fx**2 + fy**2))
    F *= np.exp(2j * np.pi * fx * shift)
    return np.fft.ifft2(F).real


def to_u8(a: np.ndarray, scale: float = 40.0) -> np.ndarray:
    return np.clip(np.round(128.0 + scale * a), 0, 255).astype(np.uint8)


def shifted_pair(d: float, shape: tuple[int, int] = (96, 192), sigma: float = 1.5, seed: int = 0):
    """Left and right images of one textured plane at disparity d: right(u - d) = left(u)."""
    base = smooth_texture(shape, sigma, seed)
    s = 1.0 / base.std()
    return to_u8(s * base), to_u8(s * smooth_texture(shape, sigma, seed, shift=d))


@pytest.mark.parametrize("d", [3.0, 3.13, 3.25, 3.5, 3.71, 3.9, 17.42])
def test_exact_subpixel_shift(d: float) -> None:
    left, right = shifted_pair(d, seed=int(d * 100))
    rng = np.random.default_rng(7)
    errors = []
    for _ in range(25):
        x, y = rng.uniform(50.0, 180.0), rng.uniform(8.0, 86.0)  # sub-pixel points
        got = match_point(left, right, x, y, 32)
        assert got is not None, f"no match at ({x:.2f}, {y:.2f})"
        errors.append(got - d)
    assert np.max(np.abs(errors)) < 0.03, f"errors {np.round(errors, 4)}"


def test_not_pixel_locked() -> None:
    """The estimate follows the true fraction linearly: no pull towards integer disparities."""
    fractions = np.linspace(0.0, 0.9, 10)
    est = []
    for f in fractions:
        left, right = shifted_pair(5.0 + f, sigma=1.2, seed=3)
        est.append(np.median([match_point(left, right, x, 40.5, 24) for x in range(60, 180, 10)]))
    assert np.max(np.abs(np.array(est) - 5.0 - fractions)) < 0.02


def test_flat_and_untextured_images_give_none() -> None:
    flat = np.full((60, 120), 90, np.uint8)
    assert match_point(flat, flat, 80.0, 30.0, 32) is None
    rows = np.tile(np.arange(60, dtype=np.uint8)[:, None] * 4, (1, 120))  # texture only across rows
    assert match_point(rows, rows, 80.0, 30.0, 32) is None


def test_repetitive_texture_is_ambiguous() -> None:
    x = np.arange(160)
    stripes = np.tile((128 + 80 * np.sin(2 * np.pi * x / 8.0)).astype(np.uint8), (60, 1))
    noise = np.random.default_rng(0).integers(0, 3, stripes.shape).astype(np.uint8)
    img = stripes + noise
    assert match_point(img, np.roll(img, -3, axis=1), 100.0, 30.0, 40) is None


def claimed_block_pair(claimed: bool) -> tuple[np.ndarray, np.ndarray]:
    """Unrelated left and right textures, except a 25 px wide left block at x 108..132 that shows the right
    image's block 6 px to its left (disparity 6) under grey-level noise. claimed: a second, noise-free copy
    of that right block also lies in the left image, at disparity 31 (x 133..157)."""
    H, W = 80, 200
    right = smooth_texture((H, W), 1.5, 3)
    left = smooth_texture((H, W), 1.5, 4)
    right, left = right / right.std(), left / left.std()
    block = right[:, 102:127]
    left[:, 108:133] = block + 0.35 * np.random.default_rng(5).standard_normal(block.shape)
    if claimed:
        left[:, 133:158] = block
    return to_u8(left), to_u8(right)


def test_a_match_that_another_left_window_fits_better_is_rejected() -> None:
    """The right-to-left check: the right window a left window matches (at disparity 6) is matched better,
    searching back along the left row, by the left image's exact copy 25 px further right, so neither
    match_window nor match_point answers there; without that copy both answer 6."""
    points = [(120.0 + dx, 40.0 + dy) for dx in (-2, 0, 2) for dy in (-4, 0, 4)]
    left, right = claimed_block_pair(claimed=False)
    windows = [match_window(left, right, x, y, 40) for x, y in points]
    answers = [match_point(left, right, x, y, 40) for x, y in points]
    assert sum(w is not None and abs(w[0] - 6.0) < 0.3 for w in windows) >= 7
    assert sum(d is not None and abs(d - 6.0) < 0.3 for d in answers) >= 7
    left, right = claimed_block_pair(claimed=True)
    assert all(match_window(left, right, x, y, 40) is None for x, y in points)
    assert all(match_point(left, right, x, y, 40) is None for x, y in points)


def test_points_outside_or_at_the_border() -> None:
    left, right = shifted_pair(4.3)
    H, W = left.shape
    for x, y in [
        (-3.0, 40.0),
        (W + 2.0, 40.0),
        (100.0, -1.0),
        (100.0, H - 2.0),
        (W - 3.0, 40.0),
        (3.0, 40.0),
    ]:
        assert match_point(left, right, x, y, 32) is None
    # the true disparity lies outside the searched range: the peak is on the search border
    assert match_point(left, right, 120.0, 40.0, 3) is None


def test_wrong_disparity_sign_is_rejected() -> None:
    left, right = shifted_pair(6.0)
    assert match_point(right, left, 120.0, 40.0, 32) is None  # right point lies to the right


def test_argument_errors() -> None:
    img = np.zeros((40, 60), np.uint8)
    with pytest.raises(FrameError, match="empty"):
        match_point(np.zeros((0, 60), np.uint8), img, 10, 10, 8)
    with pytest.raises(FrameError, match="differ in size"):
        match_point(img, np.zeros((40, 61), np.uint8), 10, 10, 8)
    with pytest.raises(FrameError, match="uint8"):
        match_point(img.astype(np.float32), img, 10, 10, 8)
    with pytest.raises(FrameError, match="uint8"):
        match_point(np.zeros((40, 60, 3), np.uint8), np.zeros((40, 60, 3), np.uint8), 10, 10, 8)
    with pytest.raises(ValueError, match="max_disparity must be >= 0"):
        match_point(img, img, 10, 10, -1)
    with pytest.raises(ValueError, match="max_disparity must be an integer"):
        match_point(img, img, 10, 10, 8.5)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="window"):
        match_point(img, img, 10, 10, 8, window=10)
    with pytest.raises(ValueError, match="finite"):
        match_point(img, img, float("nan"), 10, 8)
    with pytest.raises(ValueError, match="mask"):
        match_region(img, img, np.zeros((0, 3), bool), 10, 10, 8)


def disc_scene(d_fg: float, d_bg: float, shape: tuple[int, int] = (120, 200), seed: int = 5):
    """A textured disc (disparity d_fg) in front of a textured background (d_bg); returns left, right and
    the disc's left-image mask."""
    H, W = shape
    yy, xx = np.mgrid[0:H, 0:W]
    cx, cy, r = 120.0, 60.0, 25.0
    fg = smooth_texture(shape, 1.5, seed)
    bg = smooth_texture(shape, 1.5, seed + 1)
    s_fg, s_bg = 1.0 / fg.std(), 1.0 / bg.std()
    in_left = (xx - cx) ** 2 + (yy - cy) ** 2 <= r * r
    in_right = (xx + d_fg - cx) ** 2 + (yy - cy) ** 2 <= r * r  # right(u) shows left(u + d)
    left = np.where(in_left, s_fg * fg, s_bg * bg)
    right = np.where(
        in_right,
        s_fg * smooth_texture(shape, 1.5, seed, d_fg),
        s_bg * smooth_texture(shape, 1.5, seed + 1, d_bg),
    )
    return to_u8(left), to_u8(right), in_left


def test_match_region_uses_only_the_masked_target() -> None:
    left, right, disc = disc_scene(d_fg=12.37, d_bg=4.0)
    mask = cv2.erode(disc.astype(np.uint8), np.ones((3, 3), np.uint8))
    ys, xs = np.nonzero(mask)
    y0, x0 = int(ys.min()), int(xs.min())
    sub = mask[y0 : ys.max() + 1, x0 : xs.max() + 1].astype(bool)
    m = match_region(left, right, sub, x0, y0, 40)
    assert isinstance(m, RegionMatch)
    assert abs(m.disparity - 12.37) < 0.02
    assert 0.0 < m.sigma < 0.01 and m.score > 0.99 and abs(m.gain - 1.0) < 0.05
    m_prior = match_region(left, right, sub, x0, y0, 40, d0=11.0)
    assert m_prior is not None and abs(m_prior.disparity - m.disparity) < 1e-6
    # unmasked, the bounding box's background corners (at d = 4) spoil the whole region's score, and the
    # least-squares fit (0.047 px off, 1-σ 0.027 px); the robust fit leaves them out (tracker.stereo.outliers)
    box = match_region(left, right, np.ones_like(sub), x0, y0, 40)
    assert box is not None and box.score < 0.9
    assert abs(box.disparity - 12.37) < 0.02 and box.sigma < 2.0 * m.sigma


def test_the_robust_fit_leaves_out_what_the_cameras_see_differently() -> None:
    """A region of which a tenth shows the two cameras different things (a gap between a walker's arm and
    torso, dark to one camera): the least-squares fit is pulled off, the robust fit is not."""
    left, right, disc = disc_scene(d_fg=12.37, d_bg=4.0)
    right = right.copy()
    ys, xs = np.nonzero(cv2.erode(disc.astype(np.uint8), np.ones((3, 3), np.uint8)))
    y0, x0 = int(ys.min()), int(xs.min())
    sub = np.zeros((ys.max() + 1 - y0, xs.max() + 1 - x0), bool)
    sub[ys - y0, xs - x0] = True
    cols = np.unique(xs)
    for c in cols[len(cols) // 3 : len(cols) // 3 + 3]:  # a dark gap 3 px wide the right camera alone sees
        rows = ys[xs == c]
        right[rows, int(round(c - 12.37))] = 20
    fit = refine_region(left, right, sub, x0, y0, 12.0, min_score=0.5)
    assert fit is not None and abs(fit.disparity - 12.37) < 0.02
    plain = refine_region(left, right, sub, x0, y0, 12.0, min_score=0.5, robust=False)
    assert plain is not None and abs(plain.disparity - 12.37) > 0.05


def test_match_region_sigma_matches_the_scatter() -> None:
    rng = np.random.default_rng(11)
    left, right = shifted_pair(7.6, shape=(128, 256), seed=2)
    mask = np.ones((15, 15), bool)
    errs, sigmas = [], []
    for _ in range(60):
        noisy = np.clip(right + rng.normal(0.0, 6.0, right.shape), 0, 255).astype(np.uint8)
        x0, y0 = int(rng.integers(60, 220)), int(rng.integers(5, 105))
        m = match_region(left, noisy, mask, x0, y0, 32)
        assert m is not None
        errs.append(m.disparity - 7.6)
        sigmas.append(m.sigma)
    ratio = float(np.std(errs) / np.mean(sigmas))
    assert 0.6 < ratio < 1.6, f"scatter {np.std(errs):.4f} px vs sigma {np.mean(sigmas):.4f} px"


def test_match_region_rejections() -> None:
    left, right = shifted_pair(5.0)
    assert match_region(left, right, np.ones((5, 1), bool), 50, 50, 32) is None  # fewer than 8 px
    assert match_region(left, right, np.ones((9, 9), bool), 185, 50, 32) is None  # leaves the image
    flat = np.full_like(left, 77)
    assert match_region(flat, flat, np.ones((9, 9), bool), 100, 50, 32) is None


def middlebury_points(name: str, n: int, seed: int, window: int = 11):
    """Left, right, GT disparity (px) and n random textured points away from borders and from depth
    discontinuities (GT disparity range within the window <= 1 px)."""
    left = cv2.imread(str(STEREO_GT / name / "im2.png"), cv2.IMREAD_GRAYSCALE)
    right = cv2.imread(str(STEREO_GT / name / "im6.png"), cv2.IMREAD_GRAYSCALE)
    gt = cv2.imread(str(STEREO_GT / name / "disp2.png"), cv2.IMREAD_GRAYSCALE).astype(np.float64) / 8.0
    f = left.astype(np.float32)
    mu = cv2.blur(f, (window, window))
    sd = np.sqrt(np.maximum(cv2.blur(f * f, (window, window)) - mu * mu, 0.0))
    kernel = np.ones((window, window), np.uint8)
    gt_range = cv2.dilate(gt, kernel) - cv2.erode(gt, kernel)
    H, W = left.shape
    yy, xx = np.mgrid[0:H, 0:W]
    h = window // 2
    ok = (gt > 0) & (gt_range <= 1.0) & (sd > 5.0)
    ok &= (yy >= h + 2) & (yy < H - h - 3) & (xx >= h + 40) & (xx < W - h - 5)
    ys, xs = np.nonzero(ok)
    idx = np.random.default_rng(seed).choice(xs.size, n, replace=False)
    return left, right, gt, xs[idx], ys[idx]


@pytest.mark.skipif(not STEREO_GT.is_dir(), reason=f"Middlebury test data not found at {STEREO_GT}")
@pytest.mark.parametrize("name", PAIRS)
def test_middlebury_accuracy(name: str) -> None:
    left, right, gt, xs, ys = middlebury_points(name, 300, seed=0)
    errors, misses = [], 0
    for x, y in zip(xs, ys, strict=True):
        d = match_point(left, right, float(x), float(y), 32)
        if d is None:
            misses += 1
        else:
            errors.append(abs(d - gt[y, x]))
    med, none_frac = float(np.median(errors)), misses / xs.size
    print(
        f"{name}: median |error| {med:.3f} px, {none_frac:.1%} None, p90 {np.percentile(errors, 90):.3f} px"
    )
    assert med <= 0.25
    assert none_frac <= 0.2
    assert np.mean(np.array(errors) > 1.0) < 0.1  # gross mismatches are rare


def test_the_agreeing_windows_are_the_largest_group_with_no_window_over_1_px_away() -> None:
    import tracker.point_match as pm

    def group(ds: list[float], votes: int = 4) -> list[float] | None:
        z = np.zeros((3, 3), np.float32)
        found = [pm._Coarse(z, z, 0, 0.0, 0, 0, d, 0.01, 0.9 - 0.01 * i) for i, d in enumerate(ds)]
        g = pm._agreeing(found, votes, 0.5)
        return None if g is None else [c.d for c in g]

    assert group([5.0, 5.2, 4.9, 5.3, 5.1]) == [5.0, 5.2, 4.9, 5.3, 5.1]
    # most are within 0.5 px of 5.4 (four, itself included); 6.2 is outside that group but within 1 px
    assert group([5.0, 5.4, 5.8, 6.2, 5.2]) == [5.0, 5.4, 5.8, 5.2]
    # four agree, but one window 1.3 px away sees another surface: no answer
    assert group([5.0, 5.2, 4.9, 5.3, 6.5]) is None
    assert group([5.0, 5.2, 4.9]) is None  # fewer than `votes`
    assert group([5.0, 5.2, 4.9], votes=3) == [5.0, 5.2, 4.9]


def test_match_point_needs_the_centre_window_among_the_agreeing(monkeypatch: pytest.MonkeyPatch) -> None:
    import tracker.point_match as pm

    left, right = shifted_pair(6.3)
    d = match_point(left, right, 100.0, 40.0, 32)
    assert d is not None and abs(d - 6.3) < 0.03
    real = pm._coarse

    def no_centre(lf: np.ndarray, rt: np.ndarray, x: float, y: float, dmax: int, o: pm.WindowOptions):
        return None if (x, y) == (100.0, 40.0) else real(lf, rt, x, y, dmax, o)

    monkeypatch.setattr(pm, "_coarse", no_centre)
    assert match_point(left, right, 100.0, 40.0, 32) is None  # the eight shifted windows still agree


def test_match_point_lets_the_vote_settle_a_centre_peak_that_is_not_unique(monkeypatch: pytest.MonkeyPatch
                                                                           ) -> None:
    import tracker.point_match as pm

    left, right = shifted_pair(6.3)
    real = pm._coarse

    def centre_ambiguous(lf: np.ndarray, rt: np.ndarray, x: float, y: float, dmax: int, o: pm.WindowOptions):
        if (x, y) == (100.0, 40.0) and o.uniqueness > 0.0:
            return None  # as if a second peak came within `uniqueness` of the best
        return real(lf, rt, x, y, dmax, o)

    monkeypatch.setattr(pm, "_coarse", centre_ambiguous)
    d = match_point(left, right, 100.0, 40.0, 32)
    assert d is not None and abs(d - 6.3) < 0.03


def test_match_point_beside_a_depth_edge_answers_the_own_surface_or_nothing() -> None:
    """Background points just right of a textured disc (d 12.4 in front of d 4.0): windows over the
    edge take the disc's disparity; the answer, when given, is the background's."""
    left, right, disc = disc_scene(d_fg=12.4, d_bg=4.0)
    answered = 0
    for dx in (1, 2, 3, 5):
        for a in np.linspace(-0.9, 0.9, 15):  # along the disc's right-hand rim, angle a
            x, y = 120.0 + (25.0 + dx) * np.cos(a), 60.0 + (25.0 + dx) * np.sin(a)
            assert not disc[round(y), round(x)]
            d = match_point(left, right, float(x), float(y), 32)
            if d is not None:
                answered += 1
                assert abs(d - 4.0) < 0.5, f"({x:.1f}, {y:.1f}): {d:.2f}"
    assert answered >= 10
    with pytest.raises(ValueError, match="votes"):
        match_point(left, right, 30.0, 20.0, 16, votes=10)
