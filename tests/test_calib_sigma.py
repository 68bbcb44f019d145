"""The calibration's own uncertainty (a rig file's "calibration" standard deviations) widens the reported
1-sigma of r, θ and φ as first-order error propagation says; a rig without them reports what it did."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from tracker.geometry import StereoRig, load_rig, save_rig
from tracker.localize import Localizer
from tracker.rectify import Rectifier
from tracker.rigcheck import RigError
from tracker.sim.rig import default_rig


def _section(rig: StereoRig, T_std: float = 0.0, d_std: float = 0.0, fx_std: float = 0.0,
             c_std: float = 0.0) -> dict[str, object]:
    """What `tmeye calibrate` writes under "calibration", with the given standard deviations."""
    intr = {"fx": fx_std, "fy": fx_std, "cx": c_std, "cy": c_std}
    return {"T": rig.T.tolist(), "T_std": [T_std, 0.0, 0.0], "euler_std_deg": [0.0, 0.5, 0.0],
            "disparity_offset_std_px": d_std,
            "K_left": rig.left.K.tolist(), "K_right": rig.right.K.tolist(),
            "intrinsics_std": {"left": intr, "right": intr}}


def _locate(rig: StereoRig, z_m: float):  # type: ignore[no-untyped-def]
    rect = Rectifier(rig)
    x, y = rect.rig.left.size[0] / 2.0, rect.rig.left.size[1] / 2.0
    d = rect.f * rig.baseline / z_m
    return Localizer(rect).locate(np.array([x, y]), d, 0.05, 400, None), rect


def test_a_rig_without_calibration_figures_reports_image_noise_only(tmp_path: Path) -> None:
    rig = default_rig()
    save_rig(rig, tmp_path / "rig.json")
    loaded = load_rig(tmp_path / "rig.json")
    assert loaded.sigma.scale_rel == 0.0 and loaded.sigma.disparity_px == 0.0
    plain, _ = _locate(rig, 20.0)
    again, _ = _locate(loaded, 20.0)
    assert again.sigma_r == pytest.approx(plain.sigma_r) and again.sigma_theta == pytest.approx(plain.sigma_theta)


def test_baseline_and_focal_uncertainty_scale_the_range_sigma(tmp_path: Path) -> None:
    rig = default_rig()
    b = rig.baseline
    fx = float(rig.left.K[0, 0])
    # 1 % of the baseline along it and 1 % of each focal length: σ_ε = √(0.01² + 0.01²)
    save_rig(rig, tmp_path / "rig.json", _section(rig, T_std=0.01 * b, fx_std=0.01 * fx))
    loaded = load_rig(tmp_path / "rig.json")
    assert loaded.sigma.scale_rel == pytest.approx(math.hypot(0.01, 0.01), rel=1e-3)  # T is about along x
    plain, _ = _locate(rig, 20.0)
    cal, _ = _locate(loaded, 20.0)
    expected = math.hypot(plain.sigma_r, loaded.sigma.scale_rel * cal.r)
    assert cal.sigma_r == pytest.approx(expected, rel=0.02)  # about 0.28 m at 20 m, against a few cm
    assert cal.sigma_r > 2.5 * plain.sigma_r


def test_a_disparity_offset_uncertainty_widens_the_range_only_by_itself(tmp_path: Path) -> None:
    rig = default_rig()
    save_rig(rig, tmp_path / "rig.json", _section(rig, d_std=0.1))  # the marginal yaw σ (0.5°) is not used
    loaded = load_rig(tmp_path / "rig.json")
    cal, rect = _locate(loaded, 30.0)
    d = rect.f * rig.baseline / 30.0
    s_d = math.hypot(0.05, 0.1 * rect.f / float(rig.left.K[0, 0]))  # the disparity's own σ and the offset's
    assert cal.sigma_r == pytest.approx(30.0 * s_d / d, rel=0.03)  # σ_z = z σ_d / d at the image centre


def test_a_principal_point_uncertainty_widens_the_angles(tmp_path: Path) -> None:
    rig = default_rig()
    save_rig(rig, tmp_path / "rig.json", _section(rig, c_std=2.0))
    cal, rect = _locate(load_rig(tmp_path / "rig.json"), 10.0)
    assert cal.sigma_theta == pytest.approx(2.0 / rect.f, rel=0.05)  # rad: 2 px over the focal length
    assert cal.sigma_phi == pytest.approx(2.0 / rect.f, rel=0.05)


@pytest.mark.parametrize(("section", "message"), [
    ([1, 2], "field calibration: must be an object"),
    ({"T_std": [0.1, "x", 0]}, "field calibration.T_std: not an array of numbers"),
    ({"T_std": [0.1, 0.2]}, "field calibration.T_std: must be 3, got 2"),
    ({"disparity_offset_std_px": float("inf")}, "calibration.disparity_offset_std_px: holds an infinite number"),
    ({"disparity_offset_std_px": -0.1}, "calibration.disparity_offset_std_px: must be numbers >= 0"),
    ({"intrinsics_std": {"left": {"fx": -1.0}}}, "calibration.intrinsics_std.left.fx: must be numbers >= 0"),
    ({"intrinsics_std": {"left": {"cx": "big"}}}, "calibration.intrinsics_std.left.cx: not a number"),
])
def test_malformed_calibration_figures_name_the_field(tmp_path: Path, section: object, message: str) -> None:
    rig = default_rig()
    path = tmp_path / "rig.json"
    save_rig(rig, path, {"placeholder": 0})
    import json
    data = json.loads(path.read_text())
    data["calibration"] = section
    path.write_text(json.dumps(data))
    with pytest.raises(ValueError, match=message):
        load_rig(path)
    with pytest.raises(RigError):
        StereoRig.from_dict(data)


def test_sigmas_the_calibration_could_not_estimate_count_as_not_modelled(tmp_path: Path) -> None:
    rig = default_rig()
    section = _section(rig, d_std=0.1, c_std=2.0)
    section["disparity_offset_std_px"] = float("nan")  # json writes NaN, and reads it back
    section["intrinsics_std"] = {"left": {"cx": float("nan"), "cy": 2.0}, "right": {}}
    save_rig(rig, tmp_path / "rig.json", section)
    sigma = load_rig(tmp_path / "rig.json").sigma
    assert sigma.disparity_px == 0.0 and sigma.principal_px == (0.0, 2.0)


def test_a_centroid_whose_outline_terms_are_given_has_no_floor_of_its_own() -> None:
    """The pipeline gives the centroid's whole 1-σ as extra_px (the outline's whole pixels, tracker.segmentation):
    with centroid_sigma_px None the angles' 1-σ are those of extra_px alone, as a Localizer whose own 1-σ is
    that figure and no extra gives them; the default's 0.5 / √area floor no longer stands on top."""
    from tracker.localize import Localizer
    from tracker.rectify import Rectifier
    from tracker.sim.rig import default_rig

    rect = Rectifier(default_rig())
    c, d, area = np.array([360.0, 220.0]), 20.0, 1200  # 0.5 / √1200 = 0.0144 px
    given = Localizer(rect, centroid_sigma_px=None).locate(c, d, 0.01, area, None, (0.03, 0.03))
    own = Localizer(rect, centroid_sigma_px=0.03).locate(c, d, 0.01, area, None)
    assert np.isclose(given.sigma_phi, own.sigma_phi) and np.isclose(given.sigma_theta, own.sigma_theta)
    floor = Localizer(rect, centroid_sigma_px=0.0).locate(c, d, 0.01, area, None, (0.03, 0.03))
    assert floor.sigma_phi > 1.05 * given.sigma_phi  # √(0.03² + 0.0144²) / 0.03 = 1.11
