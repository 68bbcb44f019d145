"""Accuracy of the pipeline against the simulated rig's ground truth (`tmeye eval`)."""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, field

import cv2
import numpy as np
from numpy.typing import NDArray

from tracker.detect import DetectorConfig
from tracker.frames import GimbalState
from tracker.geometry import StereoRig, gimbal_rotation
from tracker.localize import spherical
from tracker.pipeline import Pipeline
from tracker.results import Detection, FrameResult
from tracker.sim.render import FrameTruth, TargetTruth
from tracker.sim.scenarios import Scenario, SimFrame, SimRig, get_scenario
from tracker.solid_prior import SolidPrior

F64 = NDArray[np.float64]
Progress = Callable[[int, int], None]


@dataclass(frozen=True)
class EvalReport:
    """Figures of one scenario run. Angles in degrees, lengths in metres unless named _px or _pct."""

    scenario: str
    seed: int
    frames: int
    visible_frames: int
    detection_rate: float
    false_target_frames: int
    id_switches: int
    pixel_f1: float
    centroid_rmse_px: float
    disparity_rmse_px: float
    range_rmse_m: float
    range_bias_pct: float
    range_limit_m: float
    azimuth_rmse_deg: float
    elevation_rmse_deg: float
    step_ms_median: float
    render_ms_median: float
    # issue 12 item 1: how honest the reported 1-σ are, per coordinate (see sigma_consistency)
    range_within_1sigma: float = float("nan")
    range_nees: float = float("nan")
    azimuth_within_1sigma: float = float("nan")
    azimuth_nees: float = float("nan")
    elevation_within_1sigma: float = float("nan")
    elevation_nees: float = float("nan")
    extra: dict[str, float] = field(default_factory=dict)

    def to_json(self) -> dict[str, object]:
        d = asdict(self)
        extra = d.pop("extra")
        d.update(extra)
        return {k: (round(v, 6) if isinstance(v, float) else v) for k, v in d.items()}


@dataclass
class _Acc:
    """Running sums over frames."""

    visible: int = 0
    detected: int = 0
    false_target: int = 0
    id_switches: int = 0
    last_id: int | None = None
    tp: int = 0
    fp: int = 0
    fn: int = 0
    cen: list[float] = field(default_factory=list)
    disp: list[float] = field(default_factory=list)
    rng: list[float] = field(default_factory=list)
    rng_rel: list[float] = field(default_factory=list)
    limit: list[float] = field(default_factory=list)
    near: list[float] = field(default_factory=list)  # a body's nearest point's depth before its centre (m)
    az: list[float] = field(default_factory=list)
    el: list[float] = field(default_factory=list)
    # solid bodies wider than WIDE_PX: angle errors (az, el) against the volume centroid, the seen surface's
    # mean and the silhouette's point (see _wide_errors)
    wide: list[tuple[float, ...]] = field(default_factory=list)
    z_r: list[float] = field(default_factory=list)  # error / reported 1-σ, per detected frame
    z_az: list[float] = field(default_factory=list)
    z_el: list[float] = field(default_factory=list)
    f1_frames: list[float] = field(default_factory=list)
    mog2_f1: list[float] = field(default_factory=list)
    step_ms: list[float] = field(default_factory=list)
    render_ms: list[float] = field(default_factory=list)
    # one row per frame the target is visible in (`frame_row`; `tmeye eval --frames-out`), None: not kept
    rows: list[dict[str, object]] | None = None


def _rms(v: list[float]) -> float:
    return float(np.sqrt(np.mean(np.square(v)))) if v else float("nan")


def sigma_consistency(z: list[float]) -> tuple[float, float]:
    """Of normalised errors z = error / 1-σ: the fraction with |z| <= 1 (68.3 % for honest Gaussian σ)
    and the mean normalised estimation error squared, NEES = mean(z²) (1 for honest σ); nan when empty."""
    if not z:
        return float("nan"), float("nan")
    a = np.asarray(z, float)
    return float(np.mean(np.abs(a) <= 1.0)), float(np.mean(a * a))


SIGMA_INTERVAL = (5.0, 95.0)  # percentiles of sigma_consistency_interval: a 90 % interval
SIGMA_RESAMPLES = 1000


def sigma_consistency_interval(z: list[float], block: int, resamples: int = SIGMA_RESAMPLES, seed: int = 0
                               ) -> tuple[tuple[float, float], tuple[float, float]]:
    """How far `sigma_consistency`'s two figures could move by chance alone: their 5th and 95th
    percentiles ((within lo, hi), (NEES lo, hi)) over `resamples` circular moving-block bootstrap
    resamples of the frames' normalised errors z, in their order, in blocks of `block` frames. A frame's
    error is much like the next one's (the same pose, gait, occlusion for a second or so), so 300 frames
    hold far fewer independent draws; resampling whole blocks keeps that. A figure outside its acceptance
    band whose interval reaches into the band is a miss that a run of the same length could not tell from
    honest 1-σ. Seeded: the same z give the same interval. nan when z is empty."""
    if not z:
        nan = float("nan")
        return (nan, nan), (nan, nan)
    a = np.asarray(z, float)
    n = a.size
    b = max(1, min(block, n))
    rng = np.random.default_rng(seed)
    starts = rng.integers(0, n, size=(resamples, -(-n // b)))
    idx = ((starts[:, :, None] + np.arange(b)) % n).reshape(resamples, -1)[:, :n]
    draws = a[idx]
    within = np.percentile(np.mean(np.abs(draws) <= 1.0, axis=1), SIGMA_INTERVAL)
    nees = np.percentile(np.mean(draws * draws, axis=1), SIGMA_INTERVAL)
    return (float(within[0]), float(within[1])), (float(nees[0]), float(nees[1]))


WIDE_PX = 40  # the angle acceptance lines hold for targets wider than this (px)


def _deg(a: float) -> float:
    """An angle difference (rad) wrapped to (-180°, 180°], in degrees."""
    return float(np.degrees(np.angle(np.exp(1j * a))))


def _width_px(ids_left: NDArray[np.uint8], target_id: int) -> int:
    """Width (px) of a target's pixels in the left image: its last column minus its first, plus one."""
    cols = np.flatnonzero((ids_left == target_id).any(axis=0))
    return int(cols[-1] - cols[0] + 1) if cols.size else 0


def _f1(tp: int, fp: int, fn: int) -> float:
    return 2 * tp / max(2 * tp + fp + fn, 1)


def _on(det: Detection, target: TargetTruth, ids_left: NDArray[np.uint8]) -> bool:
    """Whether a detection is a true object: most of its pixels are that object's (a target split by an
    occluder counts for each part it is seen by)."""
    if target.centroid_left is None:
        return False
    x0, y0, x1, y1 = det.blob.box
    own = np.count_nonzero(ids_left[y0:y1, x0:x1][det.blob.mask] == target.target_id)
    return bool(own > 0.5 * det.blob.area)


def score_frame(acc: _Acc, res: FrameResult, truth: FrameTruth, pipe: Pipeline, min_area: int) -> None:
    """Add one frame's figures to the running sums."""
    fg_truth = truth.ids_left > 0
    fg = res.foreground_mask(fg_truth.shape)
    tp = int(np.count_nonzero(fg & fg_truth))
    fp = int(np.count_nonzero(fg & ~fg_truth))
    fn = int(np.count_nonzero(~fg & fg_truth))
    acc.tp, acc.fp, acc.fn = acc.tp + tp, acc.fp + fp, acc.fn + fn
    acc.f1_frames.append(_f1(tp, fp, fn) if tp + fp + fn else 1.0)
    tt = truth.target(1)
    # the rig sees the target when both cameras do (a target only the left camera sees has no disparity)
    visible = tt is not None and tt.centroid_left is not None and min(tt.area_left, tt.area_right) >= min_area
    prim = res.primary
    if prim is not None and not any(_on(prim, o, truth.ids_left) for o in truth.targets):
        acc.false_target += 1  # the reported primary target is on no real object
    if not visible or tt is None or tt.centroid_left is None:
        return
    acc.visible += 1
    det = next((d for d in res.detections if _on(d, tt, truth.ids_left)), None)  # target 1, by any track
    if det is None:
        if acc.rows is not None:
            acc.rows.append({"frame": res.index, "t_s": round(truth.t, 6), "detected": False})
        return
    if acc.last_id is not None and det.track_id != acc.last_id:
        acc.id_switches += 1
    acc.last_id = det.track_id
    acc.detected += 1
    rect = pipe.rect
    _, _, d_true = rect.rig_to_rect(tt.rig[None, :])
    r_t, th_t, ph_t = spherical(tt.world - pipe.localizer.origin)
    loc = det.loc
    acc.cen.append(float(np.hypot(*(det.blob.centroid_raw - tt.centroid_left))))
    acc.disp.append(det.blob.disparity - float(d_true[0]))
    acc.rng.append(loc.r - r_t)
    acc.rng_rel.append((loc.r - r_t) / r_t)
    z = float(tt.rig[2])
    acc.limit.append(z * z * 0.1 / (rect.b * rect.f))
    acc.near.append(tt.near_depth_m)
    acc.az.append(_deg(loc.theta - th_t))
    acc.el.append(float(np.degrees(loc.phi - ph_t)))
    wide = tt.surface_world is not None and _width_px(truth.ids_left, tt.target_id) > WIDE_PX
    R_wr = gimbal_rotation(truth.gimbal.pan_deg, truth.gimbal.tilt_deg)
    if wide:
        meas = loc.world if loc.measured_world is None else loc.measured_world  # no upright shift
        c = R_wr @ rect.rig.left.c  # the left lens centre, world frame
        acc.wide.append(_wide_errors(acc.az[-1], acc.el[-1], (c, meas - c), tt, pipe.localizer.origin))
    tiny = 1e-12  # a zero σ makes any error infinitely many σ
    acc.z_r.append((loc.r - r_t) / max(loc.sigma_r, tiny))
    acc.z_az.append(float(np.radians(acc.az[-1])) / max(loc.sigma_theta, tiny))
    acc.z_el.append(float(np.radians(acc.el[-1])) / max(loc.sigma_phi, tiny))
    if acc.rows is not None:
        d_seen = None  # the disparity of the mean point of the surface the left camera sees (bodies)
        if tt.surface_world is not None:
            d_seen = float(rect.rig_to_rect((R_wr.T @ tt.surface_world)[None, :])[2][0])
        acc.rows.append(frame_row(res.index, truth.t, det, (r_t, th_t, ph_t, float(d_true[0]), d_seen), acc, wide))


def frame_row(index: int, t: float, det: Detection, truth: tuple[float, float, float, float, float | None],
              acc: _Acc, wide: bool) -> dict[str, object]:
    """A detected frame's row (`tmeye eval --frames-out`): what the tracker reported with its 1-σ, the truth
    (r, θ, φ of the volume centre about the origin, its disparity, and for a body the disparity of the mean
    point of the surface the left camera sees, what the disparity measures), the errors and normalised errors
    (error / 1-σ, as `sigma_consistency` counts them), the blob (box, area, disparity, its matcher's own 1-σ
    and the whole 1-σ the range was given, the background's disparity), the centroid's distance from the
    true silhouette's (raw left px) and, where the body is wider than WIDE_PX, the angle errors against its
    seen surface and against its silhouette's ray (`_wide_errors`). Lengths m, angles deg, disparities px."""
    loc, b = det.loc, det.blob
    r_t, th_t, ph_t, d_t, d_seen = truth
    row: dict[str, object] = {
        "frame": index, "t_s": t, "detected": True, "track_id": det.track_id,
        "r_m": loc.r, "theta_deg": float(np.degrees(loc.theta)), "phi_deg": float(np.degrees(loc.phi)),
        "sigma_r_m": loc.sigma_r, "sigma_theta_deg": float(np.degrees(loc.sigma_theta)),
        "sigma_phi_deg": float(np.degrees(loc.sigma_phi)),
        "truth_r_m": r_t, "truth_theta_deg": float(np.degrees(th_t)), "truth_phi_deg": float(np.degrees(ph_t)),
        "error_r_m": acc.rng[-1], "error_azimuth_deg": acc.az[-1], "error_elevation_deg": acc.el[-1],
        "z_r": acc.z_r[-1], "z_azimuth": acc.z_az[-1], "z_elevation": acc.z_el[-1],
        "disparity_px": b.disparity, "disparity_sigma_px": b.disparity_sigma, "sigma_d_px": loc.sigma_d_px,
        "truth_disparity_px": d_t,
        "background_disparity_px": b.bg_disparity, "area_px": b.area, "box_px": [int(v) for v in b.box],
        "extent_px": list(cv2.boundingRect(b.mask.view(np.uint8))[2:]),
        "centroid_error_px": acc.cen[-1], "one_camera": b.one_camera}
    if d_seen is not None:
        row["truth_surface_disparity_px"] = d_seen
    if wide:
        row["azimuth_surface_error_deg"], row["elevation_surface_error_deg"] = acc.wide[-1][2:4]
        row["azimuth_silhouette_error_deg"], row["elevation_silhouette_error_deg"] = acc.wide[-1][4:6]
    return {k: (round(v, 6) if isinstance(v, float) else v) for k, v in row.items()}


def _wide_errors(az: float, el: float, ray: tuple[F64, F64], tt: TargetTruth, origin: F64) -> tuple[float, ...]:
    """A solid body's angle errors (deg) against three truth points: (az, el) of the reported centre against
    its volume centroid (given), then those of the measured ray (ray: the left lens centre c and a
    direction along the centroid's own ray, without a person's shift up to its volume centre; world frame,
    Localization.measured_world - c), taken at each truth point's distance from c, against the mean of the
    surface the left camera sees, Σ a_p (c + ρ_p s_p) / Σ a_p, and against
    the silhouette's point c + s̄ m̄ / |m̄| (ρ_p: unit ray of pixel p of the body's left silhouette, s_p: the
    distance to the surface along it; a_p: its area in the undistorted normalised plane; m̄: the
    silhouette's centroid (x̄_n, ȳ_n, 1) in that plane, each pixel weighted by a_p; s̄: the same mean of s_p;
    tracker.sim.render.SimRenderer.surface_mean). The tracker measures the last: eq. (10) takes the
    area-weighted centroid of the outline's pixels in rectified coordinates, whose ray is m̄'s for the true
    silhouette; the surface mean lies off that ray where the depth along the silhouette varies (it is the
    centroid weighted by depth, Σ a_p Z_p (x_n, y_n, 1)), the volume centroid where the body's
    hidden back is not its front's mirror. At the truth point's distance: the measured point lies at the
    body's centre's depth, behind the surface, and two points on one ray from the left lens, 0.15 m beside
    the mount's axis, differ in azimuth about the origin by about 0.15 m x δ / Z² (0.015° of walk:body's
    0.088° azimuth RMSE against the seen surface; the range lines judge the depth). nan where the truth
    has no such point."""
    out = [az, el]
    c, along = ray
    u = along / float(np.linalg.norm(along))
    for p in (tt.surface_world, tt.silhouette_world):
        if p is None:
            out += [float("nan"), float("nan")]
            continue
        _, th_m, ph_m = spherical(c + float(np.linalg.norm(p - c)) * u - origin)
        _, th, ph = spherical(p - origin)
        out += [_deg(th_m - th), float(np.degrees(ph_m - ph))]
    return tuple(out)


def target_prior(scenario: Scenario) -> SolidPrior | None:
    """The localiser's prior on a scenario's targets: a solid body's unseen depth (SolidPrior) for the
    `NAME:body` scenarios, none for plates (a flat board's centre is its face)."""
    return SolidPrior() if scenario.bodies else None


def run_scenario(name: str | Scenario, frames: int | None = None, seed: int = 0, rig: StereoRig | None = None,
                 detector: DetectorConfig | None = None, progress: Progress | None = None,
                 rows: list[dict[str, object]] | None = None, edge_samples: int = 1) -> EvalReport:
    """Run the pipeline on a scenario (a name, or a Scenario not in the list) and score it. `rig`: the
    calibration the pipeline uses (default: the simulator's true rig); the simulator always renders
    through its true rig. rows: a list to append a row to for each frame the target is visible in
    (`frame_row`). edge_samples: the simulator's rays a side over a pixel a body's edge crosses (1: each
    pixel's centre alone; tracker.sim.bodies.Body.cast)."""
    scenario = get_scenario(name) if isinstance(name, str) else name
    name = scenario.name
    if scenario.closed_loop:
        raise ValueError(f"scenario {name!r} is closed-loop: run it with the servo evaluation")
    sim = SimRig(scenario, seed=seed, edge_samples=edge_samples)
    pipe = Pipeline(rig or sim.rig, detector, solid=target_prior(scenario))
    for g in survey_poses(scenario):
        pipe.learn_background(sim.background(g))
    n = min(frames or scenario.frames, scenario.frames)
    acc = _Acc(rows=rows)
    min_area = pipe.subtractor.cfg.min_area_px
    # OpenCV's MOG2 on the same left images, for comparison where the light changes
    mog = cv2.createBackgroundSubtractorMOG2(detectShadows=False) if _steps(scenario.gain, n, scenario.fps) else None
    if mog is not None:
        empty = sim.background().left
        for _ in range(30):
            mog.apply(empty)
    for i in range(n):
        sf, res = timed_step(acc, sim, pipe)
        score_frame(acc, res, sf.truth, pipe, min_area)
        if mog is not None:
            truth = sf.truth.ids_left > 0
            fg = mog.apply(sf.frame.left) > 0
            acc.mog2_f1.append(_f1(int(np.count_nonzero(fg & truth)), int(np.count_nonzero(fg & ~truth)),
                                   int(np.count_nonzero(~fg & truth))))
        if progress is not None:
            progress(i + 1, n)
    return _report(name, seed, n, acc, scenario.gain, scenario.fps)


def _steps(gain: Callable[[float], float], n: int, fps: float) -> list[int]:
    """Frames at which the illumination gain jumps by more than 5 %."""
    return [i for i in range(1, n) if abs(gain(i / fps) - gain((i - 1) / fps)) > 0.05]


def timed_step(acc: _Acc, sim: SimRig, pipe: Pipeline) -> tuple[SimFrame, FrameResult]:
    """Render the next frame and step the pipeline on it, adding the render's and the step's times (ms)
    to acc's render_ms and step_ms."""
    t0 = time.perf_counter()
    sf = sim.step()
    t1 = time.perf_counter()
    res = pipe.step(sf.frame)
    acc.render_ms.append((t1 - t0) * 1e3)
    acc.step_ms.append((time.perf_counter() - t1) * 1e3)
    return sf, res


def survey_poses(scenario: Scenario) -> list[GimbalState]:
    """Gimbal poses at which the background is learnt before a run: home, plus a sweep when the
    scenario moves the cameras."""
    poses = {(round(scenario.gimbal(t).pan_deg, 3), round(scenario.gimbal(t).tilt_deg, 3))
             for t in np.arange(0.0, scenario.frames / scenario.fps, 0.5)}
    if len(poses) == 1:
        return [GimbalState(*poses.pop())]
    return [GimbalState(p, t) for p in (-16.0, -8.0, 0.0, 8.0, 16.0) for t in (-4.0, 0.0, 4.0)]


def _report(name: str, seed: int, n: int, acc: _Acc, gain: Callable[[float], float], fps: float
            ) -> EvalReport:
    extra: dict[str, float] = {}
    steps = _steps(gain, n, fps)
    if steps:
        at = [j for i in steps for j in (i, i + 1) if j < n]
        extra["pixel_f1_at_steps_min"] = float(min(acc.f1_frames[j] for j in at))
        if acc.mog2_f1:
            extra["mog2_pixel_f1_at_steps_min"] = float(min(acc.mog2_f1[j] for j in at))
            extra["mog2_pixel_f1_at_steps_mean"] = float(np.mean([acc.mog2_f1[j] for j in at]))
    if any(v > 0 for v in acc.near):  # solid bodies: the range acceptance allows their own depth
        extra["range_depth_allowance_m"] = float(np.mean(acc.near))
        extra["range_rmse_allowed_m"] = float(1.5 * np.mean(acc.limit) + np.mean(acc.near))
    if acc.wide:  # solid bodies wider than WIDE_PX: angles against the centroid, surface mean, silhouette
        w = np.asarray(acc.wide)
        extra["wide_frames"] = float(len(w))
        for k, key in enumerate(("azimuth", "elevation", "azimuth_surface", "elevation_surface",
                                 "azimuth_silhouette", "elevation_silhouette")):
            extra[f"{key}_rmse_wide_deg"] = _rms(list(w[:, k]))
    (r_in, r_nees), (a_in, a_nees), (e_in, e_nees) = (sigma_consistency(z) for z in (acc.z_r, acc.z_az, acc.z_el))
    for q, z in (("range", acc.z_r), ("azimuth", acc.z_az), ("elevation", acc.z_el)):
        if z:  # a 90 % interval of each, by a block bootstrap over one-second blocks
            (w_lo, w_hi), (n_lo, n_hi) = sigma_consistency_interval(z, max(1, round(fps)))
            extra.update({f"{q}_within_1sigma_p05": w_lo, f"{q}_within_1sigma_p95": w_hi,
                          f"{q}_nees_p05": n_lo, f"{q}_nees_p95": n_hi})
    return EvalReport(
        scenario=name, seed=seed, frames=n, visible_frames=acc.visible,
        detection_rate=acc.detected / max(acc.visible, 1), false_target_frames=acc.false_target,
        id_switches=acc.id_switches, pixel_f1=_f1(acc.tp, acc.fp, acc.fn),
        centroid_rmse_px=_rms(acc.cen), disparity_rmse_px=_rms(acc.disp), range_rmse_m=_rms(acc.rng),
        range_bias_pct=float(np.mean(acc.rng_rel) * 100) if acc.rng_rel else float("nan"),
        range_limit_m=float(np.mean(acc.limit)) if acc.limit else float("nan"),
        azimuth_rmse_deg=_rms(acc.az), elevation_rmse_deg=_rms(acc.el),
        step_ms_median=float(np.median(acc.step_ms)), render_ms_median=float(np.median(acc.render_ms)),
        range_within_1sigma=r_in, range_nees=r_nees, azimuth_within_1sigma=a_in, azimuth_nees=a_nees,
        elevation_within_1sigma=e_in, elevation_nees=e_nees, extra=extra)
