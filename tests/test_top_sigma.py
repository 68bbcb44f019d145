"""A person placed from its top where its outline is a sliver cut at a side: the columns that show may not
hold the head, so the top may be a shoulder's (tracker.solid_prior.SolidPrior.top_sigma_px, issue 12 item 1).
endless:body seed 2, frames 3303-3430: a walker standing behind a post, a 9 px sliver of it seen at 12 m,
placed from its top 0.63-0.73 deg low with an elevation 1-sigma of 0.134 deg."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tracker.localize import Localizer
from tracker.rectify import Rectifier
from tracker.sim.rig import default_rig
from tracker.solid_prior import SolidPrior


def test_a_slivers_top_may_be_a_shoulders_a_wider_outlines_is_the_heads() -> None:
    prior = SolidPrior()
    d, b = 11.9, 0.3
    stature = prior.height_m * d / b  # 67 px
    assert prior.top_sigma_px(9.0, d, b) == pytest.approx(0.5 * prior.shoulder_drop * stature)
    assert prior.top_sigma_px(9.0, d, b) > 5.0  # the sliver's error there: 6.6 px
    assert prior.top_sigma_px(0.3 * stature, d, b) == 0.0  # as wide as a person's shoulders: its head shows
    assert prior.top_sigma_px(9.0, d, 0.0) == 0.0


def test_a_tops_own_sigma_adds_to_the_elevation_of_a_person_placed_from_it() -> None:
    rect = Rectifier(default_rig())
    d = rect.f * rect.rig.baseline / 10.0  # the face at 10 m
    args = (np.array([360.0, 220.0]), d, 0.05, 4000, None)
    loc = Localizer(rect, solid=SolidPrior())
    placed = loc.locate(*args, (0.0, 0.0), (12.0, 100.0), None, True, 150.0)
    shoulder = loc.locate(*args, (0.0, 0.0), (12.0, 100.0), None, True, 150.0, top_sigma_px=6.0)
    assert np.allclose(placed.rig, shoulder.rig, rtol=0.0, atol=1e-12)  # where it is placed: unchanged
    grown = math.hypot(placed.sigma_phi * rect.f, 6.0) / rect.f  # rad, small angles: px / f
    assert shoulder.sigma_phi == pytest.approx(grown, rel=0.05)
    # placed from its centroid (no top), the top's term does not count
    centroid = loc.locate(*args, (0.0, 0.0), (12.0, 100.0), None, True, None)
    assert loc.locate(*args, (0.0, 0.0), (12.0, 100.0), None, True, None, top_sigma_px=6.0).sigma_phi == \
        pytest.approx(centroid.sigma_phi, rel=1e-12)
