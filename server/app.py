"""The composition root: `create_app(settings)` builds the FastAPI application whose lifespan opens, in
order, the database (Alembic upgrade to head), the secret key and the initial admin, the tracker runtime,
the event bus, the calibration jobs and the track writer, and closes them in reverse order."""

from __future__ import annotations

import asyncio
import contextlib
import gc
import logging
import os
from collections.abc import AsyncIterator, Coroutine
from pathlib import Path
from typing import Any

from fastapi import FastAPI
from fastapi.staticfiles import StaticFiles

from server.alarms.faults import FaultThresholds
from server.context import AppContext
from server.db.engine import make_engine, session_factory, upgrade
from server.headers import SecurityHeaders
from server.media.webrtc import Viewers
from server.routes import (
    alarms,
    auth,
    calibration,
    errors,
    evidence,
    exports,
    health,
    live,
    recordings,
    replays,
    servo,
    telemetry_ws,
    tracker,
    tracks,
    users,
)
from server.security import IdleTimer, LoginThrottle, new_secret
from server.services import calibration as cal_service
from server.services import control, segments
from server.services import exports as export_service
from server.services import replays as replay_service
from server.services import users as user_service
from server.services.alarms import AlarmOptions, AlarmService, counter_probe
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
# The built console: inside the package when installed from a wheel (setup.py puts it there), else the
# checkout's web/dist.
_PACKAGED_WEB = Path(__file__).resolve().parent / "web_dist"
WEB_DIST = _PACKAGED_WEB if _PACKAGED_WEB.is_dir() else Path(__file__).resolve().parents[1] / "web" / "dist"


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
    servo = s.servo or ("sim" if s.source == "sim" else "none")  # the simulated gimbal moves simulated cameras only
    return RuntimeConfig(source=s.source, inputs=tuple(s.inputs), scenario=s.scenario, seed=s.seed, rig=s.rig,
                         servo=None if servo == "none" else servo, realtime=s.realtime, loop_source=True,
                         verify_budget_ms=s.verify_budget_ms or None, sigma_budget_ms=s.sigma_budget_ms or None,
                         targets=s.targets)


def recorder_config(s: Settings) -> RecorderConfig:
    return RecorderConfig(s.recording, s.segment_s, s.preroll_s, s.postroll_s, s.min_free_mb)


def retention_policy(s: Settings) -> Policy:
    return Policy({"continuous": s.retain_continuous_days, "event": s.retain_event_days},
                  int(s.recording_quota_mb * 1e6))


def alarm_options(s: Settings) -> AlarmOptions:
    return AlarmOptions(FaultThresholds(s.alarm_stall_s, s.alarm_fps_floor, disk_min_bytes=int(s.min_free_mb * 2**20)),
                        max_shelve_s=s.alarm_max_shelve_h * 3600.0)


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
        replay_service.mark_interrupted(db)
        saved = control.saved_tuning(db)
        rig = None if settings.rig else cal_service.active_rig(db)
    fixed = segments.reconcile(sessions, settings.data_dir)
    if any(fixed.values()):
        log.warning("recordings reconciled after an unclean stop: %s", fixed)
    tuning = TrackerTuning().updated(saved) if saved else TrackerTuning()
    throttle = LoginThrottle(settings.login_user_failures, settings.login_address_failures, settings.login_window_s)
    ctx = AppContext(settings, engine, sessions, key, throttle, None, None, None, Monitor(),  # type: ignore[arg-type]
                     None, None, asyncio.Event(), idle=IdleTimer(settings.session_idle_s))  # type: ignore[arg-type]
    return ctx, tuning, rig


async def _task(stack: contextlib.AsyncExitStack, coro: Coroutine[Any, Any, None], name: str,
                drain_s: float | None = None) -> None:
    """Run a background task until the app stops: cancelled then, or given drain_s seconds to end by itself
    (a consumer of the runtime's frames ends once the runtime has stopped and its hub is closed)."""
    task = asyncio.create_task(coro, name=name)

    async def finish() -> None:
        if drain_s is None:
            task.cancel()
        with contextlib.suppress(Exception, asyncio.CancelledError):
            await asyncio.wait_for(task, drain_s or 1.0)
    stack.push_async_callback(finish)


async def _start_services(stack: contextlib.AsyncExitStack, ctx: AppContext, rt: Runtime, settings: Settings) -> None:
    """Everything that consumes the runtime's frames, each stopped by the stack in reverse order."""
    s = settings
    ctx.events = EventBus(asyncio.get_running_loop())
    ctx.calibrations = CalibrationJobs(ctx.sessions, s.data_dir, ctx.events)
    stack.push_async_callback(ctx.calibrations.close)
    ctx.exports = ExportJobs(ctx.sessions, s.data_dir)
    stack.push_async_callback(asyncio.to_thread, ctx.exports.close)
    ctx.replays = replay_service.ReplayJobs(ctx.sessions, s.data_dir, s.track_sample_hz)
    stack.push_async_callback(asyncio.to_thread, ctx.replays.close)
    ctx.media = MediaPipeline(rt, MediaConfig(s.video_bitrate, s.video_gop, s.stamp_frames, s.mjpeg_fps,
                                              s.mjpeg_quality, s.media_queue, s.background_nice))
    ctx.media.start()
    stack.push_async_callback(asyncio.to_thread, ctx.media.stop)
    ctx.viewers = Viewers(ctx.media, s.ice_servers)
    stack.push_async_callback(ctx.viewers.close)
    recorder = ctx.recorder = Recorder(ctx.media, rt, ctx.sessions, s.data_dir, recorder_config(s))
    recorder.start()
    stack.push_async_callback(asyncio.to_thread, recorder.stop)
    ctx.frames = FrameCache(s.data_dir)
    retention = RetentionTask(ctx.sessions, s.data_dir, retention_policy(s), s.retention_interval_s)
    await _task(stack, retention.run(), "retention")
    writer = TrackWriter(rt, ctx.sessions, s.track_sample_hz, s.track_flush_s)
    await _task(stack, writer.run(), "track-writer", drain_s=3.0)
    ctx.extras["track_writer"] = writer
    await _task(stack, ctx.monitor.run(), "loop-monitor")
    ctx.alarms = AlarmService(rt, ctx.sessions, ctx.events, s.data_dir, alarm_options(s),
                              run_id=lambda: f"{writer.run_id}.{rt.generation}")
    ctx.alarms.probes["database"] = counter_probe(lambda: writer.errors, "writing tracks failed")
    ctx.alarms.probes["recording"] = lambda: recorder.fault
    ctx.alarms.on_activated.append(recorder.event)  # in events mode an activation is recorded
    await asyncio.to_thread(ctx.alarms.start)
    stack.push_async_callback(asyncio.to_thread, ctx.alarms.stop)


def create_app(settings: Settings, runtime: Runtime | None = None) -> FastAPI:
    """The application for `settings`; `runtime` overrides the one built from them (tests)."""

    @contextlib.asynccontextmanager
    async def lifespan(app: FastAPI) -> AsyncIterator[None]:
        ctx, tuning, rig = await asyncio.to_thread(_prepare_db, settings)
        rt = runtime or Runtime(runtime_config(settings), tuning)
        async with contextlib.AsyncExitStack() as stack:
            stack.callback(ctx.engine.dispose)
            stack.callback(log.info, "stopped")
            await asyncio.to_thread(rt.start, rig)  # type: ignore[arg-type]
            ctx.runtime = rt
            stack.push_async_callback(asyncio.to_thread, rt.stop)  # runs last of all that follow
            await _start_services(stack, ctx, rt, settings)
            # the tracker stops first: every consumer then drains what its queue holds and ends
            stack.push_async_callback(asyncio.to_thread, rt.stop)
            stack.callback(ctx.stopping.set)
            stack.callback(log.info, "stopping")
            app.state.ctx = ctx
            log.info("tracker running: %s", rt.status()["source"])
            # the start-up objects (188,000: modules, the app, the runtime) leave the collector: a full collection
            # over them holds the GIL, and with it the tracker's thread (231 ms once on the loaded 2-core VM)
            gc.collect()
            gc.freeze()
            yield

    app = FastAPI(title="TMEye", version=__version__, lifespan=lifespan, openapi_url="/api/openapi.json",
                  docs_url="/api/docs", redoc_url=None,
                  description="Stereo tracker console API: status, telemetry, servo control, tracks, calibration, "
                              "users. Log in at /api/auth/login; send the token as `Authorization: Bearer`.")
    errors.install(app)
    app.add_middleware(SecurityHeaders)
    for r in (health, auth, servo, tracks, tracker, calibration, users, live, telemetry_ws, recordings, evidence,
              exports, replays, alarms):
        app.include_router(r.router)
    if WEB_DIST.is_dir():
        app.mount("/", StaticFiles(directory=WEB_DIST, html=True), name="web")
    return app
