"""Exact rendering of the static scene at any gimbal pose, fast enough for a moving gimbal.

On a textured rectangle, a pixel's texture coordinates are a homography of its undistorted normalised
coordinates m = (x_n, y_n, 1): (X, Y, W) = H m, texture (X/W, Y/W) (texels), and with H scaled by 1/q
(q = n·(P0 - c), metres) W = 1/z, the inverse of the distance z (m) along the camera's axis (the distance
along the ray is |m| / W). X, Y and W are linear in m, and m is a smooth fixed function of the distorted
pixel, so they are evaluated exactly on a grid of nodes every STEP pixels and interpolated bilinearly (one
cv2.resize) in between: the only error is the curvature of the lens undistortion over a 4-px cell, below
0.003 texel and 2e-5 relative depth at 640x480 (cv2.remap itself rounds texture coordinates to 1/32 texel).

Which surface is nearest can only change across the image of a rectangle's edge or of the line where two
rectangles cross (fixed 3-D segments, _segments). Cells such a segment may pass through are found by
sampling its projection and cast per pixel by the reference's rule; every other cell sees one surface,
found once per run of such cells along a row (tracker.sim.static_plan, the plan). All textures share
one atlas, so one cv2.remap textures the whole image. About 2 ms a camera at 640x480 on one core: the
remap a quarter of it, the cells cast per pixel (about 4 % of the image) a fifth.

Surfaces this cannot take (discs, swaying ones, planes within 10 cm of a camera) are returned to the
caller to cast per pixel over the result (z-tested).
"""

from __future__ import annotations

import cv2
import numpy as np
from numpy.typing import NDArray

from tracker.geometry import Camera
from tracker.sim.scene import Surface
from tracker.sim.static_plan import NO_HIT, STEP, Grid, Plan, Planes, plan_camera

F64 = NDArray[np.float64]
F32 = NDArray[np.float32]
U8 = NDArray[np.uint8]
I64 = NDArray[np.int64]
B = NDArray[np.bool_]

_PAD = 2  # atlas border around each texture (texels), reflect-101 like the reference's cv2.remap border


def _fits_atlas(s: Surface) -> bool:
    """Whether the surface can be drawn from the atlas: a flat rectangle (no sway)."""
    return s.shape == "rect" and s.sway is None


def _atlas(surfaces: list[Surface]) -> tuple[U8, F64]:
    """All textures in one uint8 image (shelves of the tallest first, as wide as the widest), each inside a
    reflect-101 border (what the reference's cv2.remap reads beyond a texture) wide enough for the surface's
    extent plus _PAD texels, and each texture's origin in it, (S, 2) (x, y) texels."""
    padded = []
    for s in surfaces:
        th, tw = s.texture.shape
        px = _PAD + max(int(np.ceil(s.half_w / s.texel_m - tw / 2.0)), 0)
        py = _PAD + max(int(np.ceil(s.half_h / s.texel_m - th / 2.0)), 0)
        padded.append((px, py, cv2.copyMakeBorder(s.texture, py, py, px, px, cv2.BORDER_REFLECT101)))
    width = max(p.shape[1] for _, _, p in padded)
    place, x, y, shelf = {}, 0, 0, 0
    for k in sorted(range(len(padded)), key=lambda k: -padded[k][2].shape[0]):
        ph, pw = padded[k][2].shape
        if x + pw > width:
            x, y, shelf = 0, y + shelf, 0
        place[k] = (x, y)
        x, shelf = x + pw, max(shelf, ph)
    atlas = np.zeros((y + shelf, width), np.uint8)
    origins = np.zeros((len(surfaces), 2))
    for k, (px, py, p) in enumerate(padded):
        x, y = place[k]
        atlas[y:y + p.shape[0], x:x + p.shape[1]] = p
        origins[k] = (x + px, y + py)
    return atlas, origins


def _crossing(a: Surface, b: Surface) -> tuple[F64, F64] | None:
    """The segment (two points, world metres) where two rectangles cross, or None."""
    d = np.cross(a.normal, b.normal)
    if np.linalg.norm(d) < 1e-9:
        return None  # parallel planes
    p0 = np.linalg.solve(np.array([a.normal, b.normal, d]), np.array([a.normal @ a.P0, b.normal @ b.P0, 0.0]))
    lo, hi = -np.inf, np.inf
    for s in (a, b):  # |(p0 + t d - P0)·axis| <= half on both
        for axis, half in ((s.u, s.half_w), (s.v, s.half_h)):
            k, o = float(d @ axis), float((p0 - s.P0) @ axis)
            if abs(k) < 1e-12:
                if abs(o) > half:
                    return None
                continue
            t1, t2 = sorted(((-half - o) / k, (half - o) / k))
            lo, hi = max(lo, t1), min(hi, t2)
    return (p0 + lo * d, p0 + hi * d) if lo <= hi else None


def _on(p: F64, a: F64, b: F64) -> bool:
    """Whether point p lies on the segment from a to b (to within a micrometre)."""
    d = b - a
    t = float(np.clip((p - a) @ d / max(float(d @ d), 1e-300), 0.0, 1.0))
    return bool(np.linalg.norm(a + t * d - p) < 1e-6)


def _hidden(a: F64, b: F64, s: Surface, reach: float) -> bool:
    """Whether the segment from a to b (world, metres) is behind the rectangle s from every point within
    `reach` metres of the origin (every camera centre at every gimbal pose; world = R_wr @ rig): the line
    from each corner c of the cube [-reach, reach]³ to each end p of the segment meets s strictly inside
    it, with c more than 0.1 m in front of its plane (so the plan never leaves s to the caller as too near)
    and p behind it. For fixed p the lines from the cube meet the plane inside the hull of the corners'
    points, and for fixed c those to the segment inside the hull of the ends', so every line from the cube
    to the segment meets the plane inside the hull of these 16 points, inside s: nothing behind s there is
    seen, and the segment cannot separate what two pixels see."""
    cube = reach * np.array([(x, y, z) for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], np.float64)
    front = (s.P0 - cube) @ s.normal  # n·(P0 - c), (8,)
    if not (np.all(front > 0.1) or np.all(front < -0.1)):
        return False
    for p in (a, b):
        behind = float((p - s.P0) @ s.normal)  # n·(p - P0): the same sign as n·(P0 - c) when behind
        if not np.all(front * behind > 1e-12):
            return False
        x = cube + (p - cube) * (front / (front + behind))[:, None]  # on the plane: n·(x - P0) = 0
        if (np.abs((x - s.P0) @ s.u) >= s.half_w * (1 - 1e-9)).any() or \
                (np.abs((x - s.P0) @ s.v) >= s.half_h * (1 - 1e-9)).any():
            return False
    return True


def _segments(surfaces: list[Surface], reach: float) -> F64:
    """Where the nearest surface can change, (K, 2, 3) segments (world, metres): the rectangles' edges and
    the segments where two of them cross, without those that lie on another (a plane standing on the
    ground meets it along its own bottom edge) and those hidden behind a rectangle from every camera centre
    within `reach` metres of the origin (_hidden: a wall's foot behind a hedge)."""
    segs = [(c[i], c[(i + 1) % 4]) for c in (s.corners() for s in surfaces) for i in range(4)]
    segs += [x for i, a in enumerate(surfaces) for b in surfaces[i + 1:] if (x := _crossing(a, b)) is not None]
    keep = [(a, b) for i, (a, b) in enumerate(segs)
            if not any(_on(a, *o) and _on(b, *o) and (j < i or not (_on(o[0], a, b) and _on(o[1], a, b)))
                       for j, o in enumerate(segs) if j != i)
            and not any(_hidden(a, b, s, reach) for s in surfaces)]
    return np.array(keep, np.float64).reshape(-1, 2, 3)


def _planes(surfaces: list[Surface], origins: F64, reach: float) -> Planes:
    sizes = np.array([s.texture.shape[::-1] for s in surfaces], np.float64).reshape(-1, 2)  # (tw, th)
    texel = np.array([s.texel_m for s in surfaces])
    extent = np.array([(s.half_w, s.half_h) for s in surfaces]).reshape(-1, 2)
    normal, u, v, P0 = (np.array([getattr(s, a) for s in surfaces]).reshape(-1, 3) for a in ("normal", "u", "v", "P0"))
    return Planes(normal, u, v, P0, texel, origins + sizes / 2.0, extent / texel[:, None], _segments(surfaces, reach),
                   np.stack([u, v, normal]))


def _grid(cam: Camera) -> Grid:
    w, h = cam.size
    nx, ny = (int(np.ceil((n - 1 + (STEP + 1) / 2) / STEP)) + 1 for n in (w, h))
    wp = nx * STEP
    off = (STEP + 1) / 2  # node j sits at image pixel STEP·j - off
    xn, yn = cam.undistort_pixels(*np.meshgrid(STEP * np.arange(nx) - off, STEP * np.arange(ny) - off))
    xp, yp = cam.undistort_pixels(*np.meshgrid(np.arange(wp, dtype=np.float64) - STEP,
                                               np.arange(ny * STEP, dtype=np.float64) - STEP))
    step_m = min(float(np.hypot(np.diff(xn, axis=a), np.diff(yn, axis=a)).min()) for a in (0, 1))
    first = (STEP * np.arange(ny - 1) + STEP // 2)[:, None] * wp + (STEP * np.arange(nx - 1) + STEP // 2)[None, :]
    block = (np.arange(STEP)[:, None] * wp + np.arange(STEP)[None, :]).ravel()
    return Grid((ny, nx), np.array([xn, yn], np.float32),
                 (float(xn.min()), float(xn.max()), float(yn.min()), float(yn.max())), 1.05 * STEP / step_m,
                 np.stack([xp.ravel(), yp.ravel()]).astype(np.float32), first.astype(np.int64),
                 block.astype(np.int64))


class StaticScene:
    """The static surfaces of a scene, rendered exactly for each of a rig's cameras at any gimbal pose."""

    def __init__(self, cams: list[Camera], surfaces: list[Surface]):
        self.cams = cams
        self.surfaces = surfaces
        self._fast = [s for s in surfaces if _fits_atlas(s)][:255]  # labels are uint8, 255 for none
        self._fast_ids = {id(s) for s in self._fast}
        self._atlas, origins = _atlas(self._fast) if self._fast else (np.zeros((1, 1), np.uint8), np.zeros((0, 2)))
        reach = max((float(np.linalg.norm(c.c)) for c in cams), default=0.0)  # camera centres' distance from
        self._planes = _planes(self._fast, origins, reach)  # the gimbal's centre, the world's origin
        self._grids = [_grid(c) for c in cams]

    def render(self, k: int, R_wr: F64) -> tuple[U8, F32, list[Surface]]:
        """Camera k's image (H, W) uint8 and the inverse 1/z of each pixel's distance z (m) along the
        camera's axis to the scene, (H, W) float32 (about 1e-30 where nothing is hit; the distance along the
        ray is |m| z), at gimbal rotation R_wr (world <- rig); and the surfaces left to the caller to cast
        per pixel over them, in scene order (those this cannot render). plan() then draw()."""
        plan = self.plan(k, R_wr)
        img, W = self.draw(plan)
        return img, W, plan.rest

    def plan(self, k: int, R_wr: F64) -> Plan:
        """The sparse part of camera k's image at R_wr: which surface each cell sees, (X, Y, W) at the nodes
        and at the pixels cast one by one (tracker.sim.static_plan.plan_camera). Many small numpy steps
        that hold the GIL most of the time: run the planning of both cameras on one thread and overlap it
        with draw(), which is a few large OpenCV calls that release it."""
        return plan_camera(k, self.cams[k], self._grids[k], self._planes, R_wr, self._fast, self._fast_ids,
                           self.surfaces)

    def draw(self, plan: Plan) -> tuple[U8, F32]:
        """A plan's image (H, W) uint8 and inverse distances 1/z (H, W) float32: the node values
        interpolated (one cv2.resize), the pixels cast one by one put in, divided by W and textured (one
        cv2.remap). prepare() then texture() of every row."""
        X, Y, W = self.prepare(plan)
        img = np.empty(W.shape, np.uint8)
        if plan.nodes is None:
            img[:] = 0
        else:
            self.texture(X, Y, W, img, 0, len(img))
        return img, W

    def prepare(self, plan: Plan) -> tuple[F32, F32, F32]:
        """A plan's (X, Y, W) at every pixel, (H, W) float32 each (views with a row stride): the node
        values interpolated (one cv2.resize) and the pixels cast one by one put in. texture() turns rows of
        them into the image."""
        cam, grid = self.cams[plan.k], self._grids[plan.k]
        w, h = cam.size
        if plan.nodes is None:
            return (np.full((h, w), NO_HIT[0], np.float32), np.full((h, w), NO_HIT[1], np.float32),
                    np.full((h, w), NO_HIT[2], np.float32))
        ny, nx = grid.shape
        full = np.asarray(cv2.resize(plan.nodes.reshape(3 * ny, nx), (nx * STEP, 3 * ny * STEP),
                                     interpolation=cv2.INTER_LINEAR)).reshape(3, -1)
        for c in range(3):
            full[c][plan.idx] = plan.vals[c]
        X, Y, W = full.reshape(3, ny * STEP, nx * STEP)[:, STEP:STEP + h, STEP:STEP + w]
        return X, Y, W

    def texture(self, X: F32, Y: F32, W: F32, img: U8, r0: int, r1: int) -> None:
        """Rows r0 to r1 of the image img (H, W) uint8, in place, from prepare()'s (X, Y, W): texture
        coordinates X/W, Y/W (written over X and Y), one cv2.remap of the atlas. Rows are independent, so
        two threads may texture different rows of one image at once (OpenCV releases the GIL)."""
        x, y = X[r0:r1], Y[r0:r1]
        cv2.divide(x, W[r0:r1], dst=x)  # in place: texture coordinates, the maps of the remap
        cv2.divide(y, W[r0:r1], dst=y)
        cv2.remap(self._atlas, x, y, cv2.INTER_LINEAR, dst=img[r0:r1], borderMode=cv2.BORDER_CONSTANT,
                  borderValue=0)
