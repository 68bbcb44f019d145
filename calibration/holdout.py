"""Which lens model predicts held-out views better: triangulate the held-out views' corners through each
model and measure how far they are from a rigid copy of the board (truth-free, in the square's unit)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from calibration.evaluate import board_shape_rms, triangulate_pinhole, triangulate_polynomial
from calibration.stereo import StereoCalibration, ViewSet

B = NDArray[np.bool_]
HOLD_EVERY = 5  # every 5th stereo pair is held out when there are enough


def split(views: ViewSet, min_views: int) -> tuple[ViewSet, ViewSet | None]:
    """(training, held-out) views: every HOLD_EVERY-th pair seen by both cameras is held out, when the
    training set still has min_views + 2 pairs; otherwise nothing is held out."""
    both = views.seen[0] & views.seen[1]
    idx = np.flatnonzero(both)
    held = np.zeros(both.shape, dtype=bool)
    held[idx[HOLD_EVERY - 1 :: HOLD_EVERY]] = True
    if int(both.sum() - held.sum()) < min_views + 2 or not held.any():
        return views, None
    return views.subset(~held), views.subset(held)


@dataclass(frozen=True)
class HeldOut:
    """Mean board-shape RMS of the triangulated held-out corners per model, and the better model."""

    views: int
    board_rms: dict[str, float]
    best: str


def compare_models(cal: StereoCalibration, held: ViewSet) -> HeldOut:
    """Triangulate each held-out view (both cameras) with each model; smaller residual wins."""
    both = held.seen[0] & held.seen[1]
    errs: dict[str, list[float]] = {"pinhole": []}
    if cal.polynomial is not None:
        errs["polynomial"] = []
    for v in np.flatnonzero(both):
        pl, pr = held.obs[0, v], held.obs[1, v]
        X = triangulate_pinhole(cal.rig, pl, pr)
        errs["pinhole"].append(board_shape_rms(X, held.obj))
        if cal.polynomial is not None:
            Xp = triangulate_polynomial(cal.polynomial, cal.rig.R, cal.rig.T, pl, pr, X)
            errs["polynomial"].append(board_shape_rms(Xp, held.obj))
    means = {k: float(np.mean(v)) for k, v in errs.items()}
    return HeldOut(int(both.sum()), means, min(means, key=lambda k: means[k]))
