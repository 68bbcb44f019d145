"""Masks of a candidate box (paper eq. 9): the key-image mask against the other camera's warped image, its
largest region, and the object's outline drawn from the temporal background (tracker.verify builds on
them; tracker.temporal draws outlines with the same rule)."""

from __future__ import annotations

import cv2
import numpy as np
from numpy.typing import NDArray

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
    m8 = mask.astype(np.uint8)
    if close:
        m8 = np.asarray(cv2.morphologyEx(m8, cv2.MORPH_CLOSE, CLOSE), np.uint8) | m8
    contours, _ = cv2.findContours(m8, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    if not contours:
        return np.zeros_like(mask)
    keep = list(contours) if every else [max(contours, key=cv2.contourArea)]
    out = np.zeros(mask.shape, np.uint8)
    cv2.drawContours(out, keep, -1, 1, thickness=cv2.FILLED)
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
    Returns the mask, g (1.0 when the ring is too small) and the box's pixels that changed at the strict
    threshold."""
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
    return largest_component(inside | (band & changed), close=True), g, changed


def change(key: U8, bg: NDArray[np.float32], g: float) -> NDArray[np.float32]:
    """|Γ - g B|: how far each pixel is from the temporal background at global gain g."""
    return np.asarray(np.abs(key.astype(np.float32) - np.float32(g) * bg), np.float32)


def strict_limit(dev: NDArray[np.float32], g: float, eps: int) -> NDArray[np.float32]:
    """ε + 3 g D: the change a pixel must exceed where the background itself moves by D on average."""
    return np.asarray(np.float32(eps) + np.float32(3.0 * g) * dev, np.float32)


def texture_corr(key: U8, bg: NDArray[np.float32], mask: BoolA) -> float:
    """Zero-mean normalised correlation of Γ and B over the mask's pixels (1: the same texture)."""
    a = key[mask].astype(np.float64)
    b = bg[mask].astype(np.float64)
    a -= a.mean()
    b -= b.mean()
    den = float(np.sqrt((a @ a) * (b @ b)))
    return float(a @ b) / den if den > 1e-9 else 1.0


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
