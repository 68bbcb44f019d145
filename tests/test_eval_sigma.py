"""`tmeye eval`'s measures of the reported 1-σ (issue 12 item 1): share within 1σ and mean NEES."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tracker.evaluation import run_scenario, sigma_consistency, sigma_consistency_interval


def test_sigma_consistency_counts_and_squares() -> None:
    frac, nees = sigma_consistency([0.5, -2.0, -0.5, 1.0])
    assert frac == pytest.approx(0.75)  # |z| <= 1 counts the boundary
    assert nees == pytest.approx((0.25 + 4.0 + 0.25 + 1.0) / 4)


def test_sigma_consistency_of_honest_gaussian_errors() -> None:
    z = list(np.random.default_rng(3).standard_normal(20000))
    frac, nees = sigma_consistency(z)
    assert frac == pytest.approx(0.6827, abs=0.01)
    assert nees == pytest.approx(1.0, abs=0.03)


def test_sigma_consistency_empty_is_nan() -> None:
    assert all(math.isnan(v) for v in sigma_consistency([]))


def test_the_interval_holds_honest_figures_and_widens_with_correlated_frames() -> None:
    z = np.random.default_rng(4).standard_normal(300)
    (w_lo, w_hi), (n_lo, n_hi) = sigma_consistency_interval(list(z), block=1)
    assert w_lo < 0.6827 < w_hi and n_lo < 1.0 < n_hi
    assert sigma_consistency_interval(list(z), block=1) == ((w_lo, w_hi), (n_lo, n_hi))  # seeded
    # each draw held for 30 frames (a target's state lasting a second): 10 draws, not 300
    held = list(np.repeat(z[:10], 30))
    (a_lo, a_hi), _ = sigma_consistency_interval(held, block=1)
    (b_lo, b_hi), _ = sigma_consistency_interval(held, block=30)
    assert b_hi - b_lo > 2.0 * (a_hi - a_lo)
    assert all(math.isnan(v) for pair in sigma_consistency_interval([], block=30) for v in pair)


def test_evaluation_reports_sigma_measures() -> None:
    rep = run_scenario("approach", frames=20).to_json()
    for c in ("range", "azimuth", "elevation"):
        frac, nees = float(rep[f"{c}_within_1sigma"]), float(rep[f"{c}_nees"])  # type: ignore[arg-type]
        assert 0.0 <= frac <= 1.0
        assert nees > 0.0
        assert float(rep[f"{c}_within_1sigma_p05"]) <= frac <= float(rep[f"{c}_within_1sigma_p95"])  # type: ignore[arg-type]
        assert float(rep[f"{c}_nees_p05"]) <= float(rep[f"{c}_nees_p95"])  # type: ignore[arg-type]
