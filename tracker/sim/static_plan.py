"""Planning the static scene's render (tracker.sim.static_cast): which surface each STEP x STEP cell of a
camera's padded image sees, (X, Y, W) at the nodes, and the pixels of the cells an edge may cross cast one
by one (the module docstring of tracker.sim.static_cast has the method).
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
I64 = NDArray[np.int64]
B = NDArray[np.bool_]

STEP = 4  # node spacing (pixels); must be even
NO_HIT = (-8e-30, -8e-30, 1e-30)  # (X, Y, W) where no surface is hit: outside the atlas, ~1e30 m away
_NEAR_Z = 1e-3  # camera-frame z (m) where a surface's outline is cut before it is projected


@dataclass(frozen=True)
class Planes:
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


@dataclass(frozen=True)
class Grid:
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


def plan_camera(k: int, cam: Camera, grid: Grid, p: Planes, R_wr: F64, fast: list[Surface], fast_ids: set[int],
                surfaces: list[Surface]) -> Plan:
    """Camera k's plan (cam and grid its own) at gimbal rotation R_wr, drawing the surfaces fast (p: them as
    arrays; fast_ids: their id()s) from the atlas and leaving the rest of surfaces to the caller: which
    surface each cell sees, (X, Y, W) at the nodes and at the pixels cast one by one."""
    H, q = plane_rows(cam, R_wr, p)
    near = np.abs(q) < 0.1  # then every hit is over 0.1 m away, as the reference requires (> 0.05 m)
    too_near = {id(s) for s, n in zip(fast, near, strict=True) if n}
    rest = [s for s in surfaces if id(s) not in fast_ids or id(s) in too_near]
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


def plane_rows(cam: Camera, R_wr: F64, p: Planes) -> tuple[F64, F64]:
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


def _edge_cells(grid: Grid, cam: Camera, R_wr: F64, seg: F64) -> B:
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
    of equally near ones), (N,) (-1 for none), and its (X, Y, W), (3, N) float32 (NO_HIT where none is).
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
    out[:, lab < 0] = np.array(NO_HIT, np.float32)[:, None]
    return lab, out


def _surface_values(H: F64, lab: NDArray[np.int16], x: F32, y: F32) -> F32:
    """(X, Y, W) (3, N) float32 of surface lab (N,) at points (x_n, y_n) (NO_HIT where lab < 0)."""
    table = np.concatenate([H, np.zeros((1, 3, 3))]).astype(np.float32)  # row S: NO_HIT
    table[-1, :, 2] = NO_HIT
    coef = table[np.where(lab < 0, len(H), lab)]  # (N, 3, 3)
    return np.ascontiguousarray((coef[..., 0] * x[:, None] + coef[..., 1] * y[:, None] + coef[..., 2]).T)


def _runs(grid: Grid, exact: B) -> tuple[B, I64, I64]:
    """The runs of cells not cast per pixel along each row of cells: which cells are in one, (ny-1)·nx
    flat with a column ending each row, and each run's first pixel (flat padded index) and length."""
    ny, nx = grid.shape
    free = np.zeros((ny - 1) * nx + 2, bool)  # a False either side: every run starts and ends
    f = free[1:-1]
    f.reshape(ny - 1, nx)[:, :-1] = ~exact
    edge = np.flatnonzero(free[1:] != free[:-1])  # run starts and ends, alternating
    i, j = np.divmod(edge[::2], nx)
    return f, grid.cell_first[i, j], edge[1::2] - edge[::2]


def _spread(grid: Grid, f: B, seed: NDArray[np.intp], length: I64) -> tuple[NDArray[np.int16], B, NDArray[np.int16]]:
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


def _node_values(grid: Grid, node: NDArray[np.int16], H: F64) -> F32:
    """(X, Y, W) (3, ny, nx) float32 at the nodes of the surface given at each (node (ny, nx); -1 or less:
    NO_HIT), each coefficient looked up by cv2.LUT."""
    table = np.zeros((3, 3, 256), np.float32)  # [row, coefficient, surface]; 255: NO_HIT
    table[:, :, :len(H)] = H.transpose(1, 2, 0)
    table[:, 2, 255] = NO_HIT
    k = np.where(node < 0, 255, node).astype(np.uint8)
    x, y = grid.nodes
    out = np.empty((3,) + node.shape, np.float32)
    for r in range(3):
        np.multiply(cv2.LUT(k, table[r, 0]), x, out=out[r])
        out[r] += cv2.LUT(k, table[r, 1]) * y
        out[r] += cv2.LUT(k, table[r, 2])
    return out
