"""Camera and stereo-rig geometry: pinhole + Brown-Conrady lens, paper eq. (1)-(2), (5)-(6).

Conventions (used everywhere in TMEye):
- camera frame: OpenCV, x right, y down, z along the optical axis; pixels (u, v) with u to the right.
- rig frame: origin midway between the lens centres (paper §3), axes as the left camera's at home.
- a camera's pose in the rig frame is (R_rc, c): x_cam = R_rc @ (x_rig - c).
- stereo extrinsics in OpenCV's convention: x_right = R @ x_left + T (metres).
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from tracker.calib_sigma import CalibrationSigma

F64 = NDArray[np.float64]
F32 = NDArray[np.float32]

RIG_FORMAT = "tmeye-rig"
RIG_FORMAT_VERSION = 1


def euler_to_matrix(delta: float, phi: float, gamma: float) -> F64:
    """Rotation R of paper eq. (6) from Euler angles (δ, φ, γ) in radians; shape (3, 3)."""
    sd, cd = np.sin(delta), np.cos(delta)
    sp, cp = np.sin(phi), np.cos(phi)
    sg, cg = np.sin(gamma), np.cos(gamma)
    return np.array(
        [
            [cp * cg, sd * sp * cg - cd * sg, sd * sg + cd * cg * sp],  # r1 r2 r3
            [cp * sg, sd * sp * sg + cd * cg, cd * sp * sg - cg * sd],  # r4 r5 r6
            [-sp, cp * sd, cd * cp],  # r7 r8 r9
        ]
    )


def matrix_to_euler(R: F64) -> tuple[float, float, float]:
    """Inverse of eq. (6): (δ, φ, γ) in radians. At the singularity φ = ±90° (r7 = ∓1) only δ ∓ γ is
    defined; γ is then set to 0 and δ carries the whole rotation, so the result still reproduces R."""
    r7 = float(np.clip(-R[2, 0], -1.0, 1.0))
    phi = float(np.arcsin(r7))
    if abs(abs(r7) - 1.0) < 1e-9:
        gamma = 0.0
        # r2 = sinδ sinφ, r5 = cosδ when γ = 0
        delta = float(np.arctan2(R[0, 1] * np.sign(r7), R[1, 1]))
        return delta, phi, gamma
    delta = float(np.arctan2(R[2, 1], R[2, 2]))  # r8 / r9 = tan δ
    gamma = float(np.arctan2(R[1, 0], R[0, 0]))  # r4 / r1 = tan γ
    return delta, phi, gamma


def rot_y(angle: float) -> F64:
    """Rotation about the y (down) axis by `angle` radians: positive turns +z towards +x (pan right)."""
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def rot_x(angle: float) -> F64:
    """Rotation about the x (right) axis by `angle` radians: positive turns +z towards -y (tilt up)."""
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def gimbal_rotation(pan_deg: float, tilt_deg: float) -> F64:
    """R_world_rig for gimbal angles in degrees (pan about the vertical, then tilt); shape (3, 3)."""
    return rot_y(np.radians(pan_deg)) @ rot_x(np.radians(tilt_deg))


@dataclass(frozen=True)
class Camera:
    """A pinhole camera with Brown-Conrady distortion (OpenCV's 5-coefficient model).

    K: (3, 3) intrinsics in pixels; dist: (5,) k1 k2 p1 p2 k3; size: (width, height) in pixels;
    R_rc, c: pose in the rig frame (x_cam = R_rc @ (x_rig - c)), c in metres.
    """

    K: F64
    dist: F64
    size: tuple[int, int]
    R_rc: F64 = field(default_factory=lambda: np.eye(3))
    c: F64 = field(default_factory=lambda: np.zeros(3))

    @property
    def f(self) -> float:
        """Mean focal length in pixels."""
        return float(0.5 * (self.K[0, 0] + self.K[1, 1]))

    def field_of_view_deg(self) -> tuple[float, float]:
        """The horizontal and vertical field of view (degrees): the angles between the rays through the
        middles of the image's opposite edges (pixel edges -0.5 and size - 0.5), lens distortion included."""
        w, h = self.size
        cx, cy = float(self.K[0, 2]), float(self.K[1, 2])
        rays = self.rays_rig(np.array([-0.5, w - 0.5, cx, cx]), np.array([cy, cy, -0.5, h - 0.5]))  # unit, (4, 3)
        return (float(np.degrees(np.arccos(np.clip(rays[0] @ rays[1], -1.0, 1.0)))),
                float(np.degrees(np.arccos(np.clip(rays[2] @ rays[3], -1.0, 1.0)))))

    def distort_normalized(self, xn: F64, yn: F64) -> tuple[F64, F64]:
        """Undistorted normalized coordinates -> distorted pixel coordinates (arrays of any shape)."""
        k1, k2, p1, p2, k3 = (float(k) for k in self.dist)  # Python floats: float32 input stays float32
        r2 = xn * xn + yn * yn
        radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3))
        xy = xn * yn
        xd = xn * radial + 2.0 * p1 * xy + p2 * (r2 + 2.0 * xn * xn)
        yd = yn * radial + p1 * (r2 + 2.0 * yn * yn) + 2.0 * p2 * xy
        fx, s, cx, fy, cy = (float(self.K[0, 0]), float(self.K[0, 1]), float(self.K[0, 2]), float(self.K[1, 1]),
                             float(self.K[1, 2]))
        return fx * xd + s * yd + cx, fy * yd + cy

    def undistort_pixels(self, u: F64, v: F64, iterations: int = 8) -> tuple[F64, F64]:
        """Distorted pixel coordinates -> undistorted normalized coordinates (fixed-point iteration)."""
        K = self.K
        yd = (v - K[1, 2]) / K[1, 1]
        xd = (u - K[0, 2] - K[0, 1] * yd) / K[0, 0]
        k1, k2, p1, p2, k3 = self.dist
        xn, yn = xd.copy(), yd.copy()
        for _ in range(iterations):
            r2 = xn * xn + yn * yn
            radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3))
            dx = 2.0 * p1 * xn * yn + p2 * (r2 + 2.0 * xn * xn)
            dy = p1 * (r2 + 2.0 * yn * yn) + 2.0 * p2 * xn * yn
            xn = (xd - dx) / radial
            yn = (yd - dy) / radial
        return xn, yn

    def project(self, X_rig: F64) -> F64:
        """Rig-frame points (N, 3) in metres -> distorted pixels (N, 2); eq. (5) then the lens."""
        Xc = (X_rig - self.c) @ self.R_rc.T
        z = Xc[:, 2]
        u, v = self.distort_normalized(Xc[:, 0] / z, Xc[:, 1] / z)
        return np.stack([u, v], axis=1)

    def rays_rig(self, u: F64, v: F64) -> F64:
        """Distorted pixels -> unit ray directions in the rig frame, shape (..., 3)."""
        xn, yn = self.undistort_pixels(u, v)
        d = np.stack([xn, yn, np.ones_like(xn)], axis=-1)
        d = d / np.linalg.norm(d, axis=-1, keepdims=True)
        return np.asarray(d @ self.R_rc, dtype=np.float64)  # R_rc.T applied to row vectors

    def to_dict(self) -> dict[str, object]:
        return {
            "K": self.K.tolist(),
            "dist": self.dist.tolist(),
            "size": list(self.size),
            "R_rc": self.R_rc.tolist(),
            "c": self.c.tolist(),
        }

    @staticmethod
    def from_dict(d: object, side: str = "camera") -> Camera:
        """A camera from its rig-file fields; RigError naming `side`.field when one is malformed."""
        from tracker.rigcheck import camera_fields

        return Camera(**camera_fields(d, side))


@dataclass(frozen=True)
class StereoRig:
    """Two cameras rigidly mounted; the rig frame's origin is midway between the lens centres."""

    left: Camera
    right: Camera
    sigma: CalibrationSigma = field(default_factory=CalibrationSigma, compare=False)  # the calibration's own

    @property
    def R(self) -> F64:
        """Stereo rotation, x_right = R @ x_left + T."""
        return self.right.R_rc @ self.left.R_rc.T

    @property
    def T(self) -> F64:
        """Stereo translation in metres, x_right = R @ x_left + T."""
        return self.right.R_rc @ (self.left.c - self.right.c)

    @property
    def baseline(self) -> float:
        """b, the distance between the lens centres, in metres."""
        return float(np.linalg.norm(self.right.c - self.left.c))

    @staticmethod
    def from_extrinsics(left: Camera, right: Camera, R: F64, T: F64) -> StereoRig:
        """Build a rig from OpenCV stereo extrinsics (x_r = R x_l + T), placing the origin midway between
        the lens centres with the rig axes along the left camera's."""
        c_r_in_left = -R.T @ T  # right lens centre in the left camera frame
        c_left = -0.5 * c_r_in_left
        L = Camera(left.K, left.dist, left.size, np.eye(3), c_left)
        Rr = Camera(right.K, right.dist, right.size, R, c_left + c_r_in_left)
        return StereoRig(L, Rr)

    def to_dict(self) -> dict[str, object]:
        return {
            "format": RIG_FORMAT,
            "version": RIG_FORMAT_VERSION,
            "left": self.left.to_dict(),
            "right": self.right.to_dict(),
            "baseline_m": self.baseline,
        }

    @staticmethod
    def from_dict(d: dict[str, object], baseline_limits_m: tuple[float, float] | None = None) -> StereoRig:
        """A rig from a rig file's JSON object, checked (tracker.rigcheck): RigError names the bad field.
        baseline_limits_m: plausible |c_right - c_left| in metres (default BASELINE_LIMITS_M)."""
        from tracker.rigcheck import BASELINE_LIMITS_M, RigError, check_baseline

        if d.get("format") != RIG_FORMAT:
            raise RigError(f"not a TMEye rig file (format is {d.get('format')!r}, expected {RIG_FORMAT!r})")
        version = d.get("version")
        if version != RIG_FORMAT_VERSION:
            raise RigError(f"unsupported rig file version {version!r} (this TMEye reads {RIG_FORMAT_VERSION})")
        left, right = Camera.from_dict(d.get("left"), "left"), Camera.from_dict(d.get("right"), "right")
        if left.size != right.size:
            raise RigError(f"field right.size: {right.size} differs from left.size {left.size}")
        check_baseline(left.R_rc, left.c, right.c, baseline_limits_m or BASELINE_LIMITS_M)
        cal = d.get("calibration")
        return StereoRig(left, right, CalibrationSigma() if cal is None else CalibrationSigma.from_section(cal))


def save_rig(rig: StereoRig, path: str | Path, extra: dict[str, object] | None = None) -> None:
    """Write a rig file (JSON with format name and version); `extra` is stored under "calibration"."""
    data = rig.to_dict()
    if extra:
        data["calibration"] = extra
    Path(path).write_text(json.dumps(data, indent=2))


def load_rig(path: str | Path, baseline_limits_m: tuple[float, float] | None = None) -> StereoRig:
    """Read and check a rig file; ValueError with a one-line reason naming the file (and the field)."""
    from tracker.rigcheck import RigError

    p = Path(path)
    try:
        raw = p.read_bytes()
    except FileNotFoundError:
        raise ValueError(f"rig file not found: {p}") from None
    except OSError as exc:
        raise ValueError(f"rig file {p} is unreadable: {exc.strerror or exc}") from None
    try:
        data = json.loads(raw.decode("utf-8"))
    except UnicodeDecodeError as exc:
        raise ValueError(f"rig file {p} is unreadable: not UTF-8 JSON text (byte 0x{raw[exc.start]:02x} at offset "
                         f"{exc.start})") from None
    except json.JSONDecodeError as exc:
        raise ValueError(f"rig file {p} is unreadable: not valid JSON ({exc})") from None
    if not isinstance(data, dict):
        raise ValueError(f"rig file {p} does not hold a JSON object")
    try:
        return StereoRig.from_dict(data, baseline_limits_m)
    except RigError as exc:
        raise ValueError(f"rig file {p}: {exc}") from None
