from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from tracker.geometry import (
    Camera,
    StereoRig,
    euler_to_matrix,
    gimbal_rotation,
    load_rig,
    matrix_to_euler,
    save_rig,
)
from tracker.localize import spherical, spherical_jacobian, triangulate_dlt
from tracker.rectify import Rectifier
from tracker.sim.rig import default_rig


@pytest.mark.parametrize("angles", [(0.1, 0.2, 0.3), (-1.0, 0.7, 2.5), (0.3, np.pi / 2, 0.4), (0.3, -np.pi / 2, -1.0)])
def test_euler_eq6_round_trip_including_the_singularity(angles: tuple[float, float, float]) -> None:
    R = euler_to_matrix(*angles)
    assert np.allclose(R @ R.T, np.eye(3), atol=1e-12)
    assert np.allclose(euler_to_matrix(*matrix_to_euler(R)), R, atol=1e-9)


def test_eq6_entries_match_the_paper() -> None:
    d, p, g = 0.2, -0.3, 0.5
    R = euler_to_matrix(d, p, g)
    assert R[0, 0] == pytest.approx(np.cos(p) * np.cos(g))  # r1
    assert R[1, 2] == pytest.approx(np.cos(d) * np.sin(p) * np.sin(g) - np.cos(g) * np.sin(d))  # r6
    assert R[2, 0] == pytest.approx(-np.sin(p))  # r7


def test_gimbal_positive_pan_looks_right_and_positive_tilt_looks_up() -> None:
    assert (gimbal_rotation(10, 0) @ [0, 0, 1])[0] > 0
    assert (gimbal_rotation(0, 10) @ [0, 0, 1])[1] < 0  # y is down


def test_distortion_round_trip() -> None:
    cam = default_rig().left
    u, v = np.meshgrid(np.linspace(0, 639, 9), np.linspace(0, 479, 7))
    xn, yn = cam.undistort_pixels(u, v)
    u2, v2 = cam.distort_normalized(xn, yn)
    assert np.abs(u2 - u).max() < 1e-6 and np.abs(v2 - v).max() < 1e-6


def test_rig_file_round_trip_and_errors(tmp_path: Path) -> None:
    rig = default_rig()
    path = tmp_path / "rig.json"
    save_rig(rig, path, {"rms_px": 0.1})
    back = load_rig(path)
    assert np.allclose(back.R, rig.R) and np.allclose(back.T, rig.T)
    assert back.baseline == pytest.approx(0.3)
    data = json.loads(path.read_text())
    data["version"] = 99
    path.write_text(json.dumps(data))
    with pytest.raises(ValueError, match="unsupported rig file version 99"):
        load_rig(path)
    with pytest.raises(ValueError, match="not found"):
        load_rig(tmp_path / "missing.json")
    (tmp_path / "bad.json").write_text("{nope")
    with pytest.raises(ValueError, match="unreadable"):
        load_rig(tmp_path / "bad.json")


def test_stereo_rig_from_extrinsics_puts_the_origin_midway() -> None:
    rig = default_rig()
    rebuilt = StereoRig.from_extrinsics(rig.left, rig.right, rig.R, rig.T)
    assert np.allclose(rebuilt.left.c + rebuilt.right.c, 0.0)
    assert np.allclose(rebuilt.T, rig.T)


def test_eq2_triangulation_matches_dlt_and_truth() -> None:
    rig = default_rig()
    rect = Rectifier(rig)
    X = np.array([[0.7, -0.4, 6.0], [-2.0, 0.3, 14.0]])
    x, y, d = rect.rig_to_rect(X)
    for k in range(2):
        assert np.allclose(rect.rect_to_rig(x[k], y[k], d[k]), X[k], atol=1e-9)
    # general triangulation through the cameras' projection matrices (undistorted pixels)
    P = []
    for cam in (rig.left, rig.right):
        Rt = np.hstack([cam.R_rc, (-cam.R_rc @ cam.c)[:, None]])
        P.append(cam.K @ Rt)
    for k in range(2):
        pts = [P[i] @ np.append(X[k], 1.0) for i in range(2)]
        assert np.allclose(triangulate_dlt(P[0], P[1], pts[0][:2] / pts[0][2], pts[1][:2] / pts[1][2]), X[k])


def test_spherical_jacobian_matches_finite_differences() -> None:
    p = np.array([1.5, -0.7, 8.0])
    J = spherical_jacobian(p)
    eps = 1e-6
    num = np.column_stack([(np.array(spherical(p + eps * e)) - np.array(spherical(p - eps * e))) / (2 * eps)
                           for e in np.eye(3)])
    assert np.allclose(J, num, atol=1e-6)
    r, th, ph = spherical(p)
    assert th > 0 and ph > 0  # right of and above the axis (y is down)


def test_field_of_view_of_a_pinhole_and_of_a_barrel_lens() -> None:
    K = np.array([[500.0, 0.0, 319.5], [0.0, 500.0, 239.5], [0.0, 0.0, 1.0]])
    pinhole = Camera(K, np.zeros(5), (640, 480))
    h, v = pinhole.field_of_view_deg()
    assert h == pytest.approx(2 * np.degrees(np.arctan(320 / 500)), abs=1e-9)
    assert v == pytest.approx(2 * np.degrees(np.arctan(240 / 500)), abs=1e-9)
    # barrel distortion (k1 < 0) squeezes the edges in: the same sensor sees wider
    wide = Camera(K, np.array([-0.2, 0.0, 0.0, 0.0, 0.0]), (640, 480)).field_of_view_deg()
    assert wide[0] > h + 1.0 and wide[1] > v + 0.5
