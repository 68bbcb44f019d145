"""Replay jobs: the tracker re-run on the recordings of a range (tmeye.replay) with other settings, its tracks
stored apart from the live ones (their `replay_id` set). The request is checked before anything is stored
(range, recordings of both cameras, the calibration); jobs run one at a time in a worker thread, the row
carrying status, progress and, at the end, the agreement with the live detections of the same frames."""

from __future__ import annotations

import logging
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from sqlalchemy import delete, update
from sqlalchemy.orm import Session, sessionmaker

from server.db.models import Calibration, Replay, Track, User
from server.services.calibration import rig_of
from server.services.errors import Invalid, NotFound
from server.services.tracks import TrackBook, flush
from server.settings import Settings
from tmeye.replay import replay_config, run_replay
from tmeye.runtime import FrameEvent, Runtime, TrackerTuning
from tmeye.runtime.recording import RecordingError, plan
from tracker.geometry import StereoRig

log = logging.getLogger("tmeye.replays")
MAX_RANGE_S = 3600.0
FLUSH_FRAMES = 300  # tracks are committed every this many frames (and at the end)


@dataclass(frozen=True)
class LiveSetup:
    """What the live runtime runs with: its rig, its tuning, the simulated scene ("" for real cameras) and
    what its ranges are measured to (RuntimeConfig.targets)."""

    rig: StereoRig | None
    tuning: TrackerTuning
    scenario: str
    seed: int
    targets: str = "auto"


def live_setup(settings: Settings, runtime: Runtime) -> LiveSetup:
    """The live runtime's rig and tuning, and its simulated scene when its source is the simulator."""
    return LiveSetup(runtime.comp.rig if runtime.comp is not None else None, runtime.tuning,
                     settings.scenario if settings.source == "sim" else "", settings.seed, settings.targets)


def mark_interrupted(db: Session) -> None:
    db.execute(update(Replay).where(Replay.status.in_(("queued", "running")))
               .values(status="failed", error="interrupted by a server stop", finished_at=time.time()))
    db.commit()


def get_replay(db: Session, replay_id: int) -> Replay:
    row = db.get(Replay, replay_id)
    if row is None:
        raise NotFound(f"no replay with id {replay_id}")
    return row


class ReplayJobs:
    def __init__(self, sessions: sessionmaker[Session], data_dir: Path, sample_hz: float):
        self.sessions, self.data_dir, self.sample_hz = sessions, data_dir, sample_hz
        self.pool = ThreadPoolExecutor(1, thread_name_prefix="tmeye-replay")
        self._stop = threading.Event()  # a server stop ends a running replay (then failed, its tracks removed)
        self._jobs: dict[int, tuple[StereoRig | None, TrackerTuning]] = {}

    def create(self, db: Session, user: User, start: float, end: float, live: LiveSetup,
               threshold: int | None, calibration_id: int | None) -> Replay:
        if not end > start:
            raise Invalid("end must be after start")
        if end - start > MAX_RANGE_S:
            raise Invalid(f"a replay spans at most {MAX_RANGE_S / 60:.0f} min")
        try:
            plan(self.data_dir, start, end)
        except RecordingError as exc:
            raise Invalid(str(exc)) from None
        rig, rig_name = live.rig, "live"
        if calibration_id is not None:
            rec = db.get(Calibration, calibration_id)
            if rec is None:
                raise Invalid(f"no calibration with id {calibration_id}")
            rig, rig_name = rig_of(rec), f"calibration {calibration_id}"
        tuning = live.tuning
        if threshold is not None:
            tuning = tuning.updated({"detector": {"epsilon": threshold}})
        settings = {"threshold": tuning.detector.epsilon, "rig": rig_name, "scenario": live.scenario,
                    "seed": live.seed, "targets": live.targets,
                    "background": f"simulated scene {live.scenario}" if live.scenario else "first recorded pair",
                    "predictor": None}
        row = Replay(status="queued", progress=0.0, start=start, end=end, settings=settings, frames=0,
                     created_at=time.time(), created_by=user.id)
        db.add(row)
        db.commit()
        self._jobs[row.id] = (rig, tuning)
        self.pool.submit(self._run, row.id)
        return row

    def close(self) -> None:
        self._stop.set()
        self.pool.shutdown(wait=True, cancel_futures=True)

    def _set(self, replay_id: int, **values: Any) -> None:
        with self.sessions() as db, db.begin():
            db.execute(update(Replay).where(Replay.id == replay_id).values(**values))

    def _run(self, replay_id: int) -> None:
        rig, tuning = self._jobs.pop(replay_id)
        try:
            self._set(replay_id, status="running")
            with self.sessions() as db:
                job = get_replay(db, replay_id)
                cfg = replay_config(str(self.data_dir), job.start, job.end, job.settings["scenario"],
                                    job.settings["seed"], job.settings.get("targets", "auto"))
            frames, agreement = self._replay(replay_id, cfg, rig, tuning)
            self._set(replay_id, status="done", progress=1.0, frames=frames, agreement=agreement,
                      finished_at=time.time())
        except Exception as exc:
            log.exception("replay %d failed", replay_id)
            with self.sessions() as db, db.begin():  # nothing of a failed replay is kept
                db.execute(delete(Track).where(Track.replay_id == replay_id))
            self._set(replay_id, status="failed", error=str(exc).splitlines()[0] if str(exc) else type(exc).__name__,
                      finished_at=time.time())

    def _replay(self, replay_id: int, cfg: Any, rig: StereoRig | None, tuning: TrackerTuning
                ) -> tuple[int, dict[str, Any]]:
        book = TrackBook(self.sample_hz)
        run_id = f"replay-{replay_id}"
        count = [0]

        def on_frame(ev: FrameEvent, progress: float) -> None:
            book.add(ev.telemetry)
            count[0] += 1
            if count[0] % FLUSH_FRAMES == 0:
                flush(self.sessions, run_id, book, replay_id)
                self._set(replay_id, progress=round(0.99 * progress, 3), frames=count[0])

        agreement = run_replay(cfg, tuning, rig, on_frame, self._stop)
        flush(self.sessions, run_id, book, replay_id)
        return count[0], agreement.summary()
