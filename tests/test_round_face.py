"""Which part of a round body's face its disparity measures (tracker.round_face): a ball wider than the
central window is matched on its middle, which stands out towards the cameras, and any ball on its core,
which leaves out the deepest rim; the centre's depth behind the face measured grows by as much."""

from __future__ import annotations

import math

import numpy as np

from tracker.evaluation import run_scenario
from tracker.round_face import matched_factor
from tracker.solid_prior import SolidPrior
from tracker.strips import MATCH_HALF

FAR = 1e9  # a focal length (px) at which perspective vanishes


def _disc(radius: float) -> np.ndarray:
    n = int(2 * radius) + 6
    ys, xs = np.mgrid[0:n, 0:n]
    c = n / 2.0
    return np.asarray((xs + 0.5 - c) ** 2 + (ys + 0.5 - c) ** 2 <= radius * radius)


def _mean_height(radius: float, half_x: float, half_y: float, n: int = 801) -> float:
    """The mean of √(1 - r²/R²) over the rectangle |x| <= half_x, |y| <= half_y (within the disc),
    integrated on a fine grid: the unit sphere's height over what is matched."""
    x = np.linspace(-half_x, half_x, n)
    y = np.linspace(-half_y, half_y, n)
    X, Y = np.meshgrid(x, y)
    return float(np.sqrt(np.clip(1.0 - (X * X + Y * Y) / radius**2, 0.0, None)).mean())


def test_a_ball_wider_than_the_window_is_matched_on_its_middle() -> None:
    # a ball 120 px across (0.6 m at 3 m): the 48 x 32 px window holds its middle, whose mean height is
    # 0.96 R against the disc's 2R/3
    k = matched_factor(_disc(60.0), FAR)
    assert math.isclose(k, _mean_height(60.0, *MATCH_HALF) / (2.0 / 3.0), rel_tol=0.015)
    assert k > 1.4


def test_a_ball_inside_the_window_loses_only_its_rim() -> None:
    # 35 px across: all of it in the window; the core, a pixel in, leaves out the rim, the deepest part:
    # over a disc of radius R - 1 the mean of √(R² - r²) is 2/3 (R³ - (2R - 1)^{3/2}) / (R - 1)²
    R = 17.5
    inner = 2.0 / 3.0 * (R**3 - (2.0 * R - 1.0) ** 1.5) / (R - 1.0) ** 2
    k = matched_factor(_disc(R), FAR)
    assert math.isclose(k, inner / (2.0 * R / 3.0), rel_tol=0.03)
    assert 1.03 < k < 1.2
    # growing it past the window moves the face measured further out
    ks = [matched_factor(_disc(r), FAR) for r in (17.5, 30.0, 45.0, 60.0)]
    assert ks == sorted(ks)


def test_a_near_sphere_is_placed_by_its_face_seen_in_perspective() -> None:
    # a sphere of radius R at distance D = 10 R straight ahead, drawn by a pinhole of focal length f: each
    # pixel's ray meets it at depth z; the disparity matched is the mean of 1/z over the core's pixels in the
    # window, the face Z_m = 1 / mean(1/z); the prior puts the centre (2/3) tan a Z_m behind it, the factor
    # makes that D - Z_m
    f, D, R = 600.0, 10.0, 1.0
    n = 200
    ys, xs = np.mgrid[0:n, 0:n]
    u, v = (xs + 0.5 - n / 2) / f, (ys + 0.5 - n / 2) / f
    d = np.stack([u, v, np.ones_like(u)], -1)
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    b = d[..., 2] * D
    disc = b * b - (D * D - R * R)
    mask = disc >= 0.0
    z = (b - np.sqrt(np.where(mask, disc, 0.0))) * d[..., 2]  # the first hit's depth
    rows, cols = np.nonzero(mask)
    mask = mask[rows.min():rows.max() + 1, cols.min():cols.max() + 1]
    z = z[rows.min():rows.max() + 1, cols.min():cols.max() + 1]
    h, w = mask.shape
    core = np.zeros_like(mask)
    core[1:-1, 1:-1] = mask[:-2, 1:-1] & mask[2:, 1:-1] & mask[1:-1, :-2] & mask[1:-1, 2:] & mask[1:-1, 1:-1] \
        & mask[:-2, :-2] & mask[:-2, 2:] & mask[2:, :-2] & mask[2:, 2:]
    yy, xx = np.mgrid[0:h, 0:w]
    core &= (np.abs(xx + 0.5 - w / 2) <= MATCH_HALF[0]) & (np.abs(yy + 0.5 - h / 2) <= MATCH_HALF[1])
    z_m = 1.0 / float(np.mean(1.0 / z[core]))
    tan_a = 0.5 * float(min(w, h)) / f
    k = matched_factor(mask, f)
    assert math.isclose(k * 2.0 / 3.0 * tan_a * z_m, D - z_m, rel_tol=0.01)
    assert k > matched_factor(mask, FAR) * 1.05  # perspective adds to the window's and the core's


def test_the_factor_is_over_the_priors_own_ratio() -> None:
    mask = _disc(45.0)
    k = matched_factor(mask, 600.0)
    assert k > 1.0
    assert math.isclose(matched_factor(mask, 600.0, ratio=1.0 / 3.0), 2.0 * k, rel_tol=1e-9)


def test_an_outline_too_small_to_tell_changes_nothing() -> None:
    assert matched_factor(np.zeros((5, 5), bool), 600.0) == 1.0
    one = np.zeros((5, 5), bool)
    one[2, 2] = True
    assert matched_factor(one, 600.0) == 1.0


def test_only_a_round_bodys_depth_behind_its_face_takes_the_factor() -> None:
    p = SolidPrior()
    base = p.behind_face_px(60.0, 60.0)
    assert np.allclose(p.behind_face_px(60.0, 60.0, matched=1.3), (1.3 * base[0], 1.3 * base[1]))
    for w, h in ((40.0, 120.0), (200.0, 60.0)):  # upright (a person), wide (a vehicle): their own priors
        assert p.behind_face_px(w, h, matched=1.3) == p.behind_face_px(w, h)


def test_a_near_ball_is_ranged_at_its_centre() -> None:
    # approach:body: a ball 0.6 m across from 30 m to 2 m. At 2 to 4 m, matched on its middle and placed
    # 2R/3 behind that, it was 3.5 % too near (mean); 0.8 % without perspective; now within 1 %
    rows: list[dict[str, object]] = []
    run_scenario("approach", rows=rows)
    near = [r for r in rows if r.get("detected") and float(r["truth_r_m"]) < 4.0]  # type: ignore[arg-type]
    assert len(near) >= 15
    rel = [float(r["error_r_m"]) / float(r["truth_r_m"]) for r in near]  # type: ignore[arg-type]
    assert abs(float(np.mean(rel))) < 0.01
