"""Target motion prediction: unscented Kalman filters and an IMM over them (the `Predictor` swap point).

State (world frame, metres, seconds): s = [x, y, z, vx, vy, vz] for constant velocity (CV), plus the
horizontal turn rate ω (rad/s, about the vertical y axis) for the coordinated-turn model (CT): 7 states.
Measurement: spherical about the origin, z = [r, θ, φ] with r = |p|, θ = atan2(x, z) (azimuth),
φ = atan2(-y, hypot(x, z)) (elevation, positive up), angles in radians, each with its own 1-σ.
h(s) is non-linear, so each model runs a filterpy UnscentedKalmanFilter; the IMM mixing, mode
probabilities and combination (Bar-Shalom, Li & Kirubarajan §11.6) are written out here because
filterpy's IMMEstimator only mixes linear KalmanFilters. Time steps may be irregular: the process noise
and the Markov switching probabilities are functions of dt.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from enum import StrEnum
from typing import Protocol

import numpy as np
import scipy.linalg
from filterpy.kalman import MerweScaledSigmaPoints, UnscentedKalmanFilter, unscented_transform
from numpy.typing import NDArray

F64 = NDArray[np.float64]
FX = Callable[[F64, float], F64]


def wrap_angle(a: float) -> float:
    """Angle in radians wrapped to [-π, π)."""
    return (a + math.pi) % (2.0 * math.pi) - math.pi


def cartesian_to_spherical(p: F64) -> F64:
    """World point (3,) in metres -> [r (m), θ (rad), φ (rad)]."""
    x, y, z = float(p[0]), float(p[1]), float(p[2])
    return np.array([math.sqrt(x * x + y * y + z * z), math.atan2(x, z), math.atan2(-y, math.hypot(x, z))])


def spherical_to_cartesian(r: float, az: float, el: float) -> F64:
    """[r, θ, φ] -> world point (3,): x = r cosφ sinθ, y = -r sinφ, z = r cosφ cosθ."""
    return np.array([r * math.cos(el) * math.sin(az), -r * math.sin(el), r * math.cos(el) * math.cos(az)])


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
    (3, 3) m², all in the world frame."""

    t: float
    position: F64
    velocity: F64
    covariance: F64


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


# --- motion models ---------------------------------------------------------------------------------


def fx_cv(s: F64, dt: float) -> F64:
    """Constant velocity: p' = p + v dt, v' = v; a turn-rate state (if any) is carried unchanged."""
    out = s.copy()
    out[0:3] = s[0:3] + s[3:6] * dt  # p_k+1 = p_k + v_k dt
    return out


def fx_ct(s: F64, dt: float) -> F64:
    """Coordinated turn at rate ω = s[6] (rad/s) in the horizontal x-z plane, constant vertical velocity:
    the horizontal velocity rotates by ωdt (dvx/dt = ω vz, dvz/dt = -ω vx)."""
    out = s.copy()
    vx, vz, w = s[3], s[5], s[6]
    wt = w * dt
    if abs(wt) < 1e-6:
        a, b = dt, 0.5 * w * dt * dt  # limits of sin(ωT)/ω and (1 - cos ωT)/ω as ω -> 0
    else:
        a, b = math.sin(wt) / w, (1.0 - math.cos(wt)) / w
    c, sn = math.cos(wt), math.sin(wt)
    out[0] = s[0] + a * vx + b * vz  # x' = x + sin(ωT)/ω vx + (1-cos ωT)/ω vz
    out[1] = s[1] + s[4] * dt  # y' = y + vy T
    out[2] = s[2] - b * vx + a * vz  # z' = z - (1-cos ωT)/ω vx + sin(ωT)/ω vz
    out[3] = c * vx + sn * vz  # vx' = cos ωT vx + sin ωT vz
    out[5] = -sn * vx + c * vz  # vz' = -sin ωT vx + cos ωT vz
    return out


def fx_cv_batch(S: F64, dt: float) -> F64:
    """fx_cv for many states at once: S (N, n) -> (N, n)."""
    out = S.copy()
    out[:, 0:3] += S[:, 3:6] * dt
    return out


def fx_ct_batch(S: F64, dt: float) -> F64:
    """fx_ct for many states at once: S (N, 7) -> (N, 7)."""
    out = S.copy()
    vx, vz, w = S[:, 3], S[:, 5], S[:, 6]
    wt = w * dt
    small = np.abs(wt) < 1e-6
    w_safe = np.where(small, 1.0, w)
    a = np.where(small, dt, np.sin(wt) / w_safe)  # sin(ωT)/ω -> T
    b = np.where(small, 0.5 * w * dt * dt, (1.0 - np.cos(wt)) / w_safe)  # (1 - cos ωT)/ω -> ωT²/2
    c, sn = np.cos(wt), np.sin(wt)
    out[:, 0] = S[:, 0] + a * vx + b * vz
    out[:, 1] = S[:, 1] + S[:, 4] * dt
    out[:, 2] = S[:, 2] - b * vx + a * vz
    out[:, 3] = c * vx + sn * vz
    out[:, 5] = -sn * vx + c * vz
    return out


def hx_spherical_batch(S: F64) -> F64:
    """h for many states: S (N, n) -> (N, 3) of [r, θ, φ]."""
    x, y, z = S[:, 0], S[:, 1], S[:, 2]
    rho = np.hypot(x, z)
    return np.stack([np.sqrt(rho * rho + y * y), np.arctan2(x, z), np.arctan2(-y, rho)], axis=1)


class _FastUKF(UnscentedKalmanFilter):  # type: ignore[misc]
    """filterpy's UKF with the per-sigma-point Python loops replaced by array operations (the same
    equations: χ' = f(χ), Z = h(χ'), P_xz = Σ W_c (χ' - x)(Z - z)ᵀ)."""

    x: F64
    P: F64

    def __init__(self, dim_x: int, fx_batch: Callable[[F64, float], F64], *args: object, **kw: object):
        super().__init__(dim_x, *args, **kw)
        self.fx_batch = fx_batch

    def compute_process_sigmas(self, dt: float, fx: object = None, **fx_args: object) -> None:
        self.sigmas_f = self.fx_batch(self.points_fn.sigma_points(self.x, self.P), dt)

    def cross_variance(self, x: F64, z: F64, sigmas_f: F64, sigmas_h: F64) -> F64:
        dx = sigmas_f - x
        dz = sigmas_h - z
        dz[:, 1] = (dz[:, 1] + math.pi) % (2.0 * math.pi) - math.pi  # θ wrapped
        return np.asarray((self.Wc[:, None] * dx).T @ dz)

    def update(self, z: F64, R: F64 | None = None, UT: object = None, hx: object = None, **hx_args: object
               ) -> None:
        R = self.R if R is None else R
        self.sigmas_h = hx_spherical_batch(self.sigmas_f)
        zp = self.z_mean(self.sigmas_h, self.Wm)  # ẑ = Σ W_m Z (θ by its circular mean)
        dz = self.sigmas_h - zp
        dz[:, 1] = (dz[:, 1] + math.pi) % (2.0 * math.pi) - math.pi
        self.S = (self.Wc[:, None] * dz).T @ dz + R  # S = Σ W_c (Z - ẑ)(Z - ẑ)ᵀ + R
        self.SI = self.inv(self.S)
        Pxz = self.cross_variance(self.x, zp, self.sigmas_f, self.sigmas_h)
        self.K = Pxz @ self.SI  # Kalman gain
        self.y = self.residual_z(z, zp)  # residual
        self.x = self.x + self.K @ self.y
        self.P = self.P - self.K @ self.S @ self.K.T
        self.z = np.array(z, copy=True)
        self.x_post, self.P_post = self.x.copy(), self.P.copy()
        self._log_likelihood = self._likelihood = self._mahalanobis = None


def q_white_accel(dt: float, psd: float) -> F64:
    """Process noise (6, 6) of continuous white acceleration with spectral density psd (m²/s³) per axis:
    per axis [[dt³/3, dt²/2], [dt²/2, dt]] psd, ordered [x, y, z, vx, vy, vz]."""
    Q = np.zeros((6, 6))
    i = np.arange(3)
    Q[i, i] = psd * dt**3 / 3.0  # position variance
    Q[i, i + 3] = Q[i + 3, i] = psd * dt**2 / 2.0  # position-velocity covariance
    Q[i + 3, i + 3] = psd * dt  # velocity variance
    return Q


def hx_spherical(s: F64) -> F64:
    """Measurement function h(s) = [r, θ, φ] of the position s[0:3]."""
    return cartesian_to_spherical(s[0:3])


def _residual_z(a: F64, b: F64) -> F64:
    """z residual with θ wrapped to [-π, π) (φ stays within ±π/2)."""
    y = a - b
    y[1] = wrap_angle(float(y[1]))
    return y


def _z_mean(sigmas: F64, Wm: F64) -> F64:
    """Weighted mean of measurement sigma points; θ by its circular mean so ±π does not average to 0."""
    z: F64 = np.asarray(np.dot(Wm, sigmas), dtype=float)
    z[1] = math.atan2(float(np.dot(Wm, np.sin(sigmas[:, 1]))), float(np.dot(Wm, np.cos(sigmas[:, 1]))))
    return z


@dataclass(frozen=True)
class MotionModel:
    """One model of the bank: transition fx(s, dt), white-acceleration psd (m²/s³), turn-rate random-walk
    psd (rad²/s³, only used with 7 states) and the mean time (s) the target stays in this mode."""

    name: str
    fx: FX
    accel_psd: float
    turn_psd: float = 0.0
    mean_sojourn_s: float = 4.0

    @property
    def fx_batch(self) -> Callable[[F64, float], F64]:
        """fx over many states at once, (N, n) -> (N, n)."""
        return _BATCH.get(self.fx, lambda S, dt: np.array([self.fx(s, dt) for s in S]))

    def Q(self, dt: float, dim: int) -> F64:
        """Process noise (dim, dim) for a step of dt seconds."""
        Q = np.zeros((dim, dim))
        Q[:6, :6] = q_white_accel(dt, self.accel_psd)
        if dim == 7:
            Q[6, 6] = self.turn_psd * dt  # random-walk turn rate: var grows as psd·dt
        return Q


@dataclass(frozen=True)
class PredictorConfig:
    """Tuning shared by the predictors. init_speed_sigma (m/s) and init_turn_sigma (rad/s) are the 1-σ
    priors of an unseen velocity and turn rate; lost_after_s is the coasting time that drops the track."""

    lost_after_s: float = 1.0
    init_speed_sigma: float = 6.0
    init_turn_sigma: float = 0.5


class _FastMerwe(MerweScaledSigmaPoints):  # type: ignore[misc]
    """Van der Merwe's sigma points, built with array operations: χ_0 = x, χ_±k = x ± U_k,
    U = chol((λ + n) P) (upper triangular, rows k)."""

    def sigma_points(self, x: F64, P: F64) -> F64:
        lam = self.alpha**2 * (self.n + self.kappa) - self.n  # λ = α²(n + κ) - n
        U = scipy.linalg.cholesky((lam + self.n) * P)  # upper: UᵀU = (λ + n) P
        return np.vstack([x, x + U, x - U])


def _sigma_points(n: int) -> MerweScaledSigmaPoints:
    # α = 1, κ = 0 -> λ = 0: no negative weights, points at ±√n σ.
    return _FastMerwe(n, alpha=1.0, beta=2.0, kappa=0.0)


class UKFBankPredictor:
    """Interacting multiple model (IMM) predictor over UKFs, one per `MotionModel`; with one model it is
    a plain UKF. Implements `Predictor`. Use `IMMPredictor()` or `CVPredictor()` to construct."""

    def __init__(self, models: Sequence[MotionModel], dim: int, config: PredictorConfig | None = None):
        self.models = tuple(models)
        self.dim = dim
        self.config = config or PredictorConfig()
        pts = _sigma_points(dim)
        self._ukfs = [
            _FastUKF(dim, m.fx_batch, 3, 0.0, hx_spherical, m.fx, pts, z_mean_fn=_z_mean, residual_z=_residual_z)
            for m in self.models
        ]
        self._mu = np.full(len(self.models), 1.0 / len(self.models))
        self._t: float | None = None  # time of the filter state
        self._t_meas = 0.0  # time of the last measurement used
        self._last: TrackEstimate | None = None

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
        xs0, Ps0, cbar = self._mix(dt)
        xs, Ps = [], []
        for m, ukf, x0, P0 in zip(self.models, self._ukfs, xs0, Ps0, strict=True):
            sig = ukf.points_fn.sigma_points(x0, P0)
            sig_f = m.fx_batch(sig, dt)
            x, P = unscented_transform(sig_f, ukf.Wm, ukf.Wc, m.Q(dt, self.dim))
            xs.append(x)
            Ps.append(P)
        x, P = _combine(xs, Ps, cbar)
        return PredictedState(t, x[0:3].copy(), x[3:6].copy(), P[0:3, 0:3].copy())

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
        for ukf in self._ukfs:
            ukf.x, ukf.P = x.copy(), P.copy()
        self._mu = np.full(len(self.models), 1.0 / len(self.models))
        self._t = self._t_meas = t

    def _transition(self, dt: float) -> F64:
        """Markov matrix Π[i, j] = P(mode j after dt | mode i): stay with exp(-dt/τ_i), else switch evenly."""
        M = len(self.models)
        if M == 1:
            return np.ones((1, 1))
        Pi = np.empty((M, M))
        for i, m in enumerate(self.models):
            stay = math.exp(-dt / m.mean_sojourn_s)
            Pi[i, :] = (1.0 - stay) / (M - 1)
            Pi[i, i] = stay
        return Pi

    def _mix(self, dt: float) -> tuple[list[F64], list[F64], F64]:
        """IMM interaction: mixed initial states/covariances per model and predicted mode probabilities."""
        Pi = self._transition(dt)
        cbar = self._mu @ Pi  # c̄_j = Σ_i Π_ij μ_i
        w = Pi * self._mu[:, None] / cbar[None, :]  # μ_i|j = Π_ij μ_i / c̄_j
        xs = [u.x for u in self._ukfs]
        Ps = [u.P for u in self._ukfs]
        xs0, Ps0 = [], []
        for j in range(len(self.models)):
            x0 = sum(w[i, j] * xs[i] for i in range(len(xs)))  # x0_j = Σ_i μ_i|j x_i
            P0 = sum(
                w[i, j] * (Ps[i] + np.outer(xs[i] - x0, xs[i] - x0)) for i in range(len(xs))
            )  # P0_j = Σ_i μ_i|j [P_i + (x_i - x0_j)(x_i - x0_j)ᵀ]
            xs0.append(np.asarray(x0))
            Ps0.append(np.asarray(P0))
        return xs0, Ps0, cbar

    def _step(self, dt: float, z: Measurement | None) -> float | None:
        """Mix, predict each model by dt, update with z (if any), update μ. Returns the NIS of the most
        probable model (None without z)."""
        xs0, Ps0, cbar = self._mix(dt)
        logL = np.zeros(len(self.models))
        nis = np.zeros(len(self.models))
        for j, (m, ukf) in enumerate(zip(self.models, self._ukfs, strict=True)):
            ukf.x, ukf.P = xs0[j], _sym(Ps0[j])
            ukf.Q = m.Q(dt, self.dim)
            ukf.predict(dt=dt)
            if z is not None:
                ukf.update(z.z, R=z.R)
                ukf.P = _sym(ukf.P)
                nis[j] = float(ukf.y @ ukf.SI @ ukf.y)  # ε_ν = νᵀ S⁻¹ ν
                logL[j] = -0.5 * (nis[j] + float(np.linalg.slogdet(2.0 * math.pi * ukf.S)[1]))
        if z is None:
            self._mu = cbar  # no likelihood: μ_j = c̄_j
            return None
        lw = logL + np.log(np.maximum(cbar, 1e-300))  # μ_j ∝ L_j c̄_j, in logs to avoid underflow
        mu = np.exp(lw - lw.max())
        self._mu = np.maximum(mu / mu.sum(), 1e-12)
        self._mu /= self._mu.sum()
        return float(nis[int(np.argmax(self._mu))])

    def _estimate(self, t: float, nis: float | None) -> TrackEstimate:
        mu = tuple(float(m) for m in self._mu)
        if self._t is None:
            return TrackEstimate(t, TrackStatus.LOST, None, 0.0, None, mu)
        x, P = _combine([u.x for u in self._ukfs], [u.P for u in self._ukfs], self._mu)
        state = PredictedState(t, x[0:3].copy(), x[3:6].copy(), P[0:3, 0:3].copy())
        status = TrackStatus.TRACKING if self.coasting_s == 0.0 else TrackStatus.COASTING
        return TrackEstimate(t, status, state, self.coasting_s, nis, mu)


def _sym(P: F64) -> F64:
    """Symmetrise a covariance (round-off in the UKF update makes it drift)."""
    return np.asarray(0.5 * (P + P.T))


def _combine(xs: Sequence[F64], Ps: Sequence[F64], mu: F64) -> tuple[F64, F64]:
    """IMM output: x = Σ_j μ_j x_j, P = Σ_j μ_j [P_j + (x_j - x)(x_j - x)ᵀ]."""
    x = np.asarray(sum(m * xj for m, xj in zip(mu, xs, strict=True)))
    P = sum(m * (Pj + np.outer(xj - x, xj - x)) for m, xj, Pj in zip(mu, xs, Ps, strict=True))
    return x, np.asarray(P)


_BATCH: dict[FX, Callable[[F64, float], F64]] = {fx_cv: fx_cv_batch, fx_ct: fx_ct_batch}

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
