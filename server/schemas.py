"""Pydantic models of every request and response (the OpenAPI document is built from them). Angles in
degrees, lengths in metres, times in Unix seconds unless named otherwise."""

from __future__ import annotations

from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field

from server.recording_schemas import RecordingStatus
from server.schema_base import Strict

Role = Literal["viewer", "operator", "admin"]


class Message(BaseModel):
    model_config = ConfigDict(json_schema_extra={"examples": [{"detail": "no preset with id 99"}]})

    detail: str


class Health(BaseModel):
    status: Literal["ok", "starting", "failed", "stopped"]
    runtime: str = Field(description="runtime state: starting, running, ended, failed, stopped")
    version: str
    frame: int | None = None

    model_config = ConfigDict(json_schema_extra={"examples": [{"status": "ok", "runtime": "running",
                                                                "version": "0.1.0", "frame": 1234}]})


class LoginAnswer(BaseModel):
    model_config = ConfigDict(json_schema_extra={"examples": [
        {"access_token": "v1.SDfTtjnDHo0WuNra9dhmZ4yLiFoqs5lT.1795969483.Pt7M9g37pSTDFSAz7Z70jLSrnIZ-LkEt3P3BTzE0Uc0",
         "token_type": "bearer", "role": "operator", "expires_in": 43200,
         "csrf_token": "DgZmrHayYoo7-ZcUQ-vkkNNLJV4Ole2hZTvpCjbmdFY"}]})

    access_token: str
    token_type: Literal["bearer"] = "bearer"
    role: Role
    expires_in: int = Field(description="seconds until the token expires")
    csrf_token: str = Field(description="send as X-CSRF-Token with cookie-authenticated unsafe requests")


class Me(BaseModel):
    model_config = ConfigDict(json_schema_extra={"examples": [{"username": "alice", "role": "operator"}]})

    username: str
    role: Role


class Fault(BaseModel):
    model_config = ConfigDict(json_schema_extra={"examples": [
        {"kind": "source", "message": "no frame from the cameras for 1.2 s"}]})

    kind: str
    message: str


class ServoStatus(BaseModel):
    model_config = ConfigDict(json_schema_extra={"examples": [
        {"mode": "auto", "pan_deg": 12.31, "tilt_deg": -2.05, "fault": None, "goal": None,
         "command": {"pan_deg": 12.4, "tilt_deg": -2.0, "reason": "track"}, "configured": True,
         "limits": {"pan_deg": [-170.0, 170.0], "tilt_deg": [-30.0, 80.0]}}]})

    mode: Literal["auto", "manual", "hold", "home"] | None = None
    pan_deg: float | None = None
    tilt_deg: float | None = None
    fault: str | None = None
    goal: dict[str, float] | None = None
    command: dict[str, Any] | None = None
    configured: bool = True
    limits: dict[str, list[float]] | None = None


class Percentiles(BaseModel):
    model_config = ConfigDict(json_schema_extra={"examples": [
        {"n": 9027, "p50": 4.61, "p99": 8.767, "max": 10.617}]})

    n: int
    p50: float | None
    p99: float | None
    max: float | None


class Subscription(BaseModel):
    model_config = ConfigDict(json_schema_extra={"examples": [
        {"name": "track-writer", "queued": 9, "delivered": 235, "dropped": 0}]})

    name: str
    queued: int
    delivered: int
    dropped: int


class Status(BaseModel):
    model_config = ConfigDict(json_schema_extra={"examples": [
        {"state": "running", "frame": 250, "fps": 30.01, "skipped_frames": 0, "frames_processed": 250,
         "frame_errors": 0, "deferred_boxes": 179, "reused_sigma": 121, "source_faults": 0,
         "source": {"kind": "sim", "fps": 30.0, "width": 640, "height": 480, "hfov_deg": 57.697, "vfov_deg": 44.307,
                    "scenario": "endless", "seed": 0},
         "servo": {"mode": "auto", "pan_deg": -20.376, "tilt_deg": -4.7281, "fault": None, "goal": None,
                   "command": None, "configured": True, "limits": {"pan_deg": [-170.0, 170.0],
                                                                  "tilt_deg": [-30.0, 80.0]}},
         "faults": [], "subscribers": 4,
         "event_loop_lag_ms": {"n": 600, "p50": 0.641, "p99": 2.772, "max": 5.03},
         "ws_send_latency_ms": {"n": 9027, "p50": 4.61, "p99": 8.767, "max": 10.617},
         "ws_delivery_ms": {"n": 9027, "p50": 0.882, "p99": 1.956, "max": 2.88},
         "subscriptions": [{"name": "media", "queued": 0, "delivered": 250, "dropped": 0},
                           {"name": "track-writer", "queued": 9, "delivered": 241, "dropped": 0}],
         "frame_gap_max_ms": 41.2,
         "recording": {"mode": "continuous", "state": "recording", "fault": None, "segments": 12,
                       "frames": {"left": 240, "right": 240}, "bytes": 1843200, "errors": 0, "dropped_packets": 0,
                       "telemetry_rows": 249, "telemetry_missing": 0}}]})

    state: str
    frame: int | None
    fps: float
    skipped_frames: int
    frames_processed: int
    frame_errors: int
    deferred_boxes: int = Field(0, description="candidate boxes the tracker put off to the next frame to keep a "
                                               "busy frame within its time budget (setting verify_budget_ms), "
                                               "since the start")
    reused_sigma: int = Field(0, description="targets whose costlier 1-σ terms a busy frame took from the same "
                                             "track's recent frame instead of working them out (setting "
                                             "sigma_budget_ms), since the start")
    source_faults: int = Field(0, description="source faults (a read that failed or stalled) since the start")
    source: dict[str, Any] = Field(description="the frame source: kind, fps, width and height (px), hfov_deg and "
                                               "vfov_deg (the left camera's field of view in the rig in use, "
                                               "degrees), and its scenario and seed or its inputs")
    servo: ServoStatus
    faults: list[Fault]
    subscribers: int
    event_loop_lag_ms: Percentiles
    ws_send_latency_ms: Percentiles = Field(description="capture to WebSocket send, recent messages")
    ws_delivery_ms: Percentiles = Field(description="end of the tracker's frame to WebSocket send")
    subscriptions: list[Subscription] = Field(description="each consumer of the frames: a slow one drops its "
                                                          "oldest messages, never delaying the tracker")
    frame_gap_max_ms: float | None = Field(None, description="the longest interval between two frames the tracker "
                                                             "published over the window (a stall), ms")
    recording: RecordingStatus | None = Field(None, description="the recorder; `recording.fault` is set (and a "
                                              "fault of kind recording listed) when recording stopped on a fault")


class Detection(BaseModel):
    model_config = ConfigDict(json_schema_extra={"examples": [
        {"track_id": 1, "box": [286, 162, 386, 318], "centroid": [336.09, 238.26], "area_px": 5618,
         "disparity_px": 23.972, "size_m": [0.651, 1.714], "x": -0.0941, "y": 0.6447, "z": 7.4315, "r": 7.46,
         "theta_deg": -0.7257, "phi_deg": -4.9581, "sigma_r": 0.0073, "sigma_theta_deg": 0.10173,
         "sigma_phi_deg": 0.15651}]})

    track_id: int
    box: list[int] = Field(description="left-image box x0, y0, x1, y1 (px)")
    centroid: list[float] = Field(description="eq. (10) centroid in the left image (px)")
    area_px: int
    disparity_px: float
    size_m: list[float] | None = Field(None, description="width, height (m)")
    x: float
    y: float
    z: float
    r: float
    theta_deg: float
    phi_deg: float
    sigma_r: float
    sigma_theta_deg: float
    sigma_phi_deg: float


class Telemetry(BaseModel):
    """One frame: the fields of `tmeye track --json`, the capture time, the servo state, every detection."""

    model_config = ConfigDict(json_schema_extra={"examples": [
        {"frame": 5120, "t": 170.666667, "offset_s": 0.0, "detected": True, "track_id": 7, "objects": 1, "fps": 30.0,
         "step_ms": 2.41, "captured_at": 1795376486.828464, "x": 1.2041, "y": 0.6542, "z": 11.7028, "r": 11.7829,
         "theta_deg": 5.8745, "phi_deg": -3.1832, "sigma_r": 0.0151, "sigma_theta_deg": 0.0049,
         "sigma_phi_deg": 0.0048, "latency_ms": 2.6, "servo": {"mode": "auto", "pan_deg": 5.8, "tilt_deg": -3.1,
                                                                 "fault": None},
         "detections": [{"track_id": 7, "box": [566, 226, 622, 330], "centroid": [595.99, 275.63], "area_px": 2316,
                         "disparity_px": 15.294, "size_m": [0.549, 1.687], "x": 1.2041, "y": 0.6542, "z": 11.7028,
                         "r": 11.7829, "theta_deg": 5.8745, "phi_deg": -3.1832, "sigma_r": 0.0151,
                         "sigma_theta_deg": 0.0049, "sigma_phi_deg": 0.0048}]}]})

    frame: int
    t: float
    offset_s: float
    detected: bool
    track_id: int | None
    objects: int
    fps: float
    step_ms: float
    captured_at: float
    x: float | None = None
    y: float | None = None
    z: float | None = None
    r: float | None = None
    theta_deg: float | None = None
    phi_deg: float | None = None
    sigma_r: float | None = None
    sigma_theta_deg: float | None = None
    sigma_phi_deg: float | None = None
    latency_ms: float | None = None
    servo: ServoStatus | None = None
    detections: list[Detection] = []


class ModeRequest(Strict):
    mode: Literal["auto", "manual", "hold", "home"]


class GotoRequest(Strict):
    pan_deg: float = Field(ge=-360, le=360, examples=[12.5])
    tilt_deg: float = Field(ge=-90, le=90, examples=[-3.0])


class JogRequest(Strict):
    pan_dps: float = Field(ge=-180, le=180, description="pan rate (deg/s)", examples=[10.0])
    tilt_dps: float = Field(ge=-180, le=180, description="tilt rate (deg/s)", examples=[0.0])
    duration_s: float = Field(gt=0, le=10, description="how long to jog (s)", examples=[0.5])


class PointRequest(Strict):
    camera: Literal["left", "right"] = Field(examples=["left"])
    u: float = Field(ge=0, le=100000, description="pixel column in the full-size image", examples=[412.0])
    v: float = Field(ge=0, le=100000, description="pixel row", examples=[198.5])


class PresetIn(Strict):
    model_config = ConfigDict(json_schema_extra={"examples": [
        {"name": "gate", "pan_deg": 12.5, "tilt_deg": -3.0}, {"name": "here"}]})

    name: str = Field(min_length=1, max_length=64, pattern=r"^[\w .-]+$", examples=["gate"])
    pan_deg: float | None = Field(None, ge=-360, le=360, description="default: the mount's current angle")
    tilt_deg: float | None = Field(None, ge=-90, le=90, description="default: the mount's current angle")


class Preset(BaseModel):
    model_config = ConfigDict(from_attributes=True, json_schema_extra={"examples": [
        {"id": 1, "name": "gate", "pan_deg": 12.5, "tilt_deg": -3.0, "created_at": 1795926283.882073}]})

    id: int
    name: str
    pan_deg: float
    tilt_deg: float
    created_at: float


class TrackPointOut(BaseModel):
    model_config = ConfigDict(from_attributes=True, json_schema_extra={"examples": [
        {"t": 1795926279.683364, "x": -3.8115, "y": 0.508, "z": 7.2904, "r": 8.2423, "theta_deg": -27.6011,
         "phi_deg": -3.5334}]})

    t: float
    x: float
    y: float
    z: float
    r: float
    theta_deg: float
    phi_deg: float


class TrackOut(BaseModel):
    model_config = ConfigDict(from_attributes=True, json_schema_extra={"examples": [
        {"id": 1, "run_id": "20261129T042435-500.0", "track_no": 1, "first_seen": 1795926279.683364,
         "last_seen": 1795926286.523828, "detections": 203, "peak_speed_mps": 1.48, "width_m": 0.613,
         "height_m": 1.702, "min_range_m": 7.2159, "replay_id": None}]})

    id: int
    run_id: str
    track_no: int
    first_seen: float
    last_seen: float
    detections: int
    peak_speed_mps: float = Field(description="the largest speed (m/s) of a least-squares line through a second "
                                  "of the track's positions")
    width_m: float | None
    height_m: float | None
    min_range_m: float | None
    replay_id: int | None = Field(None, description="the replay that found it (None: seen live)")


class TrackDetail(TrackOut):
    model_config = ConfigDict(json_schema_extra={"examples": [
        {"id": 1, "run_id": "20261129T042435-500.0", "track_no": 1, "first_seen": 1795926279.683364,
         "last_seen": 1795926286.523828, "detections": 203, "peak_speed_mps": 1.48, "width_m": 0.613,
         "height_m": 1.702, "min_range_m": 7.2159, "replay_id": None, "trajectory": [
            {"t": 1795926279.683364, "x": -3.8115, "y": 0.508, "z": 7.2904, "r": 8.2423, "theta_deg": -27.6011,
         "phi_deg": -3.5334},
            {"t": 1795926279.79087, "x": -3.7722, "y": 0.5913, "z": 7.2404, "r": 8.1855, "theta_deg": -27.5192,
             "phi_deg": -4.1427}]}]})

    trajectory: list[TrackPointOut]


class CalibrationOut(BaseModel):
    model_config = ConfigDict(json_schema_extra={"examples": [
        {"id": 3, "created_at": 1795926300.12, "created_by": 1, "status": "done", "board": "9x6", "square_m": 0.025,
         "images": 13, "image_hashes": [["5f2b…e1", "9ac0…4d"]], "error": None, "finished_at": 1795926342.8,
         "active": True, "report": None}]})

    id: int
    created_at: float
    created_by: int | None
    status: Literal["running", "done", "failed"]
    board: str = Field(description="inner corners COLSxROWS")
    square_m: float
    images: int = Field(description="image pairs uploaded")
    image_hashes: list[list[str]] = Field(description="SHA-256 of each left, right image")
    error: str | None
    finished_at: float | None
    active: bool
    report: dict[str, Any] | None = None


class UserIn(Strict):
    model_config = ConfigDict(json_schema_extra={"examples": [
        {"username": "alice", "password": "correct horse battery", "role": "operator"}]})

    username: str = Field(min_length=1, max_length=64, pattern=r"^[A-Za-z0-9_.@-]+$", examples=["alice"])
    password: str = Field(min_length=12, max_length=128)
    role: Role


class UserPatch(Strict):
    model_config = ConfigDict(json_schema_extra={"examples": [
        {"role": "viewer"}, {"password": "a new long passphrase"}, {"disabled": True}]})

    password: str | None = Field(None, min_length=12, max_length=128)
    role: Role | None = None
    disabled: bool | None = None


class UserOut(BaseModel):
    model_config = ConfigDict(from_attributes=True, json_schema_extra={"examples": [
        {"id": 2, "username": "alice", "role": "operator", "created_at": 1795926283.9370143, "disabled": False}]})

    id: int
    username: str
    role: Role
    created_at: float
    disabled: bool


class AuditOut(BaseModel):
    model_config = ConfigDict(from_attributes=True, json_schema_extra={"examples": [
        {"id": 2, "at": 1795926283.8822331, "user_id": 1, "username": "admin", "address": "127.0.0.1",
         "action": "preset.create", "target": "gate", "detail": {"pan_deg": 12.5, "tilt_deg": -3.0}}]})

    id: int
    at: float
    user_id: int | None
    username: str | None
    address: str | None
    action: str
    target: str | None
    detail: dict[str, Any] | None
