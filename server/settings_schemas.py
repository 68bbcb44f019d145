"""Pydantic models of the tracker's tuning (GET and PATCH /api/tracker/config): eq. (9)'s detector, the
tracks' association and the aim. Angles in degrees, times in seconds, pixels of the left image."""

from __future__ import annotations

from typing import Any

from pydantic import ConfigDict, Field

from server.schema_base import Strict


class DetectorSettings(Strict):
    epsilon: int = Field(12, ge=1, le=254, title="Threshold ε (grey levels)",
                         description="eq. (9): a pixel is foreground where the two views differ by more")
    min_area_px: int = Field(16, ge=1, le=100000, title="Smallest object (px)",
                             description="smaller regions are not objects")
    absorb_s: float = Field(20.0, gt=0, le=3600, title="Stopped object absorbed after (s)",
                            description="a stopped object merges into the background after")
    margin_px: int = Field(6, ge=0, le=64, title="Box margin (px)",
                           description="padding around each candidate box")
    min_depth_gap: float = Field(0.04, ge=0, le=1, title="Depth gap (fraction)",
                                 description="object disparity must exceed background's by")
    min_disparity_gap_px: float = Field(0.5, ge=0, le=20, title="Depth gap, more (px)",
                                        description="plus this many pixels")
    moving_min_cells: int = Field(3, ge=1, le=100, title="Cells for a new object while moving",
                                  description="candidate cells needed while the mount moves")


class TracksSettings(Strict):
    gate_px: float = Field(40.0, gt=0, le=1000, title="Association gate (px)",
                           description="how far a detection may lie from a track's prediction to join it")
    gate_growth_px: float = Field(4.0, ge=0, le=100, title="Gate growth (px a frame)",
                                  description="the gate widens this much for each frame a track is missed")
    confirm_hits: int = Field(2, ge=1, le=30, title="Detections to confirm",
                              description="detections before a track is confirmed")
    max_missed: int = Field(60, ge=1, le=3000, title="Frames coasted",
                            description="frames a track coasts before it is dropped")


class AimSettings(Strict):
    max_rate_deg_s: float = Field(180.0, gt=0, le=1000, title="Max rate (°/s)",
                                  description="the mount's speed limit on each axis")
    max_accel_deg_s2: float = Field(1200.0, gt=0, le=20000, title="Max acceleration (°/s²)",
                                    description="the mount's acceleration limit on each axis")
    deadband_frac: float = Field(0.02, ge=0, le=0.5, title="Dead band (fraction of width)",
                                 description="deadband as a fraction of the frame width")
    loss_timeout_s: float = Field(1.5, ge=0, le=600, title="Home after a loss (s)",
                                  description="a target unseen this long is given up: the mount follows another "
                                              "target in view, or returns home")
    home_pan_deg: float = Field(0.0, ge=-170, le=170, title="Home pan (°)",
                                description="where the mount waits with no target")
    home_tilt_deg: float = Field(0.0, ge=-30, le=80, title="Home tilt (°)",
                                 description="where the mount waits with no target")
    centroid_gain: float = Field(1.0, ge=0, le=2, title="Centroid correction gain",
                                 description="weight of the image-centroid correction of the aim (0: off)")
    correction_tau_s: float = Field(0.5, gt=0, le=10, title="Correction time constant (s)",
                                    description="low-pass time constant of that correction")
    max_correction_deg: float = Field(5.0, ge=0, le=45, title="Max correction (°)",
                                      description="bound on that correction on each axis")


class TrackerSettings(Strict):
    detector: DetectorSettings
    tracks: TracksSettings
    aim: AimSettings


class TrackerSettingsPatch(Strict):
    """Any subset of the settings; the rest keep their values."""

    model_config = ConfigDict(json_schema_extra={"examples": [
        {"detector": {"epsilon": 14}, "aim": {"deadband_frac": 0.03}}]})

    detector: dict[str, Any] | None = Field(None, examples=[{"epsilon": 14}])
    tracks: dict[str, Any] | None = None
    aim: dict[str, Any] | None = None
