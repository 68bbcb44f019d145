"""How well each side of a solid body's outline is placed: the contrast of its rim (issue 12 item 1).

A solid body's outline is drawn where eq. (9) and the temporal model find it differs from the
background. Where its rim stands out strongly (a lit ball against a dark hedge), the threshold places each
side on the right pixel: on approach:body, a sphere at 30 to 12 m, eq. (10)'s centroid lay within 0.02 px
rms of the true silhouette's in the 153 frames where under a tenth of its rim was faint. Where the rim
fades into the background (shaded, curving away, a texture like the background's), pixels along it fall
either side of the threshold with the noise and the light, and the side lies a fraction of a pixel off:
0.24 px median |error| along x where that share was 0.1 to 0.3 on the same sphere, and on the walkers
errors grow with the share (walk:body: 0.11 px median |x error| at a faint share of 0.2-0.3, 0.19 at
0.3-0.4, 0.30 at 0.4-0.5, 0.9 above).

A rim pixel counts as faint where |Γ - g B| (the temporal model's residual, Γ the left image, B the
background at gain g) is under `faint_level` (2 ε: twice the threshold of eq. 9). Each side's 1-σ is
`side_px` times its rim's faint share f: the centroid's error grows about linearly with the faint share,
and a side whose whole rim is faint may lose a band of a pixel or two (tracker.rim recovers part of
it). The two sides along an axis move independently, each moving the centroid by half its shift, so the
centroid's 1-σ along x is √(σ_left² + σ_right²) / 2 (and along y with top and bottom). side_px = 1.7 px
from the frames seen whole (98 % or more) of the six still `NAME:body` scenarios: the rms |x error| of the
centroid against the true silhouette's was 0.02-0.21 px where the left and right sides' shares summed
to under 0.2, 0.18-0.26 px at 0.2-0.4, 0.29-0.36 at 0.4-0.6, 0.35-0.53 at 0.6-0.8 (about 0.6 px times
the sum: 1.7 / (2 √2) with the sum split evenly), and 0.57-1.18 above (the walkers' heavy tail, whose x
has a prior of its own: tracker.solid_prior.SolidPrior.upright_x_var). The fixed term it replaces, 0.5 /
√2 = 0.35 px, is this at a summed share of 0.6.

On approach:body the sphere's azimuth and elevation NEES went 0.68 -> 0.91 and 0.17 -> 0.80 (within 1σ
0.74 -> 0.70 and 0.95 -> 0.78); the other still scenes' figures moved by under 0.01 but for elevation
NEES (walk 1.39 -> 1.35, illumination 1.45 -> 1.39, endless 2.00 -> 1.77).

The loss has a sign: a faint side loses pixels, it never gains them, so eq. (10)'s centroid lies off the
true silhouette's towards the brighter side. On the eight still or tracked `NAME:body` scenarios (not
pan, which has no rim contrast) the centroid's x error against the true silhouette's correlated with
f_right - f_left (-0.25 on endless, -0.55 on walk, -0.70 on approach), the more for larger bodies: a
least-squares fit of e = -k (f_far - f_near) √(w h) (w, h the outline's extent, px) gave k = 0.0053
along x and 0.0085 along y, the shifts `rim_shift_px` undoes (`band` twice those: the band a wholly
faint side loses, 1.06 % and 1.7 % of √(w h)). rms x error walk 0.548 -> 0.342 px, illumination 0.515
-> 0.308, foliage 0.577 -> 0.391, two-targets 0.331 -> 0.242, approach 0.189 -> 0.153, endless 0.270 ->
0.249, occlusion's car 1.009 -> 1.010 (a vehicle's flat faces lose no such band: not undone for a wide
body); along y approach 0.466 -> 0.189 px and manoeuvre 0.344 -> 0.141 (the balls), the walkers' 1.03-
1.47 px by -4 to +4 % (a person's top and bottom are its head and feet: not undone for an upright
body). Where it is undone, a side's 1-σ is `corrected_side_px` (0.7 px along x since 2026-12-06, below; 0.9
along y; side_px elsewhere): the spread left, set by `tmeye eval --all` (along y 1.0 put manoeuvre:body's
range within 1σ past its band, 1.2 its elevation NEES; 1.7 left manoeuvre's elevation 1-σ about 1.6 times too wide,
NEES 0.40). `tmeye eval --all`: azimuth RMSE against the seen surface walk:body
0.073 -> 0.061°, illumination 0.076 -> 0.063°, foliage 0.077 -> 0.066°, two-targets 0.033 -> 0.022°,
approach 0.023 -> 0.025°; elevation approach 0.106 -> 0.065°, occlusion 0.052 -> 0.048°; against the
volume centre approach's azimuth 0.035 -> 0.027° and elevation 0.051 -> 0.032°; the walkers'
x prior refitted (tracker.solid_prior.SolidPrior.upright_swing_sigma); 117 lines met against 118:
endless:body's elevation NEES 1.44 -> 1.58, three frames of heads over a hedge already 12.5 to 20 σ off
(a bottom the hedge hides, not found as cut) whose y 1-σ narrowed.
Since the rim's recovery lets the learnt background decide where the stereo pictures cannot (tracker.rim,
2026-12-04), a still camera's outline keeps more of a faint side: refitted on approach:body (74 wide
frames, the one still ball tracked), k along y fell 0.0085 -> 0.0062, so `band_still_y` (the cameras still,
the shares from the learnt background) is 1.24 % along y, `band` (moving, the stereo residual's shares) as
before; along x the same fit gave 0.0026 -> 0.0032, left at the eight scenes' 1.06 %. approach:body's
elevation RMSE against the seen surface 0.0210 -> 0.0135° (0.0150° before the recovery's change).

A ball's faint side along x, the cameras still (2026-12-04): on approach:body's 300 frames (the sphere at
30 to 0.9 m, 11 to 152 px across) the x error of eq. (10)'s centroid against the true silhouette's,
fitted as ½ c (f_right - f_left), left 0.102 px rms with a fixed band c = 0.78 px, 0.143 px with a share
of the size (1.09 %, fitted on the same frames), 0.180 px undone by neither. Fitted alone by the ball's
disparity over its background's, c was 0.40 px at 5-10 px, 1.0 at 10-20, 0.87 at 20-40 and 0.23 at 40-80
(the nearest frames, 83-152 px across, where 1.06 % of the size says 0.9-1.6 px): the outer pixel or so
of a faint limb that the rim's recovery leaves out (tracker.rim), not a share of the ball, so
`band_still_px` (then for balls alone). Along y the share fits better (0.078 against 0.106 px rms: the
shaded bottom of the ball lit from above, wide only when near), and so it does along x on the walkers (walk:body 0.328
against 0.404 px rms), whose faint side loses a share of a limb. A larger share for them (1.49 %, fitted
on walk, illumination, foliage, two-targets and endless alike) moved their centroids nearer their
silhouettes' (walk:body's azimuth RMSE against the silhouette's ray 0.0436 -> 0.0398°) but their angles
away from the seen surface's (0.0544 -> 0.0575°) and the volume centre's: left at 1.06 %. `tmeye eval
--all`: approach:body's azimuth RMSE against the seen surface 0.0227 -> 0.0167° over its 74 wide frames
(within 1σ 0.750 -> 0.743, NEES 0.895 -> 0.884), against the volume centre 0.0442 -> 0.0491°: at 2-5 m
(32 frames) the ray moved by about -0.007° against both, the surface's mean error +0.022 -> +0.015°,
the centre's -0.058 -> -0.065° (a bias that is not the ray's); beyond 5 m the centre's RMSE went 0.0173
-> 0.0134°. Every other figure within 0.001 of its own but two-targets:body's azimuth NEES 0.340 ->
0.342 and endless:body's 1.313 -> 1.306.

A person's faint side along x, the cameras still (2026-12-06): the walkers lose the same fixed band. Over
1,053 frames of walk, illumination, foliage, two-targets and endless (bodies wider than 40 px), the
azimuth error against the seen surface's mean with nothing undone, fitted as ½ c (f_right - f_left) with c
a share of the size √(w h), gave 0.65 % overall and 0.55 to 1.05 % scene by scene (the near walkers of
walk, 120 px median size, the least; two-targets' far one, 73 px, the most); with c a fixed width, 0.89 px
overall and 0.71 to 1.06 px scene by scene, and a lower rms on each scene (all 0.0338° against 0.0340° at
the best share). The ball's 0.78 px left the walkers' rms the same to three figures (0.0338°), so one
fixed band, `band_still_px`, serves every body that is not wide. `tmeye eval --all`: azimuth RMSE against
the seen surface walk:body 0.0461 -> 0.0419°, illumination 0.0423 -> 0.0386°, foliage 0.0418 -> 0.0397°,
two-targets 0.0107 -> 0.0104°, endless 0.0308° either way; against the volume centre walk 0.092 -> 0.080°,
illumination 0.086 -> 0.073°, foliage 0.086 -> 0.075°; with `--seed 1` against the seen surface walk 0.0426
-> 0.0359°, illumination 0.0440 -> 0.0376°, foliage 0.0385 -> 0.0354°. The walkers' x prior was refitted
beside it (tracker.solid_prior.SolidPrior.upright_x_sigma).

A person's faint bottom, the cameras still (2026-12-06): a walker's lower legs, shaded where they face
away from the sun, pass both eq. (9) and the temporal model as the ground they stand on in patches (walk:body
frame 289: 702 of the body's 20,987 pixels missed, nearly all on its far shin; the centroid 3 px high), so
its bottom's faint share says how much of its legs is lost, and the centroid lies above the silhouette's.
Over the same 1,053 frames, the elevation error against the seen surface's mean, fitted as ½ c (f_bottom -
f_top) with c a share of the size, gave c 4.0-4.1 % on walk, illumination and two-targets, 3.2 % on
foliage, 12.8 % on endless (its far walkers' legs hidden and cut besides), 4.2 % with each scene weighted
alike; as a fixed width (5.8 px overall, 3.1 to 9.7 px scene by scene) or a share of the height it fitted
worse. `person_band_still_y` 4 %. `tmeye eval --all`: elevation RMSE against the seen surface walk:body
0.100 -> 0.078°, illumination 0.093 -> 0.069°, foliage 0.095 -> 0.082°, two-targets 0.067 -> 0.062°,
endless 0.142 -> 0.130°; against the volume centre about 1 % more, the volume centre's shift above the
centroid refitted beside it (tracker.solid_prior.SolidPrior.upright_shift_front). The 1-σ along y is left
as it was (a person's y is dominated by its limbs' shape, SolidPrior.upright_sigma, 2.8 % of its height).

A side's 1-σ along x for a body not wide (2026-12-06): 1.4 px was set while the
band was a share of the size (1.06 %, 1.3 px on a walker of 120 px); a fixed band of 0.78 px leaves less
spread, and only bodies neither upright nor wide take it along x (a person's x is its SolidPrior term, a
vehicle's sides are not undone). On approach:body's ball, seeds 0, 1 and 2, the azimuth's 1-σ with 1.4 px
was 0.4-0.6 px where a side was faint against errors of 0.1-0.15 px (within 1σ 0.750, 0.903, 0.907; NEES
0.927, 0.306, 0.462). Replayed from the frames' 1-σ terms, 0.70 px put five of the six lines in their bands
(0.663 / 1.227, 0.813 / 0.704, 0.667 / 1.059; Gaussian maximum likelihood, seeds weighted alike, 0.52 px,
which left seed 2's within 1σ at 0.467). `tmeye eval --all`: seed 0 117 met either way (approach 0.750 /
0.927 -> 0.673 / 1.191), seed 1 101 either way (approach 0.903 / 0.306 -> 0.813 / 0.662), seed 2 100 -> 102
(approach 0.907 / 0.462 -> 0.680 / 1.010). While the cameras move nothing is undone along x (band's x share
0), and a ball's side there had side_px, 1.7 px: on manoeuvre:body (the sphere tracked while the mount
turns) the azimuth within 1σ / NEES were 0.718 / 1.056, 0.908 / 0.369 and 0.888 / 0.425 (seeds 0, 1, 2);
the same maximum likelihood over its frames gave 0.71 px, so a body not wide takes corrected_side_px along
x moving or still. `tmeye eval --all` (both changes): seed 0 117 met either way (manoeuvre 0.639 / 1.474),
seed 1 101 -> 104 (manoeuvre's azimuth 0.735 / 0.953 and elevation within 1σ 0.588 -> 0.643, the servo's
path changing with its measurements' 1-σ), seed 2 100 -> 104 (manoeuvre 0.735 / 0.955).

With the cameras moving there is no temporal model; a rim pixel's residual against its background then
comes from the stereo pair (`stereo_residual`: eq. (9)'s left key where its test can be made, else the
right key's), the same faint_level and side_px (along x, for a body not wide, corrected_side_px since
2026-12-06, above). On manoeuvre:body (a sphere tracked while the mount turns)
its sides' faint shares were 0.07 (left), 0.15 (right), 0.01 (top), 0.49 (bottom, shaded), the two keys
alike at the bottom (0.50 on the pixels the left key tested, 0.48 on the right key's): azimuth within 1σ
0.94 -> 0.67, NEES 0.30 -> 1.17 against the fixed term's 0.35 px; elevation 0.66 -> 0.86 and 0.95 ->
0.75 (its bottom's share says 0.42 px where the centroid was off by 0.35 px rms along y; side_px is the
still scenes'). An upright body keeps the fixed term while the cameras move (tracker.solid_prior.SolidPrior:
its x term counts the rim then, the outline being warped).

Refitted on manoeuvre:body (2026-12-04, its 294 frames of a sphere 31-39 px across tracked while the mount
turns; the only body whose band the cameras' moving decides: a person keeps the fixed term then, above),
with the rim's recovery as it now is: along y the share of its size that undoes its shaded bottom's band
is 3.3 % (k = 0.033; the y error against the true silhouette 0.355 px rms undone by neither, 0.212 with
the 1.7 % it had, 0.141 with 3.3 %), along x none (the fit gave -0.023, 0.208 -> 0.194 px rms: no loss
to undo; 1.06 % made it 0.223). The y spread left, `corrected_side_moving_y_px` 0.5 px a side (a Gaussian
fit of the centroid's y errors alone gave 0.4, its normalised errors' mean square 0.99; 0.5 gave the
elevation NEES 1.20 in `tmeye eval`, 0.65 left its within 1σ at 0.80). `tmeye eval --all`: manoeuvre:body
elevation RMSE 0.0202 -> 0.0141°, azimuth 0.0199 -> 0.0201°; elevation within 1σ 0.803 -> 0.660 and NEES
0.864 -> 1.198, azimuth 0.653 -> 0.735 and 1.159 -> 1.118, range 0.782 -> 0.759 and 0.645 -> 0.656
(within chance of its band before and after); centring 1.31 -> 1.40 % rms, aim zone 100 % either way.
Every other scenario's figures unchanged (no other body's band is decided with the cameras moving).

A still ball's faint rows beyond its outline (2026-12-06): how much of a faint bottom is lost differs from
scene to scene at the same faint share (approach:body under 15 px: the centroid 0.57 px above the true
silhouette's on seed 1, 0.06 px on seed 2, bottom shares 0.90 and 0.77), since the share is counted on the
outline's own rim. In the 1-px ring below the outline the ball's missed pixels differ from the learnt
background by 7 grey levels (median; quartiles 3.9 and 10), the background's own by 1.0 (90th percentile
2). So along y a still round body's centroid takes, where it moves further than the band's, the shift of
its outline grown by up to two rings of pixels changed by 4 grey levels or 3 g D and under ε
(`grown_shift_y`; tried offline over 1-3 rings at 3-5 levels on seeds 0-2: it serves the small balls, the
band the near ones, which lose more than two rows). The y error against the true silhouette after the
shift, rms over the 300 frames: 0.077 / 0.300 / 0.116 px -> 0.077 / 0.173 / 0.111 (seeds 0 / 1 / 2). The
side's 1-σ left, corrected_side_px along y, refitted by Gaussian likelihood over the three seeds' 900
frames from two runs (the term at 0 and at 0.9): 0.42 px (0.9 before). `tmeye eval --all`: approach:body
elevation RMSE 0.0082 / 0.0285 / 0.0116 -> 0.0080 / 0.0169 / 0.0113°; its within 1σ / NEES 0.667 / 1.38,
0.727 / 0.91, 0.950 / 0.23 -> 0.653 / 1.41, 0.597 / 1.37, 0.803 / 0.59 (seed 1's within 1σ out of its
band, within chance).
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

from tracker.bgdepth import CorrespondenceMap
from tracker.rectify import Rectifier
from tracker.visibility import sides

BoolA = NDArray[np.bool_]
_RIM = np.ones((3, 3), np.uint8)  # a pixel with a neighbour outside the mask is on its rim


@dataclass(frozen=True)
class RimContrastConfig:
    """faint_level: a rim pixel is faint where its residual |Γ - g B| is under this (grey levels); side_px: a
    side's 1-σ (px) where all of its rim is faint and its expected loss is not undone (a vehicle's faces, a
    person's top and bottom); band: the band a wholly faint curved side loses, as a share of the body's size
    √(w h) (px), along x and y (`rim_shift_px`), with the cameras moving (the stereo residual's shares:
    none along x), band_still_y with them still, along y (the learnt background recovers more of it);
    band_still_px: with the cameras still, the band (px) a wholly faint side of a body not wide (a ball,
    a person) loses along x, a fixed width whatever its size; person_band_still_y: with them still, the
    band a person's wholly faint bottom loses (its lower legs over the ground), a share of its size;
    corrected_side_px: a side's 1-σ (px, x and y) left where that loss is undone (see the module's
    docstring), along x for a body not wide whether the cameras move or not (moving, nothing is undone along
    x, band's x share being 0, yet the spread is the same), corrected_side_moving_y_px along y while the
    cameras move. grow_rings, grow_level, grow_deviations: a still round body's faint rows beyond its
    outline (`grown_shift_y`): up to this many rings of pixels changed from the learnt background by at
    least max(grow_level, grow_deviations · g D) grey levels and under ε."""

    faint_level: float = 24.0
    side_px: float = 1.7
    band: tuple[float, float] = (0.0, 0.033)
    band_still_y: float = 0.0124
    band_still_px: float = 0.78
    person_band_still_y: float = 0.04
    corrected_side_px: tuple[float, float] = (0.7, 0.42)
    corrected_side_moving_y_px: float = 0.5
    grow_rings: int = 2
    grow_level: float = 4.0
    grow_deviations: float = 3.0


def faint_shares(mask: BoolA, box: tuple[int, int, int, int], image: NDArray[np.uint8],
                 background: NDArray[np.float32], gain: float, cfg: RimContrastConfig
                 ) -> tuple[float, float, float, float]:
    """The share of each side's rim (left, right, top, bottom) that is faint: the mask's own 1-px rim (its
    pixels with a 3x3 neighbour outside it), split into sides about its centroid (tracker.visibility.sides).
    mask: (h, w) over box (x0, y0, x1, y1) of the left image `image` (H, W); background: the temporal model
    B (H, W) at gain 1. A side with no rim pixels has share 0."""
    x0, y0, x1, y1 = box
    residual = np.abs(image[y0:y1, x0:x1].astype(np.float32) - np.float32(gain) * background[y0:y1, x0:x1])
    return faint_shares_of(mask, residual, np.ones_like(mask), cfg)


def grown_shift_y(mask: BoolA, box: tuple[int, int, int, int], image: NDArray[np.uint8],
                  model: tuple[NDArray[np.float32], NDArray[np.float32]], gain: float, epsilon: float,
                  cfg: RimContrastConfig) -> float:
    """How far (px, y) the centroid of a round body's outline moves when the outline is grown by up to
    cfg.grow_rings rings of pixels that changed from the learnt background (B, D = model, (H, W) each; gain g)
    by at least max(grow_level, grow_deviations · g D) grey levels and less than eq. (9)'s ε (`epsilon`):
    the body's faint rows beyond its outline, which the rim's faint share does not count (its loss measured
    rather than expected; see the module's docstring). mask: (h, w) over box (x0, y0, x1, y1) of `image`."""
    x0, y0, x1, y1 = box
    h_img, w_img = image.shape[:2]
    p = cfg.grow_rings
    X0, Y0, X1, Y1 = max(x0 - p, 0), max(y0 - p, 0), min(x1 + p, w_img), min(y1 + p, h_img)
    grown = np.zeros((Y1 - Y0, X1 - X0), np.uint8)
    grown[y0 - Y0:y1 - Y0, x0 - X0:x1 - X0] = mask
    ys0 = np.nonzero(grown)[0]
    if ys0.size == 0:
        return 0.0
    bg, dev = model[0][Y0:Y1, X0:X1], model[1][Y0:Y1, X0:X1]
    res = np.abs(image[Y0:Y1, X0:X1].astype(np.float32) - np.float32(gain) * bg)
    changed = (res >= np.maximum(np.float32(cfg.grow_level), np.float32(cfg.grow_deviations * gain) * dev)) \
        & (res < np.float32(epsilon))
    for _ in range(p):
        ring = (cv2.dilate(grown, _RIM) > 0) & (grown == 0) & changed
        if not ring.any():
            break
        grown[ring] = 1
    return float(np.nonzero(grown)[0].mean() - ys0.mean())


def faint_shares_of(mask: BoolA, residual: NDArray[np.float32], tested: BoolA, cfg: RimContrastConfig
                    ) -> tuple[float, float, float, float]:
    """faint_shares from a residual against the background (h, w) over the mask's box, counted over the rim
    pixels where it could be `tested` (h, w) only; a side with none of those has share 0."""
    m8 = mask.view(np.uint8)
    rim = mask & (cv2.erode(m8, _RIM, borderType=cv2.BORDER_CONSTANT, borderValue=0) == 0)
    mom = cv2.moments(m8, binaryImage=True)
    if mom["m00"] == 0:
        return 0.0, 0.0, 0.0, 0.0
    _, _, bw, bh = cv2.boundingRect(m8)
    centre, half = (mom["m10"] / mom["m00"], mom["m01"] / mom["m00"]), (max(bw / 2.0, 1.0), max(bh / 2.0, 1.0))
    faint = residual < cfg.faint_level
    return tuple(float(np.count_nonzero(faint[ys, xs])) / xs.size if xs.size else 0.0  # type: ignore[return-value]
                 for ys, xs in sides(rim & tested, centre, half))


def stereo_residual(left: NDArray[np.uint8], right: NDArray[np.uint8], box: tuple[int, int, int, int],
                    mask: BoolA, d: float, cm: CorrespondenceMap, rect: Rectifier
                    ) -> tuple[NDArray[np.float32], BoolA]:
    """While the cameras move (no temporal model): each pixel's residual against its background from the
    stereo pair (h, w over the raw-left box of `mask`), and where one could be worked out. With the left
    image as key, eq. (9)'s |Γ - Θ(d_bg)|; that test lands on the object itself where the pixel Δd =
    d - d_bg px to the right along the rectified row is the object's (the right camera sees the object
    where this pixel's background would be), so there, with the right image as key, |Θ(d) - Γ(x - Δd)|:
    the object as the right camera sees it against the left image where that background is seen, unless
    the pixel Δd to the left is the object's as well (tracker.rim, recover_rim_keys), or either picture
    lies outside its image. Where the background lies within a pixel of the object's disparity (the
    ground at a walker's feet) the two cannot be told apart: residual 0, faint. Where it lies a pixel or
    more before the object (a background map out of date) neither test is made. d: the object's disparity
    (px); cm: the background's correspondences over the box."""
    x0, y0, x1, y1 = box
    shift = np.float32(d) - cm.disparity
    near = cm.valid & (np.abs(shift) < 1.0)
    behind = cm.valid & (shift >= 1.0)
    res_l = np.abs(left[y0:y1, x0:x1].astype(np.float32) - cm.warp(right).astype(np.float32))
    bx, by = rect.left_along(box, -shift)
    ur, vr = rect.right_at(box, d)
    seen_bg = cv2.remap(left, bx, by, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
    seen_obj = cv2.remap(right, ur, vr, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
    res_r = np.abs(seen_obj.astype(np.float32) - seen_bg.astype(np.float32))
    ok_l = behind & ~_on_object(mask, box, *rect.left_along(box, shift))
    ok_r = behind & ~ok_l & ~_on_object(mask, box, bx, by) & _inside(bx, by, left) & _inside(ur, vr, right)
    residual = np.where(ok_l, res_l, np.where(ok_r, res_r, np.float32(0.0))).astype(np.float32)
    return residual, np.asarray(ok_l | ok_r | near)


def _inside(x: NDArray[np.float32], y: NDArray[np.float32], image: NDArray[np.uint8]) -> BoolA:
    """Whether positions x, y (h, w) lie within the image (bilinear samples of its own pixels)."""
    h, w = image.shape[:2]
    return np.asarray((x >= 0) & (x <= w - 1) & (y >= 0) & (y <= h - 1))


def _on_object(mask: BoolA, box: tuple[int, int, int, int], x: NDArray[np.float32], y: NDArray[np.float32]
               ) -> BoolA:
    """Whether the raw-left positions x, y (h, w) fall on the mask (over box); outside the box: no."""
    r, c = np.rint(y).astype(np.intp) - box[1], np.rint(x).astype(np.intp) - box[0]
    h, w = mask.shape
    inside = (r >= 0) & (r < h) & (c >= 0) & (c < w)
    return np.asarray(inside & mask[np.clip(r, 0, h - 1), np.clip(c, 0, w - 1)])


def rim_sigma_px(shares: tuple[float, float, float, float], cfg: RimContrastConfig,
                 corrected: tuple[bool, bool] = (False, False), moving: bool = False) -> tuple[float, float]:
    """The centroid's 1-σ (px, x and y) from its outline's four sides, each side's 1-σ times its faint share
    f: √(σ_left² + σ_right²) / 2 along x, the same with top and bottom along y. The side's 1-σ is side_px,
    or corrected_side_px along an axis whose expected loss `rim_shift_px` undoes (corrected: x, y); while the
    cameras move, corrected_side_px along x as well (nothing is undone there, cfg.band's x share being 0,
    but a ball's spread is the same) and corrected_side_moving_y_px along y."""
    sx = cfg.corrected_side_px[0] if corrected[0] else cfg.side_px
    sy = (cfg.corrected_side_moving_y_px if moving else cfg.corrected_side_px[1]) if corrected[1] else cfg.side_px
    v = [(sx * shares[0]) ** 2, (sx * shares[1]) ** 2, (sy * shares[2]) ** 2, (sy * shares[3]) ** 2]
    return float(np.sqrt(v[0] + v[1]) / 2.0), float(np.sqrt(v[2] + v[3]) / 2.0)


def rim_shift_px(shares: tuple[float, float, float, float], mask: BoolA, cfg: RimContrastConfig,
                 corrected: tuple[bool, bool] = (True, True), still: bool = False, person: bool = False
                 ) -> tuple[float, float]:
    """How far (px, x and y) the true silhouette's centroid lies from eq. (10)'s on the outline's pixels,
    towards its fainter sides: a curved body's side whose rim is faint (shaded, curving away) loses a band
    b wide times its faint share f, and a band lost on one side moves the centroid by half its width the
    other way: ½ b_x (f_right - f_left) along x, ½ b_y (f_bottom - f_top) along y (b in px: a share of the
    body's size s = √(w h), or a fixed width); 0 along an axis not `corrected`. mask: the outline (h, w),
    for its extent.
    still: the cameras still: along x a band of fixed width, cfg.band_still_px (a faint side loses its outer
    pixel or so whatever the body's size: a ball's, a person's limb's), along y cfg.band_still_y's share
    (cfg.person_band_still_y's for a `person`); moving, cfg.band's shares."""
    _, _, bw, bh = cv2.boundingRect(mask.view(np.uint8))
    size = float(np.sqrt(bw * bh))
    left, right, top, bottom = shares
    if still:
        band_x = cfg.band_still_px
        band_y = (cfg.person_band_still_y if person else cfg.band_still_y) * size
    else:
        band_x, band_y = cfg.band[0] * size, cfg.band[1] * size
    return (0.5 * band_x * (right - left) if corrected[0] else 0.0,
            0.5 * band_y * (bottom - top) if corrected[1] else 0.0)
