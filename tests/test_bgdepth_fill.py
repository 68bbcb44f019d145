"""The background panorama learnt from several poses: holes filled after one pose are filled again from
what a later pose learns (a later pose's points, sparse where its rays meet the canvas obliquely, once
left the earlier pose's fill between them: near surfaces speckled over a far wall, manoeuvre at 37° of
pan, and a tracked target refused there as not in front of its background)."""

from __future__ import annotations

import numpy as np

from tracker.closedloop import widen_background
from tracker.frames import GimbalState, StereoFrame
from tracker.pipeline import Pipeline
from tracker.sim.scenarios import SimRig, get_scenario


def _learnt(sim: SimRig, pairs: list[StereoFrame]) -> Pipeline:
    pipe = Pipeline(sim.rig)
    widen_background(pipe, 45.0, 10.0)
    for pair in pairs:
        pipe.learn_background(pair)
    return pipe


def test_what_a_later_pose_alone_sees_is_filled_from_its_own_points() -> None:
    sim = SimRig(get_scenario("manoeuvre"), seed=0)
    home, far = sim.background(GimbalState(0.0, 0.0)), sim.background(GimbalState(40.0, 0.0))  # noisy: once
    both, alone = _learnt(sim, [home, far]), _learnt(sim, [far])
    bg = both.bg
    u_home = bg._match_points(home, bg.num_disparities)[0]  # canvas columns of home's points
    u_far, v_far = bg._canvas_coords(bg.rays[0], far.gimbal)
    # canvas columns the home pose learnt nothing in, within the far pose's view (home's fill reaches them)
    c0, c1 = int(u_home.max()) + 20, min(int(u_far.max()), bg.canvas.shape[1]) - 20
    r0, r1 = max(int(v_far.min()), 0) + 20, min(int(v_far.max()), bg.canvas.shape[0]) - 20
    assert c1 - c0 > 100
    a, b = both.bg.canvas[r0:r1, c0:c1], alone.bg.canvas[r0:r1, c0:c1]
    assert np.count_nonzero(b) == b.size  # the far pose learnt and filled all of it
    assert np.array_equal(a, b)
