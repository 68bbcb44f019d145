"""A person near the cameras whose legs lie past the image's bottom edge, its head seen: placed from its top, as
one whose legs a nearer background hides (tracker.partly_seen, tracker.pipeline), its centre's depth behind the
seen face given a 1-σ of its own (SolidPrior.seen_in_part, past_edge). On walk:body the walker
at 3 m, 270 of its 340 px seen, had an elevation 1-σ of 9.7° (the cut's term, kappa times its seen height) for
errors of 0.73° rms, and a range 1-σ that held only through that term."""

from __future__ import annotations

import numpy as np
import pytest
from sim_helpers import each_frame

from tracker.evaluation import _on
from tracker.localize import spherical
from tracker.solid_prior import SolidPrior


def test_a_person_past_the_edge_has_a_depth_1_sigma_of_its_own() -> None:
    prior = SolidPrior()
    d, b = 60.0, 0.3
    stature = prior.stature_px(d, b)
    assert stature is not None
    whole = prior.behind_face_px(100.0, 0.8 * stature)
    assert prior.seen_in_part(whole, 0.8 * stature, d, b) == whole  # over part_share of its stature
    past = prior.seen_in_part(whole, 0.8 * stature, d, b, past_edge=True)
    assert past == (whole[0], pytest.approx(prior.edge_depth_sigma_m * d / b)) and past[1] > whole[1]
    part = prior.seen_in_part(whole, 0.4 * stature, d, b, past_edge=True)  # little seen: the larger term
    assert part == (whole[0], pytest.approx(prior.part_depth_sigma_m * d / b))


def test_the_walker_at_three_metres_cut_by_the_image_bottom() -> None:
    zs, sigmas_phi, sigmas_r = [], [], []
    for i, (_, sf, res) in enumerate(each_frame("walk:body", 16)):
        tt = sf.truth.target(1)
        assert tt is not None
        det = next(d for d in res.detections if _on(d, tt, sf.truth.ids_left))
        assert det.blob.box[3] == 480 and det.blob.box[1] > 0  # its legs past the bottom edge, its head seen
        if i < 4:  # a track's first frames: no heading yet
            continue
        r, _, phi = spherical(tt.world)
        zs.append(((det.loc.phi - phi) / det.loc.sigma_phi, (det.loc.r - r) / det.loc.sigma_r))
        sigmas_phi.append(np.degrees(det.loc.sigma_phi))
        sigmas_r.append(det.loc.sigma_r)
    z = np.array(zs)
    assert max(sigmas_phi) < 1.5  # 9.6 to 9.9 deg from the cut's term
    assert np.all(np.abs(z[:, 0]) < 3.0)  # and honest: the elevation within 3 sigma
    assert np.mean(z[:, 1] ** 2) < 4.0 and np.all(np.abs(z[:, 1]) < 4.0)  # range: NEES 3.2 here, 10 without the term
    assert min(sigmas_r) > 0.8 * SolidPrior().edge_depth_sigma_m
