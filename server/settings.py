"""Server settings (pydantic-settings): defaults, then `DATA/tmeye.toml`, then environment variables
`TMEYE_<NAME>`, then the command line (highest). Every setting is documented in its description."""

from __future__ import annotations

import ipaddress
from pathlib import Path
from typing import Any

from pydantic import Field, ValidationInfo, field_validator, model_validator
from pydantic_settings import BaseSettings, PydanticBaseSettingsSource, SettingsConfigDict, TomlConfigSettingsSource

DEFAULT_DATA_DIR = "./tmeye-data"


# the settings that take one of a few words: (what the message calls it, the words)
_CHOICES: dict[str, tuple[str, tuple[str, ...]]] = {
    "source": ("source", ("sim", "files", "usb", "rtsp")),
    "targets": ("targets", ("auto", "solid", "flat")),
    "recording": ("recording mode", ("continuous", "events", "off")),
}


class Settings(BaseSettings):
    """Everything `tmeye serve` can be told."""

    model_config = SettingsConfigDict(env_prefix="TMEYE_", extra="forbid")

    host: str = Field("127.0.0.1", description="address to listen on")
    port: int = Field(8080, ge=0, le=65535, description="TCP port (0: any free port)")
    data_dir: Path = Field(Path(DEFAULT_DATA_DIR), description="database, keys, calibration uploads, logs")
    source: str = Field("sim", description="frame source: sim, files, usb or rtsp")
    inputs: list[str] = Field(default_factory=list, description="LEFT RIGHT inputs of a real source")
    scenario: str = Field("endless", description="simulated scene (sim source); finite ones repeat")
    seed: int = Field(0, ge=0, description="seed of the simulated scene")
    rig: str | None = Field(None, description="rig file; default: the active calibration record, "
                                              "else the simulator's own rig")
    servo: str | None = Field(None, description="servo: sim (simulated gimbal), none, or a driver URL "
                                                "(maestro:/dev/ttyACM0, ascii:/dev/ttyUSB0); default: sim with "
                                                "the simulated source, none with a real one")
    targets: str = Field("auto", description="what the range is measured to: solid (a body's centre, half its "
                         "assumed unseen depth, 0.5 ± 0.3 of its smaller seen extent, behind the seen face, with that "
                         "depth's uncertainty in σ_r), flat (the seen face: flat boards) or auto (solid, except the "
                         "simulator's flat plates: a simulated scenario not named NAME:body)")
    realtime: bool = Field(True, description="pace the tracker at the source's frame rate")
    verify_budget_ms: float = Field(2.0, ge=0, le=1000, description="real time: candidate boxes that hold no "
                                    "track's prediction, and regions beside a tracked object that hold none, are "
                                    "verified only while the frame's tracker step is younger than this (ms); the rest "
                                    "wait for the next frame, where they come first, and are counted in the status "
                                    "(deferred_boxes). Bounds a busy frame's latency; "
                                    "0: no bound")
    sigma_budget_ms: float = Field(3.0, ge=0, le=1000, description="real time: a tracked target's costlier 1-σ "
                                   "terms (the scatter of its parts' disparities, a partly seen or warped outline, "
                                   "the outline's edge pixels and hull gap) "
                                   "are worked out afresh only when, at what they cost the last time, they would end "
                                   "within this many ms of the frame's tracker step, else taken from the same track "
                                   "within the last 15 frames; counted in the "
                                   "status (reused_sigma). Bounds a busy frame's latency; 0: every frame")
    token_ttl_s: int = Field(12 * 3600, ge=5, le=30 * 86400, description="absolute session lifetime (s): a login "
                                                                       "ends this long after it was made")
    session_idle_s: int = Field(30 * 60, ge=2, le=30 * 86400, description="idle session timeout (s): a session "
                                "with no request for this long ends (the timer is kept in memory: a restart "
                                "counts as activity)")
    cookie_secure: bool = Field(False, description="always mark the session cookies Secure (they are anyway when "
                                                   "the request came over HTTPS, directly or via a trusted proxy)")
    tls_cert: Path | None = Field(None, description="PEM certificate (chain) to serve HTTPS directly")
    tls_key: Path | None = Field(None, description="PEM private key of tls_cert")
    trusted_proxies: list[str] = Field(default_factory=list, description="addresses or CIDR networks of reverse "
                                       "proxies whose X-Forwarded-For and X-Forwarded-Proto are believed (none by "
                                       "default: the peer address is the client)")
    login_user_failures: int = Field(5, ge=1, description="failed logins per username per window before 429")
    login_address_failures: int = Field(20, ge=1, description="failed logins per address per window before 429")
    login_window_s: int = Field(600, ge=1, description="login throttling window (s)")
    ws_queue: int = Field(8, ge=1, le=1024, description="telemetry messages queued per WebSocket client "
                                                        "before the oldest is dropped")
    ws_ping_s: float = Field(20.0, gt=0, le=3600, description="WebSocket keep-alive ping interval (s); a client "
                                                            "that does not answer within it is disconnected")
    track_sample_hz: float = Field(10.0, gt=0, le=30, description="trajectory samples stored per second per track")
    track_flush_s: float = Field(1.0, gt=0, le=60, description="how often the track writer commits (s)")
    stamp_frames: bool = Field(False, description="measurement mode: the video (never the tracker's input) "
                                                  "carries the frame index in its top-left 16 cells of 8x8 px")
    video_bitrate: int = Field(1_500_000, ge=100_000, le=50_000_000, description="H.264 bits per second per camera")
    video_gop: int = Field(30, ge=1, le=600, description="frames between H.264 keyframes (30: 1 s at 30 fps; a "
                           "recorded frame is decoded from its keyframe on, so this bounds the playback's work)")
    media_queue: int = Field(6, ge=1, le=90, description="frames waiting for the H.264 encoders before the oldest "
                             "is dropped: a short stall of the media thread costs the recording nothing, a "
                             "long one drops frames (neither shown nor recorded) rather than delaying the video")
    background_nice: int = Field(5, ge=0, le=19, description="how much nicer (Linux nice steps) the threads that "
                                 "consume the tracker's frames (H.264 encoding) run than the tracker's own: when "
                                 "they compete for a core, the frame with a deadline goes first (0: the same)")
    mjpeg_fps: float = Field(15.0, gt=0, le=60, description="MJPEG fallback frames per second")
    mjpeg_quality: int = Field(80, ge=1, le=100, description="MJPEG fallback JPEG quality")
    ice_servers: list[str] = Field(default_factory=list, description="STUN/TURN URLs for WebRTC (none by default)")
    recording: str = Field("continuous", description="recording mode: continuous, events (footage around "
                                                     "detections, with pre- and post-roll) or off")
    segment_s: float = Field(10.0, ge=2.0, le=600.0, description="length of a recorded segment (s); each starts on "
                                                                "a keyframe")
    preroll_s: float = Field(5.0, ge=0.0, le=60.0, description="events mode: footage kept from before a detection (s)")
    postroll_s: float = Field(5.0, ge=0.0, le=600.0, description="events mode: footage kept after the last "
                                                                "detection (s)")
    retain_continuous_days: float = Field(7.0, gt=0, description="continuous footage older than this is deleted "
                                                                "(days; locked footage is kept)")
    retain_event_days: float = Field(30.0, gt=0, description="event footage older than this is deleted (days)")
    recording_quota_mb: float = Field(0.0, ge=0, description="disk quota of the recordings (MB; 0: none); the "
                                                             "oldest unlocked segments go first")
    min_free_mb: float = Field(1024.0, ge=0, description="recording stops with a fault while the disk holding the "
                                                         "data directory has less free space than this (MB)")
    retention_interval_s: float = Field(60.0, gt=0, le=86400, description="how often retention runs (s)")
    alarm_stall_s: float = Field(0.5, gt=0, le=60, description="a camera with no new frame for longer is stalled "
                                                               "(device-fault alarm, s)")
    alarm_fps_floor: float = Field(10.0, ge=0, le=240, description="frame-rate fault below this many frames per "
                                                                   "second (over 3 s)")
    alarm_max_shelve_h: float = Field(8.0, gt=0, le=168, description="the longest an alarm may be shelved (h)")
    alarm_preroll_s: float = Field(5.0, ge=0, le=600, description="an alarm's playback link starts this long "
                                                                  "before its activation (s)")
    log_level: str = Field("info", description="debug, info, warning or error")

    @field_validator("source", "targets", "recording")
    @classmethod
    def _one_of(cls, v: str, info: ValidationInfo) -> str:
        what, allowed = _CHOICES[info.field_name or ""]
        if v not in allowed:
            raise ValueError(f"unknown {what} {v!r}; use {', '.join(allowed[:-1])} or {allowed[-1]}")
        return v

    @field_validator("trusted_proxies")
    @classmethod
    def _proxies(cls, v: list[str]) -> list[str]:
        for item in v:
            try:
                ipaddress.ip_network(item, strict=False)
            except ValueError:
                raise ValueError(f"trusted proxy {item!r} is not an IP address or network") from None
        return v

    @model_validator(mode="after")
    def _tls_pair(self) -> Settings:
        if (self.tls_cert is None) != (self.tls_key is None):
            raise ValueError("tls_cert and tls_key go together: give both or neither")
        return self

    @field_validator("log_level")
    @classmethod
    def _level(cls, v: str) -> str:
        if v.lower() not in ("debug", "info", "warning", "error"):
            raise ValueError(f"unknown log level {v!r}")
        return v.lower()

    @classmethod
    def settings_customise_sources(
        cls, settings_cls: type[BaseSettings], init_settings: PydanticBaseSettingsSource,
        env_settings: PydanticBaseSettingsSource, dotenv_settings: PydanticBaseSettingsSource,
        file_secret_settings: PydanticBaseSettingsSource,
    ) -> tuple[PydanticBaseSettingsSource, ...]:
        return init_settings, env_settings, _data_dir_toml(settings_cls, init_settings, env_settings)

    @property
    def db_path(self) -> Path:
        return self.data_dir / "tmeye.db"

    @property
    def recordings_dir(self) -> Path:
        return self.data_dir / "recordings"

    @property
    def db_url(self) -> str:
        return f"sqlite:///{self.db_path}"


def _data_dir_toml(settings_cls: type[BaseSettings], *higher: PydanticBaseSettingsSource) -> PydanticBaseSettingsSource:
    """The `tmeye.toml` of the data directory chosen by the higher-priority sources (or the default)."""
    data_dir: Any = DEFAULT_DATA_DIR
    for src in higher:
        found = src().get("data_dir")
        if found:
            data_dir = found
            break
    return TomlConfigSettingsSource(settings_cls, toml_file=Path(data_dir) / "tmeye.toml")
