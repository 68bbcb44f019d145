"""The composition root: `create_app(settings)` builds the FastAPI application whose lifespan opens, in
order, the database (Alembic upgrade to head), the secret key and the initial admin, the tracker runtime,
the event bus, the calibration jobs and the track writer, and closes them in reverse order."""

from __future__ import annotations

import asyncio
import contextlib
import logging
import os
from collections.abc import AsyncIterator
from pathlib import Path

from fastapi import FastAPI
from fastapi.staticfiles import StaticFiles

from server.context import AppContext
from server.db.engine import make_engine, session_factory, upgrade
from server.media.webrtc import Viewers
from server.routes import (
    auth,
    calibration,
    errors,
    evidence,
    exports,
    health,
    live,
    recordings,
    servo,
    telemetry_ws,
    tracker,
    tracks,
    users,
)
from server.security import LoginThrottle, new_secret
from server.services import calibration as cal_service
from server.services import control, segments
from server.services import exports as export_service
from server.services import users as user_service
from server.services.calibration import CalibrationJobs
from server.services.events import EventBus
from server.services.exports import ExportJobs
from server.services.monitor import Monitor
from server.services.playback import FrameCache
from server.services.recorder import Recorder, RecorderConfig
from server.services.retention import Policy
from server.services.storage import RetentionTask
from server.services.tracks import TrackWriter
from server.settings import Settings
from tmeye import __version__
from tmeye.media.pipeline import MediaConfig, MediaPipeline
from tmeye.runtime import Runtime, RuntimeConfig, TrackerTuning

log = logging.getLogger("tmeye.server")
WEB_DIST = Path(__file__).resolve().parents[1] / "web" / "dist"


def load_key(data_dir: Path) -> bytes:
    """The server's signing key, DATA/secret-key (mode 0600), made on first start."""
    path = data_dir / "secret-key"
    if not path.exists():
        fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
        with os.fdopen(fd, "wb") as f:
            f.write(new_secret())
    key = path.read_bytes()
    if len(key) < 32:
        raise ValueError(f"{path} is damaged (shorter than 32 bytes): delete it to make a new one")
    return key


def runtime_config(s: Settings) -> RuntimeConfig:
    return RuntimeConfig(source=s.source, inputs=tuple(s.inputs), scenario=s.scenario, seed=s.seed, rig=s.rig,
                         servo=None if s.servo == "none" else s.servo, realtime=s.realtime, loop_source=True)


def recorder_config(s: Settings) -> RecorderConfig:
    return RecorderConfig(s.recording, s.segment_s, s.preroll_s, s.postroll_s, s.min_free_mb)


def retention_policy(s: Settings) -> Policy:
    return Policy({"continuous": s.retain_continuous_days, "event": s.retain_event_days},
                  int(s.recording_quota_mb * 1e6))


def _prepare_db(settings: Settings) -> tuple[AppContext, TrackerTuning, object]:
    settings.data_dir.mkdir(parents=True, exist_ok=True)
    upgrade(settings.db_url)
    engine = make_engine(settings.db_url)
    sessions = session_factory(engine)
    key = load_key(settings.data_dir)
    with sessions() as db:
        path = user_service.ensure_initial_admin(db, settings.data_dir)
        if path is not None:
            log.warning("created user 'admin'; its password is in %s (mode 0600)", path.resolve())
        cal_service.mark_interrupted(db)
        export_service.mark_interrupted(db)
        saved = control.saved_tuning(db)
        rig = None if settings.rig else cal_service.active_rig(db)
    fixed = segments.reconcile(sessions, settings.data_dir)
    if any(fixed.values()):
        log.warning("recordings reconciled after an unclean stop: %s", fixed)
    tuning = TrackerTuning().updated(saved) if saved else TrackerTuning()
    throttle = LoginThrottle(settings.login_user_failures, settings.login_address_failures, settings.login_window_s)
    ctx = AppContext(settings, engine, sessions, key, throttle, None, None, None, Monitor(),  # type: ignore[arg-type]
                     None, None, asyncio.Event())  # type: ignore[arg-type]
    return ctx, tuning, rig


def _start_recording(ctx: AppContext, rt: Runtime, settings: Settings) -> None:
    """After the media pipeline: the recorder, the playback frame cache, export jobs and the retention task."""
    ctx.recorder = Recorder(ctx.media, rt, ctx.sessions, settings.data_dir, recorder_config(settings))
    ctx.recorder.start()
    ctx.frames = FrameCache(settings.data_dir)
    ctx.exports = ExportJobs(ctx.sessions, settings.data_dir)
    retention = RetentionTask(ctx.sessions, settings.data_dir, retention_policy(settings),
                              settings.retention_interval_s)
    ctx.extras["retention"] = retention
    ctx.extras["retention_task"] = asyncio.create_task(retention.run(), name="retention")


def create_app(settings: Settings, runtime: Runtime | None = None) -> FastAPI:
    """The application for `settings`; `runtime` overrides the one built from them (tests)."""

    @contextlib.asynccontextmanager
    async def lifespan(app: FastAPI) -> AsyncIterator[None]:
        ctx, tuning, rig = await asyncio.to_thread(_prepare_db, settings)
        rt = runtime or Runtime(runtime_config(settings), tuning)
        try:
            await asyncio.to_thread(rt.start, rig)  # type: ignore[arg-type]
            ctx.runtime = rt
            ctx.events = EventBus(asyncio.get_running_loop())
            ctx.calibrations = CalibrationJobs(ctx.sessions, settings.data_dir, ctx.events)
            ctx.media = MediaPipeline(rt, MediaConfig(settings.video_bitrate, settings.video_gop, settings.stamp_frames,
                                                      settings.mjpeg_fps, settings.mjpeg_quality,
                                                      settings.media_queue))
            ctx.media.start()
            ctx.viewers = Viewers(ctx.media, settings.ice_servers)
            _start_recording(ctx, rt, settings)
            writer = TrackWriter(rt, ctx.sessions, settings.track_sample_hz, settings.track_flush_s)
            writer_task = asyncio.create_task(writer.run(), name="track-writer")
            monitor_task = asyncio.create_task(ctx.monitor.run(), name="loop-monitor")
            ctx.extras["track_writer"] = writer
            app.state.ctx = ctx
            log.info("tracker running: %s", rt.status()["source"])
            yield
        finally:
            log.info("stopping")
            ctx.stopping.set()
            if ctx.viewers is not None:
                await ctx.viewers.close()
            if "track_writer" in ctx.extras:
                monitor_task.cancel()
            if isinstance(task := ctx.extras.get("retention_task"), asyncio.Task):
                task.cancel()
            await asyncio.to_thread(rt.stop)
            if ctx.recorder is not None:
                await asyncio.to_thread(ctx.recorder.stop)
            if ctx.media is not None:
                await asyncio.to_thread(ctx.media.stop)
            if "track_writer" in ctx.extras:
                with contextlib.suppress(Exception):
                    await asyncio.wait_for(writer_task, 3.0)
            if ctx.calibrations is not None:
                await ctx.calibrations.close()
            if ctx.exports is not None:
                await asyncio.to_thread(ctx.exports.close)
            ctx.engine.dispose()
            log.info("stopped")

    app = FastAPI(title="TMEye", version=__version__, lifespan=lifespan, openapi_url="/api/openapi.json",
                  docs_url="/api/docs", redoc_url=None,
                  description="Stereo tracker console API: status, telemetry, servo control, tracks, calibration, "
                              "users. Log in at /api/auth/login; send the token as `Authorization: Bearer`.")
    errors.install(app)
    for r in (health, auth, servo, tracks, tracker, calibration, users, live, telemetry_ws, recordings, evidence,
              exports):
        app.include_router(r.router)
    if WEB_DIST.is_dir():
        app.mount("/", StaticFiles(directory=WEB_DIST, html=True), name="web")
    return app
