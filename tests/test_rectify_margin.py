"""The rectifier's wide maps (tracker.rectify.Rectifier.wide, map_window, columns): with alpha 0 the
rectified frame is cropped to the raw image's inside, so the raw columns the lens pushes past it (10-16 px
at the simulated rig's right edge) had no rectified pixels, and a region there could not be matched. The
maps now reach Rectifier.margin px past the frame on each side."""

from __future__ import annotations

from dataclasses import replace

import cv2
import numpy as np

from tracker.pipeline import Pipeline
from tracker.sim.scenarios import SimRig, get_scenario

D = 15.0  # the object's disparity (px)
ROWS = (220, 300)  # its rows (rectified)


def _pipe() -> tuple[Pipeline, SimRig]:
    sim = SimRig(get_scenario("walk"), seed=0)
    pipe = Pipeline(sim.rig)
    pipe.learn_background(sim.background())
    return pipe, sim


def test_the_wide_maps_are_the_maps_inside_the_frame_and_hold_the_raw_columns_past_it() -> None:
    pipe, _ = _pipe()
    rect = pipe.verifier.rect
    w, h = rect.rig.left.size
    for side in (0, 1):
        mx, my = rect.map_window(side, (0, 0, w, h))
        assert np.array_equal(mx, rect.maps[side][0]) and np.allclose(my, rect.maps[side][1], atol=1e-6)
    first, last = rect.columns(0, *ROWS)
    assert first < 0 and last > w - 1  # the raw left image reaches past the frame on both sides
    mx, _ = rect.map_window(0, (last, ROWS[0], last + 1, ROWS[1]))
    assert mx.max() <= w - 1.0 and mx.min() > w - 3.0  # the raw image's last columns
    assert rect.columns(1, *ROWS)[0] < 0  # the raw right image reaches left of the frame


def test_a_region_the_crop_left_out_at_the_right_edge_is_matched() -> None:
    """An object over the rectified columns right of 638 (raw left columns 628 on), at disparity D, drawn
    into both raw images through the rectification: before the wide maps its strips were None."""
    pipe, sim = _pipe()
    rect = pipe.verifier.rect
    empty = sim.background()
    tex = cv2.GaussianBlur(np.random.default_rng(4).normal(0.0, 1.0, (560, 760)).astype(np.float32), (0, 0), 1.2)
    tex = (128.0 + 40.0 * tex / tex.std()).astype(np.float32)
    images, masks = [], []
    for cam, shift in ((0, 0.0), (1, D)):  # the right camera sees left column u at u - D
        raw = (empty.left if cam == 0 else empty.right).astype(np.float32)
        u, v = rect.rect_of_raw[cam][..., 0] + np.float32(shift), rect.rect_of_raw[cam][..., 1]
        inside = (u >= 638.0) & (v >= ROWS[0]) & (v < ROWS[1])
        drawn = cv2.remap(tex, u + np.float32(40.0), v + np.float32(40.0), cv2.INTER_LINEAR)
        raw[inside] = drawn[inside]
        images.append(np.clip(raw, 0, 255).astype(np.uint8))
        masks.append(inside)
    frame = replace(empty, left=images[0], right=images[1])
    ys, xs = np.nonzero(masks[0])
    box = (int(xs.min()), int(ys.min()), int(xs.max()) + 1, int(ys.max()) + 1)
    region = masks[0][box[1]:box[3], box[0]:box[2]]
    assert box[0] >= 626  # raw columns the rectified frame (0-639) does not hold
    strips = pipe.verifier._strips(frame, box, region, None)
    assert strips is not None and strips.window[2] > 640  # the window reaches past the frame
    fit = strips.match(region, None, 0)
    assert fit is not None and abs(fit.disparity - D) < 0.2
