"""A verified object's outline in the left image: the largest connected region with its holes filled, and
the outline drawn from the temporal background model inside a stereo region (tracker.verify)."""

from __future__ import annotations

import cv2
import numpy as np
from numpy.typing import NDArray

U8 = NDArray[np.uint8]
BoolA = NDArray[np.bool_]

_CLOSE: U8 = np.asarray(cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (5, 5)), np.uint8)
_CLOSE_FILL: U8 = np.asarray(cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (9, 9)), np.uint8)
# ε_f / ε: the band's threshold for a verified object's outline (temporal_outline with fill); 8 grey levels
# at the default ε = 12, still ≥ 6 σ of the simulated sensor noise (σ = 1.2) above the background's D term
FILL_EPS_FRACTION = 2.0 / 3.0


def largest(mask: BoolA, close: bool = False, every: bool = False, kernel: U8 = _CLOSE) -> BoolA:
    """The largest 8-connected component (or with `every`, all of them) with holes filled; with `close`,
    narrow channels into the holes are sealed first (a morphological closing by `kernel`), so those are
    filled too."""
    m8 = mask.astype(np.uint8)
    if close:
        m8 = np.asarray(cv2.morphologyEx(m8, cv2.MORPH_CLOSE, kernel), np.uint8) | m8
    contours, _ = cv2.findContours(m8, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    if not contours:
        return np.zeros_like(mask)
    keep = list(contours) if every else [max(contours, key=cv2.contourArea)]
    out = np.zeros(mask.shape, np.uint8)
    cv2.drawContours(out, keep, -1, 1, thickness=cv2.FILLED)
    return out.astype(bool)


def largest_region(mask: BoolA) -> BoolA:
    """The largest 8-connected component of a mask, holes filled."""
    return largest(mask)


_RING = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (9, 9))
NEAR = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (5, 5))


def temporal_outline(key: U8, bg: NDArray[np.float32], dev: NDArray[np.float32], core: BoolA,
                      region: BoolA, eps: int, fill: bool = False) -> tuple[BoolA, float, BoolA]:
    """The object's exact outline from the temporal model, inside a stereo region.

    core: pixels both keys agree are the object (left-key ∩ warped right-key mask: no occlusion shadow,
    but holes where the object overlaps its own shadow); region: where the object may be (the keys'
    union, or the left-key mask: the object and its shadow). The global gain g is Σ Γ / Σ B on the box's
    ring outside the region; a pixel is the object if |Γ - g B| > ε in `core`, or > ε + 3 D elsewhere in
    `region` or a two-pixel rim, where D is the background's own mean deviation: a shadow falls on
    unchanged background (|Γ - g B| small) unless the background moves (foliage, large D).
    With `fill` (a verified object's outline, tracker.verify.Verifier), the band's limit is ε_f + 3 g D
    with ε_f = FILL_EPS_FRACTION · ε, and gaps up to about 9 px wide are closed before the holes are filled:
    a solid body's faces turned from the light, or textured like the background behind them, differ from
    it by less than ε over patches that otherwise drop out of the outline and pull its centroid (eq. 10)
    away from the body's (on walk:body, 13 % of the silhouette's pixels, most at the legs and head).
    Returns the mask, g (1.0 when the ring is too small) and the box's pixels that changed at the strict
    threshold."""
    grown = cv2.dilate((region | core).astype(np.uint8), NEAR) > 0
    band = grown & ~core
    ring = ((cv2.dilate(grown.view(np.uint8), _RING) == 0) & (bg > 8.0)).view(np.uint8)
    g = 1.0
    if cv2.countNonZero(ring) >= 20:
        g = cv2.mean(key, mask=ring)[0] / cv2.mean(bg, mask=ring)[0]  # Σ Γ / Σ B over the ring
    diff = _change(key, bg, g)
    changed = diff > _strict_limit(dev, g, eps)
    inside = core & (diff > eps)
    if not fill:
        return largest(inside | (band & changed), close=True), g, changed
    loose = diff > _strict_limit(dev, g, FILL_EPS_FRACTION * eps)
    return largest(inside | (band & loose), close=True, kernel=_CLOSE_FILL), g, changed


def _change(key: U8, bg: NDArray[np.float32], g: float) -> NDArray[np.float32]:
    """|Γ - g B|: how far each pixel is from the temporal background at global gain g."""
    return np.asarray(np.abs(key.astype(np.float32) - np.float32(g) * bg), np.float32)


def _strict_limit(dev: NDArray[np.float32], g: float, eps: float) -> NDArray[np.float32]:
    """ε + 3 g D: the change a pixel must exceed where the background itself moves by D on average."""
    return np.asarray(np.float32(eps) + np.float32(3.0 * g) * dev, np.float32)


