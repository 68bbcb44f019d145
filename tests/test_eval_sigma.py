"""`tmeye eval`'s measures of the reported 1-σ (issue 12 item 1): share within 1σ and mean NEES."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tracker.evaluation import run_scenario, sigma_consistency


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


def test_evaluation_reports_sigma_measures() -> None:
    rep = run_scenario("approach", frames=20).to_json()
    for c in ("range", "azimuth", "elevation"):
        frac, nees = float(rep[f"{c}_within_1sigma"]), float(rep[f"{c}_nees"])  # type: ignore[arg-type]
        assert 0.0 <= frac <= 1.0
        assert nees > 0.0
