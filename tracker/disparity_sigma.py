"""How far off a target's disparity may lie beyond what the matcher's own 1-σ says (issue 12 item 1).

The region match (tracker.stereo.refine_strip) gives the disparity's 1-σ from its Gauss-Newton normal
matrix scaled by the residual variance: right for independent pixel noise. A target's residuals are not
independent: the two cameras sample its texture at different sub-pixel phases (a texture smooth over a
few pixels leaves residuals correlated over as many), and the interpolation of the right image errs by an
amount that depends on the texture and on the disparity's fraction. And the disparity may vary over the
region (a person board turned from the rig's axis: at 3 m and 20° off it, 3 px across its width), so that
the one disparity fitted, weighted by the texture's gradients, belongs to a point other than the centroid.
On the scenes of `tmeye eval` these made the disparity's error 1.3 (walk) to 20 (endless) times the
matcher's 1-σ (0.026 and 0.137 px rms against 0.008 and 0.006 px).

All of these show in how the disparities of parts of the region disagree: the region is cut into a grid of
`COLUMNS` x `ROWS` parts over the window the matcher uses, each part refined on its own, and the standard
error of their mean, s √Σ w_i² (s their sample standard deviation, w_i their weights: s / √n with n parts
alike), is the 1-σ of the region's disparity. For most regions that disparity is the one fit over the
window, about the parts' information-weighted mean (scatter_sigma); for a person's region it is the parts'
mean weighted by their pixel counts itself (surface_mean, on_surface: the mean of the surface seen, where
the one fit leans on the best-textured parts). The spread s also holds real differences of depth between the
parts (an arm before the torso), which are no error of their mean: where they are large the 1-σ is wider
than the mean's error, where a person stands still and its parts agree it may be narrower (endless:body's
standing walkers, 29 % within 1σ; docs/evaluation.md). The grid has 8 parts so that the σ estimate itself is
not too noisy (with 4 parts the normalised errors follow Student's t with 3 degrees of freedom, whose
variance is 3); even 8 tell it poorly, and a person's spread is pooled with a prior one its track has shown
(PartSpread, surface_mean). Where fewer than MIN_PARTS parts match (a far target, about 36 px wide at 20 to
30 m in approach), the scatter cannot be told; the matcher's own σ times FEW_PARTS_FACTOR, the median ratio
of the two where both are known (1.8 to 2.1 on every scene of `tmeye eval`), stands for it: approach's far
frames had a disparity error of 2.2 times the matcher's σ rms, and a range NEES of 4.6. Not so for a person
(an upright outline): where fewer than MIN_PARTS of its parts match, its disparity is the one fit over its
outline, whose error is set by which of its limbs, rims and gaps the fit leans on, not by the matcher's
noise: on such frames of endless:body (645, at 7 to 18 px) and walk:body (66, at 36 to 62 px) the
disparity's error against the seen surface was 8 times the matcher's σ (median). Its 1-σ is then at least
FEW_PARTS_PERSON_PX: fitted, by Student-t (ν = 4) likelihood, to the range errors (against the volume
centre, the rest of the range's 1-σ as it is) of those frames on six scenes (endless, walk, illumination,
foliage, two-targets, pan; each weighted alike), 0.12 px; within 1σ then 0.67-0.78 on all but two-targets
(29 frames, 0.48). A fixed share of the disparity fits the seen surface alike (1.3 % at 8 to 60 px) but not
the range: a near walker's face error is mostly the depth its limbs swing through, which the body's own
prior (SolidPrior) covers, so 1.3 % put 89-98 % of those frames within 1σ.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import replace

import numpy as np
from numpy.typing import NDArray

from tracker.results import Blob, PartFit
from tracker.stereo import catmull_rom, refine_gram, residual_outliers
from tracker.strips import whole_outline

U8 = NDArray[np.uint8]
COLUMNS, ROWS = 4, 2
MIN_PARTS = 5
FEW_PARTS_FACTOR = 2.0
FEW_PARTS_PERSON_PX = 0.12
# a person's parts' spread is pooled with a prior spread worth PRIOR_DOF parts: SPREAD_SHARE of its track's
# mean spread (PartSpread, an exponential mean at SPREAD_RATE a frame), PRIOR_SHARE · d̄ before it has one
# (surface_mean; fitted 2026-12-06 by Gaussian likelihood on six scenes' range errors with seeds 0-2,
# docs/evaluation.md)
PRIOR_SHARE = 0.0085
PRIOR_DOF = 12.0
SPREAD_SHARE = 0.55
SPREAD_RATE = 1.0 / 120.0


def first_prior(d: float) -> tuple[float, float]:
    """(s0, ν0): the prior spread (px) of a person's parts at disparity d (px) before its track has shown
    its own (PartSpread.prior), PRIOR_SHARE · d worth PRIOR_DOF parts."""
    return PRIOR_SHARE * abs(d), PRIOR_DOF


def scatter_sigma(disparities: list[float], sigmas: list[float] | None = None,
                  prior: tuple[float, float] | None = None) -> float:
    """The standard error of the parts' mean disparity (px): s √Σ w_i², s their sample standard deviation,
    w_i their weights in the whole region's fit, which is about the information-weighted mean of its parts
    (w_i ∝ 1 / σ_i², σ_i each part's own fit's 1-σ, `sigmas`; s / √n with equal weights, or without
    `sigmas`). A walker's parts differ in depth (limbs, head, torso), so that where their texture is
    uneven the whole's fit is pulled towards the best textured: on walk:body at 9 to 17 m the disparity's
    error against its seen surface's was 0.12 px rms, s / √n a median 0.08 px, s √Σ w² 0.10 to 0.11 px;
    on walk:plate 0.026 px, against 0.012-0.024 and 0.013-0.028. 0 with fewer than MIN_PARTS (too few to
    tell: the matcher's own σ then stands). prior: (s0, ν0), a prior spread s0 (px) worth ν0 parts, pooled
    with the parts' own: s² = (ν0 s0² + (n - 1) s_parts²) / (ν0 + n - 1) (the posterior mean of a scaled
    inverse-χ² prior on the spread's variance); None: the parts' own."""
    n = len(disparities)
    if n < MIN_PARTS:
        return 0.0
    w = np.ones(n) if sigmas is None else 1.0 / np.maximum(np.asarray(sigmas, np.float64), 1e-6) ** 2
    w /= w.sum()
    var = float(np.var(disparities, ddof=1))
    if prior is not None:
        s0, nu0 = prior
        var = (nu0 * s0 * s0 + (n - 1) * var) / (nu0 + n - 1)
    return float(np.sqrt(var * np.sum(w * w)))


def parts_sigma(disparities: list[float], matcher_sigma: float, sigmas: list[float] | None = None) -> float:
    """The disparity's 1-σ from its parts (px): their scatter (scatter_sigma, with the parts' own 1-σ
    `sigmas`), or with fewer than MIN_PARTS matched FEW_PARTS_FACTOR times the matcher's own σ
    (matcher_sigma, px)."""
    if len(disparities) < MIN_PARTS:
        return FEW_PARTS_FACTOR * matcher_sigma
    return scatter_sigma(disparities, sigmas)


def surface_mean(fits: list[PartFit], prior: tuple[float, float] | None = None) -> tuple[float, float] | None:
    """The disparity of a region's seen surface's mean point (px) from its parts (part_fits over the whole
    outline): their mean weighted by their pixel counts n_i, d̄ = Σ n_i d_i / Σ n_i, and its 1-σ (px), the
    standard error s √Σ w_i² with w_i = n_i / Σ n_i (scatter_sigma). None with fewer than MIN_PARTS parts.
    The spread s is the parts' own pooled with a prior one, `prior` = (s0 px, ν0 parts; scatter_sigma;
    None: first_prior(d̄), the prior of a track not yet seen): 5 to 8
    parts tell their spread poorly (their sample deviation is off by a quarter or more), and a frame whose
    parts happen to agree got a 1-σ far under its error.

    The one disparity fitted over the whole region weights each pixel by its texture's gradient, so that
    where a walker's parts (head, torso, arms, legs) lie at depths a few centimetres apart it belongs to its
    best-textured parts, not to the mean of the surface seen (what eq. (2) places and the truth of `tmeye
    eval` measures). On walk:body at 10-30 px the whole fit's error against the seen surface was 0.122 px
    rms, d̄'s 0.090; on endless:body 0.182 and 0.115 px (2026-12-02, the parts over the whole outline)."""
    if len(fits) < MIN_PARTS:
        return None
    d = np.array([f.d for f in fits])
    n = np.array([f.pixels for f in fits], np.float64)
    mean = float(d @ n / n.sum())
    return mean, scatter_sigma(d.tolist(), (1.0 / np.sqrt(n)).tolist(), first_prior(mean) if prior is None else prior)


class PartSpread:
    """Each track's parts' spread, from which a person's disparity 1-σ takes its prior (surface_mean).

    A person's parts spread by their depths and by how each is matched, and that spread grows with d (its
    median s / d̄ 1.0-1.3 % from 5 to 70 px over six scenes of `tmeye eval`; a power law fitted d^1.02). A
    track's mean relative spread m, an exponential mean over its frames at SPREAD_RATE a frame (about 4 s
    at 30 frames a second; PRIOR_SHARE / SPREAD_SHARE before its first), gives each frame's prior: s0 =
    SPREAD_SHARE · m · d̄ worth PRIOR_DOF parts. Only a share of the spread counts: real differences of
    depth between the parts are no error of their mean. A flat board tall as a person has parts that agree
    frame after frame, and its 1-σ narrows with them. Fitted (rate, share, parts) on the range errors of
    walk, illumination, foliage, two-targets, pan and endless (bodies, seeds 0, 1 and 2, each run weighted
    alike) by Gaussian likelihood; with the parts' spread alone the range's 1-σ was too wide for most frames
    and too narrow for a few (within 1σ 0.76, NEES 0.87 on walk; 0.81, 0.87 on pan; seed 0), and one prior
    share for every track (0.85 % of d̄) took endless:plate's boards from 0.65 to 0.81 within 1σ
    (docs/evaluation.md, 2026-12-06)."""

    def __init__(self) -> None:
        self._mean: dict[int, float] = {}  # track id -> m, s / d̄

    def add(self, track_id: int, fits: tuple[PartFit, ...], d: float) -> None:
        """A frame's parts (those a person's blob keeps, Blob.parts) at its disparity d (px)."""
        if len(fits) < MIN_PARTS or d <= 0:
            return
        s = float(np.std([f.d for f in fits], ddof=1)) / d
        m = self._mean.get(track_id, PRIOR_SHARE / SPREAD_SHARE)  # its first frame's prior: first_prior's
        self._mean[track_id] = m + SPREAD_RATE * (s - m)

    def prior(self, track_id: int | None, d: float) -> tuple[float, float]:
        """(s0, ν0): the prior spread (px) at disparity d (px) and its weight in parts (surface_mean);
        first_prior for a track not yet seen (or none)."""
        m = None if track_id is None else self._mean.get(track_id)
        return first_prior(d) if m is None else (SPREAD_SHARE * m * abs(d), PRIOR_DOF)

    def keep_only(self, track_ids: list[int]) -> None:
        """Forget the tracks not in track_ids (ended)."""
        live = set(track_ids)
        self._mean = {i: m for i, m in self._mean.items() if i in live}


def on_surface(blob: Blob, fits: Callable[[], list[PartFit]]) -> Blob:
    """A person's blob (its outline upright, tracker.strips.whole_outline; seen by both cameras) with the
    parts of its whole outline (fits(): part_fits) kept on it (Blob.parts) and its disparity at their
    surface_mean (as it was with fewer than MIN_PARTS parts); any other blob as it is."""
    if blob.one_camera or not whole_outline(blob.mask):
        return blob
    parts = fits()
    mean = surface_mean(parts)
    if mean is None:
        return replace(blob, parts=tuple(parts))
    return replace(blob, disparity=mean[0], parts=tuple(parts))


def blob_sigma(blob: Blob, fits: Callable[[], list[PartFit]], prior: tuple[float, float] | None = None) -> float:
    """The disparity's 1-σ (px) from a blob's parts (where larger than the matcher's own, tracker.pipeline):
    a person's, from the parts it keeps (Blob.parts, on_surface): their surface_mean's, or with fewer than
    MIN_PARTS parts_sigma's stand-in and at least FEW_PARTS_PERSON_PX; any other's, parts_sigma of fits()
    (the parts of the window it was matched on). A blob seen by one camera has its held disparity's 1-σ
    (tracker.one_camera). prior: a person's parts' prior spread (surface_mean; PartSpread.prior)."""
    if blob.one_camera:
        return blob.disparity_sigma
    if blob.parts:
        mean = surface_mean(list(blob.parts), prior)
        if mean is not None:
            return mean[1]
    person = whole_outline(blob.mask)  # its parts are those on_surface kept, none matched again
    parts = list(blob.parts) if blob.parts or person else fits()
    sigma = parts_sigma([f.d for f in parts], blob.disparity_sigma, [f.sigma for f in parts])
    if person and len(parts) < MIN_PARTS:  # a person whose parts cannot be told
        return max(sigma, FEW_PARTS_PERSON_PX)
    return sigma


def part_fits(left: U8, right: U8, core: NDArray[np.generic], off: int, d: float,
              min_score: float, robust: bool = False) -> list[PartFit]:
    """The disparities (px), their own fits' 1-σ (px) and pixel counts of the COLUMNS x ROWS parts of a
    matched region, refined as tracker.stereo.refine_region refines each part alone from d, from one pass
    over the pixels.

    left, right: rectified strips (h, m) over the region's rows; core: the region's weights (h, n), nonzero
    where it is matched, its column j at strip column off + j; d: the whole region's disparity. The window
    is cut into a grid; for each part, the Gram matrix of its pixels over the right strip's band windows
    about x = off + j - d and the template (what refine_strip builds) is summed from per-pixel products of
    all parts at once, then refine_strip's Gauss-Newton iteration runs on it (tracker.stereo.refine_gram:
    T ~ alpha R(x) + beta, Catmull-Rom along the row). A part is left out with fewer than 8 pixels, a
    degenerate fit, an answer over 1 px from d, or a score (weighted correlation) below min_score.

    robust: the pixels the model does not fit at d, over the whole window (tracker.stereo.residual_outliers),
    are left out of every part, as the region's robust fit leaves them out of its own (tracker.stereo.
    outliers), so that the parts' scatter measures that fit's error. Not for a person's whole outline
    (RegionMatcher.part_fits): its parts are the seen surface's own, limbs at their own depths included, and
    their mean is its disparity (surface_mean); left out there, the walkers' range RMSE went 0.072 -> 0.083 m
    on walk:body (`tmeye eval --all`, 2026-12-03)."""
    h, n = core.shape
    p0 = off - d  # the strip column that template column 0 samples
    k = math.floor(p0)
    if h == 0 or n == 0 or k - 2 < 0 or k + 3 + n > right.shape[1]:
        return []
    rows, cols = np.nonzero(np.asarray(core) != 0)
    lab = (rows * ROWS // h) * COLUMNS + cols * COLUMNS // n
    order = np.argsort(lab, kind="stable")
    rows, cols, lab = rows[order], cols[order], lab[order]
    A = np.empty((lab.size, 7))
    for j in range(6):  # band window j: strip columns k - 2 + j + column
        A[:, j] = right[rows, k - 2 + j + cols]
    A[:, 6] = left[rows, off + cols]
    drop = None if not robust else residual_outliers(A[:, 6], A[:, 1:5] @ np.array(catmull_rom(p0 - k)[0]),
                                                     np.ones(lab.size))
    if drop is not None:  # the pixels the model does not fit at d (tracker.stereo.outliers)
        A, lab = A[~drop], lab[~drop]
    _, starts, counts = np.unique(lab, return_index=True, return_counts=True)
    out: list[PartFit] = []
    for a, m in zip(starts, counts, strict=True):
        if m < 8:
            continue
        P = A[a:a + m]
        s1 = P.sum(axis=0)
        fit = refine_gram((P.T @ P - np.outer(s1, s1) / m).tolist(), float(m), p0, k)
        if fit is not None and abs(fit.d + p0) <= 1.0 and fit.score >= min_score:
            out.append(PartFit(off + fit.d, fit.sigma, int(m)))
    return out
