"""Stereo frames and the frame-source interface (a swap point).

A frame source yields `StereoFrame`s: a left/right grey image pair with capture timestamps. Sources:
the simulated rig (tracker.sim), video files, USB/V4L2 cameras and RTSP streams (tracker.sources).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

U8 = NDArray[np.uint8]


class FrameError(ValueError):
    """Bad input frames: empty, mismatched in size, or of the wrong type."""


@dataclass(frozen=True)
class GimbalState:
    """Pan/tilt angles (degrees) of the mount when the frame was captured."""

    pan_deg: float = 0.0
    tilt_deg: float = 0.0


@dataclass(frozen=True)
class StereoFrame:
    """One stereo pair. Images are grey uint8 of shape (H, W); times are seconds (monotonic clock for live
    sources, scenario time for the simulator). `offset_s` = t_right - t_left. A colour source also keeps
    its images in colour, BGR uint8 (H, W, 3), for viewing and recording (the tracker works on grey);
    None for grey sources such as the simulator."""

    index: int
    left: U8
    right: U8
    t_left: float
    t_right: float
    gimbal: GimbalState | None = None
    left_colour: U8 | None = None
    right_colour: U8 | None = None

    @property
    def t(self) -> float:
        """Capture time of the pair: the left image's."""
        return self.t_left

    @property
    def offset_s(self) -> float:
        """Left/right capture-time offset in seconds (right minus left)."""
        return self.t_right - self.t_left


def check_pair(left: object, right: object) -> None:
    """Raise FrameError with a one-line reason unless left/right are non-empty grey uint8 images of one size."""
    for name, img in (("left", left), ("right", right)):
        if not isinstance(img, np.ndarray):
            raise FrameError(f"{name} image is not an array (got {type(img).__name__})")
        if img.size == 0:
            raise FrameError(f"{name} image is empty")
        if img.ndim != 2 or img.dtype != np.uint8:
            raise FrameError(f"{name} image must be grey uint8 of shape (H, W), got {img.dtype} {img.shape}")
    assert isinstance(left, np.ndarray) and isinstance(right, np.ndarray)
    if left.shape != right.shape:
        raise FrameError(f"left and right images differ in size: {left.shape} vs {right.shape}")


class FrameSource(Protocol):
    """Anything that yields stereo pairs. `read()` returns None at the end of the stream."""

    def read(self) -> StereoFrame | None: ...

    def close(self) -> None: ...
