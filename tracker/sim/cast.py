"""Ray casting of one surface into a camera's image, two ways: per pixel (cast_surface_exact, the reference)
and with OpenCV calls over its bounding box (cast_plane_fast, the same result many times faster), with the
per-camera constants they share (View) and the pixel box of a set of points (pixel_box). tracker.sim.render
draws frames with them.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

from tracker.geometry import Camera
from tracker.sim.scene import Surface

F64 = NDArray[np.float64]
F32 = NDArray[np.float32]
U8 = NDArray[np.uint8]


@dataclass
class View:
    """One camera's precomputed rays (rig frame, float32 (H, W, 3)) and its normalised-coordinate range."""

    cam: Camera
    rays: F32
    xn_range: tuple[float, float]
    yn_range: tuple[float, float]
    xy: F32  # undistorted normalised coordinates of every pixel, (H, W, 2)
    ray_len: F32  # |(xn, yn, 1)|, (H, W)
    area: F32  # each pixel's area in the undistorted normalised plane, |∂(xn, yn) / ∂(u, v)|, (H, W)


def make_view(cam: Camera) -> View:
    w, h = cam.size
    u, v = np.meshgrid(np.arange(w, dtype=np.float64), np.arange(h, dtype=np.float64))
    xn, yn = cam.undistort_pixels(u, v)
    rays = cam.rays_rig(u, v).astype(np.float32)
    xy = np.dstack([xn, yn]).astype(np.float32)
    ray_len = np.sqrt(1.0 + xn * xn + yn * yn).astype(np.float32)
    (xv, xu), (yv, yu) = np.gradient(xn), np.gradient(yn)  # d/dv (rows), d/du (columns)
    area = np.abs(xu * yv - xv * yu).astype(np.float32)
    return View(cam, rays, (float(xn.min()) - 0.02, float(xn.max()) + 0.02),
                (float(yn.min()) - 0.02, float(yn.max()) + 0.02), xy, ray_len, area)


_MARGIN = 64.0  # texels kept beyond a surface's extent before its texture is sampled (cast_plane_fast)


def cast_plane_fast(view: View, R_wr: F64, s: Surface, img: F32 | U8, depth: F32, t: float = 0.0,
                    ids: U8 | None = None, box: tuple[int, int, int, int] | None = None) -> None:
    """Ray-cast a rectangular surface over its bounding box with OpenCV calls: on a plane the texture
    coordinates are a homography of the undistorted normalised coordinates (x_n, y_n), and 1/depth is
    linear in them. Same result as cast_surface_exact (sway included), many times faster for large areas."""
    box = box or pixel_box(view, s.corners() @ R_wr)
    if box is None:
        return
    x0, y0, x1, y1 = box
    R_wc = R_wr @ view.cam.R_rc.T  # camera -> world
    c = R_wr @ view.cam.c
    n_c, u_c, v_c = R_wc.T @ s.normal, R_wc.T @ s.u, R_wc.T @ s.v
    q = float(s.normal @ (s.P0 - c))  # n·(P0 - c)
    th, tw = s.texture.shape
    a0, b0 = float((c - s.P0) @ s.u), float((c - s.P0) @ s.v)
    # x_t = a / texel + tw/2 with a = a0 + q (u_c·m)/(n_c·m), m = (x_n, y_n, 1)
    H = np.vstack([q * u_c / s.texel_m + (a0 / s.texel_m + tw / 2.0) * n_c,
                   q * v_c / s.texel_m + (b0 / s.texel_m + th / 2.0) * n_c, n_c])
    xy = view.xy[y0:y1, x0:x1]
    mxy = np.asarray(cv2.perspectiveTransform(xy.reshape(-1, 1, 2), H), np.float32).reshape(xy.shape)
    hw, hh = s.half_w / s.texel_m, s.half_h / s.texel_m
    if s.shape == "disc":
        ex, ey = mxy[..., 0] - np.float32(tw / 2.0), mxy[..., 1] - np.float32(th / 2.0)
        hit = ex * ex + ey * ey <= np.float32(hw * hw)
    else:
        hit = cv2.inRange(mxy, (tw / 2.0 - hw, th / 2.0 - hh), (tw / 2.0 + hw, th / 2.0 + hh)) > 0
    if s.sway is not None:  # texture displacement in metres at plane coordinates (a, b)
        a = (mxy[..., 0] - np.float32(tw / 2.0)) * np.float32(s.texel_m)
        b = (mxy[..., 1] - np.float32(th / 2.0)) * np.float32(s.texel_m)
        da, db = s.sway(t, a, b)
        mxy = np.dstack([mxy[..., 0] + da / np.float32(s.texel_m), mxy[..., 1] + db / np.float32(s.texel_m)])
    # where the plane is seen edge-on or behind the camera the homography sends pixels millions of texels
    # away, and OpenCV's reflect-101 border folds such a coordinate back one texture width at a time (a
    # bush beside the cameras with the mount at pan 90 deg: 40 ms a remap, 3 frames a second). Those pixels
    # are not hit; the hit ones lie within the surface's extent plus its sway (centimetres), kept whole
    lo = np.array([tw / 2.0 - hw - _MARGIN, th / 2.0 - hh - _MARGIN], np.float32)
    hi = np.array([tw / 2.0 + hw + _MARGIN, th / 2.0 + hh + _MARGIN], np.float32)
    mxy = np.clip(np.asarray(mxy, np.float32), lo, hi)
    val = cv2.remap(s._tex32, mxy, None, cv2.INTER_LINEAR,  # type: ignore[call-overload, unused-ignore]
                    borderMode=cv2.BORDER_REFLECT101)
    den = n_c[0] * xy[..., 0] + n_c[1] * xy[..., 1] + np.float32(n_c[2])
    with np.errstate(divide="ignore"):
        dist = (np.float32(q) / den) * view.ray_len[y0:y1, x0:x1]
    d_roi = depth[y0:y1, x0:x1]
    hit &= (dist > 0.05) & (dist < d_roi)
    np.copyto(d_roi, dist, where=hit)
    np.copyto(img[y0:y1, x0:x1], np.rint(val) if img.dtype == np.uint8 else val, where=hit, casting="unsafe")
    if ids is not None:
        ids[y0:y1, x0:x1][hit] = s.target_id


_NEAR_Z = 0.01  # m: pixel_box's near plane
_EDGE = np.linspace(0.0, 1.0, 9)
_BOX_X = np.concatenate([_EDGE, np.ones(9), _EDGE, np.zeros(9)])  # 9 points along each side of a unit box
_BOX_Y = np.concatenate([np.zeros(9), _EDGE, np.ones(9), _EDGE])


def pixel_box(view: View, pts_rig: F64, pad: int = 2) -> tuple[int, int, int, int] | None:
    """Pixel bounding box (x0, y0, x1, y1) of the convex hull of rig-frame points (N, 3) as seen by `view`,
    or None when it lies outside the image. Where the hull reaches behind the camera, its part in front
    of the plane z = _NEAR_Z (camera frame, m) is boxed: the points before that plane and the points where
    the segments from each of them to each point behind it cross it (the whole image was cast before: a
    bush beside the cameras with the mount at pan 90 deg, its texture sampled at every pixel, 3 frames a
    second). Casts draw no pixel nearer than 0.05 m along its ray, z > 0.038 m at this field of view."""
    cam = view.cam
    w, h = cam.size
    Xc = (pts_rig - cam.c) @ cam.R_rc.T
    front = Xc[:, 2] > _NEAR_Z
    if not front.any():
        return None
    if not front.all():
        a, b = Xc[front], Xc[~front]
        t = (_NEAR_Z - a[:, None, 2]) / (b[None, :, 2] - a[:, None, 2])  # (n_front, n_behind), in [0, 1)
        Xc = np.vstack([a, (a[:, None, :] + t[..., None] * (b[None, :, :] - a[:, None, :])).reshape(-1, 3)])
    xn, yn = Xc[:, 0] / Xc[:, 2], Xc[:, 1] / Xc[:, 2]
    x0, x1 = max(xn.min(), view.xn_range[0]), min(xn.max(), view.xn_range[1])
    y0, y1 = max(yn.min(), view.yn_range[0]), min(yn.max(), view.yn_range[1])
    if x0 >= x1 or y0 >= y1:
        return None
    u, v = cam.distort_normalized(x0 + (x1 - x0) * _BOX_X, y0 + (y1 - y0) * _BOX_Y)
    box = (max(int(u.min()) - pad, 0), max(int(v.min()) - pad, 0),
           min(int(np.ceil(u.max())) + pad + 1, w), min(int(np.ceil(v.max())) + pad + 1, h))
    return box if box[0] < box[2] and box[1] < box[3] else None


def cast_surface_exact(view: View, R_wr: F64, s: Surface, t: float, img: F32 | U8, depth: F32, ids: U8 | None,
                       origin: tuple[int, int] = (0, 0)) -> None:
    """Ray-cast one surface into img/depth/ids (in place), z-tested, intersecting every pixel's ray with
    the plane: the reference the fast renderer (cast_plane_fast) is tested against. The buffers cover
    the image window whose top-left pixel is `origin`; only the surface's bounding box is cast."""
    box = pixel_box(view, s.corners() @ R_wr)  # world -> rig is R_wr.T @ p (row vectors)
    if box is None:
        return
    ox, oy = origin
    h, w = img.shape
    x0, y0 = max(box[0], ox), max(box[1], oy)
    x1, y1 = min(box[2], ox + w), min(box[3], oy + h)
    if x0 >= x1 or y0 >= y1:
        return
    rays = view.rays[y0:y1, x0:x1].reshape(-1, 3).astype(np.float64) @ R_wr.T
    dist, val, hit = s.intersect(R_wr @ view.cam.c, rays, t)
    win = (slice(y0 - oy, y1 - oy), slice(x0 - ox, x1 - ox))
    d_roi = depth[win].reshape(-1)
    hit &= dist < d_roi
    if not hit.any():
        return
    shape = (y1 - y0, x1 - x0)
    d_roi[hit] = dist[hit]
    depth[win] = d_roi.reshape(shape)
    i_roi = img[win].reshape(-1)
    i_roi[hit] = np.rint(val[hit]) if img.dtype == np.uint8 else val[hit]
    img[win] = i_roi.reshape(shape)
    if ids is not None:
        id_roi = ids[win].reshape(-1)
        id_roi[hit] = s.target_id
        ids[win] = id_roi.reshape(shape)
