"""Bundle adjustment (paper §5, eq. 5-8) with scipy.optimize.least_squares.

Unknowns, optimised jointly: per camera c the intrinsics and Brown-Conrady distortion
(fx, fy, cx, cy, k1, k2, p1, p2, k3), per board view v the pose of the board in the left camera frame
(Rodrigues vector ω_v, translation t_v), and for a stereo rig the right camera's pose relative to the
left, x_r = R x_l + T with R from the Euler angles (δ, φ, γ) of eq. (6). Eq. (5), X_p = R X_w + T, is
applied twice: board -> left camera (ω_v, t_v), left -> right camera ((δ, φ, γ), T).

Euler singularity: eq. (6) loses one degree of freedom at φ = ±90°. When the initial |φ| exceeds
REC_ENTRE_DEG the rotation is re-centred, R = R(δ, φ, γ) R0 with R0 the initial estimate and the angles
starting at 0, so the solver always works far from the singularity; the reported angles are then
recovered from the final R with tracker.geometry.matrix_to_euler (which handles φ = ±90°).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray
from scipy.optimize import least_squares
from scipy.sparse import lil_matrix

from tracker.geometry import euler_to_matrix, matrix_to_euler

F64 = NDArray[np.float64]
B = NDArray[np.bool_]

N_INTR = 9  # fx fy cx cy k1 k2 p1 p2 k3
INTR_NAMES = ("fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2", "k3")
RECENTRE_DEG = 60.0


def intr_matrices(intr: F64) -> tuple[F64, F64]:
    """(9,) intrinsics -> K (3, 3), dist (5,)."""
    K = np.array([[intr[0], 0.0, intr[2]], [0.0, intr[1], intr[3]], [0.0, 0.0, 1.0]])
    return K, intr[4:9].copy()


def rodrigues(w: F64) -> F64:
    """Rotation matrices (V, 3, 3) from Rodrigues vectors (V, 3) in radians."""
    theta = np.linalg.norm(w, axis=1)
    small = theta < 1e-12
    k = w / np.where(small, 1.0, theta)[:, None]
    K = np.zeros((len(w), 3, 3))
    K[:, 0, 1], K[:, 0, 2], K[:, 1, 2] = -k[:, 2], k[:, 1], -k[:, 0]
    K[:, 1, 0], K[:, 2, 0], K[:, 2, 1] = k[:, 2], -k[:, 1], k[:, 0]
    s, c = np.sin(theta)[:, None, None], (1.0 - np.cos(theta))[:, None, None]
    out: F64 = np.eye(3)[None] + s * K + c * (K @ K)
    return out


def project_points(intr: F64, Xc: F64) -> F64:
    """Camera-frame points (..., 3) -> distorted pixels (..., 2) for intr = fx fy cx cy k1 k2 p1 p2 k3."""
    fx, fy, cx, cy, k1, k2, p1, p2, k3 = intr
    x, y = Xc[..., 0] / Xc[..., 2], Xc[..., 1] / Xc[..., 2]
    r2 = x * x + y * y
    radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3))
    xd = x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x)
    yd = y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y
    return np.stack([fx * xd + cx, fy * yd + cy], axis=-1)


@dataclass
class BAInput:
    """Observations: obj (V, N, 3) board points per view; obs (C, V, N, 2) px; seen (C, V) which exist.
    Start values: intr (C, 9), poses (V, 6) = ω, t of board -> left camera, R0 (3, 3) / T0 (3,) the
    right camera's pose relative to the left (ignored when C == 1). `fixed` (9,) marks intrinsics held
    at their start value (e.g. k3 for a 4-coefficient lens model)."""

    obj: F64
    obs: F64
    seen: B
    intr: F64
    poses: F64
    R0: F64
    T0: F64
    fixed: B
    loss: str = "huber"
    f_scale: float = 1.0


@dataclass
class BAResult:
    """Solution: intr (C, 9), poses (V, 6), R (3, 3), T (3,), euler (δ, φ, γ) rad; residuals (C, V, N, 2)
    px (NaN where unseen); std_intr (C, 9), std_euler (3,) rad, std_T (3,) one-sigma from the Jacobian."""

    intr: F64
    poses: F64
    R: F64
    T: F64
    euler: tuple[float, float, float]
    residuals: F64
    std_intr: F64
    std_euler: F64
    std_T: F64
    seconds: float
    nfev: int
    recentred: bool
    disparity_std_px: float = 0.0  # σ of the disparity of a far point straight ahead (px at the left fx)

    @property
    def view_rms(self) -> F64:
        """RMS reprojection error per camera and view (C, V) px, NaN where the view is unseen."""
        sq = np.sum(self.residuals**2, axis=-1)  # (C, V, N), NaN rows for unseen views
        seen = ~np.isnan(sq[..., 0])
        out: F64 = np.full(seen.shape, np.nan)
        out[seen] = np.sqrt(np.mean(sq[seen], axis=-1))
        return out

    @property
    def rms(self) -> float:
        """Overall RMS reprojection error (px) over every corner coordinate pair seen."""
        return float(np.sqrt(np.nanmean(np.sum(self.residuals**2, axis=-1))))


class _Layout:
    """Packing of the free parameters: [free intrinsics of each camera | extrinsics (6) | poses (6V)]."""

    def __init__(self, inp: BAInput, R_base: F64) -> None:
        self.C, self.V = inp.seen.shape
        self.free = ~inp.fixed
        self.nf = int(self.free.sum())
        self.n_ext = 6 if self.C == 2 else 0
        self.base_intr = inp.intr.copy()
        self.R_base = R_base
        self.ext_at = self.C * self.nf
        self.pose_at = self.ext_at + self.n_ext
        self.size = self.pose_at + 6 * self.V

    def unpack(self, p: F64) -> tuple[F64, F64, F64, F64]:
        intr = self.base_intr.copy()
        intr[:, self.free] = p[: self.ext_at].reshape(self.C, self.nf)
        if self.n_ext:
            e = p[self.ext_at : self.pose_at]
            R, T = euler_to_matrix(e[0], e[1], e[2]) @ self.R_base, e[3:6]
        else:
            R, T = np.eye(3), np.zeros(3)
        return intr, R, T, p[self.pose_at :].reshape(self.V, 6)


def _residuals(p: F64, lay: _Layout, inp: BAInput) -> F64:
    intr, R, T, poses = lay.unpack(p)
    Rv = rodrigues(poses[:, :3])
    Xl = np.einsum("vij,vnj->vni", Rv, inp.obj) + poses[:, None, 3:]  # (V, N, 3), eq. (5)
    out = []
    for c in range(lay.C):
        Xc = Xl if c == 0 else Xl @ R.T + T  # eq. (5) again for the right camera
        proj = project_points(intr[c], Xc[inp.seen[c]])
        out.append((proj - inp.obs[c][inp.seen[c]]).ravel())
    return np.concatenate(out)


def _sparsity(lay: _Layout, inp: BAInput) -> lil_matrix:
    """Which parameters each residual depends on: its camera's intrinsics, its view's pose, and the
    extrinsics for right-camera residuals."""
    n = inp.obj.shape[1] * 2
    rows = int(inp.seen.sum()) * n
    S = lil_matrix((rows, lay.size), dtype=np.int8)
    r = 0
    for c in range(lay.C):
        for v in np.flatnonzero(inp.seen[c]):
            S[r : r + n, c * lay.nf : (c + 1) * lay.nf] = 1
            if c == 1:
                S[r : r + n, lay.ext_at : lay.pose_at] = 1
            S[r : r + n, lay.pose_at + 6 * v : lay.pose_at + 6 * v + 6] = 1
            r += n
    return S


def bundle_adjust(inp: BAInput) -> BAResult:
    """Minimise the reprojection error of every seen corner over all unknowns (robust loss, sparse
    finite-difference Jacobian). Shapes as in BAInput; returns a BAResult.

    The LSMR tolerances are tightened far below SciPy's defaults: with those, the trust-region steps are
    too inexact and the solver stalls in the flat focal-length valley (calib1.dat: 791 px instead of 810)."""
    t0 = time.perf_counter()
    C = inp.seen.shape[0]
    angles = matrix_to_euler(inp.R0) if C == 2 else (0.0, 0.0, 0.0)
    recentred = C == 2 and abs(np.degrees(angles[1])) > RECENTRE_DEG
    R_base = inp.R0 if recentred else np.eye(3)
    if recentred:
        angles = (0.0, 0.0, 0.0)
    lay = _Layout(inp, R_base)
    ext = np.r_[angles, inp.T0] if C == 2 else np.zeros(0)
    p0 = np.concatenate([inp.intr[:, lay.free].ravel(), ext, inp.poses.ravel()])
    sol = least_squares(
        _residuals, p0, jac_sparsity=_sparsity(lay, inp), method="trf", loss=inp.loss,
        f_scale=inp.f_scale, x_scale="jac", args=(lay, inp), xtol=1e-12, ftol=1e-12, gtol=1e-10,
        max_nfev=200, tr_options={"atol": 1e-14, "btol": 1e-14, "maxiter": 2000},
    )
    intr, R, T, poses = lay.unpack(sol.x)
    cov = _cov_from_jacobian(sol.jac, sol.fun, lay.size)
    std = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    std_intr = np.zeros_like(intr)
    std_intr[:, lay.free] = std[: lay.ext_at].reshape(C, lay.nf)
    std_ext = std[lay.ext_at : lay.pose_at] if C == 2 else np.zeros(6)
    euler = matrix_to_euler(R) if C == 2 else (0.0, 0.0, 0.0)
    return BAResult(
        intr, poses, R, T, euler, _full_residuals(sol.fun, inp), std_intr,
        std_ext[:3] if C == 2 else np.zeros(3), std_ext[3:] if C == 2 else np.zeros(3),
        time.perf_counter() - t0, int(sol.nfev), bool(recentred),
        far_disparity_std(lay, sol.x, cov) if C == 2 else 0.0,
    )


def _cov_from_jacobian(jac: object, fun: F64, n: int) -> F64:
    """Parameter covariance (JᵀJ)⁻¹ σ², σ² = Σr² / (m - n), shape (n, n) (NaN if it cannot be formed)."""
    J = jac.toarray() if hasattr(jac, "toarray") else np.asarray(jac)
    m = len(fun)
    sigma2 = float(fun @ fun) / max(m - n, 1)
    try:
        cov = np.linalg.pinv(J.T @ J, rcond=1e-15)
    except np.linalg.LinAlgError:
        return np.full((n, n), np.nan)
    out: F64 = cov * sigma2
    return out


def far_disparity_std(lay: _Layout, x: F64, cov: F64, h: float = 1e-6) -> float:
    """σ (px, at the left camera's fx) of the disparity the rig gives a point at infinity on the left
    camera's axis: zero for the adjusted parameters, moved by any of their errors. Its gradient over the
    intrinsics and the extrinsics (forward differences) through their joint covariance: the marginal
    σ of the relative yaw alone overstates it many times, since a yaw and a shift of the right principal
    point move the right image alike and the adjustment tells only their sum well."""
    n = lay.pose_at
    intr, R, _T, _ = lay.unpack(x)
    K_l = intr_matrices(intr[0])[0]
    K_r, d_r = intr_matrices(intr[1])
    u_l = K_l[:2, 2].reshape(1, 1, 2)  # the left axis: the principal point (no distortion there)
    u_r = np.asarray(cv2.projectPoints(np.array([[0.0, 0.0, 1.0]]), cv2.Rodrigues(R)[0], np.zeros(3), K_r, d_r)[0],
                     np.float64)
    base = _far_disparity(lay, x, u_l, u_r)
    grad = np.empty(n)
    for i in range(n):
        step = h * max(abs(float(x[i])), 1.0)
        xp = x.copy()
        xp[i] += step
        grad[i] = (_far_disparity(lay, xp, u_l, u_r) - base) / step
    var = float(grad @ cov[:n, :n] @ grad)
    return float(K_l[0, 0] * np.sqrt(max(var, 0.0)))


def _far_disparity(lay: _Layout, x: F64, u_l: F64, u_r: F64) -> float:
    """The angle (rad) between the rays of raw pixels u_l and u_r seen by the rig of parameters x, along
    the baseline: the disparity of a far point divided by the focal length."""
    intr, R, T, _ = lay.unpack(x)
    (K_l, d_l), (K_r, d_r) = intr_matrices(intr[0]), intr_matrices(intr[1])
    m_l = np.r_[cv2.undistortPoints(u_l, K_l, d_l).reshape(2), 1.0]
    m_r = R.T @ np.r_[cv2.undistortPoints(u_r, K_r, d_r).reshape(2), 1.0]  # into the left camera's frame
    t = R.T @ T  # from the right lens centre to the left one, in the left frame (the baseline)
    return float((m_l / np.linalg.norm(m_l) - m_r / np.linalg.norm(m_r)) @ (t / np.linalg.norm(t)))


def _full_residuals(fun: F64, inp: BAInput) -> F64:
    """Scatter the flat residual vector back to (C, V, N, 2), NaN where a view is unseen."""
    C, V = inp.seen.shape
    N = inp.obj.shape[1]
    out = np.full((C, V, N, 2), np.nan)
    r = 0
    for c in range(C):
        k = int(inp.seen[c].sum())
        out[c][inp.seen[c]] = fun[r : r + k * N * 2].reshape(k, N, 2)
        r += k * N * 2
    return out
