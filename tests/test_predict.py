"""Predictors on simulated straight and turning flights with noisy spherical (stereo-like) measurements."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pytest
from scipy.stats import chi2

from tracker.predict import (
    CVPredictor,
    IMMPredictor,
    Measurement,
    TrackStatus,
    UKFBankPredictor,
    cartesian_to_spherical,
    spherical_to_cartesian,
    stereo_sigmas,
)

F64 = np.ndarray
HORIZON_S = 0.05  # prediction horizon of the acceptance figures
FOCAL_PX, BASELINE_M = 600.0, 0.30  # the simulated rig's


@dataclass(frozen=True)
class Flight:
    """Analytic truth: straight at velocity v until t_turn, then a level turn at ω (rad/s) about the
    vertical; the horizontal velocity c = vx + i vz obeys dc/dt = -iω c, so c(t) = c0 e^{-iωt}."""

    p0: F64
    v: F64
    omega: float
    t_turn: float = 1.0

    def position(self, t: float) -> F64:
        ts = min(t, self.t_turn)
        p = self.p0 + self.v * ts
        if t <= self.t_turn or self.omega == 0.0:
            return p + self.v * (t - ts)
        dt = t - self.t_turn
        c0 = complex(self.v[0], self.v[2])
        dc = c0 * (np.exp(-1j * self.omega * dt) - 1.0) / (-1j * self.omega)  # ∫ c0 e^{-iωs} ds
        return p + np.array([dc.real, self.v[1] * dt, dc.imag])


def make_flight(kind: str, rng: np.random.Generator) -> Flight:
    r0, az = rng.uniform(8.0, 12.0), rng.uniform(-0.5, 0.5)
    p0 = np.array([r0 * math.sin(az), rng.uniform(-2.0, 0.5), r0 * math.cos(az)])
    speed, heading = rng.uniform(3.0, 8.0), rng.uniform(0.0, 2.0 * math.pi)
    v = np.array([speed * math.sin(heading), rng.uniform(-0.3, 0.3), speed * math.cos(heading)])
    omega = 0.0 if kind == "straight" else float(rng.choice([-1.0, 1.0]) * rng.uniform(0.6, 1.0))
    return Flight(p0, v, omega)


def noisy(p: F64, rng: np.random.Generator) -> Measurement:
    """A stereo fix of p: σ_r from 0.5 px disparity noise, 1 px centroid noise on the angles."""
    sr, sa, se = stereo_sigmas(float(np.linalg.norm(p)), FOCAL_PX, BASELINE_M, 0.5, 1.0)
    r, az, el = cartesian_to_spherical(p)
    return Measurement(r + rng.normal() * sr, az + rng.normal() * sa, el + rng.normal() * se, sr, sa, se)


@dataclass
class RunResult:
    sq_errors: list[float]
    nees: list[float]


def fly(pred: UKFBankPredictor, kind: str, seed: int, duration: float = 5.0) -> RunResult:
    """30 Hz with ±5 ms jitter and 5 % dropped frames; scores after 1 s of settling."""
    rng = np.random.default_rng(seed)
    flight = make_flight(kind, rng)
    res = RunResult([], [])
    t = 0.0
    while t < duration:
        t += 1.0 / 30.0 + rng.uniform(-0.005, 0.005)
        p = flight.position(t)
        z = noisy(p, rng)
        dropped = rng.uniform() < 0.05 and pred.last is not None  # never drop the first frame
        est = pred.update(t, None if dropped else z)
        assert est.state is not None
        if t > 1.0:
            ps = pred.predict_at(t + HORIZON_S)
            assert ps is not None
            res.sq_errors.append(float(np.sum((ps.position - flight.position(t + HORIZON_S)) ** 2)))
            res.nees.append(pred.nees(p))
    return res


N_RUNS = 8
RUN_S = 4.0


@pytest.fixture(scope="module")
def runs() -> dict[tuple[str, str], list[RunResult]]:
    """The same seeded flights for both predictors: N_RUNS straight and N_RUNS turning, RUN_S each."""
    factories: dict[str, Callable[[], UKFBankPredictor]] = {"imm": IMMPredictor, "cv": CVPredictor}
    return {
        (name, kind): [fly(f(), kind, seed, RUN_S) for seed in range(N_RUNS)]
        for name, f in factories.items()
        for kind in ("turn", "straight")
    }


def rmse(results: list[RunResult]) -> float:
    return math.sqrt(float(np.mean([e for r in results for e in r.sq_errors])))


def test_imm_beats_cv_on_turns_and_matches_it_on_straight_lines(
    runs: dict[tuple[str, str], list[RunResult]],
) -> None:
    cv_turn, imm_turn = rmse(runs["cv", "turn"]), rmse(runs["imm", "turn"])
    cv_line, imm_line = rmse(runs["cv", "straight"]), rmse(runs["imm", "straight"])
    print(f"50 ms RMSE turn: IMM {imm_turn:.3f} CV {cv_turn:.3f}", end="; ")
    print(f"straight: IMM {imm_line:.3f} CV {cv_line:.3f}")
    assert imm_turn <= 0.8 * cv_turn
    assert imm_line <= 1.1 * cv_line
    assert imm_turn < 0.6 and imm_line < 0.6  # metres, at 8-15 m with σ_r ≈ 0.3 m


def test_nees_is_within_the_chi_square_band(runs: dict[tuple[str, str], list[RunResult]]) -> None:
    """Per-run time-averaged NEES of the 3-D position, averaged over N runs, must lie in the two-sided
    95 % band of χ²(3N)/N (the runs are independent; the usual N-run Monte Carlo band)."""
    lo, hi = chi2.ppf(0.025, 3 * N_RUNS) / N_RUNS, chi2.ppf(0.975, 3 * N_RUNS) / N_RUNS
    for key, results in runs.items():
        avg = float(np.mean([np.mean(r.nees) for r in results]))
        print(f"NEES {key}: {avg:.2f} in [{lo:.2f}, {hi:.2f}]")
        assert lo <= avg <= hi, (key, avg, lo, hi)


def _feed_straight(pred: UKFBankPredictor, t_end: float, seed: int = 1) -> Flight:
    rng = np.random.default_rng(seed)
    flight = Flight(np.array([0.0, -1.0, 10.0]), np.array([4.0, 0.0, 0.0]), 0.0)
    t = 0.0
    while t < t_end - 1e-9:
        t += 1.0 / 30.0
        pred.update(t, noisy(flight.position(t), rng))
    return flight


@pytest.mark.parametrize("factory", [IMMPredictor, CVPredictor])
def test_coasting_then_loss_then_reacquisition(factory: Callable[[], UKFBankPredictor]) -> None:
    pred = factory()
    flight = _feed_straight(pred, 2.0)
    t0 = pred.last.t if pred.last else 0.0
    cov0 = pred.predict_at(t0)
    assert cov0 is not None
    est = pred.update(t0 + 0.5, None)
    assert est.status is TrackStatus.COASTING and est.coasting_s == pytest.approx(0.5)
    assert est.state is not None
    e = est.state.position - flight.position(t0 + 0.5)  # kept flying at 4 m/s, within its covariance:
    assert e @ np.linalg.solve(est.state.covariance, e) < chi2.ppf(0.999, 3)
    assert abs(est.state.position[0] - flight.position(t0 + 0.5)[0]) < 0.5
    assert np.trace(est.state.covariance) > np.trace(cov0.covariance)  # uncertainty grows while coasting
    est = pred.update(t0 + 1.01, None)
    assert est.status is TrackStatus.LOST and est.state is None
    assert pred.predict_at(t0 + 1.2) is None
    with pytest.raises(ValueError):
        pred.nees(np.zeros(3))
    far = np.array([-5.0, 0.0, 20.0])  # re-acquired somewhere else: a fresh track starts there
    est = pred.update(t0 + 1.5, Measurement.from_position(far, 0.3, 0.002, 0.002))
    assert est.status is TrackStatus.TRACKING and est.coasting_s == 0.0
    assert est.state is not None and np.allclose(est.state.position, far, atol=1e-9)


def test_predict_at_does_not_change_the_filter() -> None:
    a, b = IMMPredictor(), IMMPredictor()
    rng_a, rng_b = np.random.default_rng(5), np.random.default_rng(5)
    flight = make_flight("turn", np.random.default_rng(9))
    for k in range(1, 40):
        t = k / 30.0
        ea = a.update(t, noisy(flight.position(t), rng_a))
        a.predict_at(t + 0.1)
        eb = b.update(t, noisy(flight.position(t), rng_b))
        assert ea.state is not None and eb.state is not None
        assert np.array_equal(ea.state.position, eb.state.position)
    ps = a.predict_at(a.last.t if a.last else 0.0)
    assert ps is not None and a.last is not None and a.last.state is not None
    assert np.allclose(ps.position, a.last.state.position)  # zero horizon returns the estimate


def test_time_going_backwards_is_refused() -> None:
    pred = CVPredictor()
    pred.update(1.0, Measurement.from_position(np.array([0.0, 0.0, 5.0]), 0.1, 0.01, 0.01))
    with pytest.raises(ValueError):
        pred.update(0.9, None)
    with pytest.raises(ValueError):
        pred.predict_at(0.5)


def test_azimuth_wraps_behind_the_mount() -> None:
    """A target crossing behind the mount (θ jumps from +π to -π) is tracked smoothly."""
    pred = IMMPredictor()
    rng = np.random.default_rng(3)
    flight = Flight(np.array([4.5, 0.0, -8.0]), np.array([-3.0, 0.0, 0.0]), 0.0)
    worst = 0.0
    for k in range(1, 61):
        t = k / 30.0
        p = flight.position(t)
        est = pred.update(t, noisy(p, rng))
        assert est.state is not None
        if t > 1.0:
            worst = max(worst, float(np.linalg.norm(est.state.position - p)))
    assert flight.position(1.0)[0] > 0.0 > flight.position(2.0)[0]  # it did cross θ = ±π
    assert worst < 0.5


def test_spherical_conversions_and_covariance() -> None:
    p = np.array([1.0, -2.0, 5.0])
    r, az, el = cartesian_to_spherical(p)
    assert el > 0.0 and az > 0.0  # up and to the right
    assert np.allclose(spherical_to_cartesian(r, az, el), p)
    z = Measurement.from_position(p, 0.2, 0.01, 0.02)
    rng = np.random.default_rng(0)
    samples = np.array(
        [
            spherical_to_cartesian(r + 0.2 * a, az + 0.01 * b, el + 0.02 * c)
            for a, b, c in rng.normal(size=(4000, 3))
        ]
    )
    assert np.allclose(np.cov(samples.T), z.position_covariance(), rtol=0.15, atol=1e-4)
