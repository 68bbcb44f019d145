"""Target motion prediction: unscented Kalman filters and an IMM over them (the `Predictor` swap point).

State (world frame, metres, seconds): s = [x, y, z, vx, vy, vz] for constant velocity (CV), plus the
horizontal turn rate ω (rad/s, about the vertical y axis) for the coordinated-turn model (CT): 7 states.
Measurement: spherical about the origin, z = [r, θ, φ] with r = |p|, θ = atan2(x, z) (azimuth),
φ = atan2(-y, hypot(x, z)) (elevation, positive up), angles in radians, each with its own 1-σ.
h(s) is non-linear, so each model is an unscented Kalman filter (filterpy's equations and sigma-point
weights, run on the stacked models at once by tracker.ukf); the IMM mixing, mode probabilities and
combination (Bar-Shalom, Li & Kirubarajan §11.6) are written out because filterpy's IMMEstimator only
mixes linear KalmanFilters. Time steps may be irregular: the process noise
and the Markov switching probabilities are functions of dt.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from enum import StrEnum
from typing import Protocol

import numpy as np

from tracker.motion import (
    F64,
    FX,
    MotionModel,
    cartesian_to_spherical,
    fx_ct,
    fx_cv,
    spherical_to_cartesian,
    wrap_angle,
)
from tracker.ukf import SigmaWeights, combine, mix, propagate, sigma_points, unscented_transform, update_spherical

__all__ = [
    "CVPredictor", "F64", "FX", "IMMPredictor", "Measurement", "MotionModel", "PredictedState", "Predictor",
    "PredictorConfig", "TrackEstimate", "TrackStatus", "UKFBankPredictor", "cartesian_to_spherical",
    "spherical_to_cartesian", "stereo_sigmas", "wrap_angle",
]


@dataclass(frozen=True)
class Measurement:
    """One detection in spherical coordinates: range r (m), azimuth θ and elevation φ (rad), with 1-σ
    uncertainties sigma_r (m), sigma_az and sigma_el (rad)."""

    r: float
    az: float
    el: float
    sigma_r: float
    sigma_az: float
    sigma_el: float

    @staticmethod
    def from_position(p: F64, sigma_r: float, sigma_az: float, sigma_el: float) -> Measurement:
        """Measurement of a triangulated world point p (3,) in metres."""
        r, az, el = cartesian_to_spherical(np.asarray(p, dtype=float))
        return Measurement(float(r), float(az), float(el), sigma_r, sigma_az, sigma_el)

    @property
    def z(self) -> F64:
        """[r, θ, φ]."""
        return np.array([self.r, self.az, self.el])

    @property
    def R(self) -> F64:
        """Measurement noise covariance diag(σ_r², σ_θ², σ_φ²), shape (3, 3)."""
        return np.diag([self.sigma_r**2, self.sigma_az**2, self.sigma_el**2])

    def position(self) -> F64:
        """The measured point in world coordinates (3,), metres."""
        return spherical_to_cartesian(self.r, self.az, self.el)

    def position_covariance(self) -> F64:
        """First-order covariance of position(): J R Jᵀ with J = ∂p/∂(r, θ, φ); shape (3, 3)."""
        r, a, e = self.r, self.az, self.el
        ca, sa, ce, se = math.cos(a), math.sin(a), math.cos(e), math.sin(e)
        J = np.array(
            [
                [ce * sa, r * ce * ca, -r * se * sa],  # ∂x/∂(r, θ, φ)
                [-se, 0.0, -r * ce],  # ∂y/∂(r, θ, φ)
                [ce * ca, -r * ce * sa, -r * se * ca],  # ∂z/∂(r, θ, φ)
            ]
        )
        return np.asarray(J @ self.R @ J.T)


def stereo_sigmas(
    r: float, focal_px: float, baseline_m: float, sigma_disparity_px: float = 0.5, sigma_px: float = 1.0
) -> tuple[float, float, float]:
    """1-σ (σ_r m, σ_θ rad, σ_φ rad) of a stereo fix at range r: r = f b / d so σ_r = r² σ_d / (f b);
    an angle from a centroid error of σ_px pixels is σ_px / f."""
    return r * r * sigma_disparity_px / (focal_px * baseline_m), sigma_px / focal_px, sigma_px / focal_px


@dataclass(frozen=True)
class PredictedState:
    """Predicted target state at time t (s): position (3,) m, velocity (3,) m/s, position covariance
    (3, 3) m², all in the world frame; velocity_covariance (3, 3) (m/s)², None when not known."""

    t: float
    position: F64
    velocity: F64
    covariance: F64
    velocity_covariance: F64 | None = None


class TrackStatus(StrEnum):
    """TRACKING: updated by the last call; COASTING: predicting without detections; LOST: no track."""

    TRACKING = "tracking"
    COASTING = "coasting"
    LOST = "lost"


@dataclass(frozen=True)
class TrackEstimate:
    """Result of `Predictor.update`. `state` is None when status is LOST. `nis` is the normalised
    innovation squared of this update (3 degrees of freedom; None when coasting or initialising).
    `mode_probabilities` are the IMM's (CV, CT), (1.0,) for a single model."""

    t: float
    status: TrackStatus
    state: PredictedState | None
    coasting_s: float
    nis: float | None
    mode_probabilities: tuple[float, ...]


class Predictor(Protocol):
    """Swap point for motion prediction. Times are seconds on the caller's clock, non-decreasing."""

    def update(self, t: float, z: Measurement | None) -> TrackEstimate:
        """Advance the track to t; z None means no detection (coast). Re-initialises on z after a loss."""
        ...

    def predict_at(self, t: float) -> PredictedState | None:
        """State at t >= the last update's time, without changing the filter; None if there is no track."""
        ...

    def nees(self, truth_position: F64) -> float:
        """Normalised estimation error squared of the last estimate's position: e P⁻¹ eᵀ (3 dof)."""
        ...

    @property
    def coasting_s(self) -> float:
        """Seconds since the last measurement was used (0 right after an update)."""
        ...

    def reset(self) -> None:
        """Drop the track."""
        ...


@dataclass(frozen=True)
class PredictorConfig:
    """Tuning shared by the predictors. init_speed_sigma (m/s) and init_turn_sigma (rad/s) are the 1-σ
    priors of an unseen velocity and turn rate; lost_after_s is the coasting time that drops the track."""

    lost_after_s: float = 1.0
    init_speed_sigma: float = 6.0
    init_turn_sigma: float = 0.5


class UKFBankPredictor:
    """Interacting multiple model (IMM) predictor over UKFs, one per `MotionModel`; with one model it is
    a plain UKF. Implements `Predictor`. Use `IMMPredictor()` or `CVPredictor()` to construct.
    The models' states are stacked, X (M, n) and P (M, n, n), and filtered together (tracker.ukf)."""

    def __init__(self, models: Sequence[MotionModel], dim: int, config: PredictorConfig | None = None):
        self.models = tuple(models)
        self.dim = dim
        self.config = config or PredictorConfig()
        self._w = SigmaWeights.merwe(dim)
        self._fx = [m.fx_batch for m in self.models]
        M = len(self.models)
        self._X = np.zeros((M, dim))
        self._P = np.tile(np.eye(dim), (M, 1, 1))
        self._mu = np.full(M, 1.0 / M)
        self._t: float | None = None  # time of the filter state
        self._t_meas = 0.0  # time of the last measurement used
        self._last: TrackEstimate | None = None
        self._Q_terms = np.stack([m.Q_terms(dim) for m in self.models], axis=1)  # (3, M, n, n)
        self._sojourn_s = np.array([m.mean_sojourn_s for m in self.models])

    # --- public API --------------------------------------------------------------------------------

    @property
    def coasting_s(self) -> float:
        return 0.0 if self._t is None else self._t - self._t_meas

    @property
    def last(self) -> TrackEstimate | None:
        """The estimate returned by the last update (None before the first)."""
        return self._last

    def reset(self) -> None:
        self._t = None
        self._mu = np.full(len(self.models), 1.0 / len(self.models))

    def update(self, t: float, z: Measurement | None) -> TrackEstimate:
        if self._t is not None and t < self._t:
            raise ValueError(f"update time {t:.6f} s is before the track's time {self._t:.6f} s")
        nis: float | None = None
        if z is None:
            if self._t is not None:
                self._step(t - self._t, None)
                self._t = t
                if t - self._t_meas > self.config.lost_after_s:
                    self.reset()
        elif self._t is None:
            self._initialise(t, z)
        else:
            nis = self._step(t - self._t, z)
            self._t = self._t_meas = t
        self._last = self._estimate(t, nis)
        return self._last

    def predict_at(self, t: float) -> PredictedState | None:
        if self._t is None:
            return None
        dt = t - self._t
        if dt < 0.0:
            raise ValueError(f"cannot predict at {t:.6f} s, before the track's time {self._t:.6f} s")
        xs, Ps, cbar = self._predict(dt)
        x, P = combine(xs, Ps, cbar)
        return PredictedState(t, x[0:3].copy(), x[3:6].copy(), P[0:3, 0:3].copy(), P[3:6, 3:6].copy())

    def nees(self, truth_position: F64) -> float:
        if self._last is None or self._last.state is None:
            raise ValueError("no estimate: the track is lost or was never initialised")
        st = self._last.state
        e = np.asarray(truth_position, dtype=float) - st.position
        return float(e @ np.linalg.solve(st.covariance, e))  # ε = eᵀ P⁻¹ e

    # --- internals ---------------------------------------------------------------------------------

    def _initialise(self, t: float, z: Measurement) -> None:
        """One-point initialisation: position from the measurement, velocity 0 ± init_speed_sigma."""
        x = np.zeros(self.dim)
        x[0:3] = z.position()
        P = np.zeros((self.dim, self.dim))
        P[0:3, 0:3] = z.position_covariance()
        P[3:6, 3:6] = np.eye(3) * self.config.init_speed_sigma**2
        if self.dim == 7:
            P[6, 6] = self.config.init_turn_sigma**2
        M = len(self.models)
        self._X, self._P = np.tile(x, (M, 1)), np.tile(P, (M, 1, 1))
        self._mu = np.full(M, 1.0 / M)
        self._t = self._t_meas = t

    def _constants(self, dt: float) -> tuple[F64, F64]:
        """The Markov matrix Π (M, M), Π[i, j] = P(mode j after dt | mode i): stay with exp(-dt/τ_i), else
        switch evenly; and the models' process noise Q (M, n, n) = C₁ dt + C₂ dt² + C₃ dt³."""
        C = self._Q_terms
        Q = C[0] * dt + C[1] * (dt * dt) + C[2] * (dt * dt * dt)
        M = len(self.models)
        if M == 1:
            return np.ones((1, 1)), Q
        stay = np.exp(-dt / self._sojourn_s)
        Pi = np.repeat(((1.0 - stay) / (M - 1))[:, None], M, axis=1)
        Pi[np.diag_indices(M)] = stay
        return Pi, Q

    def _predict(self, dt: float) -> tuple[F64, F64, F64]:
        """Mix, then predict every model by dt: means (M, n), covariances (M, n, n) and the predicted mode
        probabilities c̄ (M,)."""
        Pi, Q = self._constants(dt)
        X0, P0, cbar = mix(self._X, self._P, self._mu, Pi)
        x, P = unscented_transform(propagate(sigma_points(X0, P0, self._w), self._fx, dt), self._w, Q)
        return x, P, cbar

    def _step(self, dt: float, z: Measurement | None) -> float | None:
        """Mix, predict each model by dt, update with z (if any), update μ. Returns the NIS of the most
        probable model (None without z)."""
        x, P, cbar = self._predict(dt)
        if z is None:
            self._X, self._P = x, P
            self._mu = cbar  # no likelihood: μ_j = c̄_j
            return None
        sig = sigma_points(x, P, self._w)  # redrawn from the prior, as filterpy does: they carry Q too
        up = update_spherical(sig, x, P, z.z, z.R, self._w)
        self._X, self._P = up.X, up.P
        lw = up.log_likelihood + np.log(np.maximum(cbar, 1e-300))  # μ_j ∝ L_j c̄_j, in logs (underflow)
        mu = np.exp(lw - lw.max())
        self._mu = np.maximum(mu / mu.sum(), 1e-12)
        self._mu /= self._mu.sum()
        return float(up.nis[int(np.argmax(self._mu))])

    def _estimate(self, t: float, nis: float | None) -> TrackEstimate:
        mu = tuple(float(m) for m in self._mu)
        if self._t is None:
            return TrackEstimate(t, TrackStatus.LOST, None, 0.0, None, mu)
        x, P = combine(self._X, self._P, self._mu)
        state = PredictedState(t, x[0:3].copy(), x[3:6].copy(), P[0:3, 0:3].copy(), P[3:6, 3:6].copy())
        status = TrackStatus.TRACKING if self.coasting_s == 0.0 else TrackStatus.COASTING
        return TrackEstimate(t, status, state, self.coasting_s, nis, mu)


# Tuned on the seeded scenarios of tests/test_predict.py (targets 6-15 m away at 3-8 m/s, 30 Hz).
CV_ACCEL_PSD = 4.0  # m²/s³: the CV baseline's best compromise between straight and turning flight
IMM_CV_ACCEL_PSD = 0.5  # m²/s³: the IMM's quiet CV mode
IMM_CT_ACCEL_PSD = 0.5  # m²/s³
IMM_TURN_PSD = 0.5  # rad²/s³: how fast the turn rate may change


def CVPredictor(accel_psd: float = CV_ACCEL_PSD, config: PredictorConfig | None = None) -> UKFBankPredictor:
    """The baseline: one constant-velocity UKF (6 states) with white-acceleration psd (m²/s³)."""
    return UKFBankPredictor([MotionModel("cv", fx_cv, accel_psd)], 6, config)


def IMMPredictor(
    cv_accel_psd: float = IMM_CV_ACCEL_PSD,
    ct_accel_psd: float = IMM_CT_ACCEL_PSD,
    turn_psd: float = IMM_TURN_PSD,
    mean_sojourn_s: tuple[float, float] = (4.0, 4.0),
    config: PredictorConfig | None = None,
) -> UKFBankPredictor:
    """IMM of a constant-velocity and a coordinated-turn UKF over the 7-state [p, v, ω]."""
    cv = MotionModel("cv", fx_cv, cv_accel_psd, 0.0, mean_sojourn_s[0])
    ct = MotionModel("ct", fx_ct, ct_accel_psd, turn_psd, mean_sojourn_s[1])
    return UKFBankPredictor([cv, ct], 7, config)
