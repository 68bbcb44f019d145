"""A tracked body's outline grown into the pixels the temporal model sees changed next to it that the other
camera shows at the body's own depth (`grown_by_change`; tracker.verify draws the outline, then grows it)."""

from __future__ import annotations

import cv2
import numpy as np
from numpy.typing import NDArray

from tracker.bgdepth import CorrespondenceMap
from tracker.detect import Box
from tracker.frames import StereoFrame
from tracker.rectify import Rectifier

U8 = NDArray[np.uint8]
F32 = NDArray[np.float32]
BoolA = NDArray[np.bool_]


def grow_tracked(rect: Rectifier, frame: StereoFrame, box: Box, cm: CorrespondenceMap, bg: F32, obj: BoolA,
                 changed: BoolA, d: float, eps: int) -> BoolA:
    """`grown_by_change` of an outline `obj` over the raw-left box at the body's disparity d (px): cm is the
    box's correspondence map (eq. 9's), bg the temporal background B (full image), changed the box's changed
    pixels it may take, eps eq. (9)'s ε. Worked out over the
    candidates' bounding rectangle and 4 px about it only (what joins does so through them; the 7 x 7
    windows about them)."""
    ys, xs = np.nonzero(changed & ~obj)
    if xs.size == 0:
        return obj
    h, w = obj.shape
    m = 4
    sy0, sy1 = max(int(ys.min()) - m, 0), min(int(ys.max()) + m + 1, h)
    sx0, sx1 = max(int(xs.min()) - m, 0), min(int(xs.max()) + m + 1, w)
    x0, y0, x1, y1 = part = (box[0] + sx0, box[1] + sy0, box[0] + sx1, box[1] + sy1)
    at_bg = cm.crop((sx0, sy0, sx1, sy1)).warp(frame.right)
    out = obj.copy()
    out[sy0:sy1, sx0:sx1] = grown_by_change(frame.left[y0:y1, x0:x1], bg[y0:y1, x0:x1],
                                            rect.right_image_at(frame.right, part, d), at_bg,
                                            obj[sy0:sy1, sx0:sx1], changed[sy0:sy1, sx0:sx1], eps)
    return out


def local_corr(key: U8, bg: NDArray[np.float32], win: int = 7) -> NDArray[np.float32]:
    """Zero-mean normalised correlation of Γ and B over the win x win window about each pixel (1: the same
    texture; 1 where either is flat in the window, under 1 grey level rms: nothing tells them apart)."""
    a, b = key.astype(np.float32), bg.astype(np.float32)
    k = (win, win)
    ma, mb = cv2.blur(a, k), cv2.blur(b, k)
    va = cv2.blur(a * a, k) - ma * ma
    vb = cv2.blur(b * b, k) - mb * mb
    cab = cv2.blur(a * b, k) - ma * mb
    flat = (va < 1.0) | (vb < 1.0)
    return np.asarray(np.where(flat, 1.0, cab / np.sqrt(np.maximum(va * vb, 1e-6))), np.float32)


def grown_by_change(key: U8, bg: NDArray[np.float32], other_at_d: U8, other_at_bg: U8, obj: BoolA,
                    changed: BoolA, eps: int, margin: int = 2, max_corr: float = 0.6) -> BoolA:
    """The outline `obj` grown into the changed pixels connected to it that are the object's surface too.

    The temporal outline is drawn inside the region eq. (9) marks (with a two-pixel rim): a shadow falls on
    unchanged background, and stays out so. Where the object's surface passes eq. (9) because the
    background behind it is as smooth as it is, or nearly at its depth (a walker's far leg over the
    ground it stands on, a car's plain side), the temporal model still sees it change. A changed pixel
    (`changed`: |Γ - g B| past the strict limit) joins the outline where it is connected to it, the other
    camera shows the same grey there at the object's own disparity d (`other_at_d`: that camera's image
    sampled at each pixel shifted by d; |Γ - Θ_d| <= ε: a surface at the object's depth) better, by more
    than `margin` grey levels, than at the learnt background's (`other_at_bg`, eq. (9)'s Θ: a background
    the model learnt with a target standing in it shows as change where the target left, and at the
    target's depth too where the learnt geometry holds it: startup, a walker in view from frame 0), and its
    neighbourhood is not the background's own texture relit (`local_corr` at most `max_corr`), nor is each
    connected part so added as a whole (`texture_corr`): a shadow by the object's feet lies at the ground's
    depth where it touches it, and background uncovered where the object stood long (its model unlearnt
    meanwhile) at the object's depth where it stood close before it."""
    k = key.astype(np.int16)
    r_d = np.abs(k - other_at_d.astype(np.int16))
    own = (r_d <= eps) & (np.abs(k - other_at_bg.astype(np.int16)) > r_d + margin)
    cand = changed & own & ~obj
    if not cand.any():
        return obj
    ys, xs = np.nonzero(cand)  # the windows about the candidates only
    r = 3
    y0, y1 = max(int(ys.min()) - r, 0), int(ys.max()) + r + 1
    x0, x1 = max(int(xs.min()) - r, 0), int(xs.max()) + r + 1
    cand[y0:y1, x0:x1] &= local_corr(key[y0:y1, x0:x1], bg[y0:y1, x0:x1], 2 * r + 1) <= max_corr
    n, lab = cv2.connectedComponents((obj | cand).view(np.uint8), connectivity=8)
    touching = np.zeros(n, bool)
    touching[np.unique(lab[obj])] = True
    touching[0] = False
    added = cand & touching[lab]
    # a window across a shadow's edge mixes two gains and correlates poorly: the band along it is a part
    # of its own, the background's texture relit over it as a whole
    n_add, parts = cv2.connectedComponents(added.view(np.uint8), connectivity=8)
    keep = _parts_corr(key, bg, parts, n_add) <= max_corr
    keep[0] = False
    return np.asarray(obj | keep[parts])


def _parts_corr(key: U8, bg: NDArray[np.float32], parts: NDArray[np.int32], n: int) -> NDArray[np.float64]:
    """`texture_corr` of each labelled part (labels 1..n-1 of `parts`; 0 is none) at once, from its sums."""
    at = np.flatnonzero(parts)  # the parts' pixels only (label 0 stays empty)
    lab = parts.ravel()[at]
    a, b = key.ravel()[at].astype(np.float64), bg.ravel()[at].astype(np.float64)
    cnt = np.bincount(lab, minlength=n).astype(np.float64)
    sa, sb = np.bincount(lab, a, n), np.bincount(lab, b, n)
    saa, sbb, sab = np.bincount(lab, a * a, n), np.bincount(lab, b * b, n), np.bincount(lab, a * b, n)
    c = np.maximum(cnt, 1.0)
    va, vb, cab = saa - sa * sa / c, sbb - sb * sb / c, sab - sa * sb / c
    den = np.sqrt(np.maximum(va * vb, 0.0))
    return np.where(den > 1e-9, cab / np.where(den > 1e-9, den, 1.0), 1.0)
