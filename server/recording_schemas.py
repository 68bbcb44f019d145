"""Pydantic models of the recording, playback, evidence and export API. Times are Unix seconds (UTC)."""

from __future__ import annotations

from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field, model_validator

from server.schema_base import DbId, Strict, UnixTime

Camera = Literal["left", "right"]


class SegmentOut(BaseModel):
    model_config = ConfigDict(from_attributes=True, json_schema_extra={"examples": [
        {"id": 12, "camera": "left", "kind": "continuous", "status": "closed", "start": 1795376480.0,
         "end": 1795376490.0, "frames": 301, "bytes": 1893321, "keyframes": [0.0, 1.5, 3.0],
         "path": "recordings/2026-11-22/22/left/41.20.mp4"}]})

    id: int
    camera: Camera
    kind: Literal["continuous", "event"]
    status: Literal["open", "closed", "cut"] = Field(description="open: being written; cut: repaired after a crash")
    start: float = Field(description="capture time of the first frame")
    end: float | None = Field(description="capture time of the last frame (null while open)")
    frames: int
    bytes: int
    keyframes: list[float] = Field(description="keyframe times in the segment (s)")
    path: str = Field(description="relative to the data directory")


class RecordingStatus(BaseModel):
    model_config = ConfigDict(json_schema_extra={"examples": [
        {"mode": "continuous", "state": "recording", "fault": None, "segments": 12,
         "frames": {"left": 240, "right": 240}, "bytes": 1843200, "errors": 0, "dropped_packets": 0,
         "telemetry_rows": 249, "telemetry_missing": 0}]})

    mode: Literal["continuous", "events", "off"]
    state: Literal["recording", "idle", "off", "fault"]
    fault: str | None = Field(description="device fault: why recording stopped (e.g. the free-disk floor)")
    segments: int = Field(description="segments closed since start")
    frames: dict[str, int]
    bytes: int
    errors: int
    dropped_packets: int
    telemetry_rows: int
    telemetry_missing: int


class LockIn(Strict):
    """A time range, a track (its first to last sighting) or an alarm (its activation to its clear, or to now
    while it is active), the last two widened by the recording's pre- and post-roll."""

    model_config = ConfigDict(extra="forbid", json_schema_extra={"examples": [
        {"start": 1795376480.0, "end": 1795376540.0, "note": "intrusion at the gate"}, {"track_id": 42},
        {"alarm_id": 7}]})

    start: UnixTime | None = None
    end: UnixTime | None = None
    track_id: DbId | None = None
    alarm_id: DbId | None = None
    note: str = Field("", max_length=2000)

    @model_validator(mode="after")
    def _one_kind(self) -> LockIn:
        kinds = (self.start is not None or self.end is not None) + (self.track_id is not None) + \
            (self.alarm_id is not None)
        if kinds != 1:
            raise ValueError("give start and end, or track_id, or alarm_id (one of them)")
        if self.track_id is None and self.alarm_id is None and (self.start is None or self.end is None):
            raise ValueError("give start and end, or track_id, or alarm_id")
        if self.start is not None and self.end is not None and not self.end > self.start:
            raise ValueError("end must be after start")
        return self


class LockOut(BaseModel):
    model_config = ConfigDict(json_schema_extra={"examples": [
        {"id": 2, "start": 1795000000.0, "end": 1795000060.0, "track_id": 12, "alarm_id": 7,
         "note": "incident 2026-114", "created_at": 1795000100.0, "created_by": 2}]}, from_attributes=True)

    id: int
    start: float
    end: float
    track_id: int | None
    alarm_id: int | None = None
    note: str
    created_at: float
    created_by: int | None


class BookmarkIn(Strict):
    model_config = ConfigDict(extra="forbid", json_schema_extra={"examples": [{"t": 1795376486.8, "note": "van"}]})

    t: UnixTime
    note: str = Field(min_length=1, max_length=2000)


class BookmarkOut(BaseModel):
    model_config = ConfigDict(json_schema_extra={"examples": [
        {"id": 4, "t": 1795000012.4, "note": "van at the gate", "created_at": 1795000100.0, "created_by": 2}]},
        from_attributes=True)

    id: int
    t: float
    note: str
    created_at: float
    created_by: int | None


class ExportIn(Strict):
    model_config = ConfigDict(extra="forbid", json_schema_extra={"examples": [
        {"start": 1795376480.0, "end": 1795376540.0, "cameras": ["left", "right"]}]})

    start: UnixTime
    end: UnixTime
    cameras: list[Camera] = Field(default=["left", "right"], min_length=1, max_length=2)


class ExportOut(BaseModel):
    model_config = ConfigDict(json_schema_extra={"examples": [
        {"id": 5, "status": "done", "progress": 1.0, "start": 1795000000.0, "end": 1795000060.0,
         "cameras": ["left", "right"], "bytes": 7340032, "error": None, "created_at": 1795000100.0,
         "finished_at": 1795000104.2}]}, from_attributes=True)

    id: int
    status: Literal["queued", "running", "done", "failed"]
    progress: float = Field(description="0 to 1")
    start: float
    end: float
    cameras: list[str]
    bytes: int | None
    error: str | None
    created_at: float
    finished_at: float | None


class ReplayIn(Strict):
    model_config = ConfigDict(extra="forbid", json_schema_extra={"examples": [
        {"start": 1795376480.0, "end": 1795376540.0, "threshold": 16, "calibration_id": None}]})

    start: UnixTime
    end: UnixTime
    threshold: int | None = Field(None, ge=1, le=254, description="eq. (9) threshold ε in grey levels "
                                  "(default: the live one)")
    calibration_id: DbId | None = Field(None, description="replay with this calibration's rig "
                                       "(default: the live rig)")


class ReplayOut(BaseModel):
    model_config = ConfigDict(json_schema_extra={"examples": [
        {"id": 3, "status": "done", "progress": 1.0, "start": 1795000000.0, "end": 1795000030.0,
         "settings": {"threshold": 14, "rig": "live", "scenario": "endless", "seed": 0, "targets": "auto",
                      "background": "simulated scene endless", "predictor": None},
         "frames": 900, "agreement": {"frames": 900, "same_count": 0.9911, "same_detected": 0.9922,
                                      "both_detected": 861, "range_diff_median_m": 0.0031, "range_diff_p95_m": 0.0412},
         "error": None, "created_at": 1795000100.0, "finished_at": 1795000131.5}]}, from_attributes=True)

    id: int
    status: Literal["queued", "running", "done", "failed"]
    progress: float = Field(description="0 to 1")
    start: float
    end: float
    settings: dict[str, Any] = Field(description="threshold, rig, background (and the simulated scene), "
                                     "targets (what ranges are measured to: auto, solid or flat)")
    frames: int = Field(description="stereo pairs replayed")
    agreement: dict[str, Any] | None = Field(description="against the live detections of the same frames: "
                                             "frames, same_count and same_detected (fractions), both_detected, "
                                             "range_diff_median_m, range_diff_p95_m")
    error: str | None
    created_at: float
    finished_at: float | None


TelemetryRecord = dict[str, Any]
