"""SQLAlchemy 2 typed models. Times are Unix seconds (float, UTC); angles degrees; lengths metres.
The schema is made only by the Alembic migrations in alembic/versions (CI runs `alembic check`)."""

from __future__ import annotations

from typing import Any

from sqlalchemy import JSON, BigInteger, Boolean, Float, ForeignKey, Index, Integer, String, Text, false
from sqlalchemy.orm import DeclarativeBase, Mapped, mapped_column


class Base(DeclarativeBase):
    pass


class User(Base):
    __tablename__ = "users"

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    username: Mapped[str] = mapped_column(String(64), unique=True)
    password_hash: Mapped[str] = mapped_column(String(256))
    role: Mapped[str] = mapped_column(String(16))  # viewer, operator or admin
    created_at: Mapped[float] = mapped_column(Float)
    password_changed_at: Mapped[float] = mapped_column(Float)
    disabled: Mapped[bool] = mapped_column(Boolean, default=False)


class AuthSession(Base):
    """A login: the token names it; logout or a password change revokes it."""

    __tablename__ = "sessions"

    id: Mapped[str] = mapped_column(String(64), primary_key=True)
    user_id: Mapped[int] = mapped_column(ForeignKey("users.id", ondelete="CASCADE"), index=True)
    created_at: Mapped[float] = mapped_column(Float)
    expires_at: Mapped[float] = mapped_column(Float)
    revoked_at: Mapped[float | None] = mapped_column(Float, nullable=True)
    address: Mapped[str | None] = mapped_column(String(64), nullable=True)


class AuditEntry(Base):
    """Who did what, when, from which address."""

    __tablename__ = "audit_log"

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    at: Mapped[float] = mapped_column(Float, index=True)
    user_id: Mapped[int | None] = mapped_column(ForeignKey("users.id", ondelete="SET NULL"), nullable=True)
    username: Mapped[str | None] = mapped_column(String(64), nullable=True)
    address: Mapped[str | None] = mapped_column(String(64), nullable=True)
    action: Mapped[str] = mapped_column(String(64))
    target: Mapped[str | None] = mapped_column(String(256), nullable=True)
    detail: Mapped[dict[str, Any] | None] = mapped_column(JSON, nullable=True)


class Calibration(Base):
    """A calibration run: its board, the images' hashes, the rig file and report it produced, who made it
    and whether it is the active one. status: running, done or failed (with `error`)."""

    __tablename__ = "calibrations"

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    created_at: Mapped[float] = mapped_column(Float)
    created_by: Mapped[int | None] = mapped_column(ForeignKey("users.id", ondelete="SET NULL"), nullable=True)
    status: Mapped[str] = mapped_column(String(16))
    board_cols: Mapped[int] = mapped_column(Integer)
    board_rows: Mapped[int] = mapped_column(Integer)
    square_m: Mapped[float] = mapped_column(Float)
    image_hashes: Mapped[list[Any]] = mapped_column(JSON)
    image_dir: Mapped[str] = mapped_column(String(512))
    rig: Mapped[dict[str, Any] | None] = mapped_column(JSON, nullable=True)
    report: Mapped[dict[str, Any] | None] = mapped_column(JSON, nullable=True)
    error: Mapped[str | None] = mapped_column(Text, nullable=True)
    finished_at: Mapped[float | None] = mapped_column(Float, nullable=True)
    active: Mapped[bool] = mapped_column(Boolean, default=False)


class Track(Base):
    """A tracked object: `run_id` names the runtime that saw it (its ids start at 1 each run); `replay_id` the
    replay that found it (None: the live runtime)."""

    __tablename__ = "tracks"
    __table_args__ = (Index("ix_tracks_run_track", "run_id", "track_no", unique=True),)

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    run_id: Mapped[str] = mapped_column(String(32))
    track_no: Mapped[int] = mapped_column(Integer)
    first_seen: Mapped[float] = mapped_column(Float, index=True)
    last_seen: Mapped[float] = mapped_column(Float, index=True)
    detections: Mapped[int] = mapped_column(Integer)
    peak_speed_mps: Mapped[float] = mapped_column(Float)
    width_m: Mapped[float | None] = mapped_column(Float, nullable=True)
    height_m: Mapped[float | None] = mapped_column(Float, nullable=True)
    min_range_m: Mapped[float | None] = mapped_column(Float, nullable=True)
    replay_id: Mapped[int | None] = mapped_column(ForeignKey("replays.id", ondelete="CASCADE"), nullable=True,
                                                  index=True)  # None: seen live


class TrackPoint(Base):
    """One trajectory sample (at most `track_sample_hz` per second)."""

    __tablename__ = "track_points"

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    track_id: Mapped[int] = mapped_column(ForeignKey("tracks.id", ondelete="CASCADE"), index=True)
    t: Mapped[float] = mapped_column(Float)
    x: Mapped[float] = mapped_column(Float)
    y: Mapped[float] = mapped_column(Float)
    z: Mapped[float] = mapped_column(Float)
    r: Mapped[float] = mapped_column(Float)
    theta_deg: Mapped[float] = mapped_column(Float)
    phi_deg: Mapped[float] = mapped_column(Float)


class SettingsChange(Base):
    """A change of the live settings (`section` e.g. "tracker"): before and after, by whom."""

    __tablename__ = "settings_changes"

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    at: Mapped[float] = mapped_column(Float)
    user_id: Mapped[int | None] = mapped_column(ForeignKey("users.id", ondelete="SET NULL"), nullable=True)
    section: Mapped[str] = mapped_column(String(32))
    before: Mapped[dict[str, Any]] = mapped_column(JSON)
    after: Mapped[dict[str, Any]] = mapped_column(JSON)


class ServoPreset(Base):
    """A named pan/tilt position."""

    __tablename__ = "servo_presets"

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    name: Mapped[str] = mapped_column(String(64), unique=True)
    pan_deg: Mapped[float] = mapped_column(Float)
    tilt_deg: Mapped[float] = mapped_column(Float)
    created_at: Mapped[float] = mapped_column(Float)
    created_by: Mapped[int | None] = mapped_column(ForeignKey("users.id", ondelete="SET NULL"), nullable=True)


class Segment(Base):
    """One camera's recorded segment file (DATA-relative `path`): written when it opens (status open), completed
    when it closes (closed) or corrected at start-up after a crash (cut). start / end: capture times (Unix s) of
    its first and last frame; start_pts: the first frame's 90 kHz capture clock; frame_offsets: each frame's pts
    minus start_pts (ticks), frame_nos: each frame's runtime index; keyframes: keyframe times in the segment (s)."""

    __tablename__ = "segments"
    __table_args__ = (Index("ix_segments_camera_start", "camera", "start"),)

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    camera: Mapped[str] = mapped_column(String(8))
    kind: Mapped[str] = mapped_column(String(16))  # continuous or event
    path: Mapped[str] = mapped_column(String(256), unique=True)
    status: Mapped[str] = mapped_column(String(8))  # open, closed or cut
    start: Mapped[float] = mapped_column(Float, index=True)
    end: Mapped[float | None] = mapped_column(Float, nullable=True, index=True)
    start_pts: Mapped[int] = mapped_column(BigInteger)
    frames: Mapped[int] = mapped_column(Integer, default=0)
    bytes: Mapped[int] = mapped_column(BigInteger, default=0)
    keyframes: Mapped[list[Any]] = mapped_column(JSON, default=list)
    frame_offsets: Mapped[list[Any]] = mapped_column(JSON, default=list)
    frame_nos: Mapped[list[Any]] = mapped_column(JSON, default=list)


class RecordedFrame(Base):
    """The telemetry of one recorded frame (the whole per-frame message: frame index, capture time, detections,
    servo state), keyed by the frame's 90 kHz capture clock, which is also its time in every segment holding it."""

    __tablename__ = "recorded_frames"

    pts: Mapped[int] = mapped_column(BigInteger, primary_key=True, autoincrement=False)
    frame_no: Mapped[int] = mapped_column(Integer)
    captured_at: Mapped[float] = mapped_column(Float, index=True)
    data: Mapped[dict[str, Any]] = mapped_column(JSON)


class EvidenceLock(Base):
    """Footage kept until an admin unlocks it: a time range (Unix s), or a track's or an alarm's (then track_id or
    alarm_id is set)."""

    __tablename__ = "evidence_locks"

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    start: Mapped[float] = mapped_column(Float)
    end: Mapped[float] = mapped_column(Float)
    track_id: Mapped[int | None] = mapped_column(ForeignKey("tracks.id", ondelete="SET NULL"), nullable=True)
    alarm_id: Mapped[int | None] = mapped_column(ForeignKey("alarms.id", ondelete="SET NULL"), nullable=True)
    note: Mapped[str] = mapped_column(Text, default="")
    created_at: Mapped[float] = mapped_column(Float)
    created_by: Mapped[int | None] = mapped_column(ForeignKey("users.id", ondelete="SET NULL"), nullable=True)


class Bookmark(Base):
    """A moment of the recordings (Unix s) with a note."""

    __tablename__ = "bookmarks"

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    t: Mapped[float] = mapped_column(Float, index=True)
    note: Mapped[str] = mapped_column(Text)
    created_at: Mapped[float] = mapped_column(Float)
    created_by: Mapped[int | None] = mapped_column(ForeignKey("users.id", ondelete="SET NULL"), nullable=True)


class Export(Base):
    """An export job: status queued, running, done or failed; progress 0 to 1; `path` (DATA-relative) the zip."""

    __tablename__ = "exports"

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    status: Mapped[str] = mapped_column(String(16))
    progress: Mapped[float] = mapped_column(Float, default=0.0)
    start: Mapped[float] = mapped_column(Float)
    end: Mapped[float] = mapped_column(Float)
    cameras: Mapped[list[Any]] = mapped_column(JSON)
    path: Mapped[str | None] = mapped_column(String(256), nullable=True)
    bytes: Mapped[int | None] = mapped_column(BigInteger, nullable=True)
    error: Mapped[str | None] = mapped_column(Text, nullable=True)
    created_at: Mapped[float] = mapped_column(Float)
    created_by: Mapped[int | None] = mapped_column(ForeignKey("users.id", ondelete="SET NULL"), nullable=True)
    finished_at: Mapped[float | None] = mapped_column(Float, nullable=True)


class AlarmRule(Base):
    """An alarm rule made by an admin: a condition in metres (JSON, see server.alarms.conditions), a
    priority (critical, high, medium, low), on- and off-delays (s), enabled and out-of-service flags; or a
    built-in device fault rule (builtin: its fault source), made at start-up, of which only the
    out-of-service flag changes."""

    __tablename__ = "alarm_rules"

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    name: Mapped[str] = mapped_column(String(128))
    priority: Mapped[str] = mapped_column(String(16))
    condition: Mapped[dict[str, Any]] = mapped_column(JSON)
    on_delay_s: Mapped[float] = mapped_column(Float)
    off_delay_s: Mapped[float] = mapped_column(Float)
    enabled: Mapped[bool] = mapped_column(Boolean)
    out_of_service: Mapped[bool] = mapped_column(Boolean)
    created_at: Mapped[float] = mapped_column(Float)
    created_by: Mapped[int | None] = mapped_column(ForeignKey("users.id", ondelete="SET NULL"), nullable=True)
    updated_at: Mapped[float] = mapped_column(Float)
    builtin: Mapped[str | None] = mapped_column(String(16), nullable=True)  # a device fault source: built in


class Alarm(Base):
    """One alarm occurrence: from its activation until it is normal again (acknowledged and cleared),
    shelved out or taken out of service. rule_key: "rule:<id>" or "fault:<source>"; state: unack, ack,
    rtn_unack, shelved, suppressed, out_of_service or normal; run_id and target_id name the triggering track."""

    __tablename__ = "alarms"

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    rule_id: Mapped[int | None] = mapped_column(ForeignKey("alarm_rules.id", ondelete="SET NULL"), nullable=True)
    rule_key: Mapped[str] = mapped_column(String(64))
    name: Mapped[str] = mapped_column(String(128))
    priority: Mapped[str] = mapped_column(String(16))
    state: Mapped[str] = mapped_column(String(16), index=True)
    activated_at: Mapped[float] = mapped_column(Float, index=True)
    cleared_at: Mapped[float | None] = mapped_column(Float, nullable=True)
    acked_at: Mapped[float | None] = mapped_column(Float, nullable=True)
    acked_by: Mapped[str | None] = mapped_column(String(64), nullable=True)
    updated_at: Mapped[float] = mapped_column(Float)
    frame: Mapped[int | None] = mapped_column(Integer, nullable=True)
    target_id: Mapped[int | None] = mapped_column(Integer, nullable=True)
    run_id: Mapped[str | None] = mapped_column(String(40), nullable=True)
    message: Mapped[str | None] = mapped_column(Text, nullable=True)
    shelved_until: Mapped[float | None] = mapped_column(Float, nullable=True)
    shelve_reason: Mapped[str | None] = mapped_column(Text, nullable=True)
    shelved_one_shot: Mapped[bool] = mapped_column(Boolean, default=False, server_default=false())


class AlarmEvent(Base):
    """One transition of an alarm: when, what (activated, cleared, acknowledged, shelved, unshelved,
    out_of_service, removed), the states, who (None: the engine), the comment, the frame and target."""

    __tablename__ = "alarm_events"

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    alarm_id: Mapped[int] = mapped_column(ForeignKey("alarms.id", ondelete="CASCADE"), index=True)
    at: Mapped[float] = mapped_column(Float)
    kind: Mapped[str] = mapped_column(String(32))
    state_from: Mapped[str | None] = mapped_column(String(16), nullable=True)
    state_to: Mapped[str | None] = mapped_column(String(16), nullable=True)
    user_id: Mapped[int | None] = mapped_column(ForeignKey("users.id", ondelete="SET NULL"), nullable=True)
    username: Mapped[str | None] = mapped_column(String(64), nullable=True)
    comment: Mapped[str | None] = mapped_column(Text, nullable=True)
    frame: Mapped[int | None] = mapped_column(Integer, nullable=True)
    target_id: Mapped[int | None] = mapped_column(Integer, nullable=True)
    message: Mapped[str | None] = mapped_column(Text, nullable=True)


class Replay(Base):
    """The tracker re-run on the recordings of start..end (Unix s) with `settings` (threshold, rig, background):
    status queued, running, done or failed (with `error`); progress 0 to 1; its tracks carry its id. frames: pairs
    replayed; agreement: how its detections compare with the live ones of the same frames."""

    __tablename__ = "replays"

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    status: Mapped[str] = mapped_column(String(16))
    progress: Mapped[float] = mapped_column(Float, default=0.0)
    start: Mapped[float] = mapped_column(Float)
    end: Mapped[float] = mapped_column(Float)
    settings: Mapped[dict[str, Any]] = mapped_column(JSON)
    frames: Mapped[int] = mapped_column(Integer, default=0)
    agreement: Mapped[dict[str, Any] | None] = mapped_column(JSON, nullable=True)
    error: Mapped[str | None] = mapped_column(Text, nullable=True)
    created_at: Mapped[float] = mapped_column(Float)
    created_by: Mapped[int | None] = mapped_column(ForeignKey("users.id", ondelete="SET NULL"), nullable=True)
    finished_at: Mapped[float | None] = mapped_column(Float, nullable=True)
