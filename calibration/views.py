"""Loading stereo image pairs and detecting the board in them, with named skips and one-line errors."""

from __future__ import annotations

import glob
from collections.abc import Callable
from pathlib import Path

import cv2
import numpy as np
from numpy.typing import NDArray

from calibration.board import BoardSpec, align_pair, detect_board
from calibration.errors import BoardSizeError, ImageMismatchError, UnreadableImageError
from calibration.stereo import Skip, ViewSet, check_enough


def expand(pattern: str, side: str) -> list[Path]:
    """Sorted files matching a glob (or one file name); ImageMismatchError if none match."""
    paths = sorted(Path(p) for p in glob.glob(pattern))
    if not paths:
        raise ImageMismatchError(f"--{side} {pattern!r} matches no files")
    return paths


def read_gray(path: Path) -> NDArray[np.uint8]:
    """A grey uint8 image (H, W); UnreadableImageError naming the file if it cannot be decoded."""
    img = cv2.imread(str(path), cv2.IMREAD_GRAYSCALE)
    if img is None or img.size == 0:
        raise UnreadableImageError(f"cannot read image {path} (missing, not an image, or corrupt)")
    out: NDArray[np.uint8] = np.asarray(img, dtype=np.uint8)
    return out


def detect_pairs(
    left: list[Path], right: list[Path], board: BoardSpec, progress: Callable[[str], None] | None = None
) -> ViewSet:
    """Detect the board in each left/right pair (matched by sorted order). A pair where neither image
    shows the board is skipped by name; errors: different counts or sizes, unreadable file, a board
    size found in no image, too few usable pairs (TooFewViewsError gives the minimum)."""
    say = progress or (lambda _m: None)
    if len(left) != len(right):
        raise ImageMismatchError(f"{len(left)} left images but {len(right)} right images: they must pair up")
    V, N = len(left), board.n_corners
    obs = np.full((2, V, N, 2), np.nan)
    seen = np.zeros((2, V), dtype=bool)
    skipped: list[Skip] = []
    size: tuple[int, int] | None = None
    for v, pair in enumerate(zip(left, right, strict=True)):
        oriented = [False, False]
        for c, path in enumerate(pair):
            img = read_gray(path)
            this = (int(img.shape[1]), int(img.shape[0]))
            size = size or this
            if this != size:
                raise ImageMismatchError(
                    f"image {path} is {this[0]}x{this[1]}, the others {size[0]}x{size[1]}"
                )
            det = detect_board(img, board)
            if det.corners is None:
                skipped.append(Skip(str(path), det.reason))
            else:
                obs[c, v], seen[c, v], oriented[c] = det.corners, True, det.oriented
        if seen[0, v] and seen[1, v] and not all(oriented):
            obs[1, v] = align_pair(obs[0, v], obs[1, v])
        say(f"[{v + 1}/{V}] {pair[0].name} {'ok' if seen[0, v] else '--'}  {pair[1].name} "
            f"{'ok' if seen[1, v] else '--'}")
    if not seen.any():
        raise BoardSizeError(
            f"no {board.cols}x{board.rows} inner-corner chessboard found in any of the {2 * V} images: "
            "check --board (inner corners, columns x rows)"
        )
    keep: NDArray[np.bool_] = np.asarray(seen.any(axis=0), dtype=bool)
    names = [f"{a.name}|{b.name}" for a, b in zip(left, right, strict=True)]
    assert size is not None
    views = ViewSet(obs, seen, board.object_points(), size, names, skipped).subset(keep)
    check_enough(views)
    return views
