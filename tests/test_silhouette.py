"""A verified object's outline from the temporal model (tracker.silhouette.temporal_outline)."""

from __future__ import annotations

import numpy as np

from tracker.silhouette import _CLOSE_FILL, FILL_EPS_FRACTION, largest, temporal_outline

EPS = 12


def _scene(faint: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """A 100 x 80 box of flat background (100 grey levels, no deviation) with a 40 x 30 object 30 grey levels
    brighter, except its bottom-right quarter (a face in shade), which differs by `faint` only. Returns
    (key Γ, background B, deviation D, the object's true mask)."""
    bg = np.full((100, 80), 100.0, np.float32)
    key = np.full((100, 80), 100, np.uint8)
    truth = np.zeros((100, 80), bool)
    truth[30:70, 25:55] = True
    key[truth] = 130
    key[50:70, 40:55] = int(100 + faint)
    return key, bg, np.zeros_like(bg), truth


def test_fill_keeps_a_face_that_differs_from_the_background_by_less_than_eps() -> None:
    faint = 10.0  # between ε_f = 8 and ε = 12
    assert FILL_EPS_FRACTION * EPS < faint < EPS
    key, bg, dev, truth = _scene(faint)
    region = truth.copy()
    strict, g, _ = temporal_outline(key, bg, dev, np.zeros_like(truth), region, EPS)
    filled, g_fill, changed = temporal_outline(key, bg, dev, np.zeros_like(truth), region, EPS, fill=True)
    assert g == g_fill == 1.0
    assert np.count_nonzero(truth & ~strict) > 0.95 * 20 * 15  # the faint quarter is lost without fill
    assert np.array_equal(filled, truth)  # and kept with it
    assert not changed[50:70, 40:55].any()  # the strict change mask (what _taken uses) is as before


def test_fill_leaves_out_what_differs_by_less_than_eps_f() -> None:
    key, bg, dev, truth = _scene(6.0)  # below ε_f: the background's own noise level, not the object
    filled, _, _ = temporal_outline(key, bg, dev, np.zeros_like(truth), truth, EPS, fill=True)
    assert np.count_nonzero(truth & ~filled) > 0.95 * 20 * 15 and not np.any(filled & ~truth)


def test_fill_raises_eps_f_by_three_times_the_backgrounds_own_deviation() -> None:
    key, bg, dev, truth = _scene(10.0)
    dev[:] = 1.0  # ε_f + 3 g D = 11 > 10: a moving background's range keeps the faint face out
    filled, _, _ = temporal_outline(key, bg, dev, np.zeros_like(truth), truth, EPS, fill=True)
    assert np.count_nonzero(filled[50:70, 40:55]) < 0.05 * 20 * 15  # the closing rounds its inner corner only


def test_the_fill_closing_bridges_gaps_up_to_about_9_px_and_no_wider() -> None:
    mask = np.zeros((80, 80), bool)
    mask[10:70, 10:30] = True
    mask[10:70, 37:57] = True  # a 7-px gap: two legs a stride apart
    assert np.count_nonzero(largest(mask, close=True)) == 60 * 20  # the 5 x 5 closing: one leg
    both = largest(mask, close=True, kernel=_CLOSE_FILL)
    assert both[40, 15] and both[40, 50] and both[40, 33]  # both legs, joined
    wide = np.zeros((80, 80), bool)
    wide[10:70, 5:25] = True
    wide[10:70, 37:57] = True  # 12 px apart: not joined
    assert np.count_nonzero(largest(wide, close=True, kernel=_CLOSE_FILL)) == 60 * 20
