"""3-D position, range r, azimuth θ and elevation φ of a target, with 1-σ uncertainties.

Parallel-rig triangulation is paper eq. (2) in the rectified frame (tracker.rectify.Rectifier.rect_to_rig);
`triangulate_dlt` is the general linear triangulation for any calibrated pair of projection matrices.
Spherical coordinates are about a configurable origin in the world (gimbal base) frame:
r = |p|, θ = atan2(x, z) (positive to the right), φ = atan2(-y, √(x² + z²)) (positive up).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from tracker.frames import GimbalState
from tracker.geometry import gimbal_rotation
from tracker.rectify import Rectifier
from tracker.solid_prior import SolidPrior

F64 = NDArray[np.float64]

# the disparity's bias with its sub-pixel fraction (px, 1-σ): interpolating the right image pulls a match
# towards whole or half pixels by an amount that depends on the fraction (pixel locking), the same for
# every part of a region, so their scatter (tracker.disparity_sigma) cannot see it; on the scenes of
# `tmeye eval` the mean error over the fraction is a sine of 0.010 to 0.021 px amplitude
PHASE_SIGMA_PX = 0.012
# the disparity's further 1-σ (px) that neither a region's own fit nor its parts' scatter sees, added in
# quadrature (it was a floor, max(σ_d, 0.02 px), until the region's fit became robust, tracker.stereo.
# outliers): over the eight open-loop plates' frames of `tmeye eval` (2026-12-03, the robust fit), the E for which
# the errors' median over √(σ_d² + 0.012² + E²) is a Gaussian's (0.674) was 0.012 px pooled, 0.0 (walk,
# pan, approach) to 0.025 px (occlusion, the post beside the plate) by scene; 0.010 px keeps each plate's
# disparity within 1σ in 0.60-0.79 (pan 0.79) where the floor left pan and two-targets at 0.85 and 0.84
MATCH_FLOOR_PX = 0.010


def triangulate_dlt(P1: F64, P2: F64, x1: F64, x2: F64) -> F64:
    """Linear (DLT) triangulation: projection matrices (3, 4), undistorted pixel points (2,) each ->
    the 3-D point (3,) minimising the algebraic error of x ~ P X in both views."""
    A = np.array([x1[0] * P1[2] - P1[0], x1[1] * P1[2] - P1[1],
                  x2[0] * P2[2] - P2[0], x2[1] * P2[2] - P2[1]])
    _, _, vt = np.linalg.svd(A)
    X = vt[-1]
    return np.asarray(X[:3] / X[3])


def spherical(p: F64) -> tuple[float, float, float]:
    """(r, θ, φ) of a point (3,) in metres and radians."""
    x, y, z = (float(v) for v in p)
    return float(np.linalg.norm(p)), float(np.arctan2(x, z)), float(np.arctan2(-y, np.hypot(x, z)))


def spherical_jacobian(p: F64) -> F64:
    """∂(r, θ, φ)/∂(x, y, z), shape (3, 3)."""
    x, y, z = (float(v) for v in p)
    rho2 = x * x + z * z
    rho = np.sqrt(rho2)
    r2 = rho2 + y * y
    r = np.sqrt(r2)
    return np.array([[x / r, y / r, z / r],
                     [z / rho2, 0.0, -x / rho2],
                     [x * y / (r2 * rho), -rho / r2, z * y / (r2 * rho)]])


@dataclass(frozen=True)
class Localization:
    """A target's position: rig and world frames (m), covariance in the world frame (m², (3, 3)),
    and r (m), θ, φ (rad) about the origin with their 1-σ; measured_world: the world point (m, (3,)) on the
    ray of the centroid as measured, at the same depth: `world` but for an upright body's shift up to its
    volume centre (SolidPrior.upright_shift), the point the angles the cameras measure are judged on;
    sigma_d_px: the whole 1-σ (px) the disparity was given (its matcher's or its parts', the sub-pixel
    phase's and the calibration's; None where the point was not located from a disparity)."""

    rig: F64
    world: F64
    cov_world: F64
    r: float
    theta: float
    phi: float
    sigma_r: float
    sigma_theta: float
    sigma_phi: float
    measured_world: F64 | None = None
    sigma_d_px: float | None = None


def fused(a: tuple[float, float], b: tuple[float, float]) -> tuple[float, float]:
    """Two measurements (value, variance) of one quantity fused, inverse-variance weighted, the fused
    variance scaled by the Particle Data Group's factor S² = χ² / (N - 1) where that exceeds 1 (χ² = (a - b)²
    / (σ_a² + σ_b²), N = 2): measurements that disagree beyond their 1-σ say their 1-σ are too small.
    An upright body placed from its top and from its centroid while its feet are inferred (pan:body:
    elevation RMSE 0.283 and 0.358 deg on the frames where the two differ; fused, over all frames, 0.312 ->
    0.226 deg, within 1σ 0.70 and NEES 0.88; without the factor NEES 1.60, replayed; docs/evaluation.md)."""
    (ya, va), (yb, vb) = a, b
    if va <= 0.0 or vb <= 0.0:  # an exact measurement stands
        return a if va <= 0.0 else b
    wa, wb = 1.0 / va, 1.0 / vb
    chi2 = (ya - yb) ** 2 / (va + vb)
    return (wa * ya + wb * yb) / (wa + wb), max(chi2, 1.0) / (wa + wb)


class Localizer:
    """Rectified centroid + disparity -> 3-D point and spherical coordinates with uncertainties: the image
    noise of the centroid and of the disparity, the calibration's own (the rig's `sigma`) and, with a
    SolidPrior, a solid target's unseen depth. centroid_sigma_px: the centroid's own 1-σ (px), at least
    0.5 / √area; None where the caller gives all of it in `locate`'s extra_px (tracker.pipeline: the
    outline's whole pixels, tracker.segmentation, model the same error exactly, and the floor stood on top
    of them: a disc 44 px across on two-targets:plate had 0.034 px along y for a quantisation error of
    0.026 px rms, 0.031 px of it from the outline's term)."""

    def __init__(self, rect: Rectifier, origin: F64 | None = None, centroid_sigma_px: float | None = 0.05,
                 solid: SolidPrior | None = None):
        self.rect = rect
        self.origin = np.zeros(3) if origin is None else np.asarray(origin, float)
        self.centroid_sigma_px = centroid_sigma_px
        self.solid = solid

    def locate(self, centroid_rect: F64, disparity: float, disparity_sigma: float, area: int,
               gimbal: GimbalState | None, extra_px: tuple[float, float] = (0.0, 0.0),
               extent_px: tuple[float, float] | None = None, rim_px: tuple[float, float] | None = None,
               in_frame: bool = True, top_px: float | None = None, swing: float | None = None,
               upright: bool | None = None, stature: tuple[float, float] | None = None,
               gait: float | None = None, warped: bool = False, top_fused: bool = False,
               matched: float = 1.0, top_sigma_px: float = 0.0) -> Localization:
        """extra_px: the centroid's further 1-σ (px) along x and y, where the target is seen only in part
        (tracker.visibility). extent_px: the target's seen width and height (px), for the SolidPrior.
        rim_px: the outline's 1-σ (px, x and y) from its rim's contrast (tracker.rim_contrast), in place of
        the SolidPrior's fixed rim_sigma_px / √2 along each axis; None: that one. in_frame: the target is cut
        by neither the image's top nor its bottom (tracker.pipeline: its verified box reaches neither; an
        upright body's shift, SolidPrior). top_px: the rectified y (px) of the outline's top where a nearer
        background hides the target's bottom and its top is seen: an upright body's centre is found from it
        (SolidPrior.height_m). swing: the share of an upright body's limb swing seen across the image
        (tracker.heading; None: unknown, SolidPrior.upright_x_var). upright: whether the target is an upright
        body (a person) whatever its seen extent says (tracker.pipeline: a track seen upright whole, its
        lower part now hidden); None: by its seen extent (SolidPrior.upright). stature: the height (m) and its
        1-σ that the target's track measured, for an upright body placed from its top (combined with the
        SolidPrior's height_m ± height_sigma_m); None: the prior's alone. gait: how fully an upright body
        walks (tracker.heading; None: unknown, taken as walking). warped: the cameras move, so the outline is
        drawn by warping (an upright body's y 1-σ is then SolidPrior.upright_warped_sigma's). top_fused: the
        outline's bottom was inferred, not seen (tracker.results.Blob.bottom_inferred): an upright body's
        centre from its top (top_px) and the one from its centroid and shift are fused (`fused`). matched: for
        a round body, its centre's depth behind the face its matched pixels measure over the prior's
        (tracker.round_face.matched_factor; SolidPrior.behind_face_px). top_sigma_px: the outline's top's own
        further 1-σ (px) where the centre is found from it (SolidPrior.top_sigma_px: a sliver's top may be
        a shoulder's)."""
        x, y = float(centroid_rect[0]), float(centroid_rect[1])
        X_meas = self.rect.rect_to_rig(x, y, disparity)  # eq. (2)
        from_top = None
        y_centroid = y  # an upright body's centre's y from its centroid, where fused with the top's
        if upright is None:
            upright = self.solid is not None and extent_px is not None and self.solid.upright(*extent_px)
        behind = None  # a solid body's centre's depth behind its face and its 1-σ (px at the face's depth)
        if self.solid is not None and extent_px is not None:
            behind = self.solid.behind_face_px(*extent_px, upright=upright, matched=matched)
            if upright:
                past_edge = top_px is not None and not in_frame  # from its top, its legs past the image's edge
                behind = self.solid.seen_in_part(behind, extent_px[1], disparity, self.rect.b, past_edge)
                if in_frame:  # a person's volume centre above its silhouette's
                    y_centroid = y - self.solid.shift_up(swing) * extent_px[1]
                if top_px is not None:
                    from_top = self._below_top(top_px, disparity, behind[0], stature)
                y = y_centroid if from_top is None else from_top[0]
        top_fused = top_fused and from_top is not None
        s_c = 0.0 if self.centroid_sigma_px is None else max(self.centroid_sigma_px, 0.5 / np.sqrt(max(area, 1)))
        cal = self.rect.rig.sigma  # the calibration's own uncertainty (tracker.calib_sigma)
        (s_cx, s_cy), s_dcal = cal.principal_px, cal.disparity_px * self.rect.f / float(self.rect.rig.left.K[0, 0])
        S = np.diag([s_c**2 + s_cx**2 + extra_px[0] ** 2, s_c**2 + s_cy**2 + extra_px[1] ** 2,
                     disparity_sigma**2 + PHASE_SIGMA_PX**2 + MATCH_FLOOR_PX**2 + s_dcal**2])
        if self.solid is not None and extent_px is not None:  # a solid body: its rim; an upright one: its own x
            s_rim = self.solid.rim_sigma_px / np.sqrt(2.0)  # the outline's sides on a curved, shaded rim
            rx, ry = (s_rim, s_rim) if rim_px is None else rim_px
            w, h = extent_px
            whole = gait if from_top is None or top_fused else None  # the still share: of standing bodies seen whole
            s_up = self.solid.upright_y_sigma(h, whole, warped) if upright else 0.0
            if upright:  # x: its limbs and, while the cameras move (no rim contrast), the rim too
                S[0, 0] += self.solid.upright_x_var(h, swing, whole) + (rx**2 if rim_px is None else 0.0) \
                    + self.solid.upright_depth_px(disparity, self.rect.b, self.rect.f) ** 2
            else:  # x: the rim
                S[0, 0] += rx**2
            # y from the centroid: max(extra, upright) and the rim; from the top: the top's own edge and the
            # height's share, not what is hidden
            v_centroid = extra_px[1] ** 2 + ry**2 + max(s_up**2 - extra_px[1] ** 2, 0.0)
            if from_top is not None:
                v_top = self.solid.rim_sigma_px**2 + from_top[1] ** 2 + top_sigma_px**2
                if top_fused:  # the bottom inferred: both. The outline's shortfall of its stature, lost at
                    # its top or at its bottom alike, moves the top's estimate by 0 or all of it: 1-σ half of it
                    # (pan:body, frames 94-96: the head unseen by eq. (9), 8-15 rows; elevation RMSE 0.226 ->
                    # 0.206 deg, within 1σ 0.704 -> 0.746, NEES 0.88 -> 0.73)
                    short = self.solid.short_of_stature_px(h, disparity, self.rect.b,
                                                           None if stature is None else stature[0])
                    v_top += (short / 2.0) ** 2
                    y, v_top = fused((from_top[0], v_top), (y_centroid, v_centroid))
                S[1, 1] = s_c**2 + s_cy**2 + v_top
            else:
                S[1, 1] = s_c**2 + s_cy**2 + v_centroid
        X_rig = self.rect.rect_to_rig(x, y, disparity)  # eq. (2) at an upright body's centre
        J = self.rect.rig_to_rect_jacobian(x, y, disparity)
        cov_rig = J @ S @ J.T + cal.scale_rel**2 * np.outer(X_rig, X_rig)  # f·b off by ε: X -> (1 + ε) X
        if behind is not None:
            X_meas = self._behind_face(X_meas, cov_rig, behind)[0]
            X_rig, cov_rig = self._behind_face(X_rig, cov_rig, behind)
        return self._in_world(X_rig, cov_rig, X_meas, gimbal, float(np.sqrt(S[2, 2])))

    def _in_world(self, X_rig: F64, cov_rig: F64, X_meas: F64, gimbal: GimbalState | None,
                  sigma_d_px: float | None = None) -> Localization:
        """The Localization of a rig point (3,) with its covariance (3, 3) and its measured point: turned
        by the gimbal into the world frame, eq. (1)'s r, θ, φ about the origin with their 1-σ."""
        g = gimbal or GimbalState()
        R_wr = gimbal_rotation(g.pan_deg, g.tilt_deg)
        X_w = R_wr @ X_rig
        cov_w = R_wr @ cov_rig @ R_wr.T
        rel = X_w - self.origin
        r, th, ph = spherical(rel)
        Js = spherical_jacobian(rel)
        cs = Js @ cov_w @ Js.T
        sr, st, sp = (float(np.sqrt(max(cs[i, i], 0.0))) for i in range(3))
        return Localization(X_rig, X_w, cov_w, r, th, ph, sr, st, sp, R_wr @ X_meas, sigma_d_px)

    def _below_top(self, top_px: float, disparity: float, behind_px: float,
                   stature: tuple[float, float] | None = None) -> tuple[float, float]:
        """An upright body's centre's rectified y (px) from its outline's top and its 1-σ (px): c H f / Z_c
        below the top (c = centre_below_top, H = height_m ± σ_H, or that combined with the stature its
        track measured, inverse-variance weighted), Z_c = Z (1 + δ/f) the centre's depth behind the face
        seen at Z = f b / d, δ = behind_px its depth behind the face (px at Z: SolidPrior.behind_face_px of
        an upright body); 1-σ f / Z_c · √((c σ_H)² + (σ_c H)²)."""
        assert self.solid is not None
        s = self.solid
        H, s_h = s.height_m, s.height_sigma_m
        if stature is not None:
            var_m = stature[1] ** 2 + s.stature_sigma_m**2  # the outline's height is not the body's past that
            if var_m <= 0.0:  # measured exactly
                H, s_h = stature[0], 0.0
            elif s_h > 0.0:  # inverse-variance weighted with the prior (an exact prior stands)
                w_p, w_m = 1.0 / s_h**2, 1.0 / var_m
                H, s_h = (w_p * H + w_m * stature[0]) / (w_p + w_m), (w_p + w_m) ** -0.5
        f_over_z = disparity / self.rect.b / (1.0 + behind_px / self.rect.f)  # f / Z_c
        drop = s.centre_below_top * H * f_over_z
        sigma = f_over_z * float(np.hypot(s.centre_below_top * s_h, s.centre_below_top_sigma * H))
        return top_px + drop, sigma

    def _behind_face(self, X_rig: F64, cov_rig: F64, behind_px: tuple[float, float]) -> tuple[F64, F64]:
        """A solid target's centre: the measured face point X_rig (3,) moved δ Z / f behind along the
        left camera's ray through it, the variance (σ_δ Z / f)² added along that ray ((δ, σ_δ) = behind_px:
        SolidPrior.behind_face_px, pixels at the face's depth Z). The centroid of
        eq. (10) is the left image's, so the centre lies on that ray: moved along the ray from the midpoint
        of the lens centres instead, a point δ too near (the face) stayed b/2 · δ / Z² rad to the left of it
        (approach:body, a ball at 2 to 5 m: azimuth RMSE 0.137 deg; along the left ray 0.095 deg)."""
        c = self.rect.rig.left.c  # the ray eq. (10)'s centroid was measured on
        ray = X_rig - c
        dist = float(np.linalg.norm(ray))
        u = ray / dist
        m_per_px = float(X_rig[2]) / self.rect.f
        half, s_half = behind_px[0] * m_per_px, behind_px[1] * m_per_px
        return np.asarray(X_rig + half * u), np.asarray(cov_rig + s_half**2 * np.outer(u, u))


def with_gap_x(cx: float, gap_x: float, solid: SolidPrior | None, width_px: float, height_px: float) -> float:
    """The centroid's further 1-σ along x (px) with the hull gap's x term (tracker.segmentation) in quadrature,
    but for an upright body (SolidPrior.upright of its seen width and height, px): along x its notches are
    the spaces between its swinging limbs, which the SolidPrior's upright_x_var describes."""
    if solid is not None and solid.upright(width_px, height_px):
        return cx
    return float(np.hypot(cx, gap_x))
