"""Motion models of tracker.predict: transitions f(s, dt), process noise Q and the measurement h(s).

State (world frame, metres, seconds): s = [x, y, z, vx, vy, vz] (+ ω, the horizontal turn rate in rad/s).
Measurement h(s) = [r, θ, φ]: range, azimuth atan2(x, z) and elevation atan2(-y, hypot(x, z)).
Each function has a batch form over sigma points (N, n) so the filter runs without per-point loops.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
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


def hx_spherical(s: F64) -> F64:
    """Measurement function h(s) = [r, θ, φ] of the position s[0:3]."""
    return cartesian_to_spherical(s[0:3])


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

    def Q_terms(self, dim: int) -> F64:
        """(3, dim, dim) C₁, C₂, C₃ with Q(dt) = C₁ dt + C₂ dt² + C₃ dt³: continuous white acceleration of
        spectral density psd per axis gives [[dt³/3, dt²/2], [dt²/2, dt]] psd for each (position, velocity)
        pair, ordered [x, y, z, vx, vy, vz]; a random-walk turn rate ω (7 states) gives psd_ω dt."""
        C = np.zeros((3, dim, dim))
        i = np.arange(3)
        C[2, i, i] = self.accel_psd / 3.0  # position variance, × dt³
        C[1, i, i + 3] = C[1, i + 3, i] = self.accel_psd / 2.0  # position-velocity covariance, × dt²
        C[0, i + 3, i + 3] = self.accel_psd  # velocity variance, × dt
        if dim == 7:
            C[0, 6, 6] = self.turn_psd  # turn-rate variance grows as psd·dt
        return C

    def Q(self, dt: float, dim: int) -> F64:
        """Process noise (dim, dim) for a step of dt seconds."""
        C = self.Q_terms(dim)
        return np.asarray(C[0] * dt + C[1] * dt**2 + C[2] * dt**3)


_BATCH: dict[FX, Callable[[F64, float], F64]] = {fx_cv: fx_cv_batch, fx_ct: fx_ct_batch}
