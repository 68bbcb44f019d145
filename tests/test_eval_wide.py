"""Angle figures of solid bodies against the seen surface (tracker.evaluation, issue 12 item 2)."""

from __future__ import annotations

import numpy as np

from tracker.evaluation import WIDE_PX, _deg, _width_px, run_scenario


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
