"""A person's parts are matched on the pixels of its outline that changed
(tracker.region_match.RegionMatcher.part_fits): the outline is filled, so the background seen between a
walker's legs and under its arms is in it, and a part holding that background matches between the body's
depth and the background's."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

import tracker.region_match as region_match
from tracker.pipeline import Pipeline
from tracker.results import Blob, PartFit
from tracker.sim.scenarios import SimRig, get_scenario

BOX = (296, 150, 344, 310)  # 48 x 160 px: upright


def _scene(gap: int = 4) -> tuple[Pipeline, object, np.ndarray, np.ndarray]:
    """The walk scene's empty pair learnt, then a left image with two bright legs (columns 4-20 and 20 + gap
    to 44 of BOX, its rows 10-150) and the background between them: the pipeline, the frame, the filled
    outline (BOX's shape) and the legs' pixels."""
    sim = SimRig(get_scenario("walk"), seed=0)
    pipe = Pipeline(sim.rig)
    empty = sim.background()
    pipe.learn_background(empty)
    x0, y0, x1, y1 = BOX
    legs = np.zeros((y1 - y0, x1 - x0), bool)
    legs[10:150, 4:20] = True
    legs[10:150, 20 + gap:44] = True
    left = empty.left.copy()
    left[y0:y1, x0:x1][legs] = 250
    outline = np.zeros_like(legs)
    outline[10:150, 4:44] = True  # filled: the gap between the legs in it
    return pipe, replace(empty, left=left), outline, legs


def _blob(mask: np.ndarray) -> Blob:
    return Blob(BOX, mask, int(mask.sum()), np.zeros(2), np.zeros(2), 12.0, 0.01, 5.0, 0.9)


def test_the_background_a_persons_outline_encloses_is_left_out_of_its_parts(monkeypatch: pytest.MonkeyPatch
                                                                            ) -> None:
    pipe, frame, outline, legs = _scene()
    seen = pipe.verifier._changed_part(frame, _blob(outline))  # type: ignore[arg-type]
    assert np.array_equal(seen, legs) and not np.array_equal(seen, outline)
    cores: list[np.ndarray] = []

    def fits(left, right, core, off, d, min_score, robust=False):  # type: ignore[no-untyped-def]
        cores.append(core.copy())
        return [PartFit(d, 0.01, 10)]

    monkeypatch.setattr(region_match, "part_fits", fits)
    pipe.verifier.part_fits(frame, _blob(outline))  # type: ignore[arg-type]
    strips = pipe.verifier._strips(frame, BOX, outline, 12.0, region_match.first_window(outline))  # type: ignore[arg-type]
    assert strips is not None and len(cores) == 1
    assert np.array_equal(cores[0], strips.core(legs)) and cores[0].sum() < strips.core(outline).sum()


def test_where_under_half_changed_or_the_cameras_move_the_whole_outline_is_matched() -> None:
    pipe, frame, outline, _ = _scene(gap=28)  # one leg alone (the other past the box): 16 of 40 columns changed
    assert np.array_equal(pipe.verifier._changed_part(frame, _blob(outline)), outline)  # type: ignore[arg-type]
    pipe, frame, outline, _ = _scene()
    pipe.subtractor.moving = True  # no temporal background while the cameras move
    assert np.array_equal(pipe.verifier._changed_part(frame, _blob(outline)), outline)  # type: ignore[arg-type]
