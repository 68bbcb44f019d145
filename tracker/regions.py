"""Small measures of an object's region (a bool mask over its box): its centroid (paper eq. 10), the
background's disparity behind it, the nearest track's predicted disparity, and its row thirds (tracker.verify
matches a region whose depth varies on its parts)."""

from __future__ import annotations

from collections.abc import Iterator

import cv2
import numpy as np
from numpy.typing import NDArray

from tracker.bgdepth import CorrespondenceMap

F64 = NDArray[np.float64]
U8 = NDArray[np.uint8]
BoolA = NDArray[np.bool_]
Box = tuple[int, int, int, int]


def mask_centroid(m8: U8) -> tuple[int, F64]:
    """Pixel count Σ c(i, j) and centroid (Σ i c / Σ c, Σ j c / Σ c) (2,) of a 0/1 mask (eq. 10), from its
    column and row sums."""
    cols = cv2.reduce(m8, 0, cv2.REDUCE_SUM, dtype=cv2.CV_32S).ravel()  # Σ_j c(i, j) per column i
    rows = cv2.reduce(m8, 1, cv2.REDUCE_SUM, dtype=cv2.CV_32S).ravel()
    n = int(cols.sum())
    return n, np.array([float(cols @ np.arange(cols.size)) / n, float(rows @ np.arange(rows.size)) / n])


def background_disparity(cm: CorrespondenceMap, obj: BoolA, c: F64) -> float:
    """The known background's disparity right behind the object's centre c (box pixels), or at the
    object pixel nearest to it; 0 when the background behind the object is unknown (no gap test then)."""
    iy, ix = int(c[1]), int(c[0])
    if obj[iy, ix] and cm.valid[iy, ix]:
        return float(cm.disparity[iy, ix])
    ys, xs = np.nonzero(obj & cm.valid)
    if xs.size == 0:
        return 0.0
    k = int(np.argmin(np.hypot(xs - c[0], ys - c[1])))
    return float(cm.disparity[ys[k], xs[k]])


def median_behind(cm: CorrespondenceMap, obj: BoolA, default: float = 0.0) -> float:
    """The median of the known background's disparity (px) over the object's pixels (`default` where none is
    known)."""
    d = cm.disparity[obj & cm.valid]
    return float(np.median(d)) if d.size else default


def in_front(d: float, d_bg: float, gap: float, gap_px: float) -> bool:
    """Whether disparity d (px) lies in front of the background's d_bg (px) by the depth-gap test,
    d >= d_bg (1 + gap) + gap_px."""
    return d >= d_bg * (1.0 + gap) + gap_px


def row_thirds(obj: BoolA) -> Iterator[BoolA]:
    """The region, then its parts in the top, middle and bottom thirds of its rows (of 64 px or more)."""
    yield obj
    rows = np.flatnonzero(obj.any(axis=1))
    if rows.size == 0:
        return
    cuts = [int(v) for v in np.linspace(rows[0], rows[-1] + 1, 4)]
    for a, b in zip(cuts[:-1], cuts[1:], strict=True):
        part = np.zeros_like(obj)
        part[a:b] = obj[a:b]
        if int(np.count_nonzero(part)) >= 64:
            yield part


def hints_inside(hints: F64 | None, region: BoolA, box: Box, reach_px: int = 0) -> list[F64]:
    """The predicted tracks (rows (x, y, disparity), raw left pixels) whose position lies in the region, or
    within reach_px of one of its pixels (a disc)."""
    if hints is None or len(hints) == 0:
        return []
    x0, y0 = box[0], box[1]
    h, w = region.shape
    r = reach_px
    out = []
    for hint in hints:
        x, y = int(hint[0]) - x0, int(hint[1]) - y0
        if not (-r <= x < w + r and -r <= y < h + r):
            continue
        if r == 0:
            if region[y, x]:
                out.append(hint)
            continue
        ya, yb, xa, xb = max(y - r, 0), min(y + r + 1, h), max(x - r, 0), min(x + r + 1, w)
        ys, xs = np.nonzero(region[ya:yb, xa:xb])
        if xs.size and bool(np.any((xs + xa - x) ** 2 + (ys + ya - y) ** 2 <= r * r)):
            out.append(hint)
    return out


def hints_around(hints: F64 | None, region: BoolA, box: Box) -> list[float]:
    """The predicted disparities (px) of the tracks whose predicted position lies within the bounding
    rectangle of the region (box pixels): a track seen past another object's edge has its predicted
    centroid there, though often not on the region itself."""
    if hints is None or len(hints) == 0:
        return []
    bx, by, bw, bh = cv2.boundingRect(region.view(np.uint8))
    x0, y0 = box[0] + bx, box[1] + by
    return [float(h[2]) for h in hints if x0 <= h[0] < x0 + bw and y0 <= h[1] < y0 + bh]


def nearest_hint(hints: F64 | None, region: BoolA, box: Box, reach_px: int = 0) -> float | None:
    """The disparity of the predicted track nearest to the region's centre, if one lies inside it (or within
    reach_px of its pixels: hints_inside)."""
    ys, xs = np.nonzero(region)
    if xs.size == 0:
        return None
    x0, y0 = box[0], box[1]
    inside = hints_inside(hints, region, box, reach_px)
    if not inside:
        return None
    c = np.array([xs.mean() + x0, ys.mean() + y0])
    return float(min(inside, key=lambda h: float(np.hypot(*(h[:2] - c))))[2])
