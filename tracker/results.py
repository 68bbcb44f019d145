"""What the pipeline finds in a frame: a verified object's blob (eq. 10's centroid and its disparity), its
detection with eq. (1-2)'s localisation and track, and the frame's result. Immutable dataclasses that can
be handed to other threads and published to many subscribers."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from tracker.detect import Box, paint_masks
from tracker.localize import Localization

F64 = NDArray[np.float64]
BoolA = NDArray[np.bool_]


class PartFit(NamedTuple):
    """One part's match (tracker.disparity_sigma.part_fits): its disparity d (px), its own fit's 1-σ (px)
    and its pixel count."""

    d: float
    sigma: float
    pixels: int


@dataclass(frozen=True)
class Blob:
    """A verified object in one frame. box: raw-left pixels (x0, y0, x1, y1); mask: bool (y1-y0, x1-x0);
    centroid_raw: eq. (10) in raw left pixels; centroid_rect: the same pixels' centroid in rectified
    coordinates; disparity, disparity_sigma, bg_disparity in px (rectified); one_camera: seen by the left
    camera alone, its disparity the one a track holds (tracker.one_camera); parts: for a person seen by both
    cameras, the parts of its whole outline that matched (PartFit each; tracker.disparity_sigma.on_surface),
    its disparity their mean where at least MIN_PARTS did; for any other blob empty. disparity_sigma stays
    the matcher's own 1-σ of its one fit (the tracker's measurement noise); the 1-σ a location is given also
    counts the parts' scatter (tracker.disparity_sigma.blob_sigma). part_only: a region at the left border
    verified at the disparity of a track beyond it, kept only once joined to the rest."""

    box: Box
    mask: BoolA
    area: int
    centroid_raw: F64
    centroid_rect: F64
    disparity: float
    disparity_sigma: float
    bg_disparity: float
    score: float
    gain: float = 1.0
    one_camera: bool = False
    parts: tuple[PartFit, ...] = ()
    part_only: bool = False  # verified at the disparity of a track beyond it (tracker.regions.border_hints)
    bottom_inferred: bool = False  # its feet filled where eq. (9) cannot see them (bottom_edge.feet_at_ground_depth)


@dataclass(frozen=True)
class Detection:
    """One verified object: its blob, 3-D localisation and track id (a new track's id from its first
    sighting; the track becomes primary only once confirmed)."""

    blob: Blob
    loc: Localization
    track_id: int


@dataclass(frozen=True)
class FrameResult:
    """Everything the pipeline knows after a frame. primary: the primary target's detection this frame,
    None if it was not seen. stage_ms: time per stage (milliseconds). deferred_boxes: candidate boxes put
    off to the next frame by the frame's time budget (tracker.schedule)."""

    index: int
    t: float
    detections: tuple[Detection, ...]
    primary_id: int | None
    primary: Detection | None
    stage_ms: dict[str, float] = field(default_factory=dict)
    deferred_boxes: int = 0

    def foreground_mask(self, shape: tuple[int, int]) -> NDArray[np.bool_]:
        """The full-resolution left foreground mask of all verified objects, (H, W) bool."""
        return paint_masks([(d.blob.box, d.blob.mask) for d in self.detections], 0, shape)
