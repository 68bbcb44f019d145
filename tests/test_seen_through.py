"""Where the background's map puts a surface nearer than a tracked object seen there by both cameras, the
map is wrong (semi-global matching carries a post's disparity into the band left of it that the right
camera cannot see), and the object's region is judged against the farthest background about it
(tracker.verify.Verifier._seen_through)."""

from __future__ import annotations

import numpy as np
import pytest
from sim_helpers import run_frames

from tracker.bgdepth import CorrespondenceMap
from tracker.evaluation import _on
from tracker.pipeline import Pipeline
from tracker.sim.rig import default_rig


def _map(behind: float, around: float) -> tuple[CorrespondenceMap, np.ndarray]:
    """A 40 x 60 box whose object (columns 20-40) has the map's `behind` disparity behind it and `around`
    elsewhere (the post's carried over the object, a hedge beside it): the map and the object's mask."""
    shape = (40, 60)
    disp = np.full(shape, around, np.float32)
    disp[:, 20:40] = behind
    obj = np.zeros(shape, bool)
    obj[5:35, 20:40] = True
    z = np.zeros(shape, np.float32)
    return CorrespondenceMap(z, z, np.ones(shape, bool), disp, np.zeros(shape, np.uint8)), obj


def test_a_tracked_object_before_a_map_nearer_than_itself_is_judged_by_the_farthest_background_about_it() -> None:
    verifier = Pipeline(default_rig()).verifier
    cm, obj = _map(29.5, 7.4)
    assert verifier._seen_through(cm, obj, 25.0, 29.5, 25.0, []) == pytest.approx(7.4)  # tracked: the hedge's
    assert verifier._seen_through(cm, obj, 25.0, 29.5, None, []) is None  # a new region: no
    assert verifier._seen_through(cm, obj, 25.0, 25.4, 25.0, []) is None  # the map not clearly nearer: no
    # nearer by 1.3 px: clearly (min_disparity_gap_px, 0.5 px), though within the depth-gap
    # test with its relative part (4 %: 1.5 px here)
    assert verifier._seen_through(cm, obj, 25.0, 26.3, 25.0, []) == pytest.approx(7.4)
    # no track predicted on it, but one about it at its disparity: a tracked object's; at another, not
    assert verifier._seen_through(cm, obj, 25.0, 29.5, None, [25.4]) == pytest.approx(7.4)
    assert verifier._seen_through(cm, obj, 25.0, 29.5, None, [27.0]) is None
    cm, obj = _map(29.5, 29.5)  # nothing known beyond the post's: the 10th percentile is the post's
    assert verifier._seen_through(cm, obj, 25.0, 29.5, 25.0, []) == pytest.approx(29.5)


def test_a_walker_beside_a_post_keeps_its_legs() -> None:
    """endless:body frame 210: a walker standing beside a post, whose legs' region (matched at 25.1 px) the
    map puts behind the post's disparity carried leftwards (29.9 px): the legs are in its outline (1,065 px
    of them were left out when the region was refused)."""
    pipe, sf, res = run_frames("endless:body", 211)
    tt = sf.truth.target(1)
    det = next(d for d in res.detections if _on(d, tt, sf.truth.ids_left))
    x0, y0, x1, y1 = det.blob.box
    own = sf.truth.ids_left == tt.target_id
    found = np.zeros_like(own)
    found[y0:y1, x0:x1] = det.blob.mask
    assert np.count_nonzero(found & own) > 0.9 * np.count_nonzero(own)
