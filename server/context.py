"""The collaborators the routers need, built by create_app's lifespan and stored on `app.state.ctx`."""

from __future__ import annotations

import asyncio
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from sqlalchemy import Engine
from sqlalchemy.orm import Session, sessionmaker

from server.media.webrtc import Viewers
from server.security import IdleTimer, LoginThrottle
from server.services.monitor import Monitor
from server.settings import Settings
from tmeye.media.pipeline import MediaPipeline
from tmeye.runtime import Runtime

if TYPE_CHECKING:
    from server.services.alarms import AlarmService
    from server.services.calibration import CalibrationJobs
    from server.services.events import EventBus
    from server.services.exports import ExportJobs
    from server.services.playback import FrameCache
    from server.services.recorder import Recorder
    from server.services.replays import ReplayJobs


@dataclass
class AppContext:
    settings: Settings
    engine: Engine
    sessions: sessionmaker[Session]
    key: bytes
    throttle: LoginThrottle
    runtime: Runtime
    events: EventBus
    calibrations: CalibrationJobs
    monitor: Monitor
    media: MediaPipeline
    viewers: Viewers
    stopping: asyncio.Event
    extras: dict[str, object] = field(default_factory=dict)
    recorder: Recorder | None = None
    frames: FrameCache | None = None
    exports: ExportJobs | None = None
    replays: ReplayJobs | None = None
    alarms: AlarmService = None  # type: ignore[assignment]  # set by the lifespan
    idle: IdleTimer = field(default_factory=lambda: IdleTimer(30 * 60))
