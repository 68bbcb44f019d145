"""Scene content for the simulated rig: textured planes and discs at finite distances, in the world frame.

World frame: the gimbal base at home (x right, y down, z forward, metres); the ground is the plane
y = +CAMERA_HEIGHT_M. Every surface is planar, so a pixel's ray meets it at one point and its texture value
and depth are exact: ground truth (masks, depths, centroids) comes from the same computation.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import cv2
import numpy as np
from numpy.typing import NDArray

F64 = NDArray[np.float64]
FA = NDArray[np.floating]  # float32 or float64 arrays
U8 = NDArray[np.uint8]

CAMERA_HEIGHT_M = 1.5


def smooth_texture(rng: np.random.Generator, shape: tuple[int, int], sigma_px: float,
                   lo: int, hi: int) -> U8:
    """Band-limited random texture (Gaussian-smoothed noise), stretched to [lo, hi]; shape (h, w)."""
    noise = rng.standard_normal(shape).astype(np.float32)
    tex = np.asarray(cv2.GaussianBlur(noise, (0, 0), sigma_px, borderType=cv2.BORDER_REFLECT101), np.float32)
    tex = tex - np.float32(tex.min())
    tex = tex / np.float32(max(float(tex.max()), 1e-6))
    return np.asarray(lo + tex * (hi - lo), dtype=np.float32).round().astype(np.uint8)


@dataclass
class Surface:
    """A textured planar patch: points P0 + a·u + b·v with (a, b) inside the extent (metres).

    shape "rect": |a| ≤ half_w, |b| ≤ half_h; "disc": a² + b² ≤ half_w². texel_m: metres per texture
    pixel; the texture is centred on P0. sway(t) -> (da, db) arrays offset the texture lookup (foliage).
    """

    name: str
    P0: F64
    u: F64
    v: F64
    half_w: float
    half_h: float
    texture: U8
    texel_m: float
    shape: str = "rect"
    moving: bool = False
    target_id: int = 0  # > 0 for objects whose pixels are foreground in the ground truth
    sway: Callable[[float, FA, FA], tuple[FA, FA]] | None = None
    _tex32: NDArray[np.float32] = field(init=False, repr=False)
    _normal: F64 = field(init=False, repr=False)

    def __post_init__(self) -> None:
        self._tex32 = self.texture.astype(np.float32)
        n = np.cross(self.u, self.v)
        self._normal = np.asarray(n / np.linalg.norm(n), dtype=np.float64)

    @property
    def normal(self) -> F64:
        return self._normal

    def corners(self) -> F64:
        """The patch's four corners (or its bounding square for a disc), shape (4, 3)."""
        a, b = self.half_w, self.half_h
        return np.array([self.P0 + sa * a * self.u + sb * b * self.v
                         for sa, sb in ((-1, -1), (1, -1), (1, 1), (-1, 1))])

    def intersect(self, c: F64, w: F64, t: float) -> tuple[F64, NDArray[np.float32], NDArray[np.bool_]]:
        """Rays from centre c (3,) along unit directions w (N, 3): distance along the ray (N,),
        texture value (N,) float32 and a hit mask (N,)."""
        n = self.normal
        denom = w @ n
        with np.errstate(divide="ignore", invalid="ignore"):
            dist = (n @ (self.P0 - c)) / denom
        d0 = c - self.P0
        a = d0 @ self.u + dist * (w @ self.u)
        b = d0 @ self.v + dist * (w @ self.v)
        if self.shape == "disc":
            hit = a * a + b * b <= self.half_w * self.half_w
        else:
            hit = (np.abs(a) <= self.half_w) & (np.abs(b) <= self.half_h)
        hit &= np.isfinite(dist) & (dist > 0.05)
        if self.sway is not None:
            da, db = self.sway(t, a, b)
            a, b = a + da, b + db
        th, tw = self.texture.shape
        return dist, self._sample(a / self.texel_m + tw / 2.0, b / self.texel_m + th / 2.0), hit

    def _sample(self, x: F64, y: F64) -> NDArray[np.float32]:
        """Bilinear texture lookup at texel coordinates (N,), through cv2.remap in rows of 1024."""
        n = x.size
        rows = max((n + 1023) // 1024, 1)
        mx = np.zeros(rows * 1024, np.float32)
        my = np.zeros(rows * 1024, np.float32)
        mx[:n], my[:n] = x, y
        val = cv2.remap(self._tex32, mx.reshape(rows, 1024), my.reshape(rows, 1024), cv2.INTER_LINEAR,
                        borderMode=cv2.BORDER_REFLECT101)
        return np.asarray(val.reshape(-1)[:n])


Trajectory = Callable[[float], F64]


@dataclass
class MovingObject:
    """A moving target whose centre follows `trajectory(t)` (world metres, (3,)); target_id > 0, id 1 is
    the primary target. `visible(t)`: whether it is in the scene at time t (s).

    half_h_m None: a round plate of radius `radius_m`, parallel to the image planes (it turns with the
    cameras). half_h_m set: an upright board (a person) 2·radius_m wide and 2·half_h_m tall, vertical in
    the world and turned about the vertical to face the gimbal base (it does not turn with the cameras);
    its texture's width spans the board's width."""

    target_id: int
    trajectory: Trajectory
    radius_m: float
    texture: U8
    visible: Callable[[float], bool] = lambda t: True
    half_h_m: float | None = None

    @property
    def area_m2(self) -> float:
        """The object's area (m²): what its image covers at range z is about area·(f/z)² pixels."""
        if self.half_h_m is None:
            return float(np.pi * self.radius_m ** 2)
        return 4.0 * self.radius_m * self.half_h_m

    def surface(self, t: float, R_world_rig: F64) -> Surface:
        """The object at time t as a Surface: a disc along the rig's x and y axes, or an upright rect
        (u horizontal, across the line of sight from the gimbal base; v = world down)."""
        tex = self.texture
        texel = 2.0 * self.radius_m / tex.shape[1]
        p = self.trajectory(t)
        if self.half_h_m is None:
            return Surface(f"target{self.target_id}", p, R_world_rig[:, 0], R_world_rig[:, 1],
                           self.radius_m, self.radius_m, tex, texel, shape="disc", moving=True,
                           target_id=self.target_id)
        ground = float(np.hypot(p[0], p[2]))
        u = np.array([p[2], 0.0, -p[0]]) / ground if ground > 1e-9 else np.array([1.0, 0.0, 0.0])
        return Surface(f"target{self.target_id}", p, u, np.array([0.0, 1.0, 0.0]), self.radius_m,
                       self.half_h_m, tex, texel, moving=True, target_id=self.target_id)


def backdrop(rng: np.random.Generator) -> list[Surface]:
    """The static scene: a far wall at 60 m, a hedge 1.2 m tall at 24 m, a facade at 22 m, a post at 9 m,
    and the ground up to the hedge (a point-sampling renderer would alias a ground reaching the horizon)."""
    ex, ey, ez = np.eye(3)
    h = CAMERA_HEIGHT_M
    return [
        Surface("wall", np.array([0.0, h - 20.0, 60.0]), ex, ey, 60.0, 20.0,
                smooth_texture(rng, (400, 1200), 3.0, 25, 130), 0.1),
        Surface("facade", np.array([9.0, h - 4.0, 22.0]), ex, ey, 3.5, 4.0,
                smooth_texture(rng, (160, 140), 2.5, 30, 120), 0.05),
        Surface("post", np.array([-4.05, h - 2.5, 9.0]), ex, ey, 0.15, 2.5,
                smooth_texture(rng, (100, 12), 1.5, 20, 110), 0.025),
        Surface("hedge", np.array([0.0, h - 0.6, 24.0]), ex, ey, 40.0, 0.6,
                smooth_texture(rng, (40, 2400), 2.0, 20, 100), 1.0 / 30),
        Surface("ground", np.array([0.0, h, 12.75]), ex, ez, 40.0, 11.25,
                smooth_texture(rng, (225, 800), 4.0, 35, 125), 0.1),
    ]


def foliage(rng: np.random.Generator, centre: F64, half_w: float, half_h: float) -> Surface:
    """A swaying bush: a textured patch whose texture moves with a spatially varying sine (wind)."""
    def sway(t: float, a: FA, b: FA) -> tuple[FA, FA]:
        # leaves sway sideways more at the top (b = -half_h) than at the root, with a travelling phase
        b32 = b.astype(np.float32)
        s = np.sin(np.float32(2.0 * np.pi * 0.7 * t) + np.float32(3.0) * b32)
        return s * (np.float32(0.06 / (2 * half_h)) * (np.float32(half_h) - b32)), np.float32(0.02) * s

    ex, ey, _ = np.eye(3)
    return Surface("foliage", centre, ex, ey, half_w, half_h,
                   smooth_texture(rng, (int(60 * half_h), int(60 * half_w)), 1.5, 15, 120), 1.0 / 30,
                   moving=True, sway=sway)


def plate_texture(rng: np.random.Generator, lo: int = 165, hi: int = 250) -> U8:
    """A target plate's texture: bright blobs with a darker ring, so it has texture to match on."""
    tex = smooth_texture(rng, (64, 64), 2.5, lo, hi)
    yy, xx = np.mgrid[:64, :64]
    r = np.hypot(xx - 31.5, yy - 31.5)
    ring = (r > 20) & (r < 24)
    tex[ring] = np.maximum(tex[ring].astype(np.int16) - 25, lo - 10).astype(np.uint8)
    return tex


def person_texture(rng: np.random.Generator, lo: int = 110, hi: int = 240, texel_m: float = 0.01,
                   size_m: tuple[float, float] = (0.5, 1.7)) -> U8:
    """A person's texture, (round(height/texel), round(width/texel)) uint8 for size_m = (width, height)
    metres: blobs of about 2.5 cm stretched to [lo, hi] (clothing) with a darker belt and collar band.
    High contrast: a person's legs stand in front of the ground, only a few pixels of disparity nearer
    than their background, where eq. (9) compares the texture with itself shifted by those few pixels
    (at 75 grey levels of contrast about half of each person went undetected; at 130, a fifth)."""
    w, h = (max(round(v / texel_m), 4) for v in size_m)
    tex = smooth_texture(rng, (h, w), 2.5, lo, hi).astype(np.int16)
    rows = np.arange(h)[:, None] / h  # 0 at the head, 1 at the feet
    band = ((rows > 0.52) & (rows < 0.56)) | ((rows > 0.13) & (rows < 0.16))  # belt, collar
    tex -= np.where(band, 30, 0).astype(np.int16)
    return np.clip(tex, 0, 255).astype(np.uint8)
