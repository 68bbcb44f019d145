"""The background's geometry: where each key-image pixel's background is seen in the reference image.

Paper eq. (9) compares the key pixel Γ(x, y) with the reference pixel Θ(x - d_x, y - d_y) at the
background disparity. TMEye learns the background's distance per world direction (a panorama anchored to
the gimbal base, so it stays valid while the cameras pan) from empty-scene stereo pairs by semi-global
matching, and turns it into per-pixel correspondence maps for any gimbal pose.
"""

from __future__ import annotations

from dataclasses import dataclass, fields

import cv2
import numpy as np
from numpy.typing import NDArray

from tracker.frames import FrameError, GimbalState, StereoFrame, check_pair
from tracker.geometry import Camera, gimbal_rotation
from tracker.rectify import Rectifier
from tracker.rigcheck import check_disparity_range, check_disparity_sign

F32 = NDArray[np.float32]
F64 = NDArray[np.float64]
U8 = NDArray[np.uint8]


@dataclass(frozen=True)
class CorrespondenceMap:
    """For a grid of key-image pixels: where their background lies in the reference image.

    map_x, map_y: float32 (h, w) raw reference coordinates; valid: bool (h, w), False where the
    background is unknown or falls outside the reference image; disparity: float32 (h, w), rectified
    background disparity (px) for comparing against a target's; floor: uint8 (h, w), the residual of
    eq. (9) on the empty scene in that direction (imperfect warps: half-occlusions, depth edges)."""

    map_x: F32
    map_y: F32
    valid: NDArray[np.bool_]
    disparity: F32
    floor: U8

    def crop(self, box: tuple[int, int, int, int]) -> CorrespondenceMap:
        """The maps of the grid pixels in box = (x0, y0, x1, y1) (views, not copies)."""
        x0, y0, x1, y1 = box
        return CorrespondenceMap(*(getattr(self, f.name)[y0:y1, x0:x1] for f in fields(CorrespondenceMap)))

    def warp(self, other: U8) -> U8:
        """The other camera's image `other` (uint8 (H, W)) at the grid pixels' background correspondences,
        bilinear (eq. 9's Θ; the maps' shape)."""
        return np.asarray(cv2.remap(other, self.map_x, self.map_y, cv2.INTER_LINEAR,
                                    borderMode=cv2.BORDER_REPLICATE), np.uint8)

    def paste(self, box: tuple[int, int, int, int], part: CorrespondenceMap) -> None:
        """Write `part`'s maps into the pixels of box = (x0, y0, x1, y1)."""
        x0, y0, x1, y1 = box
        for f in fields(CorrespondenceMap):
            getattr(self, f.name)[y0:y1, x0:x1] = getattr(part, f.name)


@dataclass(frozen=True)
class _RayGrid:
    """Per-pixel constants of camera k's pixels (h, w) for mapping them through the background: unit
    rig-frame rays (h, w, 3); ray·c_k; the ray in the other camera's frame, R_o ray (3, h, w), and the
    origin there, R_o (c_k - c_o) (3,); the ray's depth along the rectified left z axis r₃·ray (h, w) and
    the origin's, r₃·(c_k - c_left)."""

    rays: F32
    ray_dot_c: F32
    dir_other: F32
    origin_other: tuple[float, float, float]
    dir_rect_z: F32
    origin_rect_z: float

    @staticmethod
    def of(rect: Rectifier, key: int, rays: F32) -> _RayGrid:
        rig = rect.rig
        cam_k, cam_o = (rig.left, rig.right) if key == 0 else (rig.right, rig.left)
        r64 = rays.astype(np.float64)
        r3 = (rect.R1 @ rig.left.R_rc)[2]
        o = cam_o.R_rc @ (cam_k.c - cam_o.c)
        return _RayGrid(np.ascontiguousarray(rays), (r64 @ cam_k.c).astype(np.float32),
                        np.ascontiguousarray(np.moveaxis(r64 @ cam_o.R_rc.T, -1, 0), dtype=np.float32),
                        (float(o[0]), float(o[1]), float(o[2])), (r64 @ r3).astype(np.float32),
                        float(r3 @ (cam_k.c - rig.left.c)))

    def crop(self, box: tuple[int, int, int, int]) -> _RayGrid:
        """The constants of the pixels in box = (x0, y0, x1, y1)."""
        x0, y0, x1, y1 = box
        return _RayGrid(self.rays[y0:y1, x0:x1], self.ray_dot_c[y0:y1, x0:x1], self.dir_other[:, y0:y1, x0:x1],
                        self.origin_other, self.dir_rect_z[y0:y1, x0:x1], self.origin_rect_z)


def _remap_f32(img: F32, mx: F32, my: F32) -> F32:
    """Bilinear sample of a float image at float coordinates of any 2-D shape (0 outside)."""
    return np.asarray(cv2.remap(img, mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT, borderValue=0.0))


def _distort_points(cam: Camera, x: F32, y: F32, z: F32) -> tuple[F32, F32]:
    """Pixel coordinates (u, v) of camera-frame points (x, y, z) (float32, any one shape), through the
    Brown-Conrady model of `Camera.distort_normalized` at (x_n, y_n) = (x/z, y/z):
    x_d = x_n (1 + k₁r² + k₂r⁴ + k₃r⁶) + 2p₁x_n y_n + p₂(r² + 2x_n²), y_d = y_n (...) + p₁(r² + 2y_n²) + 2p₂x_n y_n,
    u = f_x x_d + s y_d + c_x, v = f_y y_d + c_y. Works in place on x and y (the caller's temporaries) and
    leaves out terms whose coefficient is zero: the same values in fewer array passes."""
    k1, k2, p1, p2, k3 = (float(k) for k in cam.dist)
    K = cam.K
    xn, yn = np.divide(x, z, out=x), np.divide(y, z, out=y)
    xx, yy, xy = xn * xn, yn * yn, xn * yn
    r2 = xx + yy
    radial = r2 * np.float32(k3) + np.float32(k2) if k3 else np.full_like(r2, k2)
    radial *= r2
    radial += np.float32(k1)
    radial *= r2
    radial += np.float32(1.0)  # 1 + r²(k₁ + r²(k₂ + r² k₃))
    xx *= np.float32(2.0)
    xx += r2
    xx *= np.float32(p2)  # p₂(r² + 2x_n²)
    yy *= np.float32(2.0)
    yy += r2
    yy *= np.float32(p1)  # p₁(r² + 2y_n²)
    xd, yd = xn * radial, yn * radial
    xd += xy * np.float32(2.0 * p1)
    xd += xx
    yd += yy
    xy *= np.float32(2.0 * p2)
    yd += xy
    u = xd * np.float32(K[0, 0])
    if K[0, 1]:
        u += yd * np.float32(K[0, 1])
    u += np.float32(K[0, 2])
    yd *= np.float32(K[1, 1])
    yd += np.float32(K[1, 2])
    return u, yd


def match_support(lr: U8, rr: U8, nd: int) -> int:
    """Number of confident positive disparities (0.5 px to nd px) of a rectified pair (H, W), matched at
    half resolution by SGBM with its uniqueness and left-right checks."""
    a, b = cv2.pyrDown(lr), cv2.pyrDown(rr)
    n = 16 * int(np.ceil(nd / 32))
    sgbm = cv2.StereoSGBM.create(minDisparity=0, numDisparities=n, blockSize=5, P1=8 * 25, P2=32 * 25,
                                 disp12MaxDiff=1, uniquenessRatio=10, speckleWindowSize=50, speckleRange=2)
    disp = np.asarray(sgbm.compute(a, b))[:, n:].astype(np.float32) / 16.0
    return int(np.sum(disp > 0.5))


class BackgroundDepth:
    """Inverse distance 1/ρ (1/m) of the static background per world direction (0 = unknown), stored on a
    virtual pinhole canvas of focal `f` pixels looking along the gimbal base's z axis."""

    def __init__(self, rect: Rectifier, pan_range_deg: float = 25.0, tilt_range_deg: float = 12.0,
                 near_m: float = 2.5):
        self.rect = rect
        w, h = rect.rig.left.size
        self.near_m = near_m
        # disparity search length (px): f b / near_m, bounded by half the image width (RigError beyond)
        self.num_disparities = check_disparity_range(rect.f, rect.b, near_m, w)
        self._sign_checked = False
        self.f = rect.f
        self.pad = (int(self.f * np.tan(np.radians(pan_range_deg))),
                    int(self.f * np.tan(np.radians(tilt_range_deg))))
        self.canvas = np.zeros((h + 2 * self.pad[1], w + 2 * self.pad[0]), np.float32)
        # what was learnt (0 = unknown), apart from the canvas's filled holes: a later pose's points, sparse
        # where its rays meet the canvas obliquely, must not keep the holes filled before between them
        self.learnt = np.zeros(self.canvas.shape, np.float32)
        self.cx, self.cy = w / 2.0 + self.pad[0], h / 2.0 + self.pad[1]
        self.rays = tuple(self._rays(cam) for cam in (rect.rig.left, rect.rig.right))
        # per key camera: residual of eq. (9) on the surveyed empty scene, per world direction
        self.floors = (np.zeros(self.canvas.shape, np.uint8), np.zeros(self.canvas.shape, np.uint8))
        self._grids: dict[tuple[int, int], _RayGrid] = {}
        self._homography: tuple[tuple[float, float] | None, F32] = (None, np.eye(3, dtype=np.float32))

    @staticmethod
    def _rays(cam: Camera) -> F32:
        w, h = cam.size
        u, v = np.meshgrid(np.arange(w, dtype=np.float64), np.arange(h, dtype=np.float64))
        return cam.rays_rig(u, v).astype(np.float32)

    # -- learning ---------------------------------------------------------------------------------
    def learn(self, frame: StereoFrame, max_disparity: int | None = None) -> int:
        """Add an empty-scene pair to the panorama by semi-global matching on the rectified pair.
        Returns the number of background points learnt. Raises FrameError for a pair that is not grey
        uint8 of the rig's size."""
        self._check(frame)
        if not self._sign_checked:  # the first pair: would the background match better exchanged?
            rect = self.rect
            lr, rr = rect.rectify(frame.left, 0), rect.rectify(frame.right, 1)
            swapped = match_support(rect.rectify(frame.right, 0), rect.rectify(frame.left, 1), self.num_disparities)
            check_disparity_sign(match_support(lr, rr, self.num_disparities), swapped, lr.size // 400)
            self._sign_checked = True
        pu, pv, inv = self._match_points(frame, max_disparity or self.num_disparities)
        self.learnt[pv, pu] = inv
        self._fill_holes()
        for key in (0, 1):
            self._learn_floor(frame, key)
        return int(pu.size)

    def relearn(self, frame: StereoFrame, box: tuple[int, int, int, int]) -> int:
        """Learn the background again where the left pixels of box = (x0, y0, x1, y1) see it, from a pair
        at the same pose as before (what stood there has gone): the panorama and the floors inside the
        box's directions are replaced, the rest kept. Semi-global matching runs on the box's rectified
        rows only. Returns the number of background points learnt."""
        self._check(frame)
        x0, y0, x1, y1 = box
        rc = self.rect.rect_of_raw[0][y0:y1, x0:x1]
        h, w = frame.left.shape
        rows = (max(int(np.floor(rc[..., 1].min())) - 4, 0), min(int(np.ceil(rc[..., 1].max())) + 5, h))
        cols = (max(int(np.floor(rc[..., 0].min())) - 8, 0), min(int(np.ceil(rc[..., 0].max())) + 9, w))
        cu, cv = self._canvas_coords(self._grid(0, 1).crop(box).rays, frame.gimbal)
        H, W = self.canvas.shape
        u0, v0 = max(int(np.floor(cu.min())), 0), max(int(np.floor(cv.min())), 0)
        u1, v1 = min(int(np.ceil(cu.max())) + 1, W), min(int(np.ceil(cv.max())) + 1, H)
        pu, pv, inv = self._match_points(frame, self.num_disparities, rows, cols)
        inside = (pu >= u0) & (pu < u1) & (pv >= v0) & (pv < v1)
        self.learnt[v0:v1, u0:u1] = 0.0
        self.learnt[pv[inside], pu[inside]] = inv[inside]
        self.canvas[v0:v1, u0:u1] = self.learnt[v0:v1, u0:u1]
        m = 8  # fill the holes from the known directions around the box
        crop = (max(u0 - m, 0), max(v0 - m, 0), min(u1 + m, W), min(v1 + m, H))
        self.canvas[crop[1]:crop[3], crop[0]:crop[2]] = _filled(self.canvas[crop[1]:crop[3], crop[0]:crop[2]])
        for key, kbox in ((0, box), (1, (max(x0 - self.num_disparities, 0), y0, min(x1 + 8, w), y1))):
            self.floors[key][v0:v1, u0:u1] = 0
            self._learn_floor(frame, key, kbox)
        return int(np.count_nonzero(inside))

    def _check(self, frame: StereoFrame) -> None:
        check_pair(frame.left, frame.right)
        if frame.left.shape[::-1] != self.rect.rig.left.size:
            raise FrameError(f"background frame size {frame.left.shape[::-1]} does not match the rig's "
                             f"{self.rect.rig.left.size}")

    def _match_points(self, frame: StereoFrame, nd: int, rows: tuple[int, int] | None = None,
                      cols: tuple[int, int] | None = None) -> tuple[NDArray[np.intp], NDArray[np.intp], F32]:
        """Background points of a pair by semi-global matching on its rectified images (or on their rows
        rows[0]:rows[1], for left columns cols[0]:cols[1]): canvas pixels (u, v) and 1/ρ (1/m) of each, far
        first (so that nearer surfaces win where both land on one canvas pixel)."""
        rect = self.rect
        lr, rr = rect.rectify(frame.left, 0), rect.rectify(frame.right, 1)
        r0, r1 = rows or (0, lr.shape[0])
        c0, c1 = cols or (0, lr.shape[1])
        if cols is not None:  # the right image's columns the search reaches, and the left's kept
            s0 = max(c0 - nd, 0)
            lr, rr = lr[:, s0:c1], rr[:, s0:c1]
            c0, c1 = c0 - s0, c1 - s0
        else:
            s0 = 0
        sgbm = cv2.StereoSGBM.create(minDisparity=0, numDisparities=nd, blockSize=5, P1=8 * 25, P2=32 * 25,
                                     disp12MaxDiff=1, uniquenessRatio=5, speckleWindowSize=100,
                                     speckleRange=2, mode=cv2.STEREO_SGBM_MODE_HH)
        # pad on the left so that the first `nd` columns get a disparity search too
        def pad(img: U8) -> U8:
            return np.asarray(cv2.copyMakeBorder(img[r0:r1], 0, 0, nd, 0, cv2.BORDER_REPLICATE), np.uint8)

        disp = np.asarray(sgbm.compute(pad(lr), pad(rr)))[:, nd + c0:nd + c1].astype(np.float32) / 16.0
        ys, xs = np.nonzero(disp > 0.5)
        d = disp[ys, xs].astype(np.float64)
        X_rig = self._rect_points_to_rig((xs + s0 + c0).astype(np.float64), (ys + r0).astype(np.float64), d)
        g = frame.gimbal or GimbalState()
        X_w = X_rig @ gimbal_rotation(g.pan_deg, g.tilt_deg).T
        rho = np.linalg.norm(X_w, axis=1)
        cu, cv = self._to_canvas(X_w)
        pu, pv = np.round(cu).astype(int), np.round(cv).astype(int)
        ok = (X_w[:, 2] > 0) & (pu >= 0) & (pv >= 0) & (pu < self.canvas.shape[1]) & (pv < self.canvas.shape[0])
        order = np.argsort(-rho[ok])
        return pu[ok][order], pv[ok][order], (1.0 / rho[ok][order]).astype(np.float32)

    def _learn_floor(self, frame: StereoFrame, key: int, box: tuple[int, int, int, int] | None = None) -> None:
        """Store the empty scene's residual of eq. (9), less the noise level and dilated by a pixel, in
        the floor canvas of camera `key` (the largest seen per direction), for the key pixels in `box`
        (x0, y0, x1, y1) or all of them."""
        cm = self.correspondence(key, frame.gimbal, with_floor=False, box=box)
        img_k, img_o = (frame.left, frame.right) if key == 0 else (frame.right, frame.left)
        x0, y0, x1, y1 = box or (0, 0, img_k.shape[1], img_k.shape[0])
        ref = cm.warp(img_o)
        resid = np.asarray(cv2.absdiff(np.ascontiguousarray(img_k[y0:y1, x0:x1]), ref), np.uint8)
        resid = np.asarray(cv2.subtract(resid, np.full_like(resid, 3)), np.uint8)
        grid = self._grid(key, 1)
        pu, pv = self._canvas_coords(grid.crop(box).rays if box else grid.rays, frame.gimbal)
        iu, iv = np.round(pu).astype(int).ravel(), np.round(pv).astype(int).ravel()
        vals = resid.ravel()
        ok = (iu >= 0) & (iv >= 0) & (iu < self.canvas.shape[1]) & (iv < self.canvas.shape[0])
        order = np.argsort(vals[ok], kind="stable")  # ascending: the largest lands last
        layer = np.zeros_like(self.floors[key])
        layer[iv[ok][order], iu[ok][order]] = vals[ok][order]
        layer = np.asarray(cv2.dilate(layer, np.ones((3, 3), np.uint8)), np.uint8)  # close splat gaps
        cv2.max(self.floors[key], layer, dst=self.floors[key])

    def _rect_points_to_rig(self, x: F64, y: F64, d: F64) -> F64:
        r = self.rect
        Z = r.f * r.b / d
        X = np.stack([(x - r.cx) * Z / r.f, (y - r.cy) * Z / r.f, Z], axis=1)
        L = r.rig.left
        return np.asarray(X @ r.R1 @ L.R_rc + L.c)

    def _fill_holes(self) -> None:
        """Fill unknown pixels inside the learnt area with their farthest known neighbour (occlusion
        holes belong to the background behind), by repeated grey-level erosion of 1/ρ."""
        self.canvas = _filled(self.learnt)

    # -- lookup -----------------------------------------------------------------------------------
    def _grid(self, key: int, step: int) -> _RayGrid:
        """The per-pixel constants of camera `key`'s pixels on a grid of the given step (cached)."""
        g = self._grids.get((key, step))
        if g is None:
            g = self._grids[(key, step)] = _RayGrid.of(self.rect, key, self.rays[key][::step, ::step])
        return g

    def _canvas_coords(self, rays: F32, gimbal: GimbalState | None) -> tuple[F32, F32]:
        """Canvas coordinates (u, v) of rig-frame rays (h, w, 3) at the gimbal angles: the world direction
        w = R_world_rig ray seen by the canvas pinhole, u = f w_x / w_z + c_x, v = f w_y / w_z + c_y."""
        g = gimbal or GimbalState()
        pose = (g.pan_deg, g.tilt_deg)
        if self._homography[0] != pose:  # K R_world_rig, kept for the frame's boxes at one pose
            K = np.array([[self.f, 0.0, self.cx], [0.0, self.f, self.cy], [0.0, 0.0, 1.0]])
            self._homography = (pose, (K @ gimbal_rotation(*pose)).astype(np.float32))
        h = np.asarray(cv2.transform(rays, self._homography[1]))
        return (np.asarray(cv2.divide(h[..., 0], h[..., 2]), np.float32),
                np.asarray(cv2.divide(h[..., 1], h[..., 2]), np.float32))

    def _to_canvas(self, w: NDArray[np.floating]) -> tuple[F32, F32]:
        """Canvas coordinates (u, v) of world directions (..., 3): the virtual pinhole at home."""
        return (np.asarray(self.f * w[..., 0] / w[..., 2] + self.cx, np.float32),
                np.asarray(self.f * w[..., 1] / w[..., 2] + self.cy, np.float32))

    def correspondence(self, key: int, gimbal: GimbalState | None, step: int = 1,
                       box: tuple[int, int, int, int] | None = None, with_floor: bool = True
                       ) -> CorrespondenceMap:
        """Background correspondences from camera `key` (0 left, 1 right) into the other camera, for key
        pixels on a grid with the given step, optionally only inside box = (x0, y0, x1, y1) (full-size
        pixels; with a step, grid cells)."""
        g = self._grid(key, step)
        if box is not None:
            g = g.crop(box)
        pu, pv = self._canvas_coords(g.rays, gimbal)
        inv = _remap_f32(self.canvas, pu, pv)  # 1/ρ of the background in that direction
        floor = (np.asarray(cv2.remap(self.floors[key], pu, pv, cv2.INTER_NEAREST,
                                      borderMode=cv2.BORDER_CONSTANT, borderValue=0), np.uint8)
                 if with_floor else np.zeros(pu.shape, np.uint8))
        valid = inv > 0
        # distance along the ray from the lens centre c_k: ρ is measured from the pivot, so to first
        # order t = ρ - ray·c_k; the point is X = c_k + t ray (rig frame)
        # numpy, not cv2.divide(1.0, a): OpenCV takes an (4, 1) array for a scalar and refuses the pair
        t = np.float32(1.0) / np.where(valid, inv, np.float32(1.0)).astype(np.float32)
        t -= g.ray_dot_c
        # in the other camera: X_o = R_o (X - c_o) = R_o (c_k - c_o) + t R_o ray
        x, y, z = (g.dir_other[i] * t for i in range(3))
        for c, a in zip((x, y, z), g.origin_other, strict=True):
            c += np.float32(a)
        valid &= z > 0
        cam_r = self.rect.rig.right if key == 0 else self.rect.rig.left
        mx, my = _distort_points(cam_r, x, y, z)
        W, H = cam_r.size
        valid &= (mx >= 0) & (my >= 0) & (mx <= W - 1) & (my <= H - 1)
        # rectified disparity f b / z_rect, z_rect = r₃·(X - c_left) = r₃·(c_k - c_left) + t r₃·ray
        z_rect = np.multiply(g.dir_rect_z, t, out=t)
        z_rect += np.float32(g.origin_rect_z)
        disp = np.divide(np.float32(self.rect.f * self.rect.b), np.maximum(z_rect, np.float32(1e-3), out=z_rect),
                         out=z_rect)
        return CorrespondenceMap(mx, my, valid, disp, floor)


def _filled(canvas: F32, iterations: int = 200) -> F32:
    """`canvas` (1/ρ, 0 = unknown) with each unknown pixel within `iterations` pixels of known ones set to
    its farthest known neighbour's value (grey-level erosion of 1/ρ, repeated)."""
    known = canvas > 0
    inv = np.where(known, canvas, np.float32(1e6)).astype(np.float32)
    kernel = np.ones((3, 3), np.uint8)
    for _ in range(iterations):
        unknown = inv >= 1e6
        if not unknown.any():
            break
        grown = cv2.erode(inv, kernel)
        inv = np.where(unknown, grown, inv)
    return np.where(inv >= 1e6, 0.0, inv).astype(np.float32)
