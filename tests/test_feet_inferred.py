"""While the cameras move, eq. (9) cannot see a foot where it meets the ground at its own depth: the feet are
filled from the keys (tracker.bottom_edge.feet_at_ground_depth), the blob says its bottom was inferred
(Blob.bottom_inferred), and an upright body's centre is then the fusion of the one found from its top and the
one found from its centroid (tracker.localize.fused, with the Particle Data Group's scale factor)."""

from __future__ import annotations

import math

import numpy as np
from sim_helpers import run_frames

from tracker.bottom_edge import feet_at_ground_depth
from tracker.evaluation import _on
from tracker.localize import Localizer, fused
from tracker.rectify import Rectifier
from tracker.sim.rig import default_rig
from tracker.solid_prior import SolidPrior


def _legs(h: int = 80, w: int = 48) -> np.ndarray:
    """A body's outline over a box: a torso and two legs 12 px apart (wider than the closing), their lowest
    10 rows (the feet) lost."""
    obj = np.zeros((h + 12, w), bool)
    obj[0:40, 6:38] = True  # torso
    obj[40:h - 10, 8:15] = True  # legs down to row h - 11
    obj[40:h - 10, 27:34] = True
    return obj


def test_the_feet_against_ground_at_their_own_depth_are_filled_from_the_keys() -> None:
    obj = _legs()
    keys = obj.copy()
    keys[70:80, 8] = keys[70:80, 14] = keys[70:80, 27] = keys[70:80, 33] = True  # the feet's edges alone
    bg = np.full(obj.shape, 10.0, np.float32)  # the ground below: at the feet's disparity
    valid = np.ones(obj.shape, bool)
    out = feet_at_ground_depth(obj, keys, bg, valid, 10.3)
    assert out is not obj
    assert out[70:80, 8:15].all() and out[70:80, 27:34].all()  # each foot closed between its edges
    assert not out[70:80, 16:26].any()  # the ground between the legs stays out
    assert (out & ~obj)[:60].sum() == 0  # nothing added above the outline's lowest quarter
    assert not out[80:].any()  # nor below what the keys saw


def test_nothing_is_filled_where_the_background_lies_apart_from_the_target_or_the_keys_see_nothing() -> None:
    obj = _legs()
    keys = obj.copy()
    keys[70:80, 8] = keys[70:80, 14] = True
    valid = np.ones(obj.shape, bool)
    far = np.full(obj.shape, 6.0, np.float32)  # a wall behind, 4 px of disparity away: eq. (9) sees the feet
    assert feet_at_ground_depth(obj, keys, far, valid, 10.0) is obj
    level = np.full(obj.shape, 10.0, np.float32)
    assert feet_at_ground_depth(obj, obj.copy(), level, valid, 10.0) is obj  # no key pixel below the outline
    assert feet_at_ground_depth(obj, keys, level, np.zeros_like(valid), 10.0) is obj  # the background unknown
    empty = np.zeros_like(obj)
    assert feet_at_ground_depth(empty, keys, level, valid, 10.0) is empty


def test_two_measurements_are_fused_by_their_weights_and_their_disagreement_widens_the_result() -> None:
    y, v = fused((10.0, 1.0), (11.0, 4.0))  # χ² = 1 / 5: consistent, no scale
    assert math.isclose(y, (10.0 + 11.0 / 4.0) / 1.25) and math.isclose(v, 1.0 / 1.25)
    y, v = fused((10.0, 1.0), (16.0, 4.0))  # χ² = 36 / 5: the variance scaled by it
    assert math.isclose(y, (10.0 + 16.0 / 4.0) / 1.25) and math.isclose(v, 36.0 / 5.0 / 1.25)
    assert fused((3.0, 2.0), (3.0, 2.0)) == (3.0, 1.0)
    assert fused((3.0, 0.0), (5.0, 2.0)) == (3.0, 0.0) and fused((3.0, 2.0), (5.0, 0.0)) == (5.0, 0.0)


def test_a_person_whose_bottom_was_inferred_is_placed_between_its_top_and_its_centroid() -> None:
    rect = Rectifier(default_rig())
    d = rect.f * rect.rig.baseline / 10.0
    loc = Localizer(rect, solid=SolidPrior())

    def placed(top_px: float | None, top_fused: bool = False):  # type: ignore[no-untyped-def]
        args = (np.array([360.0, 220.0]), d, 0.05, 4000, None, (0.0, 0.0), (60.0, 100.0), None, True, top_px)
        p = loc.locate(*args, top_fused=top_fused)
        return float(rect.rig_to_rect(p.rig[None, :])[1][0]), p.sigma_phi

    (y_c, s_c), (y_t, s_t), (y_f, s_f) = placed(None), placed(150.0), placed(150.0, True)
    assert abs(y_t - y_c) > 10.0  # the top's estimate 22 px above the centroid's here
    assert min(y_t, y_c) < y_f < max(y_t, y_c)
    plain = (s_t**-2 + s_c**-2) ** -0.5
    chi2 = ((y_t - y_c) / rect.f) ** 2 / (s_t**2 + s_c**2)  # about 31: they disagree
    assert math.isclose(s_f, plain * math.sqrt(chi2), rel_tol=0.05) and s_f > max(s_t, s_c)
    # a top that agrees with the centroid: the plain fusion, narrower than either
    (y_a, s_a), (y_g, s_g) = placed(150.0 + y_c - y_t), placed(150.0 + y_c - y_t, True)
    assert abs(y_a - y_c) < 0.01 and math.isclose(y_g, y_c, abs_tol=0.01)
    assert math.isclose(s_g, (s_a**-2 + s_c**-2) ** -0.5, rel_tol=0.05) and s_g < min(s_a, s_c)
    # without a top the flag changes nothing
    assert placed(None, True) == (y_c, s_c)


def test_an_outline_short_of_its_stature_widens_its_tops_estimate_by_half_the_shortfall() -> None:
    rect = Rectifier(default_rig())
    d = rect.f * rect.rig.baseline / 10.0  # 1.70 m at 10 m: 1.7 f / 10 px high
    prior, b = SolidPrior(), rect.b
    tall = 1.70 * d / rect.rig.baseline
    assert math.isclose(prior.short_of_stature_px(tall - 12.0, d, b), 12.0, abs_tol=1e-9)
    assert prior.short_of_stature_px(tall + 5.0, d, b) == 0.0  # never negative
    assert math.isclose(prior.short_of_stature_px(tall, d, b, 1.80), 0.10 * d / rect.rig.baseline, abs_tol=1e-9)
    # an exact prior (no σ on the top's own estimate): the top stands, unless the outline falls short of the
    # stature its track measured, which leaves the top's estimate half that shortfall of 1-σ
    exact = Localizer(rect, solid=SolidPrior(rim_sigma_px=0.0, height_sigma_m=0.0, centre_below_top_sigma=0.0))

    def y_of(stature: tuple[float, float], top_fused: bool) -> float:
        args = (np.array([360.0, 220.0]), d, 0.05, 4000, None, (0.0, 0.0), (60.0, tall), None, True, 150.0,
                None, None, stature)
        return float(rect.rig_to_rect(exact.locate(*args, top_fused=top_fused).rig[None, :])[1][0])

    assert math.isclose(y_of((1.70, 0.01), True), y_of((1.70, 0.01), False), abs_tol=1e-9)
    y_c = float(rect.rig_to_rect(exact.locate(np.array([360.0, 220.0]), d, 0.05, 4000, None, (0.0, 0.0),
                                              (60.0, tall)).rig[None, :])[1][0])
    y_t, y_f = y_of((2.20, 0.01), False), y_of((2.20, 0.01), True)
    assert min(y_t, y_c) + 0.1 < y_f < max(y_t, y_c) - 0.1


def test_a_walker_seen_while_the_cameras_pan_keeps_its_feet() -> None:
    # pan:body frame 84: eq. (9) lost rows 337-347 of the walker's feet against the ground at their depth
    # (its outline ended at row 336, the centroid 7.8 px off the truth's); filled, the outline reaches 343
    _, sf, res = run_frames("pan:body", 85)
    tt = sf.truth.target(1)
    assert tt is not None and tt.centroid_left is not None
    on = [d for d in res.detections if _on(d, tt, sf.truth.ids_left)]
    assert len(on) == 1
    blob = on[0].blob
    assert blob.bottom_inferred
    truth_rows = np.flatnonzero((sf.truth.ids_left == 1).any(axis=1))
    rows = np.flatnonzero(blob.mask.any(axis=1)) + blob.box[1]
    assert rows[0] == truth_rows[0] and truth_rows[-1] - rows[-1] <= 5
    assert float(np.hypot(*(blob.centroid_raw - tt.centroid_left))) < 5.0
