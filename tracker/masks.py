"""Masks of a candidate box (paper eq. 9): the key-image mask against the other camera's warped image, its
largest region, and the object's outline drawn from the temporal background (tracker.verify builds on
them; tracker.temporal draws outlines with the same rule)."""

from __future__ import annotations

from collections.abc import Sequence

import cv2
import numpy as np
from cv2.typing import MatLike
from numpy.typing import NDArray

from tracker.split import same_body

U8 = NDArray[np.uint8]
BoolA = NDArray[np.bool_]


def key_mask(key: U8, other: U8, mx: NDArray[np.float32], my: NDArray[np.float32], valid: BoolA,
             eps: int, floor: U8 | None) -> BoolA:
    """eq. (9) for the pixels of a box: |Γ - Θ(x', y')| > ε (+ the temporal floor B)."""
    ref = cv2.remap(other, mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
    resid = cv2.absdiff(key, ref)
    if floor is not None:
        resid = cv2.subtract(resid, floor)
    return np.asarray((resid > eps) & valid)


CLOSE = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (5, 5))


def largest_component(mask: BoolA, close: bool = False, every: bool = False) -> BoolA:
    """The largest 8-connected component (or with `every`, all of them) with holes filled; with `close`,
    narrow channels into the holes are sealed first (a morphological closing), so those are filled too."""
    contours = _outer_contours(mask, close)
    if not contours:
        return np.zeros_like(mask)
    keep = list(contours) if every else [max(contours, key=cv2.contourArea)]
    return _filled(keep, mask.shape)


# a component above an outline's largest is its head when it covers this share of the largest's pixels
# (and HEAD_MIN_PX, its outline's area): a walker's head is 5 to 7 % of its silhouette; specks of change
# stay out. 64 px until 2026-12-06 left out the head of every walker past about 10 m (a disc 9 px across at
# 14 m: 56 px): endless:body seed 1, frames 1106-1202, a walker standing at 14 m was placed from its
# shoulders, 0.7 deg low (elevation z -3.7 over 95 frames); pan:body's elevation RMSE 0.192 / 0.208 / 0.232
# -> 0.185 / 0.184 / 0.231 deg (seeds 0 / 1 / 2) with 16 px and SolidPrior.upright_warped_sigma refitted
HEAD_MIN_SHARE = 0.02
HEAD_MIN_PX = 16
# a part below or beside an outline the left camera alone sees (`with_parts`) needs this many pixels
PART_MIN_PX = 64


def with_head(mask: BoolA, close: bool = False) -> BoolA:
    """largest_component, and each other component wholly above it that is a part of its body
    (split.same_body at one depth): a head past the neck's gap. A neck is narrower than the head and often
    near the background's grey (the simulator's walkers have none: the head 2 cm above the torso, 4 px of
    background at 3 m), so the change mask holds the head as a region apart. Left out, the centroid
    falls by 10-12 px on a walker 3 m away (walk:body, frames 2-3; against the seen surface, elevation RMSE
    0.316 -> 0.256 deg on walk:body, 0.338 -> 0.273 on illumination, 0.304 -> 0.252 on foliage). Only
    above: legs cut from a torso by the background's bands, added back, moved the track's prediction off
    the torso a stopped walker's key region was left with (endless:body, identity switches 5 -> 10)."""
    contours = _outer_contours(mask, close)
    if len(contours) < 2:
        return _filled(list(contours), mask.shape) if contours else np.zeros_like(mask)
    areas = [cv2.contourArea(c) for c in contours]
    big = int(np.argmax(areas))
    top = cv2.boundingRect(contours[big])[1]
    body: BoolA | None = None
    keep = [contours[big]]
    for c, area in zip(contours, areas, strict=True):
        if c is contours[big] or area < max(HEAD_MIN_PX, HEAD_MIN_SHARE * areas[big]):
            continue
        _, y, _, h = cv2.boundingRect(c)
        if y + h - 1 >= top:  # not wholly above the body: not drawn at all
            continue
        body = _filled([contours[big]], mask.shape) if body is None else body
        if same_body(body, 1.0, _filled([c], mask.shape), 1.0):
            keep.append(c)
    return _filled(keep, mask.shape)


def with_parts(outline: BoolA, region: BoolA) -> BoolA:
    """The outline and each other component of `region` (after a closing, holes filled; at least PART_MIN_PX)
    that is a part of its body (split.same_body at one depth), above it or below: a body the left camera
    alone sees, at the left border, whose change mask the background's bands split at the waist. There
    `with_head`'s largest component may be its legs alone (endless:body, frames 486-488: 24-32 px from the
    truth's centroid), and no stereo match tells the parts apart (tracker.temporal's one-camera sightings)."""
    every = largest_component(region, close=True, every=True) & ~outline
    n, lab = cv2.connectedComponents(every.view(np.uint8), connectivity=8)
    out = outline.copy()
    for k in range(1, n):
        part = lab == k
        if int(np.count_nonzero(part)) >= PART_MIN_PX and same_body(outline, 1.0, part, 1.0):
            out |= part
    return out


def _outer_contours(mask: BoolA, close: bool) -> Sequence[MatLike]:
    """The outer contours of a mask's 8-connected components; with `close`, after a morphological closing."""
    m8 = mask.astype(np.uint8)
    if close:
        m8 = np.asarray(cv2.morphologyEx(m8, cv2.MORPH_CLOSE, CLOSE), np.uint8) | m8
    contours, _ = cv2.findContours(m8, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    return contours


def _filled(contours: Sequence[MatLike], shape: tuple[int, ...]) -> BoolA:
    """The contours drawn filled (holes and all) on an empty mask of `shape`."""
    out = np.zeros(shape, np.uint8)
    cv2.drawContours(out, contours, -1, 1, thickness=cv2.FILLED)
    return out.astype(bool)


def largest_region(mask: BoolA) -> BoolA:
    """The largest 8-connected component of a mask, holes filled."""
    return largest_component(mask)


RING = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (9, 9))
NEAR = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (5, 5))


def temporal_outline(key: U8, bg: NDArray[np.float32], dev: NDArray[np.float32], core: BoolA,
                     region: BoolA, eps: int, taken: BoolA | None = None) -> tuple[BoolA, float, BoolA]:
    """The object's exact outline from the temporal model, inside a stereo region.

    core: pixels both keys agree are the object (left-key ∩ warped right-key mask: no occlusion shadow,
    but holes where the object overlaps its own shadow); region: where the object may be (the keys'
    union, or the left-key mask: the object and its shadow). The global gain g is Σ Γ / Σ B on the box's
    ring outside the region, less the pixels `taken` by objects found before in the box (a bright disc
    beside a second object made g 1.47 where the light had not changed); a pixel is the object if
    |Γ - g B| > ε in `core`, or > ε + 3 D elsewhere in
    `region` or a two-pixel rim, where D is the background's own mean deviation: a shadow falls on
    unchanged background (|Γ - g B| small) unless the background moves (foliage, large D).
    Returns the mask (its largest region and a head above it: with_head), g (1.0 when the ring is too
    small) and the box's pixels that changed at the strict threshold."""
    grown = cv2.dilate((region | core).astype(np.uint8), NEAR) > 0
    band = grown & ~core
    ring = (cv2.dilate(grown.view(np.uint8), RING) == 0) & (bg > 8.0)
    if taken is not None:
        ring &= ~taken
    ring = ring.view(np.uint8)
    g = 1.0
    if cv2.countNonZero(ring) >= 20:
        g = cv2.mean(key, mask=ring)[0] / cv2.mean(bg, mask=ring)[0]  # Σ Γ / Σ B over the ring
    diff = change(key, bg, g)
    changed = diff > strict_limit(dev, g, eps)
    inside = core & (diff > eps)
    return with_head(inside | (band & changed), close=True), g, changed


SMALL_HOLE = 0.01  # of the mask's area: a hole smaller is filled whether it changed or not


def changed_holes_filled(mask: BoolA, changed: BoolA, share: float = 0.25, small: float = SMALL_HOLE) -> BoolA:
    """The mask with each of its holes (4-connected) filled where at least `share` of the hole's pixels
    changed (`changed`: |Γ - g B| past its strict limit, same shape), and each hole under `small` of the
    mask's area filled whatever changed.

    The rim's growth (tracker.rim) closes the mouths of notches the outline left on a walker's shaded side,
    and may not take changed pixels in (they may be another object's); the notch stays a hole. Over
    walk:body's walkers, 2,810 hole pixels were changed, all on the body; of holes with a quarter or more
    changed, 3,000 of 3,008 pixels were the body's (endless:body: 2,543 of 2,551).

    A walker's leg whose shade and texture match the ground it covers passes both eq. (9) and the temporal
    model as background in patches (walk:body frame 288: 1,340 of the body's pixels missed, most in its
    lower legs; the centroid 4.5 px off). Over walk:body's outlines the holes under 1 % of the outline's
    area held 12,781 px, 12,060 of them the body's; on endless:body, whose walkers are far and small, 1,620
    px and 607. Filled, `tmeye eval --all` (2026-12-05) gave azimuth / elevation RMSE against the seen
    surface walk:body 0.054 -> 0.050° / 0.117 -> 0.104°, illumination 0.051 -> 0.048 / 0.114 -> 0.098,
    foliage 0.052 -> 0.050 / 0.116 -> 0.111, endless 0.0313 -> 0.0313 / 0.144 -> 0.142. Larger holes with no
    change are mostly the background between a walker's legs (endless:body: 27,678 px in holes over 3 % of
    their outlines, 1,228 of them a body's) and stay."""
    contours = _outer_contours(mask, False)
    if not contours:
        return mask
    holes = (_filled(list(contours), mask.shape) & ~mask).view(np.uint8)
    n, labels = cv2.connectedComponents(holes, connectivity=4)
    if n < 2:
        return mask
    size = np.bincount(labels.ravel(), minlength=n)
    moved = np.bincount(labels[changed], minlength=n)
    fill = (moved >= share * size) | (size < small * int(np.count_nonzero(mask)))
    fill[0] = False
    return np.asarray(mask | fill[labels])


def global_gain(key: U8, bg: NDArray[np.float32]) -> float | None:
    """g = median of Γ / B over grid cells whose background is not dark (B > 8); None with too few."""
    ok = bg > 8.0
    if int(np.count_nonzero(ok)) < 64:
        return None
    return float(np.median(key[ok].astype(np.float32) / bg[ok]))


def frame_gain(key: U8, bg: NDArray[np.float32], stride: int) -> float | None:
    """global_gain of a whole frame Γ (H, W) against its temporal background B (H, W), on every second cell
    of the stride grid: about 5,000 cells at 640 x 480, plenty for a median (about 60 µs)."""
    s = 2 * stride
    return global_gain(key[::s, ::s], bg[::s, ::s])


def change(key: U8, bg: NDArray[np.float32], g: float) -> NDArray[np.float32]:
    """|Γ - g B|: how far each pixel is from the temporal background at global gain g."""
    return np.asarray(np.abs(key.astype(np.float32) - np.float32(g) * bg), np.float32)


def strict_limit(dev: NDArray[np.float32], g: float, eps: int) -> NDArray[np.float32]:
    """ε + 3 g D: the change a pixel must exceed where the background itself moves by D on average."""
    return np.asarray(np.float32(eps) + np.float32(3.0 * g) * dev, np.float32)


def seen_changed(mask: BoolA, changed: BoolA, key: BoolA) -> BoolA:
    """The pixels of an object's mask (h, w) to match its disparity on: those the temporal model (`changed`:
    |Γ - g B| past its strict limit) or eq. (9) (`key`: the left-key mask) sees change. A pixel neither
    sees change is the background showing through the outline, which fills the gaps it encloses (between
    a walker's legs, under its arms): the background there matches at its own disparity and pulls the
    object's towards it. endless:body frame 1005, a walker at 20 m before a hedge: 61 of its 592 pixels
    lay off it, and its region matched at 8.85 px; the visible surface's disparity is 9.04 px, the core
    of its true silhouette matched at 8.93. The whole mask where those pixels are over half of it (what
    is left would be too little to match)."""
    return half_or_whole(mask & (changed | key), mask)


def changed_part(mask: BoolA, key: U8, bg: NDArray[np.float32], g: float, eps: int) -> BoolA:
    """A person's outline (h, w) less the background seen through it: its pixels unlike the temporal
    background (|Γ - g B| > ε; key and bg the box's (h, w) left image and background), or the whole outline
    where those are under half of it (half_or_whole). The outline is filled (with_head closes and fills the
    gaps between a walker's legs and under its arms: 12 % of a standing walker's outline at 13 m on
    endless:body, frame 1800), and a part of it holding that background matches between the body's depth
    and the background's (tracker.disparity_sigma.part_fits). Against the seen surface's disparity, the
    parts' mean over the whole outline was off by a median 0.073 px on endless:body's 1,116 even frames
    with a person's outline, over its changed pixels 0.046 px, over the true silhouette's pixels 0.043 px
    (an oracle); walk:body's gaps are narrower: 0.090, 0.097 and 0.098 px."""
    return half_or_whole(mask & (change(key, bg, g) > eps), mask)


def half_or_whole(part: BoolA, whole: BoolA) -> BoolA:
    """`part` of a region to match on where it is at least half of `whole`, else `whole` (what is left would
    be too little to match on)."""
    return part if 2 * int(np.count_nonzero(part)) >= int(np.count_nonzero(whole)) else whole


_CLAIM = np.ones((5, 5), np.uint8)


def _grown(m8: U8) -> BoolA:
    """A uint8 mask's pixels grown by two (the 5x5 square): what a found object claims about it."""
    return np.asarray(cv2.dilate(m8, _CLAIM) > 0)


def taken_pixels(mask: BoolA, shadow_px: float, changed: BoolA | None) -> BoolA:
    """The pixels of a box that a found object (its mask) explains: the object and its occlusion shadow (the
    object shifted left by shadow_px = d - d_background, approximately, in raw pixels), grown by two. With the
    temporal model (`changed`: pixels unlike the background), shadow pixels that changed are left: they
    are another object seen there, not the shadow of this one."""
    m8 = mask.astype(np.uint8)
    shift = np.array([[1.0, 0.0, -shadow_px], [0.0, 1.0, 0.0]], np.float32)
    shadow = np.asarray(cv2.warpAffine(m8, shift, (m8.shape[1], m8.shape[0]), flags=cv2.INTER_NEAREST), np.uint8)
    if changed is not None:
        shadow[changed] = 0
    return _grown(m8 | shadow)


def found_pixels(found: list[BoolA]) -> BoolA | None:
    """The pixels (grown by two) of the objects found before in a box (their masks), or None: not the background of a
    region verified after them, so left out of its temporal outline's gain. Parts of the same body too:
    a region beside a bright torso whose ring took the torso in got g 1.28 where the light had not
    changed, and most of the region looked changed (a ghost of 5,400 px joined to a walker at 3 m,
    walk:body frame 24)."""
    if not found:
        return None
    m8 = np.zeros(found[0].shape, np.uint8)
    for mask in found:
        m8 |= mask.view(np.uint8)
    return _grown(m8)
