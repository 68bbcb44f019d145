"""Background correspondences for boxes of any shape, a column of four pixels included (OpenCV's
arithmetic takes an (4, 1) array for a scalar: a frame of the endless scene once failed on it)."""

from __future__ import annotations

import numpy as np
import pytest

from tracker.frames import GimbalState
from tracker.pipeline import Pipeline
from tracker.sim.scenarios import SimRig, get_scenario


@pytest.fixture(scope="module")
def pipe() -> Pipeline:
    sim = SimRig(get_scenario("walk"))
    p = Pipeline(sim.rig)
    p.learn_background(sim.background())
    return p


@pytest.mark.parametrize("box", [(300, 200, 301, 204), (300, 200, 304, 201), (300, 200, 301, 201),
                                 (300, 200, 302, 202), (10, 10, 11, 15)])
def test_small_boxes_equal_the_slice_of_a_large_one(pipe: Pipeline, box: tuple[int, int, int, int]) -> None:
    g = GimbalState(1.5, -0.5)
    big = pipe.bg.correspondence(0, g, 1, box=(0, 0, 400, 300))
    small = pipe.bg.correspondence(0, g, 1, box=box)
    x0, y0, x1, y1 = box
    np.testing.assert_array_equal(small.valid, big.valid[y0:y1, x0:x1])
    np.testing.assert_allclose(small.map_x, big.map_x[y0:y1, x0:x1], atol=1e-4)
    np.testing.assert_allclose(small.disparity, big.disparity[y0:y1, x0:x1], rtol=1e-5)
