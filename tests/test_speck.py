"""A speck: an outline smaller along both axes than any whole body the SolidPrior is for, a piece of one whose
rest may lie anywhere about it (tracker.solid_prior.SolidPrior.speck, tracker.partly_seen.speck_rest; issue
12 item 1). endless:body with seed 1, frames 880-883: a head over a hedge at 25 m, 5 x 4 px against a
person's 40 px, no cut found, was placed 1.6 deg above the person's centre with an elevation 1-sigma of
0.006 deg."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tracker import pipeline
from tracker.bgdepth import CorrespondenceMap
from tracker.partly_seen import speck_rest
from tracker.results import Blob
from tracker.sim.rig import default_rig
from tracker.solid_prior import SolidPrior
from tracker.visibility import padded

D, BASELINE = 7.0, 0.3  # px, m: a person (1.70 m) is 39.7 px high at this disparity; a speck under 11.9 px


def _blob(w: int, h: int, x0: int = 300, y0: int = 200, d: float = D) -> Blob:
    mask = np.ones((h, w), bool)
    return Blob((x0, y0, x0 + w, y0 + h), mask, w * h, np.zeros(2), np.zeros(2), d, 0.05, 2.0, 1.0)


def test_a_speck_is_under_speck_share_of_a_persons_stature_along_both_axes() -> None:
    prior = SolidPrior()
    limit = prior.speck_share * prior.height_m * D / BASELINE
    assert limit == pytest.approx(11.9)
    assert prior.speck(5.0, 4.0, D, BASELINE)
    assert prior.speck(11.0, 11.0, D, BASELINE)
    assert not prior.speck(13.0, 4.0, D, BASELINE)  # wider than a speck: a whole ball at this range is 14 px
    assert not prior.speck(5.0, 13.0, D, BASELINE)
    assert not prior.speck(5.0, 4.0, D / 3.0, BASELINE)  # three times as far: 0.6 m across, a whole ball
    assert not prior.speck(5.0, 4.0, D, 0.0)  # no baseline, no stature in pixels


def test_a_specks_rest_may_lie_anywhere_within_a_person_about_it() -> None:
    prior = SolidPrior()
    stature = prior.height_m * D / BASELINE
    (x, y), whole = speck_rest(_blob(5, 4), prior, BASELINE, (0.0, 0.0), (True, True))
    assert x == pytest.approx((prior.upright_girth * stature - 5.0) / math.sqrt(12.0))
    assert y == pytest.approx((stature - 4.0) / math.sqrt(12.0))
    assert whole == (False, False)
    # a cut found below it (the hedge): its term, a share of the speck's own extent, describes the same
    # hidden part, and the larger holds
    (x2, y2), _ = speck_rest(_blob(6, 6), prior, BASELINE, (0.3, 2.4), (True, False))
    assert y2 == pytest.approx((stature - 6.0) / math.sqrt(12.0))
    assert x2 == pytest.approx((prior.upright_girth * stature - 6.0) / math.sqrt(12.0))
    (x3, y3), _ = speck_rest(_blob(6, 6), prior, BASELINE, (20.0, 30.0), (False, False))
    assert (x3, y3) == (20.0, 30.0)
    # not a speck: nothing changes
    assert speck_rest(_blob(20, 20), prior, BASELINE, (0.1, 0.2), (True, True)) == ((0.1, 0.2), (True, True))


def _extra(pipe: pipeline.Pipeline, b: Blob) -> tuple[tuple[float, float], tuple[bool, bool]]:
    """pipeline's cut terms and seen_whole for blob b alone before a far background (2 px) that hides nothing."""
    size = pipe.rig.left.size
    grown, gbox = padded(b.mask, b.box, size, left=2 + int(math.ceil(b.disparity)), below=2 + b.mask.shape[0])
    shape = grown.shape
    cm = CorrespondenceMap(np.zeros(shape, np.float32), np.zeros(shape, np.float32), np.ones(shape, bool),
                           np.full(shape, 2.0, np.float32), np.zeros(shape, np.uint8))
    frame = type("Frame", (), {"gimbal": None})()
    out = pipe._centroid_extra(frame, b, [b], None, (grown, gbox, cm))
    return out[3], out[4]


def test_the_pipeline_gives_a_speck_its_rest_and_an_upright_fragment_its_own() -> None:
    rig = default_rig()
    pipe = pipeline.Pipeline(rig, solid=SolidPrior())
    stature = 1.70 * D / pipe.rect.b
    cut, whole = _extra(pipe, _blob(5, 4))
    assert cut[1] == pytest.approx((stature - 4.0) / math.sqrt(12.0)) and whole == (False, False)
    # no SolidPrior (a flat board): a small board is whole as seen
    flat = pipeline.Pipeline(rig)
    cut, whole = _extra(flat, _blob(5, 4))
    assert cut == (0.0, 0.0) and whole == (True, True)
    # a blob as large as a whole ball at this range is not a speck
    cut, whole = _extra(pipe, _blob(15, 15))
    assert cut == (0.0, 0.0) and whole == (True, True)
