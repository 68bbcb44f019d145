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
sampling its projection (_edge_cells) and cast per pixel by the reference's rule (_nearest); every other
cell sees one surface, found once per run of such cells along a row (_runs, _spread). All textures share
one atlas, so one cv2.remap textures the whole image. About 2 ms a camera at 640x480 on one core: the
remap a quarter of it, the cells cast per pixel (about 4 % of the image) a fifth.

Surfaces this cannot take (discs, swaying ones, planes within 10 cm of a camera) are returned to the
caller to cast per pixel over the result (z-tested).
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
I64 = NDArray[np.int64]
B = NDArray[np.bool_]

STEP = 4  # node spacing (pixels); must be even
_PAD = 2  # atlas border around each texture (texels), reflect-101 like the reference's cv2.remap border
_NO_HIT = (-8e-30, -8e-30, 1e-30)  # (X, Y, W) where no surface is hit: outside the atlas, ~1e30 m away
_NEAR_Z = 1e-3  # camera-frame z (m) where a surface's outline is cut before it is projected


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


@dataclass(frozen=True)
class _Planes:
    """The atlas surfaces as arrays: unit normal, u and v axes, and centre P0, (S, 3) each (world, metres);
    texel size (S,) metres; each texture's centre in the atlas and half extent, (S, 2) (x, y) texels; and
    the segments where the nearest surface can change (K, 2, 3) (see _segments); and u, v, normal stacked,
    (3, S, 3)."""

    normal: F64
    u: F64
    v: F64
    P0: F64
    texel: F64
    centre: F64
    half: F64
    segments: F64
    axes: F64


def _planes(surfaces: list[Surface], origins: F64, reach: float) -> _Planes:
    sizes = np.array([s.texture.shape[::-1] for s in surfaces], np.float64).reshape(-1, 2)  # (tw, th)
    texel = np.array([s.texel_m for s in surfaces])
    extent = np.array([(s.half_w, s.half_h) for s in surfaces]).reshape(-1, 2)
    normal, u, v, P0 = (np.array([getattr(s, a) for s in surfaces]).reshape(-1, 3) for a in ("normal", "u", "v", "P0"))
    return _Planes(normal, u, v, P0, texel, origins + sizes / 2.0, extent / texel[:, None], _segments(surfaces, reach),
                   np.stack([u, v, normal]))


def _plane_rows(cam: Camera, R_wr: F64, p: _Planes) -> tuple[F64, F64]:
    """At gimbal rotation R_wr (world <- rig): H (S, 3, 3) mapping m to atlas (X, Y, W), W = 1/z; and q
    (S,), the signed distance (m) from the camera centre to each plane."""
    R_wc = R_wr @ cam.R_rc.T  # camera -> world
    c = R_wr @ cam.c
    axes = p.axes  # (3, S, 3): u, v, normal
    u_c, v_c, n_c = axes @ R_wc  # rows: R_wc.T @ vector
    a0, b0, q = (axes * (p.P0 - c)).sum(axis=2)  # -(c - P0)·u, -(c - P0)·v, n·(P0 - c)
    qd = np.where(np.abs(q) > 1e-9, q, 1e-9)[:, None]  # the camera in a plane: left to the caller
    a0, b0 = p.centre[:, :1] - a0[:, None] / p.texel[:, None], p.centre[:, 1:] - b0[:, None] / p.texel[:, None]
    H = np.stack([qd * u_c / p.texel[:, None] + a0 * n_c, qd * v_c / p.texel[:, None] + b0 * n_c, n_c], axis=1)
    return H / qd[:, :, None], q


@dataclass(frozen=True)
class _Grid:
    """One camera's constants. The padded image is the image with STEP pixels more on every side; node
    (i, j) sits at padded pixel (STEP·j + (STEP-1)/2, STEP·i + (STEP-1)/2), so cv2.resize by STEP of the
    (ny, nx) node values gives the bilinear interpolation at every padded pixel; cell (i, j) is the
    STEP x STEP block of padded pixels between nodes (i, j) and (i+1, j+1)."""

    shape: tuple[int, int]  # (ny, nx)
    nodes: F32  # (2, ny, nx): undistorted (x_n, y_n) of the nodes
    m_box: tuple[float, float, float, float]  # x_n and y_n ranges of the nodes (x0, x1, y0, y1)
    px_per_m: float  # the most pixels per unit of x_n or y_n anywhere
    xy_pad: F32  # (2, Hp·Wp): undistorted (x_n, y_n) of every padded pixel
    cell_first: I64  # (ny-1, nx-1): flat padded index of each cell's top-left pixel
    block: I64  # (STEP², ): flat offsets of a cell's pixels from its top-left pixel


def _grid(cam: Camera) -> _Grid:
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
    return _Grid((ny, nx), np.array([xn, yn], np.float32),
                 (float(xn.min()), float(xn.max()), float(yn.min()), float(yn.max())), 1.05 * STEP / step_m,
                 np.stack([xp.ravel(), yp.ravel()]).astype(np.float32), first.astype(np.int64),
                 block.astype(np.int64))


def _clip(a: F64, b: F64, box: tuple[float, float, float, float]) -> tuple[F64, F64, B]:
    """Segments from a to b (K, 2) clipped to the box (x0, x1, y0, y1) (Liang-Barsky), and which meet it."""
    d = b - a
    x0, x1, y0, y1 = box
    p = np.stack([-d[:, 0], d[:, 0], -d[:, 1], d[:, 1]], axis=1)
    q = np.stack([a[:, 0] - x0, x1 - a[:, 0], a[:, 1] - y0, y1 - a[:, 1]], axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        r = q / p
    t0 = np.maximum(np.where(p < 0, r, 0.0).max(axis=1), 0.0)
    t1 = np.minimum(np.where(p > 0, r, 1.0).min(axis=1), 1.0)
    ok = (t0 <= t1) & ~((p == 0) & (q < 0)).any(axis=1)
    return a + t0[:, None] * d, a + t1[:, None] * d, ok


def _edge_cells(grid: _Grid, cam: Camera, R_wr: F64, seg: F64) -> B:
    """The cells (ny-1, nx-1) whose pixels a segment (K, 2, 3) (world, metres) may separate, as seen by
    camera cam at gimbal rotation R_wr (world <- rig): each segment's part in front of the camera is
    projected, clipped to the nodes' range, sampled every 0.9 px or less and distorted exactly, and each
    sample marks its cell. A cell's pixel centres lie 0.5 px or more inside it, so a curve that passes
    between two of them, in one cell or in two neighbours, has a sample in one of those cells."""
    P = (seg - R_wr @ cam.c) @ (R_wr @ cam.R_rc.T)  # camera frame (x_cam = R_cw (x - c))
    a, b = P[:, 0], P[:, 1]
    za, zb = a[:, 2:], b[:, 2:]
    with np.errstate(divide="ignore", invalid="ignore"):
        cut = a + (b - a) * (_NEAR_Z - za) / (zb - za)
    front = ((za >= _NEAR_Z) | (zb >= _NEAR_Z))[:, 0]
    a, b = np.where(za < _NEAR_Z, cut, a)[front], np.where(zb < _NEAR_Z, cut, b)[front]
    ma, mb, ok = _clip(a[:, :2] / a[:, 2:], b[:, :2] / b[:, 2:], grid.m_box)
    ma, mb = ma[ok], mb[ok]
    n = np.ceil(np.hypot(*(mb - ma).T) * grid.px_per_m / 0.9).astype(np.intp) + 2
    t = (np.arange(int(n.sum())) - np.repeat(np.cumsum(n) - n, n)) / np.repeat(n - 1, n)
    d = mb - ma
    u, v = cam.distort_normalized(np.repeat(ma[:, 0], n) + np.repeat(d[:, 0], n) * t,
                                  np.repeat(ma[:, 1], n) + np.repeat(d[:, 1], n) * t)
    ny, nx = grid.shape
    off = (STEP + 1) / 2  # node j at image pixel STEP·j - off; cell j between nodes j and j+1
    j = np.clip(((u + off) * (1.0 / STEP)).astype(np.intp), 0, nx - 2)  # truncation: floor where >= 0
    i = np.clip(((v + off) * (1.0 / STEP)).astype(np.intp), 0, ny - 2)
    marks = np.zeros((ny - 1, nx - 1), bool)
    marks[i, j] = True
    return marks


def _nearest(H: F64, centre: F64, half: F64, x: F32, y: F32) -> tuple[NDArray[np.intp], F32]:
    """The rule of the per-pixel reference at N points (x_n, y_n): the nearest surface hit (texture
    coordinates within half (S, 2) texels of its centre (S, 2), inclusive; in front of the camera; the first
    of equally near ones), (N,) (-1 for none), and its (X, Y, W), (3, N) float32 (_NO_HIT where none is).
    About each texture's centre and in units of its half extent, so that float32 decides the side of an
    edge to within 1e-5 texel: hit where |X'| <= W and |Y'| <= W (which imply W >= 0)."""
    S, n = len(H), len(x)
    Hs = H.copy()
    Hs[:, :2] -= centre[:, :, None] * H[:, 2:]  # (X - cx W, Y - cy W, W)
    Hs[:, :2] /= half[:, :, None]
    H32 = Hs.astype(np.float32)[..., None]
    hom = H32[:, :, 0] * x  # (S, 3, N)
    hom += H32[:, :, 1] * y
    hom += H32[:, :, 2]
    W = hom[:, 2]
    hit = np.abs(hom[:, 0]) <= W
    hit &= np.abs(hom[:, 1]) <= W
    np.copyto(W, np.float32(-np.inf), where=~hit)  # W of what is not hit: never the nearest
    best = W.max(axis=0)
    lab = np.full(n, -1, np.intp)
    for s in range(S - 1, -1, -1):
        lab[W[s] == best] = s
    lab[best == -np.inf] = -1
    k = np.maximum(lab, 0)
    pick = k * (3 * n) + np.arange(n)
    out = np.array([np.take(hom, pick + r * n) for r in range(3)])
    out[:2] *= np.take(half.T.astype(np.float32), k, axis=1)
    out[:2] += np.take(centre.T.astype(np.float32), k, axis=1) * out[2]
    out[:, lab < 0] = np.array(_NO_HIT, np.float32)[:, None]
    return lab, out


def _surface_values(H: F64, lab: NDArray[np.int16], x: F32, y: F32) -> F32:
    """(X, Y, W) (3, N) float32 of surface lab (N,) at points (x_n, y_n) (_NO_HIT where lab < 0)."""
    table = np.concatenate([H, np.zeros((1, 3, 3))]).astype(np.float32)  # row S: _NO_HIT
    table[-1, :, 2] = _NO_HIT
    coef = table[np.where(lab < 0, len(H), lab)]  # (N, 3, 3)
    return np.ascontiguousarray((coef[..., 0] * x[:, None] + coef[..., 1] * y[:, None] + coef[..., 2]).T)


def _runs(grid: _Grid, exact: B) -> tuple[B, I64, I64]:
    """The runs of cells not cast per pixel along each row of cells: which cells are in one, (ny-1)·nx
    flat with a column ending each row, and each run's first pixel (flat padded index) and length."""
    ny, nx = grid.shape
    free = np.zeros((ny - 1) * nx + 2, bool)  # a False either side: every run starts and ends
    f = free[1:-1]
    f.reshape(ny - 1, nx)[:, :-1] = ~exact
    edge = np.flatnonzero(free[1:] != free[:-1])  # run starts and ends, alternating
    i, j = np.divmod(edge[::2], nx)
    return f, grid.cell_first[i, j], edge[1::2] - edge[::2]


def _spread(grid: _Grid, f: B, seed: NDArray[np.intp], length: I64) -> tuple[NDArray[np.int16], B, NDArray[np.int16]]:
    """Given each run's surface (seed): the surface nearest at each node (ny, nx) of the cells not cast per
    pixel (-1 for none; -2 at nodes only of cells cast per pixel), the cells (ny-1, nx-1) around a node
    where they disagree, which cannot be interpolated, and each cell's surface (ny-1, nx-1) (-2: cast per
    pixel). No segment separates the pixels of a cell, or of two cells side by side, so a run sees one
    surface; only two cells that meet at a corner may see different ones."""
    ny, nx = grid.shape
    cell = np.full(f.size, -2, np.int16)
    cell[f] = np.repeat(seed, length)
    pad = np.full((ny + 1, nx + 1), -2, np.int16)
    pad[1:-1, 1:-1] = cell.reshape(ny - 1, nx)[:, :-1]
    hi_lab = np.maximum(np.maximum(pad[:-1, :-1], pad[:-1, 1:]), np.maximum(pad[1:, :-1], pad[1:, 1:]))
    big = (pad + np.int16(1)).view(np.uint16)  # label + 1, and -2 wrapped to the largest: never the least
    lo_lab = np.minimum(np.minimum(big[:-1, :-1], big[:-1, 1:]), np.minimum(big[1:, :-1], big[1:, 1:]))
    clash = (lo_lab != (hi_lab + np.int16(1)).view(np.uint16)) & (hi_lab > -2)
    hi_lab[clash] = -2
    return hi_lab, clash[:-1, :-1] | clash[1:, :-1] | clash[:-1, 1:] | clash[1:, 1:], pad[1:-1, 1:-1]


def _node_values(grid: _Grid, node: NDArray[np.int16], H: F64) -> F32:
    """(X, Y, W) (3, ny, nx) float32 at the nodes of the surface given at each (node (ny, nx); -1 or less:
    _NO_HIT), each coefficient looked up by cv2.LUT."""
    table = np.zeros((3, 3, 256), np.float32)  # [row, coefficient, surface]; 255: _NO_HIT
    table[:, :, :len(H)] = H.transpose(1, 2, 0)
    table[:, 2, 255] = _NO_HIT
    k = np.where(node < 0, 255, node).astype(np.uint8)
    x, y = grid.nodes
    out = np.empty((3,) + node.shape, np.float32)
    for r in range(3):
        np.multiply(cv2.LUT(k, table[r, 0]), x, out=out[r])
        out[r] += cv2.LUT(k, table[r, 1]) * y
        out[r] += cv2.LUT(k, table[r, 2])
    return out


@dataclass(frozen=True)
class Plan:
    """Camera k's sparse render: (X, Y, W) at the nodes (3, ny, nx) float32 (None: every plane is within
    0.1 m of the camera, nothing drawn), and at the padded pixels idx (N,) cast one by one, (3, N); and the
    surfaces left to the caller (off the atlas, or planes within 0.1 m of the camera), in scene order."""

    k: int
    nodes: F32 | None
    idx: I64
    vals: F32
    rest: list[Surface]


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
        and at the pixels cast one by one. Many small numpy steps that hold the GIL most of the time: run
        the planning of both cameras on one thread and overlap it with draw(), which is a few large OpenCV
        calls that release it."""
        cam, grid, p = self.cams[k], self._grids[k], self._planes
        H, q = _plane_rows(cam, R_wr, p)
        near = np.abs(q) < 0.1  # then every hit is over 0.1 m away, as the reference requires (> 0.05 m)
        too_near = {id(s) for s, n in zip(self._fast, near, strict=True) if n}
        rest = [s for s in self.surfaces if id(s) not in self._fast_ids or id(s) in too_near]
        if near.all():
            return Plan(k, None, np.zeros(0, np.int64), np.zeros((3, 0), np.float32), rest)
        centre, half = p.centre, p.half
        if near.any():
            H, centre, half = H[~near], centre[~near], half[~near]
        exact = _edge_cells(grid, cam, R_wr, p.segments)
        f, first, length = _runs(grid, exact)
        idx = (grid.cell_first[exact][:, None] + grid.block[None, :]).ravel()
        pts = np.concatenate([first, idx])  # each run's first pixel, then the cells cast per pixel
        lab, vals = _nearest(H, centre, half, np.take(grid.xy_pad[0], pts), np.take(grid.xy_pad[1], pts))
        node, more, cell = _spread(grid, f, lab[:len(first)], length)
        vals = vals[:, len(first):]
        more &= ~exact
        if more.any():  # cells that see one surface but whose nodes do not: that surface at each pixel
            extra = (grid.cell_first[more][:, None] + grid.block[None, :]).ravel()
            idx = np.concatenate([idx, extra])
            vals = np.hstack([vals, _surface_values(H, np.repeat(cell[more], STEP * STEP),
                                                    grid.xy_pad[0][extra], grid.xy_pad[1][extra])])
        return Plan(k, _node_values(grid, node, H), idx, vals, rest)

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
            return (np.full((h, w), _NO_HIT[0], np.float32), np.full((h, w), _NO_HIT[1], np.float32),
                    np.full((h, w), _NO_HIT[2], np.float32))
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
