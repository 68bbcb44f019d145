"""The acceptance lines `tmeye eval --all` checks each report against (tmeye.eval_all.checks): a pure
function of the report, True where a line is met, False where it is missed, None without frames for it."""

from __future__ import annotations

from tmeye.eval_all import by_chance, checks, summary_lines

BODY = {
    "detection_rate": 0.995, "false_target_frames": 0, "azimuth_surface_rmse_wide_deg": 0.019,
    "elevation_surface_rmse_wide_deg": 0.5, "range_rmse_m": 0.30, "range_rmse_allowed_m": 0.31,
    "range_within_1sigma": 0.68, "range_nees": 1.0, "azimuth_within_1sigma": 0.59, "azimuth_nees": 0.7,
    "elevation_within_1sigma": 0.75, "elevation_nees": 1.51,
}


def test_a_bodys_lines_at_and_about_their_limits() -> None:
    c = checks("walk:body", BODY)
    assert c["detection_rate >= 0.99"] and c["false_target_frames == 0"]
    assert c["azimuth_surface_rmse_wide_deg <= 0.02"] and not c["elevation_surface_rmse_wide_deg <= 0.02"]
    assert c["range_rmse_m <= range_rmse_allowed_m"]
    assert c["range_within_1sigma in 0.60-0.75"] and c["range_nees in 0.7-1.5"]
    assert not c["azimuth_within_1sigma in 0.60-0.75"] and c["azimuth_nees in 0.7-1.5"]  # 0.59 < 0.60; 0.7 in
    assert c["elevation_within_1sigma in 0.60-0.75"] and not c["elevation_nees in 0.7-1.5"]  # 1.51 > 1.5
    worse = checks("walk:body", {**BODY, "detection_rate": 0.989, "false_target_frames": 1, "range_rmse_m": 0.32})
    assert not any(worse[k] for k in ("detection_rate >= 0.99", "false_target_frames == 0",
                                      "range_rmse_m <= range_rmse_allowed_m"))


def test_plates_are_held_to_the_sigma_lines_and_nan_means_no_frames() -> None:
    c = checks("walk:plate", {**BODY, "azimuth_nees": float("nan")})
    assert set(c) == {f"{q}_{k}" for q in ("range", "azimuth", "elevation")
                      for k in ("within_1sigma in 0.60-0.75", "nees in 0.7-1.5")}
    assert c["azimuth_nees in 0.7-1.5"] is None
    narrow = checks("walk:body", {k: v for k, v in BODY.items() if "surface" not in k})  # never wider than 40 px
    assert narrow["azimuth_surface_rmse_wide_deg <= 0.02"] is None


def test_the_summary_names_each_missed_line() -> None:
    table = {"walk:body": checks("walk:body", BODY), "walk:plate": checks("walk:plate", {**BODY, "range_nees": 1.2})}
    flat = [v for c in table.values() for v in c.values()]
    lines = summary_lines({"checks": table, "met": flat.count(True), "missed": flat.count(False), "no_frames": 0})
    assert lines[0].startswith("walk:body") and "elevation_nees in 0.7-1.5" in lines[0]
    assert "azimuth_within_1sigma in 0.60-0.75" in lines[1] and "range_nees" not in lines[1]
    assert lines[-1] == f"met {flat.count(True)}, missed {flat.count(False)} (0 of them 1-σ lines within chance of " \
        "their band), no frames 0"


def test_a_sigma_miss_is_by_chance_only_where_its_interval_reaches_the_band() -> None:
    rep = {**BODY, "azimuth_within_1sigma_p05": 0.50, "azimuth_within_1sigma_p95": 0.65,  # reaches 0.60
           "elevation_nees_p05": 1.52, "elevation_nees_p95": 2.1,  # wholly above 1.5
           "range_nees_p05": 0.2, "range_nees_p95": 3.0}  # a met line is never listed
    assert by_chance("walk:body", rep) == ["azimuth_within_1sigma in 0.60-0.75"]
    assert by_chance("walk:body", BODY) == []  # no interval reported: nothing to say
    table = {"walk:body": checks("walk:body", rep)}
    flat = list(table["walk:body"].values())
    lines = summary_lines({"checks": table, "met": flat.count(True), "missed": flat.count(False), "no_frames": 0,
                           "missed_by_chance": {"walk:body": by_chance("walk:body", rep)},
                           "missed_by_chance_count": 1})
    assert "azimuth_within_1sigma in 0.60-0.75 (chance)" in lines[0]
    assert "elevation_nees in 0.7-1.5;" in lines[0] + ";" and "elevation_nees in 0.7-1.5 (chance)" not in lines[0]
    assert "(1 of them 1-σ lines within chance of their band)" in lines[-1]
