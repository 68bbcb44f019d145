"""A tracked object only the left camera sees: half-occlusion and the image border.

Stereo needs both cameras to see the same surface. Near a pole, or at the left border, the left camera sees
parts of an object the right camera cannot: the right camera's ray to them (rectified x_r = x_l - d, same
row; paper eq. 1-2) leaves its image, or meets a nearer background surface first (a post whose disparity
D > d covers right columns x_q - D). The strips find no disparity there, and a tracked walker passing
behind a post was lost for its whole passage (endless:body, frames 2298-2314).

Where a changed region of the left temporal model matches at no disparity, its centroid lies within the
association gate of a confirmed track's predicted position (`nearest_prediction`), and the right camera
cannot see at least half of it at the disparity the track holds (the median of its last stereo sightings;
`hidden_from_right`), the region is taken as that track's object at that disparity, with a 1-σ that grows
as the object's range may change (`coast_sigma_px`); the tracker (tracker.tracks.MultiTracker.coasting)
offers a track for such sightings for at most `max_frames` updates after its last stereo sighting.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from tracker.bgdepth import CorrespondenceMap
from tracker.masks import half_or_whole
from tracker.rectify import Rectifier

F64 = NDArray[np.float64]
BoolA = NDArray[np.bool_]
Box = tuple[int, int, int, int]


@dataclass(frozen=True)
class OneCameraConfig:
    """min_hidden: the share of a region the right camera must be unable to see at the held disparity
    (below it a failed stereo match says the region is not the track's object); depth_tol_px: how much
    nearer (disparity, px) a background surface must be to hide it; cover_px: how near (right rectified
    columns, px) its image must fall; sigma0_px: a 1-σ (px) added in quadrature to that of the stereo
    sightings' disparity held (a partly seen object's, before it went out of the right camera's view);
    range_rate_mps: how fast (m/s) a tracked object's range may change (a walker's pace) while only the
    left camera sees it; max_frames: a track may be continued so while fewer updates than this (sightings
    by the left camera alone and misses) have passed since its last stereo sighting; max_missed: the most
    frames in a row a track so continued may have been missed (a thin sliver of it shows in no
    candidate); gate_px: how far (px) from the region's centroid the track's predicted position may lie
    (the tracker's association gate, TrackerConfig.gate_px:
    the part of a body a post hides may hold its centre)."""

    min_hidden: float = 0.5
    depth_tol_px: float = 1.0
    cover_px: float = 0.75
    sigma0_px: float = 0.2
    range_rate_mps: float = 1.5
    max_frames: int = 30
    max_missed: int = 8
    gate_px: float = 40.0


def hidden_from_right(rect: Rectifier, box: Box, obj: BoolA, d: float, cm: CorrespondenceMap, ext: Box,
                      config: OneCameraConfig) -> BoolA:
    """The region's pixels (bool (h, w) over box) the right camera cannot see at disparity d (px): their
    right image point (rectified x - d on the same row) lies outside the rectified frame or the raw right
    image (the first is what the matchers, working in rectified coordinates, see), or within `cover_px` of
    the right image of a known background pixel nearer by more than `depth_tol_px` (background pixels in
    the same raw row: exact without lens distortion, and for upright posts).

    cm: the learnt background's correspondence over `ext`, a box with box's rows that reaches at least as
    far right as the nearest background can hide (x1 + D_max - d)."""
    x0, y0, x1, y1 = box
    ux, _ = rect.right_at(box, d)  # its map's border replicated: the rectified column is tested apart
    w = rect.rig.right.size[0]
    xt = rect.rect_of_raw[0][y0:y1, x0:x1, 0] - np.float32(d)  # right rectified column of each pixel
    out = (ux < 0.0) | (ux > w - 1.0) | (xt < 0.0) | (xt > rect.maps[1][0].shape[1] - 1.0)
    xb = rect.rect_of_raw[0][y0:y1, ext[0]:ext[2], 0] - cm.disparity  # that of each background pixel
    near = cm.valid & (cm.disparity > d + config.depth_tol_px)
    hidden = out.copy()
    for i in np.flatnonzero(obj.any(axis=1) & near.any(axis=1)):
        cols = np.sort(xb[i][near[i]])
        k = np.clip(np.searchsorted(cols, xt[i]), 1, max(cols.size - 1, 1))
        gap = np.minimum(np.abs(cols[k - 1] - xt[i]), np.abs(cols[np.minimum(k, cols.size - 1)] - xt[i]))
        hidden[i] |= gap <= config.cover_px
    return np.asarray(hidden & obj)


def seen_by_right(rect: Rectifier, box: Box, region: BoolA, d: float, cm: CorrespondenceMap, ext: Box,
                  config: OneCameraConfig) -> BoolA:
    """The pixels of a tracked object's region (bool (h, w) over box) to match its disparity d (px) on: those
    the right camera sees (the region less `hidden_from_right`; cm, ext as there), or the whole region where
    that is under half of it (too little to match on). A plate at 12 m passing behind a post at 9 m
    (occlusion:plate) was matched with the columns the post hides from the right camera, and its disparity
    crept from 14.9 to 16 px in three frames: the post's image pulled it."""
    return half_or_whole(region & ~hidden_from_right(rect, box, region, d, cm, ext, config), region)


def coast_sigma_px(d: float, matched_sigma: float, age_s: float, fb: float, config: OneCameraConfig) -> float:
    """The 1-σ (px) of a disparity d held from stereo sightings `age_s` seconds old (on average), in
    quadrature: theirs (`matched_sigma`), `sigma0_px`, and the range the object may have covered since at
    `range_rate_mps`, as disparity (d = f b / z, so δd = d² δz / (f b); fb: f·b in px·m)."""
    drift = d * d * config.range_rate_mps * age_s / fb
    return float(np.sqrt(matched_sigma**2 + config.sigma0_px**2 + drift**2))


def nearest_prediction(coast: F64, centroid: F64, config: OneCameraConfig) -> int | None:
    """The row of `coast` (tracker.tracks.MultiTracker.coasting: x, y, d, ...) whose predicted position lies
    nearest to a region's centroid (raw left x, y), if within `gate_px`; None otherwise."""
    if len(coast) == 0:
        return None
    dist = np.hypot(coast[:, 0] - centroid[0], coast[:, 1] - centroid[1])
    k = int(np.argmin(dist))
    return k if dist[k] <= config.gate_px else None
