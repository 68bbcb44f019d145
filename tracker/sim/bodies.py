"""Solid targets for the simulated rig (issue 12 item 2): textured, lit 3-D bodies of spheres and boxes.

Opt-in: the scenario `NAME:body` (tracker.sim.scenarios.get_scenario) draws its targets as bodies instead
of flat plates. Kinds (`BodyObject.kind`):
- "sphere": a ball of radius 0.3 m on the scenario's path, spinning slowly about the vertical;
- "person": torso and limbs as boxes, head a sphere, `stature_m` tall (PERSON_STATURE_M, 1.69 m, unless the
  scenario draws one: `draw_stature`), standing on the ground under the path, facing where it walks (facing
  the gimbal base when it stands), legs and arms swinging as it walks;
- "vehicle": a car of two boxes (body 1.8 x 0.8 x 4.2 m, 0.25 m above the ground; cabin), driving along
  the path with its length forward.

Each part is ray cast exactly over the body's pixel box and z-tested against the scene's depth and the
other parts (so bodies are seen from any side, hidden where the scene's geometry is nearer). Texture is
attached to the body (it turns and swings with it). Light: Lambertian under a sun, a texture value τ at a
surface of unit normal n is drawn τ · (a + (1 - a) · max(n · s, 0)), a = AMBIENT, s = SUN (world, unit).

Truth. A body's centre is the volume centroid of its parts, Σ V_i c_i / Σ V_i (world metres; parts that
overlap count twice), the point `trajectory(t)` returns. The tracker sees only the body's visible surface,
which lies nearer than that centre by up to `near_depth_m` along the line of sight: the distance from the
centre's depth to the body's nearest point's (a sphere: its radius); the evaluation allows it on range.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Protocol

import cv2
import numpy as np
from numpy.typing import NDArray

from tracker.geometry import rot_x, rot_y
from tracker.sim.scene import CAMERA_HEIGHT_M, U8, smooth_texture

F64 = NDArray[np.float64]
F32 = NDArray[np.float32]
Trajectory = Callable[[float], F64]

AMBIENT = 0.45
SUN = np.array([-0.5, -0.75, -0.45]) / np.linalg.norm([-0.5, -0.75, -0.45])  # towards the sun: up, left, behind
TEXEL_M = 0.01
SPHERE_R_M = 0.3
PERSON_STATURE_M = 1.69  # the person of _person_parts at scale 1: soles to the top of its head
KINDS = ("sphere", "person", "vehicle")
_SIGNS = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], float)  # (8, 3)


class _ViewLike(Protocol):  # tracker.sim.cast.View
    @property
    def cam(self) -> _CamLike: ...
    @property
    def rays(self) -> F32: ...


class _CamLike(Protocol):
    @property
    def c(self) -> F64: ...


@dataclass(frozen=True)
class Part:
    """A sphere (radius half[0]) or a box (half extents half, (3,) m) centred at `centre` (world, (3,)), its
    axes the columns of R (part -> world, (3, 3)). `tex_at`: texture offset (m), so parts differ."""

    kind: str
    centre: F64
    R: F64
    half: F64
    tex_at: float = 0.0

    @property
    def volume(self) -> float:
        h = self.half
        return float(4.0 / 3.0 * np.pi * h[0] ** 3) if self.kind == "sphere" else float(8.0 * np.prod(h))

    def corners(self) -> F64:
        """World corners of the part's bounding box, (8, 3)."""
        h = np.full(3, self.half[0]) if self.kind == "sphere" else self.half
        return np.asarray(self.centre + (_SIGNS * h) @ self.R.T)

    def intersect(self, c: F64, w: F64) -> tuple[F64, NDArray[np.bool_], F64, F64]:
        """Rays from c (3,) along unit w (N, 3): distance (N,), hit (N,), world normal (N, 3) and texture
        coordinates (N, 2) in metres on the part's surface."""
        if self.kind == "sphere":
            return self._sphere(c, w)
        return self._box(c, w)

    def _sphere(self, c: F64, w: F64) -> tuple[F64, NDArray[np.bool_], F64, F64]:
        r = float(self.half[0])
        oc = c - self.centre
        b = w @ oc
        disc = b * b - (oc @ oc - r * r)
        dist = -b - np.sqrt(np.maximum(disc, 0.0))
        hit = (disc >= 0.0) & (dist > 0.05)
        n = (c + dist[:, None] * w - self.centre) / r
        loc = n @ self.R  # in the part's frame
        lon = np.arctan2(loc[:, 0], loc[:, 2])
        lat = np.arcsin(np.clip(-loc[:, 1], -1.0, 1.0))
        return dist, hit, n, np.stack([lon * r + self.tex_at, lat * r], axis=1)

    def _box(self, c: F64, w: F64) -> tuple[F64, NDArray[np.bool_], F64, F64]:
        o = (c - self.centre) @ self.R
        d = w @ self.R
        d = np.where(np.abs(d) < 1e-12, 1e-12, d)  # a ray parallel to a face: far slab bounds, no nan
        t1, t2 = (-self.half - o) / d, (self.half - o) / d
        tn, tf = np.minimum(t1, t2), np.maximum(t1, t2)
        axis = np.argmax(tn, axis=1)
        near = tn[np.arange(len(w)), axis]
        hit = (near <= tf.min(axis=1)) & (near > 0.05)
        n_loc = np.zeros_like(d)
        n_loc[np.arange(len(w)), axis] = -np.sign(d[np.arange(len(w)), axis])
        p = o + near[:, None] * d
        # the face's own two coordinates: x faces (z, y), y faces (x, z), z faces (x, y); each face offset
        u = np.where(axis == 0, p[:, 2], p[:, 0]) + self.tex_at + 0.61 * axis + 0.37 * (n_loc.sum(axis=1) > 0)
        v = np.where(axis == 1, p[:, 2], p[:, 1])
        return near, hit, n_loc @ self.R.T, np.stack([u, v], axis=1)


@dataclass
class Body:
    """A body at one instant, as the renderer casts it (tracker.sim.render.SimRenderer): its parts, its
    texture (float32 (h, w), TEXEL_M metres a texel) and the id its pixels get in the truth."""

    name: str
    target_id: int
    parts: tuple[Part, ...]
    tex32: F32

    def corners(self) -> F64:
        """World points whose projections bound the body's image, (8·parts, 3)."""
        return np.concatenate([p.corners() for p in self.parts])

    def cast(self, view: _ViewLike, R_wr: F64, img: U8, depth: F32, t: float, ids: U8 | None,
             box: tuple[int, int, int, int], edge_samples: int = 1) -> None:
        """Ray-cast every part over the pixel box (x0, y0, x1, y1) into img (uint8), depth (distance along
        each pixel's ray, m) and ids, z-tested: what is nearer than the depth already there is drawn. depth
        and ids are the pixel centre's; img too, or with edge_samples > 1 the mean over edge_samples²
        rays over a pixel an edge crosses (_edges)."""
        x0, y0, x1, y1 = box
        c = R_wr @ view.cam.c
        w = view.rays[y0:y1, x0:x1].reshape(-1, 3).astype(np.float64) @ R_wr.T
        behind = depth[y0:y1, x0:x1].astype(np.float64).reshape(-1)
        best, which, val = self._trace(c, w, behind)
        drawn = which >= 0
        if not drawn.any():
            return
        shape = (y1 - y0, x1 - x0)
        m = drawn.reshape(shape)
        edges = (self._edges(view, R_wr, c, which.reshape(shape), behind.reshape(shape), img[y0:y1, x0:x1], box,
                             edge_samples) if edge_samples > 1 else None)
        np.copyto(depth[y0:y1, x0:x1], best.reshape(shape).astype(np.float32), where=m)
        np.copyto(img[y0:y1, x0:x1], np.clip(np.rint(val), 0, 255).reshape(shape), where=m, casting="unsafe")
        if edges is not None:
            img[y0 + edges[0], x0 + edges[1]] = np.clip(np.rint(edges[2]), 0, 255).astype(np.uint8)
        if ids is not None:
            ids[y0:y1, x0:x1][m] = self.target_id

    def _trace(self, c: F64, w: F64, behind: F64, only: list[NDArray[np.bool_]] | None = None
               ) -> tuple[F64, NDArray[np.intp], F64]:
        """Rays from c along unit w (N, 3), each drawn where a part is nearer than `behind` (N,) m: the
        distance to what each ray meets (N,), the part it meets (-1: none) and its lit texture value.
        only: for each part, the rays that may meet it (default all)."""
        best = behind.copy()
        which = np.full(len(w), -1, np.intp)
        val = np.zeros(len(w), np.float64)
        for k, part in enumerate(self.parts):
            idx = np.arange(len(w)) if only is None else np.flatnonzero(only[k])
            if idx.size == 0:
                continue
            dist, hit, n, uv = part.intersect(c, w[idx])
            hit &= dist < best[idx]
            if not hit.any():
                continue
            at = idx[hit]
            best[at] = dist[hit]
            which[at] = k
            shade = AMBIENT + (1.0 - AMBIENT) * np.maximum(n[hit] @ SUN, 0.0)
            val[at] = self._sample(uv[hit]) * shade
        return best, which, val

    def _edges(self, view: _ViewLike, R_wr: F64, c: F64, which: NDArray[np.intp], behind: F64, under: U8,
               box: tuple[int, int, int, int], samples: int) -> tuple[NDArray[np.intp], NDArray[np.intp], F64]:
        """A camera integrates light over each pixel; where the body's outline or one part's edge over
        another crosses a pixel (its centre's part differs from a 4-neighbour's, the box's rim counting as
        none), its value is the mean over samples² rays spread evenly over the pixel, those that miss the
        body taking what lay under it (under: the box of the image before the cast; behind: its depth along
        the pixel's centre ray). Sub-pixel rays: the pixel's ray moved by its derivatives along u and v
        (central differences of view.rays; distortion is smooth over a pixel), each tested against the
        parts its pixel's 5 x 5 centres meet. Returns the edge pixels' box rows, columns and values."""
        lab = np.pad(which, 1, constant_values=-1)
        core = lab[1:-1, 1:-1]
        edge = ((core != lab[:-2, 1:-1]) | (core != lab[2:, 1:-1]) | (core != lab[1:-1, :-2])
                | (core != lab[1:-1, 2:]))
        ys, xs = np.nonzero(edge)
        if ys.size == 0:
            return ys, xs, np.zeros(0)
        x0, y0, _, _ = box
        rays = view.rays
        h, w_img = rays.shape[:2]
        gy, gx = y0 + ys, x0 + xs
        du = (rays[gy, np.minimum(gx + 1, w_img - 1)].astype(np.float64)
              - rays[gy, np.maximum(gx - 1, 0)]) / (np.minimum(gx + 1, w_img - 1) - np.maximum(gx - 1, 0))[:, None]
        dv = (rays[np.minimum(gy + 1, h - 1), gx].astype(np.float64)
              - rays[np.maximum(gy - 1, 0), gx]) / (np.minimum(gy + 1, h - 1) - np.maximum(gy - 1, 0))[:, None]
        off = (np.arange(samples) + 0.5) / samples - 0.5
        ou, ov = (a.reshape(-1) for a in np.meshgrid(off, off))  # (S²,) offsets in pixels
        sub = (rays[gy, gx].astype(np.float64)[:, None, :] + ou[None, :, None] * du[:, None, :]
               + ov[None, :, None] * dv[:, None, :]).reshape(-1, 3)
        sub /= np.linalg.norm(sub, axis=1, keepdims=True)
        kernel = np.ones((5, 5), np.uint8)  # a sub-ray may meet the parts its pixel's 5 x 5 centres meet
        only = [np.repeat(cv2.dilate((which == k).astype(np.uint8), kernel)[ys, xs] > 0, ou.size)
                for k in range(len(self.parts))]
        _, hit_part, val = self._trace(c, sub @ R_wr.T, np.repeat(behind[ys, xs], ou.size), only)
        bg = np.repeat(under[ys, xs].astype(np.float64), ou.size)
        return ys, xs, np.where(hit_part >= 0, val, bg).reshape(-1, ou.size).mean(axis=1)

    def _sample(self, uv: F64) -> F64:
        """Bilinear texture values at surface coordinates (N, 2) m (centred on the texture, reflected)."""
        th, tw = self.tex32.shape
        x = (uv[:, 0] / TEXEL_M + tw / 2.0).astype(np.float32)[None, :]
        y = (uv[:, 1] / TEXEL_M + th / 2.0).astype(np.float32)[None, :]
        out = cv2.remap(self.tex32, x, y, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT101)
        return np.asarray(out, np.float64).reshape(-1)


def draw_stature(rng: np.random.Generator) -> float:
    """A person's stature (m): a woman's 1.63 or a man's 1.76 m, alike likely, each ± 0.07 m (1-σ, adults'
    spread within a sex), clipped to 1.45-1.98 m; the mixture is 1.695 ± 0.095 m."""
    mean = 1.63 if rng.random() < 0.5 else 1.76
    return float(np.clip(rng.normal(mean, 0.07), 1.45, 1.98))


def _person_parts(base: F64, R: F64, phase: float, scale: float = 1.0) -> list[Part]:
    """A person standing at `base` (its ground point, world (3,)) turned by R (body -> world): local
    x right, y down, z forward, heights negative. phase (rad): the walking cycle (0: standing). scale:
    every length times it (PERSON_STATURE_M tall at 1)."""
    swing = 0.4 * np.sin(phase)

    def part(kind: str, at: tuple[float, float, float], half: tuple[float, float, float], Rl: F64,
             tex: float) -> Part:
        return Part(kind, base + scale * (R @ np.array(at)), R @ Rl, scale * np.array(half), tex)

    def limb(pivot: tuple[float, float, float], length: float, half_xz: float, a: float, tex: float) -> Part:
        Rl = rot_x(a)
        at = np.array(pivot) + Rl @ np.array([0.0, length, 0.0])
        return part("box", (float(at[0]), float(at[1]), float(at[2])), (half_xz, length, half_xz + 0.02), Rl, tex)

    eye = np.eye(3)
    return [
        part("box", (0.0, -1.17, 0.0), (0.19, 0.28, 0.11), eye, 0.0),  # torso
        part("sphere", (0.0, -1.58, 0.0), (0.11, 0.11, 0.11), eye, 1.3),  # head
        limb((-0.1, -0.88, 0.0), 0.43, 0.07, swing, 2.1), limb((0.1, -0.88, 0.0), 0.43, 0.07, -swing, 2.9),
        limb((-0.25, -1.42, 0.0), 0.3, 0.05, -0.8 * swing, 3.7), limb((0.25, -1.42, 0.0), 0.3, 0.05, 0.8 * swing, 4.5),
    ]


def _vehicle_parts(base: F64, R: F64) -> list[Part]:
    """A car standing at `base` (ground point under its centre), its length along R's local z."""
    return [Part("box", base + R @ np.array([0.0, -0.65, 0.0]), R, np.array([0.9, 0.4, 2.1]), 0.0),
            Part("box", base + R @ np.array([0.0, -1.35, -0.2]), R, np.array([0.8, 0.3, 1.1]), 1.9)]


_TEXTURE_RANGE = {"sphere": (150, 250), "person": (90, 230), "vehicle": (70, 230)}


def body_texture(rng: np.random.Generator, kind: str) -> U8:
    """A body's texture: 2.5 cm blobs over 2.56 x 2.56 m (TEXEL_M a texel), stretched to the kind's range."""
    lo, hi = _TEXTURE_RANGE[kind]
    return smooth_texture(rng, (256, 256), 2.5, lo, hi)


def _always(t: float) -> bool:
    return True


@dataclass
class BodyObject:
    """A moving target drawn as a body of `kind` (KINDS) following `path` (world m, (3,) at time t s);
    people and vehicles stand on the ground under the path. Same interface as scene.MovingObject for the
    simulator: target_id, trajectory(t) (the truth centre), visible(t), area_m2, surface(t, R_wr)."""

    target_id: int
    kind: str
    path: Trajectory
    texture: U8
    visible: Callable[[float], bool] = _always
    stature_m: float = PERSON_STATURE_M  # a person's height (m); other kinds ignore it
    _tex32: F32 = field(init=False, repr=False)

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise ValueError(f"unknown body kind {self.kind!r}; known: {', '.join(KINDS)}")
        if not 0.5 <= self.stature_m <= 2.5:
            raise ValueError(f"a person's stature must lie in 0.5-2.5 m, got {self.stature_m}")
        self._tex32 = self.texture.astype(np.float32)

    @property
    def area_m2(self) -> float:
        """About the silhouette's area (m²) seen side on."""
        person = 0.6 * (self.stature_m / PERSON_STATURE_M) ** 2
        return {"sphere": float(np.pi * SPHERE_R_M**2), "person": person, "vehicle": 7.0}[self.kind]

    def parts(self, t: float) -> list[Part]:
        p = self.path(t)
        if self.kind == "sphere":
            return [Part("sphere", p, rot_y(0.5 * t), np.full(3, SPHERE_R_M))]
        v = (self.path(t + 0.05) - p) / 0.05
        moving = float(np.hypot(v[0], v[2])) > 0.2
        yaw = np.arctan2(v[0], v[2]) if moving else np.arctan2(-p[0], -p[2])  # else face the gimbal base
        base = np.array([p[0], CAMERA_HEIGHT_M, p[2]])
        if self.kind == "vehicle":
            return _vehicle_parts(base, rot_y(float(yaw)))
        return _person_parts(base, rot_y(float(yaw)), 2.0 * np.pi * t / 1.1 if moving else 0.0,
                             self.stature_m / PERSON_STATURE_M)

    def trajectory(self, t: float) -> F64:
        """The truth: the parts' volume centroid Σ V_i c_i / Σ V_i (world m, (3,))."""
        parts = self.parts(t)
        vol = np.array([q.volume for q in parts])
        return np.asarray(vol @ np.array([q.centre for q in parts]) / vol.sum())

    def near_depth_m(self, t: float, eye: F64) -> float:
        """How much nearer than the centre the body's nearest point is, seen from `eye` (world, (3,)), m."""
        centre = self.trajectory(t)
        u = (centre - eye) / np.linalg.norm(centre - eye)
        near = min(float(np.min(q.corners() @ u)) if q.kind == "box" else float(q.centre @ u - q.half[0])
                   for q in self.parts(t))
        return float(centre @ u) - near

    def surface(self, t: float, R_world_rig: F64) -> Body:
        return Body(f"target{self.target_id}", self.target_id, tuple(self.parts(t)), self._tex32)
