"""How far off a partly seen target's centroid may lie: the uncertainty of eq. (10) where the target goes on
beyond what the cameras see (issue 12 item 1).

The centroid of the visible pixels (eq. 10) is the target's centre only when all of it is seen. Where its
outline meets the image border, or a background nearer than the target (a hedge before a walker's legs, a
post), it may go on out of sight: the visible centroid then lies off the centre, towards the visible part,
by half of what is hidden. How much is hidden is unknown from one frame; the 1-σ added along that axis is
`kappa` times the visible extent (a person two-thirds hidden by a hedge is off by about one visible height).
Where the hidden part lies to one side of a cut side, the centroid moves along it too (`cut_and_skew`); where a
nearer background hides the bottom, the target goes on at most that occluder's height down (bottom_edge.occluder_below).
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

from tracker.bottom_edge import convex_tip, stepped_below

BoolA = NDArray[np.bool_]
F32 = NDArray[np.float32]
_RING = np.ones((5, 5), np.uint8)


@dataclass(frozen=True)
class VisibilityConfig:
    """kappa: extra 1-σ per cut side, as a fraction of the visible extent along that axis; nearer_px: how
    much larger (px) the background's disparity must be than the target's for it to hide the target (the
    ground just before a target's feet rises about b / h = 0.2 px a row for a rig 1.5 m above it, so it
    stays under this for the 2 rows of the ring; a solid body's front foot nearer than its centroid may not:
    a jump test against the background just inside the outline was tried in its place and, on the endless
    scene, missed the hedge before people's legs: elevation within 1σ 0.34 -> 0.19); min_share: the share
    of a side's ring pixels that must be hidden for it to count. level_px, jump_px: a side whose ring lies
    on a background at about the target's depth or nearer (disparity above d - level_px: a bumpy hedge
    at 24 m, 6.8-7.6 px, before a walker at 25 m, 7.2 px; the stereo and temporal tests cannot tell a
    target from a background at its own depth, so it may go on there unseen) is cut as well where the
    background just inside the outline on that side lies farther than the target by jump_px: the
    background steps there from behind the target to about its depth, as it does at an occluder's edge
    and not under a target's feet (the ground behind the feet's lowest rows is within 0.2 px a row of the
    target's own disparity). ground_step_px: the largest change of the background's disparity from one
    row to the next on the ground below a target (bottom_edge.unseen_below; about 0.2 px a row, as above).
    convex_solidity, tip_rows: a bottom side that a nearer background meets is not cut where the outline is
    convex (its area at least convex_solidity of its hull's) and narrows to a tip within tip_rows rows below
    its lowest one (tracker.bottom_edge.convex_tip). step_px: below the target, how much nearer (px) a
    background must be than the farthest behind its lowest four pixels to hide it (the ground rises about
    1.0 px over those six rows; tracker.bottom_edge.stepped_below). aside_px, aside_share: how much nearer
    (px, and as a share of the target's disparity, the larger) a background beside or below a target's lower
    half must be to count as an occluder across its legs (Cuts.hidden_from): on walk:body the ground beside
    a walker's feet reads 1.2 px nearer than the walker's disparity at 4.5 m (39 px) and up to 2.8 px at 7.6
    m (24 px), over the floor there (the term then adds 0.01-0.3 px); the crates before walkers on the
    endless scene are 4.6 to 15 px nearer at 15 to 25 px."""

    kappa: float = 0.4
    nearer_px: float = 0.5
    min_share: float = 0.3
    level_px: float = 0.5
    jump_px: float = 1.0
    ground_step_px: float = 0.5
    convex_solidity: float = 0.9
    tip_rows: float = 4.0
    step_px: float = 1.5
    aside_px: float = 2.0
    aside_share: float = 0.1


def cut_sides(mask: BoolA, box: tuple[int, int, int, int], size: tuple[int, int], disparity: float,
              bg_disparity: F32 | None, bg_valid: BoolA | None, cfg: VisibilityConfig,
              objects: BoolA | None = None) -> tuple[int, int]:
    """How many sides along x (left, right) and along y (top, bottom) the target is cut at: the mask meets
    that edge of the image (on the left, within the target's disparity of it plus 2 px: the right camera
    does not see those columns, so the stereo outline stops short of the edge) or, where the background's
    rectified disparity is known (bg_disparity and bg_valid, (h, w) over the box; None: not known), at
    least min_share of the side's part of its 2-px ring outside the mask lies on a background nearer than
    the target by nearer_px (the ring split into sides about the mask's centroid, scaled by its extent).
    Or at least min_share of it lies on a background at about the target's depth or nearer (above d -
    level_px) and of the outline's rim on that side on a background farther by jump_px (VisibilityConfig).
    The ring may lie a band away from the occluder: the right camera, d px to the left, does not see the
    target over the d_near - d columns right of a nearer background at disparity d_near, so the stereo
    outline stops there (the post of the occlusion scene: 5 px; the bush before a walker's legs on the
    endless scene, 12 px, on the ring's bottom side too), and that band counts as hidden.
    mask: (h, w) over box (x0, y0, x1, y1), raw left pixels; size: the image's (width, height). Only the
    ring and band inside the box are looked at: pass the mask `padded`."""
    return cut_and_skew(mask, box, size, disparity, bg_disparity, bg_valid, cfg, objects)[0]


@dataclass(frozen=True)
class Cuts:
    """Which sides (left, right, top, bottom) a target is cut at (`cut_sides`' rules), and the centroid's
    move across them (px, x and y; `cut_and_skew`). bottom_by_background: the bottom is cut by a nearer
    or level background (not the image's edge): an occluder below, which bottom_edge.occluder_below measures.
    hidden_from: the highest row (of the mask given) of the ring pixels below the mask's centroid that a
    nearer background hides at its left, right or bottom side, whether or not enough of that side is hidden
    to cut it (an occluder's top edge across a person's legs); None: none."""

    sides: tuple[bool, bool, bool, bool]
    skew: tuple[float, float]
    bottom_by_background: bool = False
    hidden_from: int | None = None

    @property
    def counts(self) -> tuple[int, int]:
        """How many sides along x (left, right) and along y (top, bottom) are cut."""
        left, right, top, bottom = self.sides
        return int(left) + int(right), int(top) + int(bottom)


def cut_and_skew(mask: BoolA, box: tuple[int, int, int, int], size: tuple[int, int], disparity: float,
                 bg_disparity: F32 | None, bg_valid: BoolA | None, cfg: VisibilityConfig,
                 objects: BoolA | None = None) -> tuple[tuple[int, int], tuple[float, float]]:
    """`cut_sides` and the centroid's move across the cut sides (px, x and y): `cuts`, counted."""
    c = cuts(mask, box, size, disparity, bg_disparity, bg_valid, cfg, objects)
    return c.counts, c.skew


def cuts(mask: BoolA, box: tuple[int, int, int, int], size: tuple[int, int], disparity: float,
         bg_disparity: F32 | None, bg_valid: BoolA | None, cfg: VisibilityConfig,
         objects: BoolA | None = None, level_from: float | None = None) -> Cuts:
    """The sides `cut_sides` counts, and how far (px, x and y) the centroid may move across the sides cut by a
    nearer or level background, which need not hide the target evenly: a board behind a bush's round top loses
    its lower left corner, and its centroid moves right, along x, though only its bottom side is cut (endless,
    frames 1195-1244: 2.1 px). The hidden part is taken to go on beyond each ring pixel that hid it, away from
    the visible centroid, about as far as a cut side's extra 1-σ supposes (kappa times the visible extent that
    way); the centroid moves by that part's share of the whole area times its centroid's offset. The move's x is
    returned where a top or bottom side is cut, its y where a left or right one is (the cut sides' own axis has
    `extra_sigma_px`).

    Below the target a nearer or level background counts only where it steps forward from the background
    behind the target's lowest pixels in that column (tracker.bottom_edge.stepped_below); other objects
    painted in (`objects`, (h, w) bool over the box: `with_objects`, `painted`) and the right camera's
    shadow band count as they are. On the left and right sides the learnt map is too often wrong for that
    test: a nearer post's disparity runs on over the band left of it that the right camera does not see
    (occlusion, frame 65: 13 px, the post's disparity less the wall's), so that the background behind a
    target emerging there reads as near as the post itself.

    level_from: the disparity (px) the level test starts from where not the target's own: its track's held
    disparity where farther (`Pipeline._level_from`). A far target's disparity jumps by a few tenths of a
    pixel from one frame to the next (endless:body, a walker's head and shoulders over a hedge at 25 m:
    7.2-7.4 px, then 7.66 and 7.70), and the hedge just behind it, level by the track's disparities, was
    taken for a background behind it in those frames: the body placed from its outline's centroid, 11 px
    too high, with a 1-σ of 0.4 px (frame 913, its elevation error 26 σ)."""
    x0, y0, _, _ = box
    w, h = size
    m8 = mask.view(np.uint8)
    bx, by, bw, bh = cv2.boundingRect(m8)
    if bw == 0:
        return Cuts((False, False, False, False), (0.0, 0.0))
    left_edge = int(np.ceil(max(disparity, 0.0))) + 2
    cut = [x0 + bx <= left_edge, x0 + bx + bw >= w, y0 + by <= 0, y0 + by + bh >= h]  # left, right, top, bottom
    if bg_disparity is None or bg_valid is None:
        return Cuts((cut[0], cut[1], cut[2], cut[3]), (0.0, 0.0))
    mom = cv2.moments(m8, binaryImage=True)
    centre, half = (mom["m10"] / mom["m00"], mom["m01"] / mom["m00"]), (max(bw / 2.0, 1.0), max(bh / 2.0, 1.0))
    ring_px = (cv2.dilate(m8, _RING) > 0) & ~mask  # the 2-px ring inside the box
    ring = sides(ring_px, centre, half)
    edge = sides(mask & (cv2.erode(m8, _RING) == 0), centre, half)  # the outline's own 2-px rim
    nearer = bg_valid & (bg_disparity > disparity + cfg.nearer_px)
    hidden = right_shadow(nearer, bg_disparity, disparity)
    level = bg_valid & (bg_disparity > (disparity if level_from is None else level_from) - cfg.level_px)
    behind = bg_valid & (bg_disparity < disparity - cfg.jump_px)
    by_bg = [False] * 4
    hiding = np.zeros_like(ring_px)  # the ring pixels beyond which the target may go on unseen
    hids: list[BoolA] = []  # each side's ring pixels a nearer background hides
    for k, ((ys, xs), (ey, ex)) in enumerate(zip(ring, edge, strict=True)):
        need = cfg.min_share * xs.size
        # below: an occluder's top edge, not the ground going on under the target
        steps = stepped_below(m8, bg_disparity, bg_valid, ys, xs, cfg.step_px) if k == 3 and xs.size else (
            np.ones(xs.size, bool))
        if objects is not None:
            steps |= objects[ys, xs]
        hid, lev = hidden[ys, xs] & (steps | ~nearer[ys, xs]), level[ys, xs] & steps
        by_bg[k] = xs.size > 0 and (int(np.count_nonzero(hid)) >= need or (
            int(np.count_nonzero(lev)) >= need and int(np.count_nonzero(behind[ey, ex])) >= cfg.min_share * ex.size))
        hiding[ys, xs] = hid | (lev & by_bg[k])  # a level background only on a side it cuts (not the ground)
        hids.append(hid)
    clearly = bg_valid & (bg_disparity > disparity + max(cfg.aside_px, cfg.aside_share * disparity))
    hidden_from = _hidden_from(ring, hids, clearly, centre[1])
    tip = convex_tip(mask, hidden | level, cfg.convex_solidity, cfg.tip_rows) if by_bg[3] and not cut[3] else None
    by_bg[3] &= tip is None
    for k in range(4):
        cut[k] |= by_bg[k]
    skew = (0.0, 0.0) if tip is None else tip
    if any(by_bg):
        sx, sy = _hidden_shift(hiding, centre, (bw, bh), mom["m00"], cfg.kappa)
        sx, sy = (abs(sx) if by_bg[2] or by_bg[3] else 0.0, abs(sy) if by_bg[0] or by_bg[1] else 0.0)
        skew = (float(np.hypot(skew[0], sx)), float(np.hypot(skew[1], sy)))
    return Cuts((cut[0], cut[1], cut[2], cut[3]), skew, by_bg[3], hidden_from)


def _hidden_from(ring: list[tuple[NDArray[np.intp], NDArray[np.intp]]], hids: list[BoolA], clearly: BoolA,
                 centre_y: float) -> int | None:
    """Cuts.hidden_from: the highest row of the ring pixels (each side's rows and columns, left, right, top,
    bottom) below centre_y, on the left, right or bottom side, that hide the target (hids, each side's) on a
    background clearly nearer (`clearly`, over the box); None: none. The right camera's shadow band beside a
    nearer thing does not count: the ring pixel itself must be nearer."""
    low = [ys[hid & clearly[ys, xs] & (ys > centre_y)] for k, ((ys, xs), hid) in enumerate(zip(ring, hids, strict=True))
           if k != 2]
    rows = np.concatenate(low)
    return int(rows.min()) if rows.size else None


def _hidden_shift(hid: BoolA, centre: tuple[float, float], extent: tuple[int, int], area: float, kappa: float
                  ) -> tuple[float, float]:
    """The visible centroid's offset (px, x and y) from that of the whole target, if it went on unseen
    beyond the ring pixels `hid` (each half a pixel of outline, the ring being 2 px wide) away from the
    centroid `centre`, by kappa times the visible extent (width, height) that way. area: visible (px²)."""
    ys, xs = np.nonzero(hid)
    if xs.size == 0:
        return 0.0, 0.0
    dx, dy = xs - centre[0], ys - centre[1]
    r = np.maximum(np.hypot(dx, dy), 1e-9)
    ux, uy = dx / r, dy / r
    depth = kappa * (np.abs(ux) * extent[0] + np.abs(uy) * extent[1])  # how far it goes on, px
    a = 0.5 * depth  # the hidden area behind each ring pixel, px²
    hx, hy = xs + 0.5 * depth * ux, ys + 0.5 * depth * uy  # its centroid
    share = float(a.sum()) / (area + float(a.sum()))
    return (share * (float(np.average(hx, weights=a)) - centre[0]),
            share * (float(np.average(hy, weights=a)) - centre[1]))


def with_objects(bg_disparity: F32 | None, bg_valid: BoolA | None, box: tuple[int, int, int, int],
                 others: list[tuple[tuple[int, int, int, int], BoolA, float]]) -> tuple[F32 | None, BoolA | None]:
    """The background's disparity over box (None: not known) with the other objects found this frame
    painted over it (box, mask and disparity each; `object_and_shadow`): a target passing before another
    hides it as a nearer background does (two-targets: the crosser at 5 m before the target at 10 m, whose
    outline stopped at the crosser's shadow and put its centroid 8 px off). None, None without either."""
    x0, y0, x1, y1 = box
    near = list(_overlaps(box, others))
    if not near:
        return bg_disparity, bg_valid
    disp = np.zeros((y1 - y0, x1 - x0), np.float32) if bg_disparity is None else bg_disparity.copy()
    valid = np.zeros(disp.shape, bool) if bg_valid is None else bg_valid.copy()
    for at, sub, d in near:
        dv, vv = disp[at], valid[at]
        dv[sub] = np.maximum(np.where(vv[sub], dv[sub], 0.0), d)
        vv[sub] = True
    return disp, valid


def painted(box: tuple[int, int, int, int], others: list[tuple[tuple[int, int, int, int], BoolA, float]]
            ) -> BoolA | None:
    """Where the others' masks (box, mask, disparity each, as for `with_objects`) lie over box: (h, w) bool;
    None where none does."""
    x0, y0, x1, y1 = box
    out = np.zeros((y1 - y0, x1 - x0), bool)
    for at, sub, _ in _overlaps(box, others):
        out[at] |= sub
    return out if out.any() else None


def _overlaps(box: tuple[int, int, int, int], others: list[tuple[tuple[int, int, int, int], BoolA, float]]
              ) -> Iterator[tuple[tuple[slice, slice], BoolA, float]]:
    """For each of the others (box, mask, disparity) that overlaps box: where (rows, columns of box), its
    mask there, and its disparity."""
    x0, y0, x1, y1 = box
    for (ox0, oy0, ox1, oy1), m, d in others:
        X0, Y0, X1, Y1 = max(ox0, x0), max(oy0, y0), min(ox1, x1), min(oy1, y1)
        if X0 < X1 and Y0 < Y1:
            yield (slice(Y0 - y0, Y1 - y0), slice(X0 - x0, X1 - x0)), m[Y0 - oy0:Y1 - oy0, X0 - ox0:X1 - ox0], d


def object_and_shadow(box: tuple[int, int, int, int], mask: BoolA, disparity: float, bg_disparity: float
                      ) -> list[tuple[tuple[int, int, int, int], BoolA, float]]:
    """Another object for `with_objects`: its mask, and the mask again shifted left by its disparity less
    its background's, its occlusion shadow, which verification takes from the box as that object's
    (tracker.verify), so that a target behind it goes on unseen there too."""
    s = int(round(max(disparity - bg_disparity, 0.0)))
    x0, y0, x1, y1 = box
    return [(box, mask, disparity), ((x0 - s, y0, x1 - s, y1), mask, disparity)]


def right_shadow(nearer: BoolA, bg_disparity: F32, disparity: float) -> BoolA:
    """The nearer background and the columns the right camera does not see the target in because of it:
    each nearer pixel's copy d_near - d px to its right (d_near its disparity, d the target's; both pixels
    a fractional shift falls between). A post at least that wide hides one band from its left edge to
    d_near - d px past its right one; a thinner pole hides two strips, itself and its copy, and not the
    columns between them."""
    if not nearer.any():
        return nearer
    ys, xs = np.nonzero(nearer)
    shift = np.maximum(bg_disparity[ys, xs].astype(np.float64) - disparity, 0.0)
    out = nearer.copy()
    w = nearer.shape[1]
    for x in (xs + np.floor(shift).astype(np.intp), xs + np.ceil(shift).astype(np.intp)):
        inside = x < w
        out[ys[inside], x[inside]] = True
    return out


def occluded(disp: F32, valid: BoolA, disparity: float, gap: float, gap_px: float, share: float,
             cols: slice = slice(None)) -> bool:
    """Whether at least `share` of the known background (disp px, where valid) in columns `cols` is nearer
    than a target at `disparity` px by the depth-gap test turned round (d_bg > d (1 + gap) + gap_px) or in
    that nearer background's shadow for the right camera (right_shadow, cast from anywhere on the rows
    given); False where no background is known there. What hides a body's part between two seen pieces
    (split.occluded_gap) or beyond one (regions.beyond_occluder_hints)."""
    known = valid[:, cols]
    n = int(np.count_nonzero(known))
    if n == 0:
        return False
    hidden = right_shadow(valid & (disp > disparity * (1.0 + gap) + gap_px), disp, disparity)[:, cols]
    return int(np.count_nonzero(hidden & known)) >= share * n


def padded(mask: BoolA, box: tuple[int, int, int, int], size: tuple[int, int], pad: int = 2, left: int = 2,
           below: int = 2) -> tuple[BoolA, tuple[int, int, int, int]]:
    """The mask and its box grown by `pad` px on the top and right, by `left` px on the left and `below`
    px at the bottom (within the image of size (width, height)), so that the ring `cut_sides` looks at
    exists where the mask reaches its box's edge, on the left the band of a nearer background's shadow
    (pass 2 + the target's disparity: occluders up to half the target's distance), and below the ground
    bottom_edge.unseen_below looks down to: a verified box is often tight about its object, and a ring clipped off
    by the box missed the post before the emerging target of the occlusion scene (azimuth errors of 190 σ)."""
    x0, y0, x1, y1 = box
    w, h = size
    X0, Y0, X1, Y1 = max(x0 - left, 0), max(y0 - pad, 0), min(x1 + pad, w), min(y1 + below, h)
    out = np.zeros((Y1 - Y0, X1 - X0), bool)
    out[y0 - Y0:y1 - Y0, x0 - X0:x1 - X0] = mask
    return out, (X0, Y0, X1, Y1)


def sides(pixels: BoolA, centre: tuple[float, float], half: tuple[float, float]
           ) -> list[tuple[NDArray[np.intp], NDArray[np.intp]]]:
    """The (rows, columns) of the pixels on each side (left, right, top, bottom) of a mask whose centroid
    is centre (x, y) and half extent half (x, y): by the larger of |dx| / half x and |dy| / half y."""
    ys, xs = np.nonzero(pixels)
    dx, dy = (xs - centre[0]) / half[0], (ys - centre[1]) / half[1]
    across = np.abs(dx) >= np.abs(dy)
    return [(ys[m], xs[m]) for m in (across & (dx < 0), across & (dx > 0), ~across & (dy < 0), ~across & (dy > 0))]


def extra_sigma_px(mask: BoolA, cut: tuple[int, int], cfg: VisibilityConfig, occluder_px: float | None = None
                   ) -> tuple[float, float]:
    """The centroid's extra 1-σ (px) along x and y: kappa times the visible width / height for each cut
    side (added in quadrature); with occluder_px (bottom_edge.occluder_below, and a y side cut), one y side's term is
    half the occluder's height instead."""
    _, _, bw, bh = cv2.boundingRect(mask.view(np.uint8))
    sx = cfg.kappa * bw * float(np.sqrt(cut[0]))
    if occluder_px is None or not cut[1]:
        return sx, cfg.kappa * bh * float(np.sqrt(cut[1]))
    return sx, float(np.hypot(cfg.kappa * bh * np.sqrt(cut[1] - 1), 0.5 * occluder_px))


def cut_sigma_px(mask: BoolA, seen: Cuts, cfg: VisibilityConfig, occluder_px: float | None = None
                 ) -> tuple[float, float]:
    """`extra_sigma_px` of the sides `seen` (`cuts`) counts, with the occluder's height
    (bottom_edge.occluder_below) bounding the bottom's term only where a nearer or level background cuts
    the bottom: with the top cut and the bottom not, what lies below says nothing of how far the target
    goes on above (occlusion:plate, frames 59-90: a plate's top cut by the learnt map's band left of a
    post, which runs on 61 px below it, gave a y 1-σ of 31 px, half of that, for kappa times its 29 px
    height, 12 px)."""
    if not any(seen.sides):
        return 0.0, 0.0
    return extra_sigma_px(mask, seen.counts, cfg, occluder_px if seen.bottom_by_background else None)
