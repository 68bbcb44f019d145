"""What a runtime is built from: the source, the rig, the servo and the pacing (`RuntimeConfig`), and the
tracker settings an operator may change while it runs (`TrackerTuning`)."""

from __future__ import annotations

from dataclasses import dataclass, field, fields, replace
from typing import Any

from tracker.aim import AimConfig
from tracker.detect import DetectorConfig
from tracker.tracks import TrackerConfig

SOURCE_KINDS = ("sim", "files", "usb", "rtsp", "recording")
TARGET_KINDS = ("auto", "solid", "flat")


@dataclass(frozen=True)
class RuntimeConfig:
    """source: "sim" (the simulated rig), "files", "usb" or "rtsp" with `inputs` (LEFT, RIGHT).
    scenario / seed: the simulated scene (`endless` never ends; finite ones end, or repeat with
    `loop_source`). rig: a rig file (required for real sources; the simulator's own rig otherwise).
    servo: None (open loop, no mount), "sim" (the simulated gimbal; the simulated rig then renders
    from its angles) or a driver URL (maestro:/dev/ttyACM0, ascii:/dev/ttyUSB0). realtime: pace the
    worker at the source's frame rate (frames that could not be processed in time are skipped and
    counted); otherwise run as fast as possible. max_frames: stop after this many processed frames.
    origin: (X, Y, Z) m, the point about which r, θ, φ are given. verify_budget_ms: with realtime, the
    tracker step's time budget for candidate boxes (and regions beside tracked objects) that hold no
    track's prediction (None: no bound; see tracker.schedule). sigma_budget_ms: with realtime, a tracked
    target's costly 1-σ terms are worked out afresh only when they would end within this many ms of the
    step's start, else taken from a recent frame (None: every frame;
    tracker.schedule.SigmaSchedule). baseline_limits_m: the plausible
    baselines (m) a rig file is checked against (default tracker.rigcheck.BASELINE_LIMITS_M, 1 cm to 10 m).
    targets: what the range is measured to: "solid" (a body's centre, half its assumed unseen depth behind
    the seen face, with that depth's uncertainty in σ_r: tracker.solid_prior.SolidPrior), "flat" (the seen
    face: flat boards) or "auto" (solid, except for the simulator's flat plates: a simulated scene, or the
    recording of one, whose scenario is not NAME:body)."""

    source: str = "sim"
    inputs: tuple[str, ...] = ()
    scenario: str = "endless"
    seed: int = 0
    rig: str | None = None
    servo: str | None = "sim"
    realtime: bool = True
    loop_source: bool = True
    max_frames: int | None = None
    verify_budget_ms: float | None = None
    sigma_budget_ms: float | None = None
    origin: tuple[float, float, float] = (0.0, 0.0, 0.0)
    baseline_limits_m: tuple[float, float] | None = None
    start: float | None = None
    end: float | None = None
    targets: str = "auto"

    def __post_init__(self) -> None:
        if self.targets not in TARGET_KINDS:
            raise ValueError(f"unknown targets {self.targets!r}; use one of {', '.join(TARGET_KINDS)}")
        if self.source not in SOURCE_KINDS:
            raise ValueError(f"unknown source {self.source!r}; use one of {', '.join(SOURCE_KINDS)}")
        if self.source == "sim" and self.inputs:
            raise ValueError("the simulated source takes no LEFT RIGHT inputs")
        if self.source == "recording":
            if len(self.inputs) != 1 or self.start is None or self.end is None:
                raise ValueError("source recording needs one input, the data directory, and start and end")
        elif self.source != "sim" and len(self.inputs) != 2:
            raise ValueError(f"source {self.source} needs two inputs, LEFT and RIGHT (got {len(self.inputs)})")
        if self.max_frames is not None and self.max_frames < 1:
            raise ValueError(f"max_frames must be at least 1, got {self.max_frames}")


# Tracker settings that may change from one frame to the next (the rest need a new runtime).
DETECTOR_FIELDS = ("epsilon", "min_area_px", "absorb_s", "margin_px", "min_depth_gap", "min_disparity_gap_px",
                   "moving_min_cells")
TRACKS_FIELDS = ("gate_px", "gate_growth_px", "confirm_hits", "max_missed")
AIM_FIELDS = ("max_rate_deg_s", "max_accel_deg_s2", "deadband_frac", "loss_timeout_s", "home_pan_deg",
              "home_tilt_deg", "centroid_gain", "correction_tau_s", "max_correction_deg")


@dataclass(frozen=True)
class TrackerTuning:
    """The live-tunable settings: detection (eq. 9 threshold and friends), identities and aiming."""

    detector: DetectorConfig = field(default_factory=DetectorConfig)
    tracks: TrackerConfig = field(default_factory=TrackerConfig)
    aim: AimConfig = field(default_factory=AimConfig)

    def track_config(self) -> TrackerConfig:
        """The identities' settings, the primary target given up after the aim's loss timeout: a target
        unseen that long passes the role to one in view, which the mount then follows instead of going home."""
        return replace(self.tracks, primary_hold_s=self.aim.loss_timeout_s)

    def as_dict(self) -> dict[str, dict[str, Any]]:
        return {"detector": {k: getattr(self.detector, k) for k in DETECTOR_FIELDS},
                "tracks": {k: getattr(self.tracks, k) for k in TRACKS_FIELDS},
                "aim": {k: getattr(self.aim, k) for k in AIM_FIELDS}}

    def updated(self, changes: dict[str, dict[str, Any]]) -> TrackerTuning:
        """A copy with `changes` ({section: {field: value}}) applied; ValueError names a bad field."""
        allowed = {"detector": DETECTOR_FIELDS, "tracks": TRACKS_FIELDS, "aim": AIM_FIELDS}
        parts: dict[str, Any] = {"detector": self.detector, "tracks": self.tracks, "aim": self.aim}
        for section, values in changes.items():
            if section not in allowed:
                raise ValueError(f"unknown tracker settings section {section!r}")
            bad = sorted(set(values) - set(allowed[section]))
            if bad:
                raise ValueError(f"{section}: unknown or read-only setting(s) {', '.join(bad)}")
            names = {f.name for f in fields(parts[section])}
            parts[section] = replace(parts[section], **{k: v for k, v in values.items() if k in names})
        return TrackerTuning(parts["detector"], parts["tracks"], parts["aim"])
