"""Angle figures of solid bodies against the seen surface (tracker.evaluation, issue 12 item 2)."""

from __future__ import annotations

import numpy as np

from tracker.evaluation import WIDE_PX, _deg, _wide_errors, _width_px, run_scenario
from tracker.sim.render import TargetTruth


def test_width_and_wrapped_degrees() -> None:
    ids = np.zeros((10, 100), np.uint8)
    ids[2:5, 10:51] = 1
    ids[7, 60] = 2
    assert _width_px(ids, 1) == 41 > WIDE_PX and _width_px(ids, 2) == 1 and _width_px(ids, 3) == 0
    assert abs(_deg(np.radians(359.0)) + 1.0) < 1e-9 and abs(_deg(np.radians(-181.0)) - 179.0) < 1e-9


def test_bodies_report_angles_against_the_seen_surface_and_plates_do_not() -> None:
    body = run_scenario("walk:body", frames=6).to_json()
    assert body["wide_frames"] == 6.0
    for key in ("azimuth", "elevation", "azimuth_surface", "elevation_surface", "azimuth_silhouette",
                "elevation_silhouette"):
        assert np.isfinite(float(body[f"{key}_rmse_wide_deg"]))  # type: ignore[arg-type]
    plate = run_scenario("walk", frames=6).to_json()
    assert "wide_frames" not in plate and "azimuth_surface_rmse_wide_deg" not in plate


def test_the_measured_ray_is_judged_at_the_truth_points_distance() -> None:
    # a measured point on the very ray from the left lens (0.15 m left of the mount's axis) through the
    # seen surface's mean, but 0.2 m deeper (the body's centre): no error against the surface; its own
    # angles about the origin differ by about 0.15 x 0.2 / 7² rad (0.035°)
    c, origin = np.array([-0.15, 0.0, 0.0]), np.zeros(3)
    surface = np.array([0.3, -0.2, 7.0])
    u = (surface - c) / np.linalg.norm(surface - c)
    centre = surface + 0.2 * u
    z3 = np.zeros(3)
    tt = TargetTruth(1, centre, centre, z3[:2], z3[:2], None, None, 1000, 1.0, surface_world=surface,
                     silhouette_world=surface + np.array([0.01, 0.0, 0.0]))
    az, el, az_s, el_s, az_m, el_m = _wide_errors(0.0, 0.0, (c, centre - c), tt, origin)
    assert (az, el) == (0.0, 0.0) and abs(az_s) < 1e-9 and abs(el_s) < 1e-9
    theta = lambda p: np.degrees(np.arctan2(p[0], p[2]))  # noqa: E731
    assert abs(theta(centre) - theta(surface)) > 0.02  # what comparing the points themselves would say
    assert abs(az_m) > 0.05 and abs(el_m) < 1e-3  # the silhouette's point, 1 cm to the side
