"""A new person near the cameras whose whole outline matches nowhere at one disparity (its limbs and slanted
faces lie centimetres to decimetres apart, several pixels at 3 m), and whose coarse disparity its left-key
region, its occlusion shadow in it, put 5 px behind it: found from its first frame, its outline searched anew
over the whole range and, where the larger windows match nowhere, on windows half as wide
(RegionMatcher._coarse_disparity, Verifier._verify_region). walk:body with seed 0 draws a walker of 1.693 m:
frames 0 and 1 were lost, its left-key region at 57.6 px for a walker at 62.7 px."""

from __future__ import annotations

import numpy as np
import pytest
from sim_helpers import each_frame

import tracker.sim.scenarios as scenarios
from tracker.evaluation import _on


def test_a_new_walker_at_three_metres_is_found_from_its_first_frame(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(scenarios, "draw_stature", lambda rng: 1.693)
    for pipe, sf, res in each_frame("walk:body", 2):
        tt = sf.truth.target(1)
        assert tt is not None and tt.silhouette_world is not None
        det = next((d for d in res.detections if _on(d, tt, sf.truth.ids_left)), None)
        assert det is not None, f"frame {sf.frame.index}: the walker is not found"
        d_true = pipe.rect.f * pipe.rect.b / float(tt.silhouette_world[2])  # eq. (2): d = f b / Z
        assert abs(det.blob.disparity - d_true) < 1.0, (sf.frame.index, det.blob.disparity, d_true)
        assert np.hypot(*(det.blob.centroid_raw - tt.centroid_left)) < 10.0
