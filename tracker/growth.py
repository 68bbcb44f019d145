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
                 changed: BoolA, d: float, eps: int, min_area_px: int, at_depth: BoolA | None = None) -> BoolA:
    """`grown_by_change` of an outline `obj` over the raw-left box at the body's disparity d (px): cm is the
    box's correspondence map (eq. 9's), bg the temporal background B (full image), changed the box's changed
    pixels it may take, eps eq. (9)'s ε. Worked out over the
    candidates' bounding rectangle and 4 px about it only (what joins does so through them; the 7 x 7
    windows about them). at_depth: the box's pixels whose background lies at the body's own depth and that
    changed (grown_by_change's; tracker.verify.Verifier.at_depth; None: no part joins so). A sliver (under
    4 min_area_px pixels) is kept as it is: see grown_by_change."""
    if not can_grow(obj, changed, min_area_px):
        return obj
    ys, xs = np.nonzero(changed & ~obj)
    h, w = obj.shape
    m = 4
    sy0, sy1 = max(int(ys.min()) - m, 0), min(int(ys.max()) + m + 1, h)
    sx0, sx1 = max(int(xs.min()) - m, 0), min(int(xs.max()) + m + 1, w)
    x0, y0, x1, y1 = part = (box[0] + sx0, box[1] + sy0, box[0] + sx1, box[1] + sy1)
    out = obj.copy()
    out[sy0:sy1, sx0:sx1] = grown_by_change(frame.left[y0:y1, x0:x1], bg[y0:y1, x0:x1],
                                            rect.right_image_at(frame.right, part, d),
                                            cm.crop((sx0, sy0, sx1, sy1)).warp(frame.right),
                                            obj[sy0:sy1, sx0:sx1], changed[sy0:sy1, sx0:sx1], eps,
                                            at_depth=None if at_depth is None else at_depth[sy0:sy1, sx0:sx1])
    return out


def can_grow(obj: BoolA, changed: BoolA, min_area_px: int) -> bool:
    """Whether grow_tracked may add to the outline `obj` (bool, box-sized): it is no sliver (at least 4
    min_area_px pixels) and some `changed` pixel lies outside it. Callers ask first to spare the box's
    correspondence map and at-depth pixels when it may not."""
    return int(np.count_nonzero(obj)) >= 4 * min_area_px and bool((changed & ~obj).any())


def at_own_depth(cm: CorrespondenceMap, d: float, gap: float, gap_px: float) -> BoolA:
    """Where the background's map (cm, over a box) is known and lies at a body's own depth d (px): neither
    in front of the other by twice the depth-gap test (tracker.regions.in_front, d >= d_bg (1 + gap) +
    gap_px, both ways round; twice, as tracker.temporal takes an object near its background: d is a
    track's prediction, 0.8 px off its match at endless:body frame 1333). There eq. (9) and the other
    camera alike see the body as its background."""
    d_bg, g, g_px = cm.disparity, 2.0 * gap, 2.0 * gap_px
    return np.asarray(cm.valid & (d < d_bg * (1.0 + g) + g_px) & (d_bg < d * (1.0 + g) + g_px))


def without_uncovered(parts: BoolA, key: U8, bg: NDArray[np.float32]) -> BoolA:
    """`parts` less each of its connected parts (joined by a 5 x 5 closing) whose edge is the background
    model's rather than the frame's: the mean gradient magnitude (3 x 3 Sobel) along the part's own
    boundary is more than 1.5 times higher in B (g B, as the caller passes it) than in Γ. That is
    background uncovered where an object stood while the model learnt it, a "ghost" (Cucchiara et al. 2003
    tell one from an object by the gradient along its boundary): the object's outline shows in B, not in
    the frame. Measured on at_own_depth's parts: a
    walker's legs before a low wall at its depth 70-82 against 19-44 (endless:body frames 1318-1334), a
    plate before a post 250-317 against 25-31 (endless:plate), where a walker stood at start-up 27
    against 199 (startup, stream learning, frame 56). At a factor of 1 a few parts of bodies were lost:
    occlusion:body's and endless:body's azimuth against the seen surface 0.1791 -> 0.1798° and 0.0396 ->
    0.0398°; at 1.5 no figure of `eval --all` moved."""
    if not parts.any():
        return parts
    bx, by, bw, bh = cv2.boundingRect(parts.view(np.uint8))
    h, w = parts.shape  # worked out over the parts' rectangle and 4 px about it (the closing reaches 4 px)
    y0, y1, x0, x1 = max(by - 4, 0), min(by + bh + 4, h), max(bx - 4, 0), min(bx + bw + 4, w)
    sub = np.ascontiguousarray(parts[y0:y1, x0:x1])
    n, lab = cv2.connectedComponents(cv2.morphologyEx(sub.view(np.uint8), cv2.MORPH_CLOSE, _CLOSE),
                                     connectivity=8)
    edge = sub & ~cv2.erode(sub.view(np.uint8), _EDGE).view(bool)
    at = np.flatnonzero(edge)
    lab_e = np.asarray(lab, np.int32).ravel()[at]
    frame_g = np.bincount(lab_e, _grad(key[y0:y1, x0:x1]).ravel()[at], n)
    model_g = np.bincount(lab_e, _grad(bg[y0:y1, x0:x1]).ravel()[at], n)
    keep = 1.5 * frame_g >= model_g  # sums over the same pixels: the means compared
    keep[0] = False
    out = np.zeros_like(parts)
    out[y0:y1, x0:x1] = sub & keep[lab]
    return out


def _grad(img: NDArray[np.uint8] | NDArray[np.float32]) -> NDArray[np.float32]:
    """The gradient magnitude (3 x 3 Sobel) of an image, float32 of its shape."""
    a = img.astype(np.float32)
    return np.asarray(np.hypot(cv2.Sobel(a, cv2.CV_32F, 1, 0, ksize=3), cv2.Sobel(a, cv2.CV_32F, 0, 1, ksize=3)),
                      np.float32)


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
                    changed: BoolA, eps: int, margin: int = 2, max_corr: float = 0.6,
                    at_depth: BoolA | None = None) -> BoolA:
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
    meanwhile) at the object's depth where it stood close before it. Then whole parts of the changed pixels
    join where pixel by pixel the other camera cannot tell the object's depth from the background's but on
    the whole can (`_grown_by_parts`; endless:body, a walker's legs: elevation RMSE against the seen
    surface approach:body 0.065 -> 0.015 deg, the ball's shaded lower limb). Where the background itself
    lies at the object's depth (`at_depth`, at_own_depth: a walker's legs before a low wall it walks
    along) no camera tells the two apart, and a part joins on the temporal model's word: most of it at
    the object's depth as above and over such background (`_grown_by_parts`)."""
    k = key.astype(np.int16)
    r_d = np.abs(k - other_at_d.astype(np.int16))
    r_bg = np.abs(k - other_at_bg.astype(np.int16))
    out = _grown_pixelwise(key, bg, obj, changed & (r_d <= eps) & (r_bg > r_d + margin), max_corr)
    return _grown_by_parts(key, bg, out, changed, at_object_depth(r_d, r_bg, eps, at_depth), r_bg - r_d, margin,
                           max_corr, at_depth=at_depth)


def at_object_depth(r_d: NDArray[np.int16], r_bg: NDArray[np.int16], eps: int, at_depth: BoolA | None) -> BoolA:
    """The pixels the other camera shows at the object's depth: |Γ - Θ_d| <= ε (r_d), or, where the
    background's map lies at the object's own depth (`at_depth`, at_own_depth), |Γ - Θ_bg| <= ε (r_bg): the
    map's disparity there is the object's depth as well, to within the depth-gap test, and a leg a little
    nearer or farther than the body's centre matches at it rather than at d. endless:body frame 1332, a
    walker's legs before a low wall at its depth: 49 % of them matched at d, 84 % lay over the wall, and
    they stayed out (the centroid 20.4 px off the truth's, 3.8 px with them; elevation RMSE against the seen
    surface 0.182 -> 0.153°)."""
    at_d = r_d <= eps
    return at_d if at_depth is None else np.asarray(at_d | (at_depth & (r_bg <= eps)))


def _grown_pixelwise(key: U8, bg: NDArray[np.float32], obj: BoolA, own: BoolA, max_corr: float) -> BoolA:
    """`obj` grown by the pixels of `own` (changed, and the object's surface by the other camera) that are
    not the background's texture relit, connected to it (grown_by_change)."""
    cand = own & ~obj
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


def _grown_by_parts(key: U8, bg: NDArray[np.float32], obj: BoolA, changed: BoolA, at_d: BoolA,
                    gap: NDArray[np.int16], margin: int, max_corr: float, min_share: float = 0.5,
                    at_depth: BoolA | None = None) -> BoolA:
    """`obj` grown by whole parts of the changed pixels next to it that the other camera shows at the object's
    disparity though pixel by pixel it cannot tell that from the background's: a smooth surface seen
    against itself a few pixels off (a walker's leg, 12 px wide, over the ground it stands on, whose
    disparity is 5 px off its own). A part: the changed pixels not in `obj` that a closing (5 x 5) joins,
    as the temporal model leaves gaps of a few pixels where the object's grey passes for the background's;
    it joins where it lies within 8 px of `obj` or of a part joined before (up to 4 rounds: the next part
    down a leg), or within 24 px where the other camera tells it (the mean gap past the margin) and it lies
    above or below the outline, its columns within 8 px of the outline's (walk:body frame 10, patches of a
    shaded far leg 10-20 px below the outline's: the centroid 8.2 -> 5.1 px off; elevation RMSE against the
    seen surface walk, illumination and foliage 0.134, 0.129 and 0.132 -> 0.117, 0.114 and 0.116°; a thing
    beside the outline stays out), most of it (min_share) is at the object's depth (`at_d`:
    at_object_depth), the other camera shows it at the object's disparity better than at the background's on
    the whole, by more than `margin` grey levels a pixel (mean of gap = |Γ - Θ_bg| - |Γ - Θ_d|: uncovered background
    and a shadow on the ground match at the background's as well or better), and its texture is not the
    background's relit (texture_corr at most max_corr). at_depth, where the background's map lies at the
    object's depth (None: nowhere), stands in for the margin where most of the part (min_share) lies over
    it."""
    rest = changed & ~obj
    if not rest.any():
        return obj
    closed = cv2.morphologyEx(rest.view(np.uint8), cv2.MORPH_CLOSE, _CLOSE)
    n, labels = cv2.connectedComponents(closed, connectivity=8)
    lab = np.where(rest, np.asarray(labels, np.int32), np.int32(0))
    flat = lab.ravel()
    cnt = np.maximum(np.bincount(flat, minlength=n), 1)
    share = np.bincount(flat, at_d.ravel().astype(np.float64), n) / cnt
    mean_gap = np.bincount(flat, gap.ravel().astype(np.float64), n) / cnt
    told = mean_gap > margin
    if at_depth is not None:  # or no camera can tell: the background lies at the object's depth
        told |= np.bincount(flat, at_depth.ravel().astype(np.float64), n) / cnt >= min_share
    fit = (share >= min_share) & told
    fit[0] = False
    if not fit.any():
        return obj
    fit &= _parts_corr(key, bg, lab, n) <= max_corr
    out, taken = obj.copy(), np.zeros(n, bool)
    ys, xs = np.nonzero(lab)
    x_lo, x_hi = np.full(n, lab.shape[1]), np.full(n, -1)
    np.minimum.at(x_lo, lab[ys, xs], xs)
    np.maximum.at(x_hi, lab[ys, xs], xs)
    told_by_camera = mean_gap > margin
    for _ in range(_ROUNDS):  # parts within _REACH of the outline, then of what joined
        near, far = np.zeros(n, bool), np.zeros(n, bool)
        near[np.unique(lab[cv2.dilate(out.view(np.uint8), _REACH).view(bool)])] = True
        far[np.unique(lab[cv2.dilate(out.view(np.uint8), _FAR_REACH).view(bool)])] = True
        cols = np.flatnonzero(out.any(axis=0))  # farther: above or below the outline, within its columns
        far &= told_by_camera & (x_lo >= cols[0] - _SIDE_PX) & (x_hi <= cols[-1] + _SIDE_PX) if cols.size else False
        new = fit & (near | far) & ~taken
        if not new.any():
            break
        taken |= new
        out |= new[lab]
    return out


_CLOSE = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (5, 5))
_EDGE = np.ones((3, 3), np.uint8)
# a part joins within 8 px of the outline (a walker's knees where the model saw no change), in up to 4 rounds;
# one the other camera tells within 24 px, above or below the outline (its columns within _SIDE_PX of its)
_REACH = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (17, 17))
_ROUNDS = 4
_FAR_REACH = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (49, 49))
_SIDE_PX = 8


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
