"""What is known of a solid target's shape that its seen face does not tell (issue 12 item 1): the depth
behind that face, a person's volume centre above its silhouette's centroid and its centroid's own spread,
a vehicle's depth. tracker.localize places the target's centre and grows its covariance by them."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class SolidPrior:
    """What is known of a solid target's depth D behind the face the cameras see (issue 12 item 1): the
    disparity, and so eq. (2), measures that face, while the target's centre lies D/2 behind it along the
    left camera's line of sight through the centroid. D is unseen; it is taken as ρ times the target's
    smaller seen extent (width or height, m), ρ = `ratio` ± `ratio_sigma` (1-σ). The centre is then placed
    ρ/2 · extent behind the measured point and its range's variance grows by (ratio_sigma/2 · extent)².
    The default, ρ = 2/3 ± 0.01, is a round body's (a ball; an upright body and a wide one have priors of
    their own, below): the seen face's mean depth lies, for a sphere of radius R seen from afar, 2R/3
    before its centre (the mean of √(R² - r²) over the disc it is seen as), so ρ/2 · 2R = 2R/3. Both terms
    are scaled by tracker.round_face.matched_factor (`behind_face_px`, matched): the pixels matched (the
    outline's core within a central window) stand out further than the face's mean, and a near sphere is
    seen in perspective. ± 0.01 is the spread left about a true sphere once those are allowed for, fitted to
    the range errors of approach:body and manoeuvre:body (a ball 0.6 m across, at 2 to 30 m and at 8 to 12
    m) with seeds 0, 1 and 2, each run weighted alike (2026-12-06): Student-t (ν = 4) 0.0065, Gaussian
    0.011. It is a sphere's, not round shapes': a body round but not a sphere lies outside it (a cylinder
    seen side-on has ρ = π/4, its face's mean πR/4 before its axis). It had been ± 0.15, spanning such
    shapes, while the ball's ranges were 3.5 % too near at 2-4 m (its central window matched its middle)
    and 0.3 % beyond 8 m (its core left out the rim), within the 1-σ by that margin: approach:body range
    NEES 1.29, 6.2 at 2-4 m, manoeuvre:body within 1σ 0.81, NEES 0.60. With 0.5 ± 0.3 (a person's depth
    over its width, before upright bodies had their own) the ball of approach:body and manoeuvre:body was
    placed R/6 too near: range bias -1.0 % and -0.8 %, RMSE 0.186 and 0.088 m; with 2/3, -0.6 % and -0.3 %,
    0.167 and 0.045 m. Flat targets (a board facing the cameras) have ρ = 0: no prior (None).

    A wide body (seen width at least `wide_aspect` times its height: a vehicle side-on) is deeper than its
    smaller extent, its height, says under the general ρ: a car is about 1.8 m deep and 1.4-1.5 m high
    (ρ 1.2-1.3), a van 2 m and 2 m (ρ 1.0). ρ = `wide_ratio` ± `wide_ratio_sigma`, 1.2 ± 0.25, the spread of
    those classes. On occlusion:body (a car 4.2 x 1.8 x 1.4 m side-on at 12 m) the ρ that puts each frame's
    range on the truth is 1.19 (± 0.02) where the car is seen whole, 1.37 (median) where the post hides part
    of it and the seen width is 2 to 2.5 heights. With the general ρ its ranges were 0.49 m too near where
    seen whole (range RMSE 0.61 m, bias -4.5 %); with this one RMSE 0.39 m, bias -1.3 %.

    A solid body's outline is also less certain than a flat board's: its rim curves away from the cameras,
    shaded, and fades into the background there, so eq. (9) and the temporal model place each side of the
    outline within about a pixel, not exactly. `rim_sigma_px` is that side's 1-σ (px); the two sides along
    an axis move independently, each moving the centroid of eq. (10) by half its shift (a w x h box losing
    a strip δ x h on one side: δ h · w/2 / (w h) = δ/2), so the centroid's 1-σ grows by rim_sigma_px / √2
    along x and y. 0.5 px: on the simulator's bodies the median |centroid error| against the true seen
    silhouette is 0.24-0.31 px along x (walkers), a Gaussian's median |e| being 0.674 σ.

    An upright body (seen height at least `upright_aspect` times its width: a person) carries its volume
    unevenly along its height, a deep torso over thin legs, so its volume centre lies above the centroid of
    its silhouette by a share of its height (a person's centre of mass lies at about 55 % of the height, not
    midway). On the simulator's walkers seen whole (98 % or more of the body, not cut by the image's edge)
    the volume centre projects above the silhouette's centroid by a mean 2.65 % of the seen height on walk
    and illumination, 1.7 % on foliage, 3.6 % on pan, 2.3 to 2.7 % scatter about that. The centroid is
    moved up by `upright_shift` times the seen height, unless the outline meets the image's top or bottom
    (`in_frame`: the silhouette seen is then not the body's, and the share says nothing); 1-σ along y is
    then at least `upright_sigma` times the seen height, the rms about the shift on those scenes: the
    larger of that and the further 1-σ of a target seen in part (extra_px), which describes the same
    thing, where the body's unseen volume lies, when part of it is hidden. Without the shift the elevation
    NEES was 1.45 on walk, 1.54 on illumination, 2.67 on pan (the errors' mean -0.7 to -1.2 σ). The share
    depends on the heading (`shift_up`): walking across the line of sight, its striding legs and swinging
    arms spread the silhouette low and the centre lies higher above its centroid than seen from the front.
    On 2,150 frames of six scenes' walkers seen whole, the elevation error (with the fixed share) was +0.9
    to +2.4 % of the height seen from the front (s < 0.3, tracker.heading) and -2.5 to -3.8 % from the
    side (s > 0.85), alike on all six; a least-squares fit in s² (each scene weighted alike) gave 1.12 %
    (`upright_shift_front`) and 6.83 % (`upright_shift_side`), the errors' rms 3.35 -> 2.84 % of the
    height (walk 3.54 -> 2.88, pan 3.91 -> 3.31, foliage 2.66 -> 2.07); `upright_sigma` 2.8 %, that rms
    (2.6 % before), and the hull gap's y term no longer counts for an upright body (the space between its
    legs is its shape, as along x). Elevation RMSE walk:body 0.478 -> 0.454°, illumination 0.482 ->
    0.457°, foliage 0.457 -> 0.436°, pan 0.377 -> 0.323°, two-targets 0.727 -> 0.716°, endless 0.413 ->
    0.421°.
    Refitted the same way (2026-12-06) once a still camera's faint bottom is undone for a person too
    (tracker.rim_contrast.RimContrastConfig.person_band_still_y: its centroid moves down by up to 2 % of
    its size): 1.52 % and 6.42 %; elevation RMSE against the volume centre walk:body 0.481 -> 0.487°,
    illumination 0.476 -> 0.482°, foliage 0.478 -> 0.486°, two-targets 0.298 -> 0.302°, endless 0.311 ->
    0.318°, pan 0.199 -> 0.197° (0.488, 0.483, 0.486, 0.300, 0.314 and 0.199° before the refit).
    Standing still, its limbs hang where they hang and the shift varies far less: with tracker.heading's
    gait share m (0 standing, 1 walking), the 1-σ is h (σ0² + (σ² - σ0²) √m)^½, σ = `upright_sigma`, σ0 =
    `upright_still_y_sigma` 1.27 %, the rms of the elevation errors of endless:body's 176 frames of walkers
    at m < 0.1, seen whole and not placed from their top (the only scene where people stand). The errors
    grow fast with m: 2.2 % rms at m 0.1-0.2, 2.8-3.8 % from 0.2 on (1,036 such frames of walk, foliage,
    pan, two-targets and endless); of the weights m², m, √m and a step at m = 0.1 or 0.2, √m had the
    highest log-likelihood (Student-t, ν = 4: 3,322 against 3,298 for m²). With σ for standing bodies too,
    99 % of their frames were within 1σ (NEES 0.20), and endless:body's elevation within 1σ was 0.772.
    Since the rim's recovery lets the learnt background decide at a body's ground-deep foot (tracker.rim,
    2026-12-04) the outlines of still cameras lose less of the legs: the rms of those errors (walking frames,
    each scene's clipped at 5 robust σ, the scenes averaged) fell 2.87 -> 2.58 % of the height over walk,
    illumination, foliage, two-targets and endless, and stayed 3.23 % on pan, whose cameras move (the
    outline warped, no learnt background). So σ is `upright_sigma` 2.4 % with the cameras still and
    `upright_warped_sigma` 2.8 % while they move: 2.4 %, not the rms, is what keeps walk's, illumination's,
    two-targets' and endless's elevation within 1σ in their bands together (replayed on per-frame dumps:
    at 2.6 % walk:body's was 0.753, at 2.4 % 0.710, two-targets 0.602; `tmeye eval --all` 0.713 and 0.605).
    `upright_warped_sigma` 2.6 % since a far walker's head past the neck's gap is kept (tracker.masks,
    HEAD_MIN_PX, 2026-12-06): on pan:body's upright frames, seeds 0, 1 and 2, the elevation errors' rms
    (each seed's clipped at 5 robust σ, the seeds averaged) fell 2.06 -> 1.88 % of the seen height, and
    2.8 % was scaled by that ratio.

    An upright body has a prior of its own on two more counts, measured on the simulator's walkers (walk,
    illumination, foliage, pan; a person 0.3 m deep, 0.6 m wide, limbs swinging):
    - its depth behind the seen face: ρ = `upright_ratio` ± `upright_ratio_sigma` (1-σ) of its seen width.
      The seen face's mean point lies a median 0.18 of the seen width before the volume centre (0.177 to
      0.187 on the four scenes), ρ = 0.36; with the general ρ = 0.5 ranges were 0.03 to 0.05 m too far
      on them. `upright_ratio_sigma` 0.035: the spread of the face's depth left over the disparity's, fitted
      by Student-t (ν = 4) likelihood of the range errors under the whole range 1-σ, each scene weighted
      alike, replayed from the frame rows: 0.034 over walk, illumination, foliage and pan, 0.036 with
      two-targets (2026-12-03, once the region's fit was robust, tracker.stereo.outliers, and the walkers'
      ranges were 76-79 % within the 1-σ of 0.055). 0.055 was the same fit's (2026-12-02) once a person's
      disparity was its seen surface's mean (tracker.disparity_sigma.surface_mean). It had been 0.12
      (0.067 m robust sd of the residuals on 1,221 frames against 0.056 m of the disparity's 1-σ), fitted
      while the one whole-region fit's error, which the best-textured parts pull, was in those residuals:
      with it the walkers' ranges were then 80-90 % within 1σ. Refitted (2026-12-04, the same likelihood
      with endless and two-targets too) once a person's parts were matched on its changed pixels and one
      whose parts cannot be told had a disparity 1-σ of its own (tracker.disparity_sigma,
      FEW_PARTS_PERSON_PX): 0.015, with `upright_side_sigma` 0.20 (below); at 0.035 and 0.5 the walkers'
      ranges were 79-82 % within 1σ (NEES 0.72-0.77), at 0.015 and 0.20 76-78 % (NEES 0.87-0.99).
    - seen side-on, its silhouette narrow (a walker's stride closed, or standing turned): the face is the
      side of a body as deep as it is wide, and ρ of a width that narrow puts it too near. The seen width w
      and the depth along the line of sight add up to about the body's width plus its depth whatever way
      it is turned (exactly for a box turned 0 or 90°), g h with g = `upright_girth` (the simulator's
      person: 0.6 + 0.22 m over 1.69 m); the face's mean lies κ (g h - w) before the volume centre, κ =
      `upright_side_ratio`, where that exceeds ρ/2 · w, with a 1-σ of `upright_side_sigma` times itself.
      Fitted (Student-t) over 1,428 upright frames of walk, illumination, foliage, pan and two-targets: κ 0.44, g
      0.50; on its 207 side-on frames the residuals' robust sd was 0.096 m against 0.061 m elsewhere, so the 1-σ
      was half the depth (0.20 of it since the refit above). Where the silhouette was narrow (seen width under 0.3
      of its height) ranges had been 0.15-0.23 m too near on walk, illumination and foliage (NEES 4.8-13 on those
      frames); range RMSE walk 0.103 -> 0.095 m, illumination 0.104 -> 0.097, foliage 0.104 -> 0.099, pan 0.082 ->
      0.077, two-targets 0.101 -> 0.099, endless 0.394 either way.
    - seen in part (its outline under `part_share` of a person's height at its disparity: its legs hidden
      behind a post or the image's edge, or only its legs seen), the seen width says little of the depth
      behind what is seen: that depth's 1-σ is at least `part_depth_sigma_m` (seen_in_part). On
      endless:body's 365 such frames the range error left once the face's disparity error is taken out
      was 0.057 m rms, against 0.026-0.029 m where more of the body is seen; 0.115 m, about half a
      person's depth, is the Student-t fit (as above, six scenes), and took endless:body's range NEES 2.20
      -> 1.30 (share 0.6; 0.7 and 0.8 fitted 0.105 and 0.055 m, NEES 1.29 and 1.43). A person near the
      cameras whose legs lie past the image's bottom edge, over part_share of it seen, is placed from its top
      (tracker.partly_seen) and has `edge_depth_sigma_m` 0.041 m: on the 168 such frames of walk, illumination
      and foliage (seed 0, 3 to 4 m, 270 of 340 px seen) the range errors were 0.043 m rms against a 1-σ of
      0.013 m without it; before, the cut's y term (kappa times the seen height, 100 px) had leaked into σ_r.
    - the centroid's 1-σ along x: h (a² + b² s²)^½ (h the seen height, a = `upright_x_sigma`, b =
      `upright_swing_sigma`, s the share of its limbs' swing seen across the image, tracker.heading), in
      place of the rim's term, the hull gap's and the outline's edge term along x (tracker.pipeline: the
      errors it was fitted to hold them all; over 2,085 upright frames with no cut, a Student-t fit of h
      (a² + b² s²)^½ with the edge term added in quadrature had a log-likelihood 87 lower than without it:
      endless:body azimuth within 1σ 0.794 -> 0.779, NEES 0.750 -> 0.849). Standing still it swings
      nothing: with tracker.heading's gait share m (0 standing, 1 walking), h² (a0² + (a² - a0²) m² + b²
      s²), a0 = `upright_still_sigma` 0.22 % (it counts only where the body is not placed from its top).
      0.13 % had been fitted on endless:body's 328 frames of walkers standing with seed 0 alone, where the
      other terms held their errors (within 1σ 0.96); a standing person's silhouette lies off its volume
      centre by a fixed amount for as long as it stands (its pose, its shaded side), one draw per person, and
      with seeds 1 and 2 those standing were within 1σ 0.43 and 0.49 (NEES 2.9 and 2.7; endless:body seed 1,
      frames 2151-2203: 0.40 px off, 0.34 % of h, for a 1-σ of 0.19 px). Gaussian maximum likelihood of a0
      over the upright frames of endless:body seen whole and not from the top with seeds 0, 1 and 2 (3,226;
      each seed weighted alike, the other terms as they were) gave 0.22 %. Its
      arms and legs swing across the
      outline, so the notches of its outline are the spaces between its limbs, not parts the segmentation
      missed, and the volume centre lies off the silhouette's centroid by an amount that scales with the
      body's size: the azimuth errors against the volume centre are 0.47 to 0.52 % of the seen height rms
      on those scenes, near-Gaussian in that unit (in pixels, as the rim's term and the hull gap's gave
      them, their distribution was far from it: 97 % of frames within 1σ on walk:body). They swing in the
      plane the body walks in, so how much of that shows depends on its heading: over the frames of walk,
      illumination, foliage, pan, endless and two-targets not cut by an edge or another object (1,250),
      a Student-t (ν = 4) fit of the errors gave 0.19 % of h for a and 0.48 % for b (scales; a Student-t
      with ν = 4 is within 1.2 scales on 70 % of draws), its log-likelihood 81 higher than that of a
      single share of h (0.33 %); the heading alone (s), not the speed, made the difference. a = 0.28 %
      and b = 0.58 % (0.50 % of h with s unknown, s² = 1/2; 0.45 % before the heading was used): with
      0.23 % and 0.58 %, foliage:body's and illumination:body's azimuth NEES were 1.49 and 1.50, at the
      band's edge. b = 0.48 % since the centroid is moved to undo the band a faint side loses
      (tracker.rim_contrast.rim_shift_px): the same fit over 2,095 frames of those six scenes then gave b
      0.37 % against 0.45 % on the same code without it (a 0.21 % either way, log-likelihood 115 higher),
      and b was scaled by that ratio, 0.82. a = 0.22 % and b = 0.44 % since the centroid is moved to the
      direction centroid along x (tracker.pipeline, perspective): the same fit over 3,221 upright frames of
      those six scenes gave a 0.146 % and b 0.294 % against 0.185 % and 0.324 % on the same code without it,
      and a and b were scaled by those ratios, 0.79 and 0.91. While the cameras move there is no temporal model
      to measure the rim's contrast by (`locate`'s rim_px None), the outline is drawn by warping, and the
      rim's fixed term counts along x as well: on pan:body the silhouette's centroid was found 0.33 px
      off the truth's (median |error|) against 0.26 px on walk:body and 0.12 px on endless:body, and the
      azimuth errors were 0.39 % of the seen height (median |error|) against 0.29 to 0.33 % on walk and
      foliage; with the upright term alone 59 % of pan:body's frames were within 1σ (NEES 1.41), with
      both 70 % (0.87). A body whose cross-section is not round (a person's torso, a box of half-width p =
      0.19 m and half-depth q = 0.11 m) shows a silhouette whose centre lies off its centre's direction by
      perspective: the box's extreme corners are at different depths, so the mean of their directions moves
      by P z_r / Z² (rad; P the half-width seen across, z_r the signed depth, m, of the corner that bounds it):
      with α the heading from the line of sight, pq cos 2α + (q² - p²)/2 · sin 2α on α in (0°, 90°) and the
      same with -α on the other quadrant, amplitude (p² + q²)/2, rms over headings (p² + q²) / (2√2) =
      `upright_depth_m2` 0.017 m² (square-on and side-on it turns over, within about p / Z of the heading): a
      1-σ along x of k f / Z² px (upright_depth_px), 1.1 px at 3 m, 0.1 px at 10 m. It is derived from the
      simulator's person's torso, not fitted, and from the bounding corners alone: eq. (10) weighs the nearer
      columns, taller in the image, a little more (a full-height box, about 0.020 m²). With it, a and b were
      refitted (Gaussian maximum likelihood over 3,944 upright frames of walk, illumination, foliage, pan,
      two-targets and endless, the last once a leg seen beside an occluder had its own term,
      tracker.partly_seen.legs_aside_px): a 0.175 % and b 0.255 %,
      log-likelihood 141 higher than the best a and b without it (0.198 % and 0.324 %). eval --all: the
      azimuth within 1σ walk 0.743 -> 0.717, illumination 0.760 -> 0.740, foliage 0.697 -> 0.657, pan 0.767
      -> 0.688, endless 0.795 -> 0.756, two-targets 0.920 -> 0.903 (its slow walker's errors are half those
      of walk's at the same seen height and heading). Refitted once more since a still camera's faint side
      is undone by a band of fixed width along x (tracker.rim_contrast: 0.78 px in place of 1.06 % of the
      size; the walkers' azimuth errors against their volume centre fell by 8 to 14 %): a 0.172 % and b
      0.13 %, Gaussian maximum likelihood over the same six scenes' 3,945 upright frames with each scene
      weighted alike (pooled, endless's 2,517 frames decide it, and the fit, a 0.235 % and b 0, follows
      their tail: walk's and illumination's within 1σ 0.79 and 0.80, NEES 0.72 and 0.63). eval --all: the
      azimuth within 1σ walk 0.777 -> 0.713, illumination 0.777 -> 0.733, foliage 0.713 -> 0.653, pan
      0.688 -> 0.650, endless 0.769 -> 0.743, two-targets 0.893 -> 0.870; NEES 0.760 -> 0.918, 0.653 ->
      0.802, 0.942 -> 1.214, 1.032 -> 1.152, 1.259 -> 1.345, 0.393 -> 0.439.

    Where a nearer background hides an upright body's lower part (a walker behind a hedge, a bush, a car)
    and its top is seen, the silhouette says little of where its centre lies: the centre is found from its
    top instead, `centre_below_top` (± `centre_below_top_sigma`) of a person's height `height_m`
    (± `height_sigma_m`) below it, at the centre's depth (ρ/2 of the seen width behind the face). An adult's
    stature is about 1.70 ± 0.10 m and the centre of mass lies at about 55 % of it above the soles; the
    simulator's walkers are 1.69 m tall with their volume centre 0.465 of that below the top. On the frames
    where the learnt background cuts an upright walker's bottom and not its top (endless 846, foliage 109,
    walk 39), the centre so found lay 1.63, 1.59 and 0.84 px rms from the truth's image; the silhouette's
    centroid 10.7, 4.0 and 4.8 px. A track that saw the person whole measured its stature (tracker.
    extent_history.ExtentHistory.stature_m: 1.67 m median on the simulator's 1.69 m walkers, the outline
    missing a sliver), which weighs in with the prior's, inverse-variance weighted, its 1-σ widened by
    `stature_sigma_m` (shoes, hair, a sole lost against the ground: the outline's height is not the
    body's): elevation NEES on those frames' scenes foliage 0.50 -> 0.77, endless within 1σ 0.85 -> 0.75,
    two-targets 0.66 -> 0.60 (the simulator's walkers all 1.69 m: the prior's 0.10 m never shows). The
    image's bottom edge cutting a near walker's legs, its head seen, places it from its top as well (once
    judged worse, 13 px rms off against the centroid's 10 px): on the 56 such frames of walk:body with seed
    0 (3 to 4 m) the elevation errors were 0.39° rms from the top against 0.73° from the centroid, which
    had a 1-σ of 9.7° (the cut's kappa term)."""

    ratio: float = 2.0 / 3.0
    ratio_sigma: float = 0.01
    height_m: float = 1.70
    height_sigma_m: float = 0.10
    centre_below_top: float = 0.45
    centre_below_top_sigma: float = 0.02
    stature_sigma_m: float = 0.02
    rim_sigma_px: float = 0.5
    upright_sigma: float = 0.024
    upright_warped_sigma: float = 0.026
    upright_shift: float = 0.026
    upright_shift_front: float = 0.0152
    upright_shift_side: float = 0.0642
    upright_aspect: float = 1.5
    upright_ratio: float = 0.36
    upright_ratio_sigma: float = 0.015
    upright_girth: float = 0.50
    thinnest: float = 0.12
    upright_side_ratio: float = 0.44
    upright_side_sigma: float = 0.20
    upright_x_sigma: float = 0.00172
    upright_swing_sigma: float = 0.0013
    upright_still_sigma: float = 0.0022
    upright_still_y_sigma: float = 0.0127
    upright_depth_m2: float = 0.017
    wide_aspect: float = 2.0
    wide_ratio: float = 1.2
    wide_ratio_sigma: float = 0.25
    part_share: float = 0.6
    speck_share: float = 0.3
    shoulder_drop: float = 0.18
    shoulder_width: float = 0.23
    part_depth_sigma_m: float = 0.115
    edge_depth_sigma_m: float = 0.041

    def upright(self, width_px: float, height_px: float) -> bool:
        """Whether a target seen width_px wide and height_px high is an upright body (a person)."""
        return height_px > 0 and height_px >= self.upright_aspect * width_px

    def shift_up(self, swing: float | None) -> float:
        """An upright body's volume centre above its silhouette's centroid, a share of its seen height:
        upright_shift_front + (upright_shift_side - upright_shift_front) s² with s the share of its limbs'
        swing seen across the image (tracker.heading); upright_shift where s is unknown."""
        if swing is None:
            return self.upright_shift
        return self.upright_shift_front + (self.upright_shift_side - self.upright_shift_front) * swing * swing

    def upright_x_var(self, height_px: float, swing: float | None, gait: float | None = None) -> float:
        """An upright body's centroid variance along x (px²): h² (a0² + (a² - a0²) m² + b² s²), a =
        upright_x_sigma, a0 = upright_still_sigma (standing still), b = upright_swing_sigma, s the share of
        its limbs' swing seen across the image, m how fully it walks (tracker.heading); s² = 1/2 (a heading
        at random) and m = 1 where unknown."""
        s2 = 0.5 if swing is None else swing * swing
        m2 = 1.0 if gait is None else gait * gait
        a0, a = self.upright_still_sigma, self.upright_x_sigma
        return height_px * height_px * (a0**2 + (a**2 - a0**2) * m2 + self.upright_swing_sigma**2 * s2)

    def upright_depth_px(self, disparity: float, baseline_m: float, f_px: float) -> float:
        """An upright body's silhouette's 1-σ (px) along x about its centre's direction for the depth of its
        cross-section: k f / Z² with Z = f b / d (k = upright_depth_m2, m²; d the rectified disparity and f the
        focal length, px; b the baseline, m; Z the seen face's depth, m); 0 without a baseline."""
        if baseline_m <= 0 or f_px <= 0:
            return 0.0
        return self.upright_depth_m2 * disparity * disparity / (baseline_m * baseline_m * f_px)

    def upright_y_sigma(self, height_px: float, gait: float | None = None, warped: bool = False) -> float:
        """An upright body's 1-σ (px) about its shift along y: h (σ0² + (σ² - σ0²) √m)^½, σ = upright_sigma
        (upright_warped_sigma where `warped`: the cameras moving, the outline drawn by warping), σ0 =
        upright_still_y_sigma (no more than σ), m how fully it walks (tracker.heading; 1 where unknown)."""
        weight = 1.0 if gait is None else float(np.sqrt(max(gait, 0.0)))
        s = self.upright_warped_sigma if warped else self.upright_sigma
        s0 = min(self.upright_still_y_sigma, s)
        return height_px * float(np.sqrt(s0**2 + (s**2 - s0**2) * weight))

    def seen_in_part(self, behind: tuple[float, float], height_px: float, disparity: float, baseline_m: float,
                     past_edge: bool = False) -> tuple[float, float]:
        """An upright body's behind_face_px (depth, 1-σ; px at the face's depth, times Z / f = b / d: m), its
        1-σ at least part_depth_sigma_m where its outline, height_px high, is under part_share of a person
        of height_m at its disparity (px; baseline_m the rig's): seen in part (its legs hidden, or only its
        legs seen), the seen width says little of the depth behind what is seen. past_edge: its legs lie past
        the image's bottom edge, more of it seen: at least edge_depth_sigma_m."""
        stature = self.stature_px(disparity, baseline_m)
        if stature is None:
            return behind
        if height_px < self.part_share * stature:
            return behind[0], max(behind[1], self.part_depth_sigma_m * disparity / baseline_m)
        if past_edge:
            return behind[0], max(behind[1], self.edge_depth_sigma_m * disparity / baseline_m)
        return behind

    def stature_px(self, disparity: float, baseline_m: float) -> float | None:
        """A person of height_m at disparity `disparity` (px, rectified; baseline_m the rig's baseline, m):
        H d / b px high. None without a baseline."""
        return self.height_m * disparity / baseline_m if baseline_m > 0 else None

    def fragment_px(self, disparity: float, baseline_m: float) -> tuple[float, float] | None:
        """The extents (px) under which a track's outline seen whole at disparity `disparity` (px, rectified;
        baseline_m the rig's) is a person's fragment, not a whole body: (part_share H, shoulder_width H) of
        its stature H there, the height of an upright outline and the width of one whose height was never
        seen whole (narrower than a person's shoulders: a sliver beside what hides the rest). None without a
        baseline."""
        stature = self.stature_px(disparity, baseline_m)
        return None if stature is None else (self.part_share * stature, self.shoulder_width * stature)

    def top_sigma_px(self, width_px: float, disparity: float, baseline_m: float) -> float:
        """The 1-σ (px) of a person's top where its outline, width_px wide, is cut at a side and narrower than
        a person's shoulders (`shoulder_width` of its stature H at its disparity, px; baseline_m the rig's):
        the columns that show may not hold the head, so the outline's top may be a shoulder's,
        `shoulder_drop` H below the head's top, or the head's: half that (a person's shoulders stand at
        about 0.82 of the stature and are about 0.23 of it across). endless:body seed 2, frames 3303-3430: a
        walker standing behind a post, a 9 px sliver of it seen at 12 m, placed from its top 0.63-0.73 deg
        low with an elevation 1-σ of 0.134 deg. 0 where not so narrow."""
        stature = self.stature_px(disparity, baseline_m)
        if stature is None or width_px >= self.shoulder_width * stature:
            return 0.0
        return 0.5 * self.shoulder_drop * stature

    def short_of_stature_px(self, height_px: float, disparity: float, baseline_m: float,
                            stature_m: float | None = None) -> float:
        """How much shorter (px) an upright outline height_px high is than a person of height_m (or of
        stature_m, the stature its track measured) at its disparity (px; rectified, baseline_m the rig's
        baseline): H d / b - h, at least 0. Seen only in part at a side (a walker entering the image), the
        rest of the person may lie above or below it; its bottom inferred (tracker.localize), its top or its
        bottom may be the part lost."""
        height = self.height_m if stature_m is None else stature_m
        return max(height * disparity / baseline_m - height_px, 0.0) if baseline_m > 0 else 0.0

    def unseen_rest_px(self, width_px: float, height_px: float, disparity: float, baseline_m: float,
                       cut: tuple[bool, bool]) -> tuple[float | None, float | None]:
        """What an upright outline width_px x height_px under part_share of a person of height_m at its
        disparity (px; baseline_m the rig's) says of the rest of the person, hidden where no cut was seen
        (cut: whether one was seen across x, at the left or right, and across y, at the top or bottom): the
        centroid's 1-σ (px) along an axis with no cut, its shortfall / √12 (anywhere about what is seen):
        the height's against the stature H; the width's against a person's girth (upright_girth H) where the
        outline is narrower than any side of a person (`thinnest` H: a sliver beside what hides the rest).
        None for an axis not so."""
        stature = self.stature_px(disparity, baseline_m)
        if stature is None or height_px >= self.part_share * stature:
            return None, None
        thin_or_low = width_px < self.thinnest * stature or height_px < self.part_share * stature / 2.0
        x = None if cut[0] or not thin_or_low else max(self.upright_girth * stature - width_px, 0.0) / 12**0.5
        return x, None if cut[1] else (stature - height_px) / 12**0.5

    def speck(self, width_px: float, height_px: float, disparity: float, baseline_m: float) -> bool:
        """Whether an outline width_px x height_px is a speck: under `speck_share` of a person's stature H at
        its disparity (px; baseline_m the rig's) along both axes, 0.51 m for H = 1.70 m. No whole body this
        prior is for is seen that small (the simulator's ball, the smallest, is 0.35 H; a person's girth
        0.5 H, a car's height 0.8 H): it is a piece of one whose rest is hidden or lost, and may lie anywhere
        about it (unseen_rest_px, as for a thin or low piece of a person). endless:body with seed 1, frames
        846-883: a head over a hedge at 25 m, 5-11 px across against H = 40 px, placed 0.8-1.6 deg above the
        person's centre with an elevation 1-sigma of 0.006-0.23 deg."""
        stature = self.stature_px(disparity, baseline_m)
        return stature is not None and max(width_px, height_px) < self.speck_share * stature

    def wide(self, width_px: float, height_px: float) -> bool:
        """Whether a target seen width_px wide and height_px high is a wide body (a vehicle side-on)."""
        return width_px > 0 and width_px >= self.wide_aspect * height_px

    def depth_ratio(self, width_px: float, height_px: float, upright: bool | None = None) -> tuple[float, float]:
        """ρ and its 1-σ for a target seen width_px wide and height_px high: an upright body's, a wide
        body's or the general one (upright: known to be a person or not; None: by the extent)."""
        if self.upright(width_px, height_px) if upright is None else upright:
            return self.upright_ratio, self.upright_ratio_sigma
        if self.wide(width_px, height_px):
            return self.wide_ratio, self.wide_ratio_sigma
        return self.ratio, self.ratio_sigma

    def behind_face_px(self, width_px: float, height_px: float, upright: bool | None = None,
                       matched: float = 1.0) -> tuple[float, float]:
        """The target's centre's depth behind its seen face's mean and that depth's 1-σ, in pixels at the
        face's depth (times Z / f: metres), for a target seen width_px wide and height_px high: ρ/2 · e ±
        σ_ρ/2 · e (depth_ratio; e its seen width if upright, else its smaller extent); for an upright body
        at least κ (g h - w) ± upright_side_sigma times that (seen side-on; upright_girth g,
        upright_side_ratio κ). upright: known to be a person or not; None: by the extent. matched: for a
        round body (neither upright nor wide), its centre's depth behind the face its matched pixels measure
        over this prior's (tracker.round_face.matched_factor): both terms times it."""
        up = self.upright(width_px, height_px) if upright is None else upright
        ratio, ratio_sigma = self.depth_ratio(width_px, height_px, up)
        e = width_px if up else min(width_px, height_px)
        k = 1.0 if up or self.wide(width_px, height_px) else matched
        half, s_half = 0.5 * ratio * e * k, 0.5 * ratio_sigma * e * k
        if up:
            side = self.upright_side_ratio * (self.upright_girth * height_px - width_px)
            if side > half:
                half, s_half = side, max(s_half, self.upright_side_sigma * side)
        return half, s_half
