"""Render the simulated stereo rig: exact per-pixel ray casting of textured planes, with ground truth.

The static scene is rendered exactly for each gimbal pose (tracker.sim.static_cast: about 2 ms a camera
at 640x480 on one core, where a ray cast of every pixel of every plane took 10) and the last few poses are
cached; each frame re-casts only the pixels inside the bounding boxes of moving things (targets, foliage),
applies the illumination gain and adds sensor noise from a pre-drawn bank.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from typing import Protocol, TypeVar

import cv2
import numpy as np
from numpy.typing import NDArray

from tracker.frames import GimbalState, StereoFrame
from tracker.geometry import StereoRig, gimbal_rotation
from tracker.sim.cast import View, cast_plane_fast, make_view, pixel_box
from tracker.sim.scene import Surface
from tracker.sim.static_cast import StaticScene
from tracker.sim.static_plan import Plan

F64 = NDArray[np.float64]
F32 = NDArray[np.float32]
U8 = NDArray[np.uint8]
_T = TypeVar("_T")


class Solid(Protocol):
    """A moving thing that casts itself (tracker.sim.bodies.Body): world points bounding its image, and
    a z-tested ray cast over a pixel box into the image, its depth (distance along the ray, m) and ids."""

    def corners(self) -> F64: ...

    def cast(self, view: View, R_wr: F64, img: U8, depth: F32, t: float, ids: U8 | None,
             box: tuple[int, int, int, int], edge_samples: int = 1) -> None: ...


@dataclass(frozen=True)
class TargetTruth:
    """Truth for one moving object in one frame. Positions in metres; pixel coordinates distorted (raw).
    centroid_*: eq. (10) over the object's visible pixels (None when not visible); area_*: those pixels."""

    target_id: int
    world: F64
    rig: F64
    proj_left: F64
    proj_right: F64
    centroid_left: F64 | None
    centroid_right: F64 | None
    area_left: int
    visible_fraction: float
    area_right: int = 0
    near_depth_m: float = 0.0  # a solid body: how much nearer than `world` its nearest point is (m)
    # a solid body: the mean world point (m, (3,)) of the surface the left camera sees of it (Renderer.
    # surface_mean): the point a camera can measure; None for plates (their centre is that point) or unseen
    surface_world: F64 | None = None
    # a solid body: the point the tracker measures, on the mean ray of its silhouette in the left image at
    # the seen surface's mean distance (Renderer.surface_mean with on_mean_ray); None as surface_world
    silhouette_world: F64 | None = None


@dataclass(frozen=True)
class FrameTruth:
    """Ground truth of a frame: gimbal angles, per-object truth, and the left foreground id image
    (uint8 (H, W): 0 background, k for moving object k)."""

    t: float
    gimbal: GimbalState
    targets: tuple[TargetTruth, ...]
    ids_left: U8
    ids_right: U8

    def target(self, target_id: int) -> TargetTruth | None:
        return next((tt for tt in self.targets if tt.target_id == target_id), None)


class _Bands:
    """Rows 0 to h of an image, in bands of BAND rows, done by whichever thread takes them first: run()
    takes and does bands until none is left; wait() returns once every band is done, raising what a band
    raised."""

    BAND = 96  # 5 bands at 480 rows: 0.05-0.13 ms a frame less than 48 (fewer hand-overs; pan, interleaved runs)

    def __init__(self, h: int, fn: Callable[[int, int], None]):
        self._starts = list(range(0, h, self.BAND))
        self._h, self._fn = h, fn
        self._next = 0
        self._lock = threading.Lock()
        self._done = [threading.Event() for _ in self._starts]
        self._error: BaseException | None = None

    def run(self) -> None:
        while True:
            with self._lock:
                i = self._next
                if i >= len(self._starts):
                    return
                self._next += 1
            r0 = self._starts[i]
            try:
                self._fn(r0, min(r0 + self.BAND, self._h))
            except BaseException as e:  # handed to wait(), on the caller's thread
                self._error = e
            finally:
                self._done[i].set()

    def wait(self) -> None:
        for e in self._done:
            e.wait()
        if self._error is not None:
            raise self._error


class SimRenderer:
    """Renders stereo pairs of a scene for given gimbal angles. Not thread-safe; one per worker.

    The two cameras are rendered concurrently (camera 0 on a helper thread, camera 1 on the caller's),
    except the planning of the static scene (StaticScene.plan: many small numpy steps that hold the GIL),
    done for both on the caller's thread while camera 0 is drawn. Random draws are made on the caller's
    thread, in camera order, so frames do not depend on the threads' timing."""

    def __init__(self, rig: StereoRig, static: list[Surface], seed: int, noise_sigma: float = 1.2,
                 edge_samples: int = 1):
        self.rig = rig
        self.edge_samples = edge_samples  # solids: rays a side over a pixel an edge crosses (Body.cast)
        self.static = static
        self.views = (make_view(rig.left), make_view(rig.right))
        self._scene = StaticScene([v.cam for v in self.views], static)
        self._cache: dict[tuple[float, float], tuple[list[U8], list[F32]]] = {}
        rng = np.random.default_rng(seed + 7919)
        w, h = rig.left.size
        self._noise = [self._noise_bank(rng, h, w, noise_sigma) for _ in range(2)]
        self._rng = np.random.default_rng(seed + 104729)
        self.windows: list[tuple[int, int, int, int] | None] = [None, None]
        self._depth = [np.empty((h, w), np.float32) for _ in range(2)]
        self._pool: ThreadPoolExecutor | None = None

    @staticmethod
    def _noise_bank(rng: np.random.Generator, h: int, w: int, sigma: float) -> tuple[U8, U8]:
        """Positive and negative parts of Gaussian noise, (h + 64, w) each, as uint8."""
        n = np.round(rng.standard_normal((h + 64, w)) * sigma).clip(-60, 60)
        return np.maximum(n, 0).astype(np.uint8), np.maximum(-n, 0).astype(np.uint8)

    def _both(self, fn: Callable[[int, Plan | None], _T], R_wr: F64 | None) -> tuple[_T, _T]:
        """(fn(0, plan 0), fn(1, plan 1)), camera 0's on the helper thread: both plans are made on this
        thread (small numpy steps holding the GIL), camera 0's draw overlapping camera 1's plan. Two whole
        renders on two threads instead fight over the GIL at every step. R_wr None: no static render, the
        plans are None. This thread waits until the helper has started camera 0: woken while this thread
        plans camera 1, the helper would wait for the GIL until a numpy step let go of it (about 0.3 ms
        later, pan), and the time lost there is lost at the end of the frame."""
        if self._pool is None:
            self._pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix="sim-render")
        plan0 = self._scene.plan(0, R_wr) if R_wr is not None else None
        started = threading.Event()

        def helper() -> _T:
            started.set()
            return fn(0, plan0)

        first = self._pool.submit(helper)
        started.wait()
        try:
            second = fn(1, self._scene.plan(1, R_wr) if R_wr is not None else None)
        finally:
            out = first.result()
        return out, second

    def _static_camera(self, plan: Plan, R_wr: F64) -> tuple[U8, F32]:
        """A camera's static image (H, W) uint8 and inverse distances 1/z (1/m), (H, W) float32, drawn from
        its plan. Camera 1 is drawn on the caller's thread after camera 0's work was handed to the helper
        (_both): its texturing is split into row bands that the helper joins in when it is done with
        camera 0 (_Bands), which shortens the frame by up to half of camera 1's remap."""
        view = self.views[plan.k]
        if plan.k == 1 and self._pool is not None and plan.nodes is not None:
            X, Y, inv_z = self._scene.prepare(plan)
            img = np.empty(inv_z.shape, np.uint8)
            bands = _Bands(len(img), lambda r0, r1: self._scene.texture(X, Y, inv_z, img, r0, r1))
            self._pool.submit(bands.run)
            bands.run()
            bands.wait()
        else:
            img, inv_z = self._scene.draw(plan)
        if plan.rest:  # what the static renderer cannot take (discs, swaying, too near), cast per pixel
            depth = view.ray_len / inv_z
            for surface in plan.rest:
                cast_plane_fast(view, R_wr, surface, img, depth)
            inv_z = view.ray_len / depth
        return img, inv_z

    def _static(self, gimbal: GimbalState) -> tuple[list[U8], list[F32]]:
        """The static scene at a gimbal pose, per camera: the image (H, W) uint8 and the inverse 1/z (1/m)
        of each pixel's distance along the camera's axis, (H, W) float32 (about 1e-30 where nothing is
        hit). Cached for the last 4 poses."""
        key = (round(gimbal.pan_deg, 6), round(gimbal.tilt_deg, 6))
        hit = self._cache.get(key)
        if hit is not None:
            return hit
        R_wr = gimbal_rotation(gimbal.pan_deg, gimbal.tilt_deg)

        def static(_k: int, plan: Plan | None) -> tuple[U8, F32]:
            assert plan is not None  # planned: R_wr is given
            return self._static_camera(plan, R_wr)

        pair = self._both(static, R_wr)
        self._remember(key, ([p[0] for p in pair], [p[1] for p in pair]))
        return self._cache[key]

    def _remember(self, key: tuple[float, float], value: tuple[list[U8], list[F32]]) -> None:
        if len(self._cache) >= 4:
            self._cache.pop(next(iter(self._cache)))
        self._cache[key] = value

    def static_depth(self, gimbal: GimbalState) -> list[F32]:
        """Distance (m) along each pixel's ray to the static scene, per camera, (H, W) float32, inf where
        nothing is hit."""
        with np.errstate(divide="ignore"):
            return [np.where(inv > 1e-20, view.ray_len / inv, np.float32(np.inf))
                    for view, inv in zip(self.views, self._static(gimbal)[1], strict=True)]

    def render(self, index: int, t: float, gimbal: GimbalState, moving: Sequence[Surface | Solid], gain: float,
               noisy: bool = True, right_gain: float = 1.0) -> tuple[StereoFrame, list[U8]]:
        """Render one pair at time t (s). Returns the frame and the (left, right) id images. gain: the
        scene's light on both cameras; right_gain: the right camera's exposure over the left's."""
        key = (round(gimbal.pan_deg, 6), round(gimbal.tilt_deg, 6))
        cached = self._cache.get(key)
        R_wr = gimbal_rotation(gimbal.pan_deg, gimbal.tilt_deg)
        offsets = [int(self._rng.integers(0, 64)) if noisy else 0 for _ in range(2)]

        def camera(k: int, plan: Plan | None) -> tuple[U8, U8, U8, F32]:
            if plan is not None:
                base_img, base_inv = self._static_camera(plan, R_wr)
            else:
                assert cached is not None  # not planned: the pose's static render is cached
                base_img, base_inv = cached[0][k], cached[1][k]
            img8 = base_img.copy()
            ids = np.zeros(img8.shape, np.uint8)
            if moving:
                self._cast_moving(k, R_wr, moving, t, img8, base_inv, ids)
            g = gain * right_gain if k == 1 else gain
            if g != 1.0:
                img8 = np.asarray(cv2.convertScaleAbs(img8, alpha=g), np.uint8)
            if noisy:
                pos, neg = self._noise[k]
                o, h = offsets[k], img8.shape[0]
                img8 = np.asarray(cv2.subtract(cv2.add(img8, pos[o:o + h]), neg[63 - o:63 - o + h]), np.uint8)
            return img8, ids, base_img, base_inv

        left, right = self._both(camera, None if cached else R_wr)
        if cached is None:
            self._remember(key, ([left[2], right[2]], [left[3], right[3]]))
        frame = StereoFrame(index, left[0], right[0], t, t, gimbal)
        return frame, [left[1], right[1]]

    def depth_window(self, k: int) -> tuple[tuple[int, int, int, int], F32] | None:
        """A copy of camera k's window of moving objects in the last render and the distances (m) along
        each pixel's ray drawn there, (y1 - y0, x1 - x0) float32; None when nothing moving was drawn."""
        win = self.windows[k]
        if win is None:
            return None
        x0, y0, x1, y1 = win
        return win, self._depth[k][y0:y1, x0:x1].copy()

    def surface_mean(self, k: int, ids: U8, target_id: int, window: tuple[tuple[int, int, int, int], F32] | None,
                     on_mean_ray: bool = False) -> F64 | None:
        """The mean point (rig frame, m, (3,)) of the surface an object shows camera k in a render (window:
        that render's depth_window(k)): over its pixels (ids == target_id), Σ a_p (c + ρ_p s_p) / Σ a_p, c
        the camera centre, ρ_p the pixel's unit ray, s_p the distance along it to the surface drawn there
        and a_p the pixel's area in the undistorted normalised plane (each pixel of a pinhole camera alike,
        whatever the lens's distortion). As ρ_p s_p = Z_p (x_n, y_n, 1), Z_p the depth, the point lies on
        the ray of the silhouette's centroid in that plane weighted by depth: what eq. (10), which weights
        the outline's pixels by their area in rectified coordinates, measures on a true outline, carried to
        the surface by its pixels' depths. With each raw pixel alike (as judged until 2026-12-05) the point
        moved with the lens's distortion: 0.11° above this one on walk:body's walker at 3-4 m.
        With on_mean_ray, the silhouette's point instead: c + s̄ m̄ / |m̄|, m̄ = Σ a_p ℓ_p ρ_p / Σ a_p and
        s̄ = Σ a_p s_p / Σ a_p, ℓ_p ρ_p = (x_n, y_n, 1): the ray of the silhouette's area-weighted centroid
        in that plane at the surface's mean distance. None when the object shows no pixel."""
        if window is None:
            return None
        (x0, y0, x1, y1), depth = window
        m = ids[y0:y1, x0:x1] == target_id
        if not m.any():
            return None
        view = self.views[k]
        s = depth[m].astype(np.float64)
        rays = view.rays[y0:y1, x0:x1][m].astype(np.float64)
        a = view.area[y0:y1, x0:x1][m].astype(np.float64)
        if on_mean_ray:
            ray = (a * view.ray_len[y0:y1, x0:x1][m]) @ rays  # Σ a_p ℓ_p ρ_p, a multiple of m̄
            return np.asarray(view.cam.c + float(a @ s / a.sum()) * ray / np.linalg.norm(ray))
        return np.asarray(view.cam.c + (a * s) @ rays / a.sum())

    def _cast_moving(self, k: int, R_wr: F64, moving: Sequence[Surface | Solid], t: float, img8: U8,
                     base_inv: F32, ids: U8) -> None:
        """Cast moving surfaces over the static scene (base_inv: its inverse distances 1/z, (H, W)), only
        over their bounding boxes: the static depth is filled in for the window around them all. Solids
        (tracker.sim.bodies) cast themselves, z-tested in the same depth."""
        view = self.views[k]
        cast = [(s, b) for s, b in ((s, pixel_box(view, s.corners() @ R_wr)) for s in moving) if b is not None]
        self.windows[k] = None
        if not cast:
            return
        boxes = [b for _, b in cast]
        x0, y0 = min(b[0] for b in boxes), min(b[1] for b in boxes)
        x1, y1 = max(b[2] for b in boxes), max(b[3] for b in boxes)
        depth = self._depth[k]  # valid inside the window only
        np.divide(view.ray_len[y0:y1, x0:x1], base_inv[y0:y1, x0:x1], out=depth[y0:y1, x0:x1])
        for s, b in cast:
            if isinstance(s, Surface):
                cast_plane_fast(view, R_wr, s, img8, depth, t, ids, b)
            else:
                s.cast(view, R_wr, img8, depth, t, ids, b, self.edge_samples)
        self.windows[k] = (x0, y0, x1, y1)
