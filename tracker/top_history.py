"""A track's outline's top over its frames, in the world, to tell a piece lost there (issue 12 item 1).

Where a nearer background hides a person's lower part, its centre is found from its outline's top
(tracker.localize.Localizer._below_top): c H below it. That top is the head's only while the head is in
the outline. Against a background like it, or once a person has stood still long enough for the temporal
model to take its head in, the head and shoulders may drop out of the outline, and the top seen is then
the chest's: endless:body with seed 1, frames 1387-1451, a person standing at 19 m behind a hedge, its
outline's top 16 px below its head's (54 px seen high, then 36-38 px), was placed 1.48° low with an
elevation 1-σ of 0.12° (z -12.6, three quarters of the scenario's elevation NEES).

A person's top stays at one height in the world as it walks (its head bobs by a few centimetres; the
cameras' turning is taken out by the gimbal's angles), whatever its range. So where the top lies lower
than the median of the track's last tops by more than twice their scatter and the pixel the outline's top
may round to, a piece was lost there, or the person bent: the top is taken halfway, with a 1-σ of half the
difference (either is then within 1σ), and the frame is not kept. A top higher than the history's is kept
and moves nothing: a track is often born on a person whose head is not yet in its outline (endless:body
with seed 0, track 6: its first six tops 0.24 m low; judged both ways, where it was placed from its top in
frames 1978-2289 it was moved about 5 px too high, elevation error +0.16 -> -0.28°, 1-σ 0.13 -> 0.45°).

The history is the last `frames` tops kept, however old: nothing ages it. A person who crouches or sits,
or a track handed to a shorter person, stays judged against its old tops for the rest of the track: its
top taken halfway with a 1-σ of half the drop, wider than it needs but holding the error. A history is
kept for every track whose top is seen (a ball's, a car's too); only a person placed from its top uses it.
"""

from __future__ import annotations

import math
import statistics

from tracker.frames import GimbalState
from tracker.geometry import gimbal_rotation
from tracker.rectify import Rectifier


def top_world_y_m(rect: Rectifier, gimbal: GimbalState | None, x_px: float, top_px: float, disparity: float) -> float:
    """The world y (m, down positive) of the rectified point (x_px, top_px) at disparity (px): eq. (2),
    turned by the gimbal (tracker.geometry.gimbal_rotation)."""
    g = gimbal or GimbalState()
    return float((gimbal_rotation(g.pan_deg, g.tilt_deg) @ rect.rect_to_rig(x_px, top_px, disparity))[1])


class TopHistory:
    """Per track, the world heights (y, m) of its outline's last `frames` tops not found lowered (see the
    module's docstring); used from `min_frames`."""

    def __init__(self, frames: int = 15, min_frames: int = 3, round_px: float = 1.0):
        self.frames = frames
        self.min_frames = min_frames
        self.round_px = round_px
        self._kept: dict[int, list[float]] = {}  # track id -> the tops' world y (m)

    def offset_px(self, track_id: int, y_m: float, disparity: float, baseline_m: float) -> float:
        """How far (px at this disparity, + down) the track's top at world y_m (m) lies below its history's
        median, 0 within twice the history's scatter and round_px or above it; a top not found lower is
        kept. A world height Y at disparity d spans Y d / b px (f Y / Z, Z = f b / d)."""
        if disparity <= 0 or baseline_m <= 0 or not math.isfinite(y_m):  # no depth: nothing judged or kept
            return 0.0
        kept = self._kept.setdefault(track_id, [])
        px_per_m = disparity / baseline_m
        off = 0.0
        if len(kept) >= self.min_frames:
            med = statistics.median(kept)  # a few µs on 15 floats, unlike np.median
            spread = 1.4826 * statistics.median([abs(v - med) for v in kept])
            diff = (y_m - med) * px_per_m
            off = diff if diff > 2.0 * spread * px_per_m + self.round_px else 0.0
        if off == 0.0:
            kept.append(y_m)
            del kept[:-self.frames]
        return off

    def keep_only(self, track_ids: list[int]) -> None:
        """Forget the tops of tracks not in track_ids (ended)."""
        live = set(track_ids)
        self._kept = {i: v for i, v in self._kept.items() if i in live}
