"""The unscented Kalman filter for a bank of models at once (tracker.predict's IMM), as array operations
over stacked states: means X (M, n), covariances P (M, n, n), sigma points χ (M, 2n+1, n).

The equations and weights are filterpy's (`UnscentedKalmanFilter` with `MerweScaledSigmaPoints`):

    predict:  χ = σ(x, P),  χ' = f(χ, dt),  x̄ = Σ W_m χ',  P̄ = Σ W_c (χ' - x̄)(χ' - x̄)ᵀ + Q
    update:   χ' = σ(x̄, P̄) (redrawn, as filterpy does),  Z = h(χ'),  ẑ = Σ W_m Z,
              S = Σ W_c (Z - ẑ)(Z - ẑ)ᵀ + R,  P_xz = Σ W_c (χ' - x̄)(Z - ẑ)ᵀ,
              K = P_xz S⁻¹,  x = x̄ + K (z - ẑ),  P = P̄ - K S Kᵀ

with the azimuth θ of Z averaged on the circle and its residuals wrapped. tests/test_ukf.py checks each
step against filterpy's own filter. Batched, a step of the two IMM models is about forty array operations
(filterpy's filter makes hundreds of Python calls per model): the predictor is on the capture-to-command
path of the servo loop.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from filterpy.kalman import MerweScaledSigmaPoints

from tracker.motion import F64, hx_spherical_batch

BatchFx = Callable[[F64, float], F64]
_TWO_PI = 2.0 * math.pi


@dataclass(frozen=True)
class SigmaWeights:
    """Van der Merwe's scaled sigma points for n states: weights W_m, W_c (2n+1,) and the spread
    c = λ + n = α²(n + κ) (the points are x ± columns of chol(c P))."""

    n: int
    Wm: F64
    Wc: F64
    c: float

    @staticmethod
    def merwe(n: int, alpha: float = 1.0, beta: float = 2.0, kappa: float = 0.0) -> SigmaWeights:
        """filterpy's weights. α = 1, κ = 0 (the default here) -> λ = 0: no negative weights, points at ±√n σ."""
        pts = MerweScaledSigmaPoints(n, alpha=alpha, beta=beta, kappa=kappa)
        return SigmaWeights(n, np.asarray(pts.Wm, float), np.asarray(pts.Wc, float), alpha**2 * (n + kappa))


@dataclass(frozen=True)
class Update:
    """A measurement update of every model: posterior X (M, n), P (M, n, n); the normalised innovation
    squared νᵀ S⁻¹ ν (M,) and the log-likelihood of the innovation, log N(ν; 0, S) (M,)."""

    X: F64
    P: F64
    nis: F64
    log_likelihood: F64


def symmetric(P: F64) -> F64:
    """(P + Pᵀ) / 2 over the last two axes (round-off makes covariances drift)."""
    return np.asarray(0.5 * (P + np.swapaxes(P, -1, -2)))


def sigma_points(X: F64, P: F64, w: SigmaWeights) -> F64:
    """χ (M, 2n+1, n): χ_0 = x, χ_k = x + L_k, χ_n+k = x - L_k, L_k the columns of chol((λ + n) P)."""
    L = np.linalg.cholesky(w.c * P)  # (M, n, n), L Lᵀ = (λ + n) P
    Lk = np.swapaxes(L, 1, 2)  # row k = column k of L
    x = X[:, None, :]
    return np.concatenate([x, x + Lk, x - Lk], axis=1)


def propagate(sigmas: F64, fxs: Sequence[BatchFx], dt: float) -> F64:
    """χ' = f_j(χ_j, dt) for each model j: (M, 2n+1, n) -> (M, 2n+1, n)."""
    return np.stack([fx(s, dt) for fx, s in zip(fxs, sigmas, strict=True)])


def unscented_transform(sigmas: F64, w: SigmaWeights, Q: F64) -> tuple[F64, F64]:
    """x̄ = Σ W_m χ' (M, n) and P̄ = Σ W_c (χ' - x̄)(χ' - x̄)ᵀ + Q (M, n, n)."""
    x = w.Wm @ sigmas
    D = sigmas - x[:, None, :]
    return x, np.swapaxes(D * w.Wc[:, None], 1, 2) @ D + Q


def _wrap(a: F64) -> F64:
    return np.asarray((a + math.pi) % _TWO_PI - math.pi)


def update_spherical(sigmas: F64, x: F64, P: F64, z: F64, R: F64, w: SigmaWeights) -> Update:
    """The update of every model with one measurement z = [r, θ, φ] (3,) of covariance R (3, 3), from
    the prior x̄ (M, n), P̄ (M, n, n) and its sigma points χ' = σ(x̄, P̄) (M, 2n+1, n)."""
    M, K, n = sigmas.shape
    Z = hx_spherical_batch(sigmas.reshape(M * K, n)).reshape(M, K, 3)  # Z = h(χ')
    zp = w.Wm @ Z  # ẑ = Σ W_m Z ...
    zp[:, 1] = np.arctan2(w.Wm @ np.sin(Z[:, :, 1].T), w.Wm @ np.cos(Z[:, :, 1].T))  # ... θ on the circle
    dz = Z - zp[:, None, :]
    dz[:, :, 1] = _wrap(dz[:, :, 1])
    WdzT = np.swapaxes(dz * w.Wc[:, None], 1, 2)  # (M, 3, K)
    S = WdzT @ dz + R  # S = Σ W_c (Z - ẑ)(Z - ẑ)ᵀ + R
    Pxz = np.swapaxes((sigmas - x[:, None, :]) * w.Wc[:, None], 1, 2) @ dz  # P_xz (M, n, 3)
    SI = np.linalg.inv(S)
    Kg = Pxz @ SI  # K = P_xz S⁻¹
    y = z[None, :] - zp  # ν = z - ẑ
    y[:, 1] = _wrap(y[:, 1])
    X = x + (Kg @ y[:, :, None])[:, :, 0]  # x = x̄ + K ν
    P_post = P - Kg @ S @ np.swapaxes(Kg, 1, 2)  # P = P̄ - K S Kᵀ
    nis = np.einsum("mi,mij,mj->m", y, SI, y)  # ε_ν = νᵀ S⁻¹ ν
    logdet = np.linalg.slogdet(_TWO_PI * S)[1]
    return Update(X, symmetric(P_post), nis, -0.5 * (nis + logdet))


def mix(X: F64, P: F64, mu: F64, Pi: F64) -> tuple[F64, F64, F64]:
    """IMM interaction (Bar-Shalom, Li & Kirubarajan §11.6) of M models: predicted mode probabilities
    c̄_j = Σ_i Π_ij μ_i (M,); mixing weights μ_i|j = Π_ij μ_i / c̄_j; mixed means x0_j = Σ_i μ_i|j x_i
    (M, n) and covariances P0_j = Σ_i μ_i|j [P_i + (x_i - x0_j)(x_i - x0_j)ᵀ] (M, n, n)."""
    cbar = mu @ Pi
    W = Pi * mu[:, None] / cbar[None, :]  # W[i, j] = μ_i|j
    X0 = W.T @ X
    D = X[None, :, :] - X0[:, None, :]  # D[j, i] = x_i - x0_j
    M, n = X.shape
    P0 = (W.T @ P.reshape(M, n * n)).reshape(M, n, n) + np.swapaxes(D * W.T[:, :, None], 1, 2) @ D
    return X0, symmetric(P0), cbar


def combine(X: F64, P: F64, mu: F64) -> tuple[F64, F64]:
    """IMM output: x = Σ_j μ_j x_j (n,), P = Σ_j μ_j [P_j + (x_j - x)(x_j - x)ᵀ] (n, n)."""
    x = mu @ X
    D = X - x
    n = X.shape[1]
    return x, (mu @ P.reshape(len(mu), n * n)).reshape(n, n) + (D * mu[:, None]).T @ D
