"""The batched unscented filter (tracker.ukf) against filterpy's own UnscentedKalmanFilter, step by step."""

from __future__ import annotations

import numpy as np
from filterpy.kalman import MerweScaledSigmaPoints, UnscentedKalmanFilter

from tracker.motion import fx_ct, fx_ct_batch, fx_cv, fx_cv_batch, hx_spherical
from tracker.predict import MotionModel
from tracker.ukf import SigmaWeights, combine, mix, propagate, sigma_points, unscented_transform, update_spherical


def _z_mean(sigmas: np.ndarray, Wm: np.ndarray) -> np.ndarray:
    z = np.dot(Wm, sigmas)
    z[1] = np.arctan2(np.dot(Wm, np.sin(sigmas[:, 1])), np.dot(Wm, np.cos(sigmas[:, 1])))
    return z


def _residual_z(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    y = a - b
    y[1] = (y[1] + np.pi) % (2 * np.pi) - np.pi
    return y


def _reference(fx, x: np.ndarray, P: np.ndarray, Q: np.ndarray) -> UnscentedKalmanFilter:  # type: ignore[no-untyped-def]
    pts = MerweScaledSigmaPoints(7, alpha=1.0, beta=2.0, kappa=0.0)
    ukf = UnscentedKalmanFilter(7, 3, 0.0, hx_spherical, fx, pts, z_mean_fn=_z_mean, residual_z=_residual_z)
    ukf.x, ukf.P, ukf.Q = x.copy(), P.copy(), Q.copy()
    return ukf


def test_a_step_of_two_models_equals_filterpys_filter() -> None:
    rng = np.random.default_rng(4)
    x = np.array([2.0, -0.5, 9.0, 3.0, 0.2, -4.0, 0.6])
    A = rng.normal(size=(7, 7)) * 0.1
    P = A @ A.T + np.diag([0.02, 0.02, 0.05, 1.0, 1.0, 1.0, 0.1])
    models = [MotionModel("cv", fx_cv, 2.0, 0.0), MotionModel("ct", fx_ct, 0.25, 0.5)]
    dt, w = 1.0 / 30.0, SigmaWeights.merwe(7)
    Q = np.stack([m.Q(dt, 7) for m in models])
    X, Ps = np.stack([x, x + 0.1]), np.stack([P, 1.5 * P])
    z = np.array([9.8, 0.3, 0.05])
    R = np.diag([0.05**2, 0.002**2, 0.002**2])

    xb, Pb = unscented_transform(propagate(sigma_points(X, Ps, w), [fx_cv_batch, fx_ct_batch], dt), w, Q)
    up = update_spherical(sigma_points(xb, Pb, w), xb, Pb, z, R, w)
    for j, m in enumerate(models):
        ref = _reference(m.fx, X[j], Ps[j], Q[j])
        ref.predict(dt=dt)
        assert np.allclose(xb[j], ref.x, atol=1e-12) and np.allclose(Pb[j], ref.P, atol=1e-12)
        ref.update(z, R=R)
        assert np.allclose(up.X[j], ref.x, atol=1e-10)
        assert np.allclose(up.P[j], 0.5 * (ref.P + ref.P.T), atol=1e-10)
        y = ref.y
        assert np.isclose(up.nis[j], y @ np.linalg.solve(ref.S, y), rtol=1e-9)
        assert np.isclose(up.log_likelihood[j], ref.log_likelihood, rtol=1e-9)


def test_mixing_and_combination_follow_the_imm_equations() -> None:
    rng = np.random.default_rng(1)
    X = rng.normal(size=(2, 7))
    P = np.stack([np.eye(7) * 0.5, np.eye(7) * 2.0])
    mu, Pi = np.array([0.3, 0.7]), np.array([[0.9, 0.1], [0.2, 0.8]])
    X0, P0, cbar = mix(X, P, mu, Pi)
    assert np.allclose(cbar, [0.3 * 0.9 + 0.7 * 0.2, 0.3 * 0.1 + 0.7 * 0.8])
    for j in range(2):
        wij = [Pi[i, j] * mu[i] / cbar[j] for i in range(2)]
        x0 = sum(wij[i] * X[i] for i in range(2))
        P0j = sum(wij[i] * (P[i] + np.outer(X[i] - x0, X[i] - x0)) for i in range(2))
        assert np.allclose(X0[j], x0) and np.allclose(P0[j], P0j)
    x, Pc = combine(X, P, mu)
    assert np.allclose(x, mu @ X)
    assert np.allclose(Pc, sum(mu[j] * (P[j] + np.outer(X[j] - x, X[j] - x)) for j in range(2)))
