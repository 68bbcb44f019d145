"""Closed-loop evaluation (`tmeye eval --scenario manoeuvre`): the pipeline, predictor and aim controller
drive a SimulatedGimbal, and the simulated rig renders from its angles.

Two runs of the same scenario and seed: the predictive loop (IMM + AimController) and the reactive
baseline (ReactiveController, no prediction); they run side by side in two processes. Figures:
- aim zone: the target's centroid (mean of its left and right truth centroids, relative to the mean
  principal point) inside the central 10 % of the width and of the height;
- centring RMS: RMS of that offset's length, in % of the width, over frames where the target is seen;
- track losses: gaps longer than the predictor's coasting limit (1 s) without a detection on the target;
- prediction RMSE (m) at the loop's horizon (latency + lead) of the IMM and of a constant-velocity UKF
  whose acceleration psd is tuned on the same measurements (best overall RMSE over a grid), both replayed
  on the predictive run's measurements and scored against the true path, split into turn and straight
  frames (turning anywhere between capture and the predicted time);
- the usual detection figures of the predictive run (tracker.evaluation), latency of the loop.
"""

from __future__ import annotations

import math
import multiprocessing
import time
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor
from dataclasses import asdict, dataclass, field

import cv2
import numpy as np

from tracker.aim import AimConfig, AimController, ReactiveController
from tracker.closedloop import LoopConfig, ServoLoop, background_range, survey_grid, widen_background
from tracker.closedloop_path import LegPath
from tracker.evaluation import EvalReport, _Acc, _report, score_frame, target_prior
from tracker.pipeline import Pipeline
from tracker.predict import CVPredictor, IMMPredictor, Measurement, TrackStatus, UKFBankPredictor
from tracker.servo.sim import SimGimbalConfig, SimulatedGimbal
from tracker.sim import endless
from tracker.sim.render import FrameTruth
from tracker.sim.scenarios import Scenario, SimRig, get_scenario

Progress = Callable[[int, int], None]
AIM_ZONE_FRAC = 0.10  # the aim zone: central 10 % of the width and of the height
CV_PSD_GRID = (0.25, 0.5, 1.0, 2.0, 4.0, 8.0, 16.0, 32.0)  # m²/s³, searched for the tuned CV filter
WARMUP_UPDATES = 10  # predictions are scored from this many updates after a track (re)starts
SIM_LATENCY_S = 0.005  # capture-to-command latency modelled in the simulated loop (s): the budget


def closed_loop_imm() -> UKFBankPredictor:
    """The IMM of the closed loop: a manoeuvring CV mode (2 m²/s³, takes the along-track accelerations)
    and a quiet CT mode (0.25 m²/s³, turn-rate psd 0.5 rad²/s³), mean sojourn 2 s. Chosen on seed 0 of
    `manoeuvre` from a grid (CV mode 0.25-2, CT mode 0.25-2, turn 0.1-2); the library default (0.5, 0.5,
    0.5, 4 s) was tuned on faster, less manoeuvring flights."""
    return IMMPredictor(2.0, 0.25, 0.5, (2.0, 2.0))


@dataclass(frozen=True)
class PredictionSample:
    """One frame's input to the prediction replay: capture time t (s), the measurement (or None), the
    horizon (s), the true position at t + horizon (m, (3,)) and whether the target turns meanwhile."""

    t: float
    z: Measurement | None
    horizon_s: float
    truth: tuple[float, float, float]
    turning: bool


@dataclass
class RunRecord:
    """Per-run results (picklable: the reactive run comes back from another process). Offsets in % of
    the width; latencies in ms."""

    frames: int
    fps: float
    in_zone: int = 0
    offsets_pct: list[float] = field(default_factory=list)
    losses: int = 0
    commands: int = 0
    latency_ms: list[float] = field(default_factory=list)
    samples: list[PredictionSample] = field(default_factory=list)
    detection: EvalReport | None = None


@dataclass(frozen=True)
class PredictionFigures:
    """Prediction RMSE (m) at the loop's horizon: all scored frames, turn and straight frames."""

    rmse: float
    turn: float
    straight: float
    frames: int


@dataclass(frozen=True)
class ClosedLoopReport:
    """Closed-loop figures (percentages, metres, milliseconds, commands per second); `detection` holds
    the open-loop figures of the predictive run."""

    scenario: str
    seed: int
    frames: int
    aim_zone_pct: float
    centring_rms_pct: float
    track_losses: int
    servo_commands_per_s: float
    aim_zone_pct_reactive: float
    centring_rms_pct_reactive: float
    track_losses_reactive: int
    servo_commands_per_s_reactive: float
    prediction_horizon_ms: float
    imm: PredictionFigures
    cv: PredictionFigures
    cv_accel_psd: float
    latency_ms_median: float
    latency_ms_p99: float
    modelled_latency_ms: float
    detection: EvalReport
    wall_s: float

    def to_json(self) -> dict[str, object]:
        d = {k: v for k, v in asdict(self).items() if k not in ("imm", "cv", "detection")}
        d.update({"prediction_rmse_m": self.imm.rmse, "prediction_rmse_m_cv": self.cv.rmse,
                  "prediction_rmse_m_turn": self.imm.turn, "prediction_rmse_m_cv_turn": self.cv.turn,
                  "prediction_rmse_m_straight": self.imm.straight,
                  "prediction_rmse_m_cv_straight": self.cv.straight,
                  "prediction_frames": self.imm.frames,
                  "imm_vs_cv_turn": self.imm.turn / self.cv.turn,
                  "imm_vs_cv_straight": self.imm.straight / self.cv.straight})
        det = self.detection.to_json()
        for k in ("scenario", "seed", "frames"):
            det.pop(k)
        d.update(det)
        return {k: (round(v, 6) if isinstance(v, float) else v) for k, v in d.items()}


def _path(scenario: Scenario) -> Callable[[float], np.ndarray]:
    return dict(scenario.paths)[1]


def mount_range(scenario: Scenario, margin_deg: float = 4.0) -> tuple[tuple[float, float], tuple[float, float]]:
    """(pan, tilt) ranges in degrees the mount visits following the primary target: its azimuth and
    elevation over the scenario, widened by margin_deg. An endless scenario has a fixed range covering
    every direction its objects reach (tracker.sim.endless.mount_range)."""
    if scenario.endless:
        return endless.mount_range(margin_deg)
    path = _path(scenario)
    pts = np.array([path(t) for t in np.arange(0.0, scenario.frames / scenario.fps, 0.05)])
    az = np.degrees(np.arctan2(pts[:, 0], pts[:, 2]))
    el = np.degrees(np.arctan2(-pts[:, 1], np.hypot(pts[:, 0], pts[:, 2])))
    return ((float(az.min()) - margin_deg, float(az.max()) + margin_deg),
            (float(el.min()) - margin_deg, float(el.max()) + margin_deg))


def closed_loop_pipeline(sim: SimRig, scenario: Scenario) -> Pipeline:
    """A pipeline whose background is learnt over the mount's range for this scenario."""
    pipe = Pipeline(sim.rig, solid=target_prior(scenario))
    pan, tilt = mount_range(scenario)
    widen_background(pipe, *background_range(pan, tilt, sim.rig.left.size, sim.rig.left.f))
    for g in survey_grid(pan, tilt):
        pipe.learn_background(sim.background(g))
    return pipe


def _aim_offset(truth: FrameTruth, sim: SimRig) -> tuple[float, float] | None:
    """Offset (px) of the target's cyclopean centroid from the mean principal point, or None if unseen."""
    tt = truth.target(1)
    if tt is None or tt.centroid_left is None or tt.centroid_right is None:
        return None
    L, R = sim.rig.left.K, sim.rig.right.K
    c = 0.5 * (tt.centroid_left + tt.centroid_right)
    return float(c[0] - 0.5 * (L[0, 2] + R[0, 2])), float(c[1] - 0.5 * (L[1, 2] + R[1, 2]))


def run_loop(name: str, seed: int, frames: int | None, predictive: bool,
             progress: Progress | None = None, rows: list[dict[str, object]] | None = None,
             edge_samples: int = 1) -> RunRecord:
    """One closed-loop run of a scenario with the predictive or the reactive controller; rows and
    edge_samples: as tracker.evaluation.run_scenario's."""
    cv2.setNumThreads(1)
    scenario = get_scenario(name)
    sim = SimRig(scenario, seed=seed, edge_samples=edge_samples)
    pipe = closed_loop_pipeline(sim, scenario)
    w, h = sim.rig.left.size
    aim_cfg = AimConfig(frame_width_px=w, focal_px=pipe.rect.f)
    gimbal = SimulatedGimbal(SimGimbalConfig())
    ctrl = AimController(aim_cfg) if predictive else ReactiveController(aim_cfg)
    lead = gimbal.config.latency_s + gimbal.config.time_constant_s
    loop = ServoLoop(pipe, ctrl, closed_loop_imm() if predictive else None, gimbal,
                     LoopConfig(lead_s=lead, latency_s=SIM_LATENCY_S))
    path = _path(scenario)
    assert isinstance(path, LegPath)
    n = min(frames or scenario.frames, scenario.frames)
    rec = RunRecord(n, scenario.fps)
    acc = _Acc(rows=rows)
    gap, lost_after = 0, round(1.0 * scenario.fps)
    for i in range(n):
        t = i / scenario.fps
        t0 = time.perf_counter()
        sf = sim.step(gimbal.state_at(t))
        acc.render_ms.append((time.perf_counter() - t0) * 1e3)
        st = loop.step(sf.frame)
        rec.latency_ms.append(st.latency_ms)
        acc.step_ms.append(st.pipeline_ms)
        rec.commands += st.command is not None
        off = _aim_offset(sf.truth, sim)
        if off is not None:
            rec.in_zone += abs(off[0]) <= 0.5 * AIM_ZONE_FRAC * w and abs(off[1]) <= 0.5 * AIM_ZONE_FRAC * h
            rec.offsets_pct.append(100.0 * math.hypot(*off) / w)
        held = acc.detected
        score_frame(acc, st.result, sf.truth, pipe, pipe.subtractor.cfg.min_area_px)
        gap = 0 if acc.detected > held else gap + 1
        rec.losses += gap == lost_after + 1  # counted once per gap, when it exceeds the coasting limit
        hz = st.horizon_s
        truth = path(t + hz)
        rec.samples.append(PredictionSample(t, st.measurement, hz, (float(truth[0]), float(truth[1]),
                                            float(truth[2])), path.turning(t, t + hz)))
        if progress is not None:
            progress(i + 1, n)
    rec.detection = _report(name, seed, n, acc, scenario.gain, scenario.fps)
    return rec


def prediction_errors(predictor: UKFBankPredictor, samples: list[PredictionSample]
                      ) -> list[tuple[float, bool]]:
    """Replay the measurements through a predictor; (position error (m) at the horizon, turning) for
    frames with a fresh update at least WARMUP_UPDATES into the track."""
    out: list[tuple[float, bool]] = []
    updates = 0
    for s in samples:
        est = predictor.update(s.t, s.z)
        updates = 0 if est.status is TrackStatus.LOST else updates + (s.z is not None)
        if est.status is not TrackStatus.TRACKING or updates <= WARMUP_UPDATES:
            continue
        p = predictor.predict_at(s.t + s.horizon_s)
        assert p is not None
        out.append((float(np.linalg.norm(p.position - np.array(s.truth))), s.turning))
    return out


def _figures(errors: list[tuple[float, bool]]) -> PredictionFigures:
    def rms(v: list[float]) -> float:
        return float(np.sqrt(np.mean(np.square(v)))) if v else float("nan")

    return PredictionFigures(rms([e for e, _ in errors]), rms([e for e, turn in errors if turn]),
                             rms([e for e, turn in errors if not turn]), len(errors))


def tuned_cv(samples: list[PredictionSample]) -> tuple[float, PredictionFigures]:
    """The CV filter's acceleration psd (m²/s³) from CV_PSD_GRID with the lowest overall RMSE, and its
    figures."""
    best = min(((psd, _figures(prediction_errors(CVPredictor(psd), samples))) for psd in CV_PSD_GRID),
               key=lambda pf: pf[1].rmse)
    return best


def _pct(n: int, d: int) -> float:
    return 100.0 * n / max(d, 1)


def _rms(v: list[float]) -> float:
    return float(np.sqrt(np.mean(np.square(v)))) if v else float("nan")


def evaluate_closed_loop(name: str, frames: int | None = None, seed: int = 0,
                         progress: Progress | None = None, parallel: bool = True,
                         rows: list[dict[str, object]] | None = None, edge_samples: int = 1
                         ) -> ClosedLoopReport:
    """Both runs of a closed-loop scenario (the reactive one in a second process when `parallel`); rows:
    the predictive run's frames (tracker.evaluation.frame_row), as the report's detection figures are;
    edge_samples: as tracker.evaluation.run_scenario's."""
    t0 = time.perf_counter()
    if parallel:
        ctx = multiprocessing.get_context("spawn")  # a fresh interpreter: no forked OpenCV threads
        with ProcessPoolExecutor(max_workers=1, mp_context=ctx) as pool:
            fut = pool.submit(run_loop, name, seed, frames, False, None, None, edge_samples)
            main = run_loop(name, seed, frames, True, progress, rows, edge_samples)
            reactive = fut.result()
    else:
        main = run_loop(name, seed, frames, True, progress, rows, edge_samples)
        reactive = run_loop(name, seed, frames, False, edge_samples=edge_samples)
    imm = _figures(prediction_errors(closed_loop_imm(), main.samples))
    psd, cv = tuned_cv(main.samples)
    assert main.detection is not None
    dur = main.frames / main.fps
    return ClosedLoopReport(
        scenario=name, seed=seed, frames=main.frames,
        aim_zone_pct=_pct(main.in_zone, main.frames), centring_rms_pct=_rms(main.offsets_pct),
        track_losses=main.losses, servo_commands_per_s=main.commands / dur,
        aim_zone_pct_reactive=_pct(reactive.in_zone, reactive.frames),
        centring_rms_pct_reactive=_rms(reactive.offsets_pct), track_losses_reactive=reactive.losses,
        servo_commands_per_s_reactive=reactive.commands / dur,
        prediction_horizon_ms=1e3 * float(np.median([s.horizon_s for s in main.samples])),
        imm=imm, cv=cv, cv_accel_psd=psd,
        latency_ms_median=float(np.median(main.latency_ms)),
        latency_ms_p99=float(np.percentile(main.latency_ms, 99)),
        modelled_latency_ms=SIM_LATENCY_S * 1e3, detection=main.detection,
        wall_s=time.perf_counter() - t0)
