"""The paper's polynomial distortion model, eq. (3)-(4) and (7)-(8).

A pixel (x_k, y_k) seen at depth Z_c maps to camera coordinates
    X_c = Σ_ij α_ij x_k^i y_k^j,   Y_c = Σ_ij β_ij x_k^i y_k^j                (3)
with every coefficient quadratic in Z_c/f:
    α_ij = Σ_k c_αk,ij (Z_c/f)^k,  β_ij = Σ_k c_βk,ij (Z_c/f)^k, k = 0..2     (4)
i.e. [X_c Y_c]ᵀ = M [(Z_c/f)² Z_c/f 1]ᵀ with M's entries polynomials in x_k, y_k      (7)-(8).
i, j run 0..I and 0..J (I = J = 3 by default, 16 monomials, 48 coefficients per coordinate). Pixel
coordinates are centred and scaled to about [-1, 1] for conditioning. The coefficients are fitted by
linear least squares from board corners whose camera-frame positions come from the bundle adjustment
(board views at three or more distances are needed to separate the three powers of Z_c/f).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

F64 = NDArray[np.float64]


@dataclass(frozen=True)
class PolynomialLens:
    """Eq. (3)-(4) for one camera. coef_x, coef_y: (3, (I+1)(J+1)) c_αk,ij / c_βk,ij (row k = power of
    Z_c/f, column i*(J+1)+j); f: focal length (px) used in Z_c/f; centre (2,) px and scale (px) normalise
    the pixel coordinates; X_c, Y_c come out in the units of Z_c."""

    coef_x: F64
    coef_y: F64
    f: float
    centre: F64
    scale: float
    order_i: int = 3
    order_j: int = 3

    def _monomials(self, u: F64, v: F64) -> F64:
        """x_k^i y_k^j of normalised pixel coordinates, shape (M, (I+1)(J+1))."""
        x = (u - self.centre[0]) / self.scale
        y = (v - self.centre[1]) / self.scale
        cols = [x**i * y**j for i in range(self.order_i + 1) for j in range(self.order_j + 1)]
        return np.stack(cols, axis=1)

    def camera_xy(self, u: F64, v: F64, z: F64) -> tuple[F64, F64]:
        """Eq. (7): pixels (M,) at depths Z_c (M,) -> camera coordinates X_c, Y_c (M,) each."""
        mono = self._monomials(u, v)
        zf = z / self.f
        powers = np.stack([np.ones_like(zf), zf, zf * zf], axis=1)  # (M, 3): k = 0, 1, 2
        X = np.einsum("mk,kq,mq->m", powers, self.coef_x, mono)
        Y = np.einsum("mk,kq,mq->m", powers, self.coef_y, mono)
        return X, Y

    def normalized(self, u: F64, v: F64, z: F64) -> F64:
        """Ray directions (X_c/Z_c, Y_c/Z_c) of pixels (M,) at depths z (M,), shape (M, 2)."""
        X, Y = self.camera_xy(u, v, z)
        return np.stack([X / z, Y / z], axis=1)

    def to_dict(self) -> dict[str, object]:
        return {
            "model": "paper-polynomial eq. (3)-(4)",
            "order": [self.order_i, self.order_j],
            "f_px": self.f,
            "centre_px": self.centre.tolist(),
            "scale_px": self.scale,
            "c_alpha": self.coef_x.tolist(),
            "c_beta": self.coef_y.tolist(),
        }


def fit_polynomial(pix: F64, Xc: F64, f: float, size: tuple[int, int], order: int = 3) -> PolynomialLens:
    """Least-squares fit of eq. (3)-(4): pixels (M, 2) and their camera-frame points (M, 3) -> the lens.
    Raises ValueError if the depths do not span enough range for the quadratic in Z_c/f."""
    w, h = size
    centre = np.array([w / 2, h / 2])
    proto = PolynomialLens(np.zeros((3, 1)), np.zeros((3, 1)), f, centre, w / 2, order, order)
    mono = proto._monomials(pix[:, 0], pix[:, 1])
    zf = Xc[:, 2] / f
    if np.ptp(zf) < 0.05 * float(np.mean(zf)):
        raise ValueError("polynomial model needs board views at three or more distinct distances")
    zs = zf / np.mean(zf)  # rescale the powers for conditioning, undone below
    A = np.concatenate([mono, mono * zs[:, None], mono * (zs * zs)[:, None]], axis=1)
    q = mono.shape[1]
    sol, *_ = np.linalg.lstsq(A, np.stack([Xc[:, 0], Xc[:, 1]], axis=1), rcond=None)
    m = float(np.mean(zf))
    undo = np.array([1.0, 1.0 / m, 1.0 / (m * m)])[:, None]
    cx = sol[:, 0].reshape(3, q) * undo
    cy = sol[:, 1].reshape(3, q) * undo
    return PolynomialLens(cx, cy, f, proto.centre, proto.scale, order, order)


def effective_pinhole(lens: PolynomialLens, z: float) -> tuple[float, float, float, float]:
    """The pinhole a polynomial lens amounts to at depth z: principal point (cx, cy) px = the pixel whose
    ray is the optical axis (X_c = Y_c = 0, Newton), focal lengths (fx, fy) px = 1 / d(X_c/Z_c)/du there."""
    p = lens.centre.astype(np.float64).copy()
    zz = np.array([z])
    h = 1e-3
    J = np.eye(2)
    for _ in range(20):
        n0 = lens.normalized(p[:1], p[1:], zz)[0]
        du = (lens.normalized(p[:1] + h, p[1:], zz)[0] - n0) / h
        dv = (lens.normalized(p[:1], p[1:] + h, zz)[0] - n0) / h
        J = np.stack([du, dv], axis=1)
        step = np.linalg.solve(J, n0)
        p = p - step
        if np.linalg.norm(step) < 1e-9:
            break
    return float(1.0 / J[0, 0]), float(1.0 / J[1, 1]), float(p[0]), float(p[1])
