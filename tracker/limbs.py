"""A person's limbs closed along the image's columns where the pictures do not say background (issue 12
item 2).

A walker's shaded lower legs often match the ground behind them to a grey level or two over a whole window:
walk:body frame 11, a walker at 3 m, lost 1,334 of its pixels, most of them patches of its far leg, where
the costs of the object's picture, of the background's in the right image and of the temporal picture
(tracker.rim.Pictures) were a median 1.4, 1.6 and 1.6 grey levels a pixel. No test of the pictures tells
them apart, and the outline's centroid moves up: on walk:body's walker at 3-4 m by 1.16 px on average (raw
pixels, against the true silhouette's).

A leg is a solid limb: where the outline holds it above and below such a patch in one column, the patch is
the leg's. `limbs_closed` closes an upright outline (tracker.strips.whole_outline: a person's, or an upright
board's, which has no gaps to close) along its columns (a morphological closing with a
vertical line LIMB_SHARE of the outline's height long) and takes in what the closing adds where the
pictures do not say background: the object's picture fits at least as well as the background's in the
right image and, with the cameras still, as the temporal picture (C_o <= C_s, C_o <= C_t; tracker.rim).
The space beneath an arm or between two legs that the closing also spans is background that one of those
fits better, and stays out. On walk:body's 300 frames, the outlines' pixels outside the true silhouettes
went 18,957 -> 20,146 and those missed 63,683 -> 44,980; the centroid of its walker at 3-4 m lies 0.78 px
above the true silhouette's (1.16 px before). A plain closing of the outline's lower half by a 21-px line,
without the tests, missed 46,121 and left 27,692 outside. Lines of a tenth of the height, and of 21 px and
31 px with the cameras still only, gave elevation RMSE within 0.003° of each other on `tmeye eval --all`
(docs/evaluation.md); a tenth kept walk:body's azimuth 1-σ line in its band."""

from __future__ import annotations

import cv2
import numpy as np
from numpy.typing import NDArray

from tracker.rim import Pictures

BoolA = NDArray[np.bool_]

LIMB_SHARE = 0.1  # the closing's line: this share of the outline's height (odd, at least 3 px)


def limbs_closed(obj: BoolA, pictures: Pictures, allowed: BoolA, share: float = LIMB_SHARE) -> BoolA:
    """obj (bool (h, w), over the box of `pictures`) with the pixels that a closing along the columns by a
    vertical line of `share` of its height adds where `allowed` and where C_o <= C_s and, where the pictures
    hold the temporal picture (the cameras still), C_o <= C_t."""
    rows = np.flatnonzero(obj.any(axis=1))
    if rows.size == 0:
        return obj
    length = max(int(share * (rows[-1] - rows[0] + 1)) | 1, 3)
    m8 = cv2.copyMakeBorder(obj.view(np.uint8), length, length, 0, 0, cv2.BORDER_CONSTANT, value=0)
    closed = np.asarray(cv2.morphologyEx(m8, cv2.MORPH_CLOSE, np.ones((length, 1), np.uint8))[length:-length],
                        bool)
    add = closed & ~obj & allowed
    if not add.any():
        return obj
    c_o, c_t = pictures.c_o, pictures.c_t
    keep = add & (c_o <= pictures.c_s)
    return obj | (keep if c_t is None else keep & (c_o <= c_t))
