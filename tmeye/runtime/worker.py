"""The runtime: one rig (`Composition`) run frame by frame in a worker thread, results published to
subscribers (`Hub` of `FrameEvent`s), operator requests applied between frames.

Real time: with `realtime`, frame k is due at t0 + k / fps. A frame that took too long makes the worker
skip the frames it missed (the simulator jumps ahead, a file source reads past them), so the next frame
processed is the newest one and no queue grows; skipped frames are counted. Requests from other threads
(servo modes, go-to, jog, tracker settings, a new rig) are queued and run in the worker between frames;
each returns a Future. A frame that raises is logged and counted, and the worker goes on. A source that
raises or blocks is a `source` fault in the status (tmeye/runtime/faults.py), retried with a back-off;
after it the pacing starts afresh (the frames missed meanwhile are not counted as skipped).
"""

from __future__ import annotations

import logging
import math
import queue
import threading
import time
from collections.abc import Callable
from concurrent.futures import Future
from typing import Any, TypeVar

from tmeye.runtime.compose import Composition, apply_tuning, compose, describe_source, rebuild_pipeline
from tmeye.runtime.config import RuntimeConfig, TrackerTuning
from tmeye.runtime.events import FrameEvent, ServoState
from tmeye.runtime.faults import SourceHealth
from tmeye.runtime.pointing import pixel_angles
from tmeye.runtime.publish import Hub
from tmeye.runtime.servo import ServoControl, ServoMode, ServoWish
from tmeye.runtime.stalls import StallLog
from tmeye.runtime.telemetry import detection_json, telemetry
from tracker.closedloop import LoopStep
from tracker.frames import StereoFrame
from tracker.geometry import StereoRig
from tracker.tracks import PrimaryBefore

log = logging.getLogger("tmeye.runtime")
R = TypeVar("R")
BETWEEN_FRAMES_MARGIN_S = 0.004  # work between frames ends this long before the next frame is due
# ... and starts this long after the frame is published: the telemetry WebSockets send it meanwhile, on
# the event loop, without this thread's Python code taking the interpreter's lock between theirs
BETWEEN_FRAMES_DELAY_S = 0.003


class Runtime:
    """Build with a config; `start()` composes the rig (ComposeError on a bad config) and starts the
    worker; `stop()` ends it and closes the source and the servo."""

    def __init__(self, config: RuntimeConfig, tuning: TrackerTuning | None = None):
        self.config = config
        self.tuning = tuning or TrackerTuning()
        self.hub: Hub[FrameEvent] = Hub()
        self.latest: FrameEvent | None = None
        self.state = "created"
        self.error: str | None = None
        self.frames = self.skipped = self.frame_errors = 0
        self.deferred_boxes = 0  # candidate boxes put off to the next frame by the time budget
        self.fps = 0.0
        self.comp: Composition | None = None
        self.servo: ServoControl | None = None
        self._requests: queue.SimpleQueue[tuple[Callable[[], Any], Future[Any]]] = queue.SimpleQueue()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._base = 0  # added to source frame indices (a rebuilt source starts again at 0)
        self._last_t: float | None = None
        self._last_done: float | None = None
        self.generation = 0
        self.stalls = StallLog()
        self._closing = False
        self.source_health = SourceHealth()
        self._resync = False

    @property
    def source_fault(self) -> str | None:
        """The frame source's fault now (it raises, or a read blocks), or None."""
        return self.source_health.fault()

    # --- life cycle ----------------------------------------------------------------------------------
    def start(self, rig: StereoRig | None = None) -> None:
        self.state = "starting"
        try:
            self.comp = compose(self.config, self.tuning, rig)
        except Exception as exc:
            self.state, self.error = "failed", str(exc)
            raise
        if self.comp.controller is not None:
            self.servo = ServoControl(self.comp.controller, self.comp.track_limits)
        self._thread = threading.Thread(target=self._run, name="tmeye-runtime", daemon=True)
        self.state = "running"
        self._thread.start()

    def stop(self, timeout: float = 3.0) -> None:
        """End the worker, then close the source and the servo (once, however often it is called)."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout)
        comp, self._closing = (None if self._closing else self.comp), True
        if comp is not None:
            comp.close()
        self.hub.close()
        if self.state == "running":
            self.state = "stopped"

    def join(self, timeout: float | None = None) -> None:
        if self._thread is not None:
            self._thread.join(timeout)

    @property
    def running(self) -> bool:
        return self._thread is not None and self._thread.is_alive()

    # --- requests (any thread) -----------------------------------------------------------------------
    def submit(self, fn: Callable[[], R]) -> Future[R]:
        """Run fn in the worker before the next frame; its result or exception comes in the Future."""
        fut: Future[R] = Future()
        if not self.running:
            fut.set_exception(RuntimeError("the tracker runtime is not running"))
            return fut
        self._requests.put((fn, fut))
        return fut

    def set_tuning(self, tuning: TrackerTuning) -> Future[None]:
        def apply() -> None:
            assert self.comp is not None
            apply_tuning(self.comp, tuning)
            self.tuning = tuning
        return self.submit(apply)

    def switch_rig(self, rig: StereoRig) -> Future[None]:
        """Build a pipeline for `rig` (background learnt anew) off the worker, then swap it in."""
        assert self.comp is not None
        comp = self.comp
        fut: Future[None] = Future()

        def build() -> None:
            try:
                new = rebuild_pipeline(comp, rig, self.tuning)
            except Exception as exc:
                fut.set_exception(exc)
                return
            swap = self.submit(lambda: self._install(comp, new))
            swap.add_done_callback(lambda f: fut.set_exception(e) if (e := f.exception()) else fut.set_result(None))

        threading.Thread(target=build, name="tmeye-rig-switch", daemon=True).start()
        return fut

    def _install(self, comp: Composition, new: Composition) -> None:
        """In the worker: a real source's new pipeline learns the background from the latest frame, then the stream."""
        if comp.sim is None:
            if self.latest is None:
                raise RuntimeError("no frame yet to learn the background from")
            new.pipeline.learn_background_from_stream(self.latest.frame)
        comp.rig, comp.pipeline, comp.loop = new.rig, new.pipeline, new.loop
        self.generation += 1
        if self.servo is not None and comp.controller is not None:
            self.servo.controller = comp.controller

    # --- status --------------------------------------------------------------------------------------
    def status(self, window_s: float = 60.0) -> dict[str, Any]:
        """The runtime's state; frame_gap_max_ms: the longest interval between published frames over the
        last window_s seconds (an open one included)."""
        ev = self.latest
        faults: list[dict[str, str]] = []
        if self.error:
            faults.append({"kind": "runtime", "message": self.error})
        if (source_fault := self.source_health.fault()) is not None and self.state == "running":
            faults.append({"kind": "source", "message": source_fault})
        if ev is not None and ev.servo is not None and ev.servo.fault:
            faults.append({"kind": "servo", "message": ev.servo.fault})
        servo = ev.servo.as_dict() if ev is not None and ev.servo is not None else None
        return {"state": self.state, "frame": ev.frame_no if ev else None, "fps": round(self.fps, 2),
                "frames_processed": self.frames, "skipped_frames": self.skipped, "frame_errors": self.frame_errors,
                "deferred_boxes": self.deferred_boxes,
                "reused_sigma": self.comp.pipeline.sigma_schedule.reused if self.comp else 0,
                "source_faults": self.source_health.faults,
                "source": describe_source(self.comp) if self.comp else {"kind": self.config.source},
                "servo": servo, "subscribers": self.hub.subscribers, "subscriptions": self.hub.stats(),
                "faults": faults,
                "frame_gap_max_ms": self.stalls.longest_ms(window_s, time.monotonic()) if self.state == "running"
                else None}

    # --- the worker ----------------------------------------------------------------------------------
    def _run(self) -> None:
        assert self.comp is not None
        period = 1.0 / self.comp.fps if self.config.realtime else 0.0
        t0, k = time.monotonic(), 0
        try:
            while not self._stop.is_set():
                self._apply_requests()
                if not self._one_frame():
                    break
                if self._resync:  # after a source fault: pace from the frame that ended it
                    t0, k, self._resync = time.monotonic(), 0, False
                    continue
                if self.config.max_frames is not None and self.frames >= self.config.max_frames:
                    break
                if period:
                    k += 1
                    self._between_frames(t0 + k * period)
                    late = time.monotonic() - (t0 + k * period)
                    if late < 0:
                        self._stop.wait(-late)
                    elif (behind := int(late / period)) > 0:
                        self._skip(behind)
                        k += behind
        except Exception as exc:  # a bug: keep the message for the status, end cleanly
            log.exception("runtime worker stopped")
            self.state, self.error = "failed", f"worker stopped: {exc}"
        finally:
            self._fail_requests()
            self.hub.close()  # subscribers see the end once they have read what is queued
            if self.state == "running":
                self.state = "ended" if not self._stop.is_set() else "stopped"

    def _one_frame(self) -> bool:
        comp = self.comp
        assert comp is not None
        if comp.sim is not None and comp.config.loop_source and comp.sim.exhausted:
            comp.sim.rewind()  # a finite scenario again from its start; frame times keep counting
        self.source_health.reading()
        try:
            frame = comp.source.read()
        except Exception as exc:  # a camera or stream error: reported, retried after a back-off
            self._stop.wait(self.source_health.failed(exc))
            self._resync = True
            return True
        if self.source_health.read():
            self._resync = True
        captured_at = time.time()  # a rendered or decoded frame exists from now on
        if frame is None:
            log.info("source ended after %d frames", self.frames)
            return False
        if comp.config.source in ("usb", "rtsp"):  # live stamps are time.monotonic()
            captured_at = time.time() - (time.monotonic() - frame.t)
        elif comp.config.source == "recording":  # replayed: the recorded capture time
            from tmeye.runtime.recording import RecordingSource  # PyAV only for replays

            assert isinstance(comp.source, RecordingSource)
            captured_at = comp.source.captured_at
        try:
            ev = self._process(frame, captured_at)
        except Exception as exc:
            self.frame_errors += 1
            log.warning("frame %d failed: %s", frame.index, exc, exc_info=self.frame_errors == 1)
            return True
        self.latest = ev
        self.hub.publish(ev)
        self.stalls.frame(time.monotonic())
        return True

    def _process(self, frame: StereoFrame, captured_at: float) -> FrameEvent:
        comp = self.comp
        assert comp is not None
        dt = 0.0 if self._last_t is None else max(frame.t - self._last_t, 0.0)
        self._last_t = frame.t
        if self.servo is not None:
            self.servo.tick(frame.t, dt)
        step = comp.loop.step(frame) if comp.loop is not None else None
        res = step.result if step is not None else comp.pipeline.step(frame)
        now = time.monotonic()
        if self._last_done is not None and now > self._last_done:
            rate = 1.0 / (now - self._last_done)  # frames processed per wall-clock second
            self.fps = rate if self.fps == 0 else 0.9 * self.fps + 0.1 * rate
        self._last_done = now
        self.frames += 1
        self.deferred_boxes += res.deferred_boxes
        servo = self._servo_state(step)
        frame_no = self._base + frame.index
        tm = telemetry(res, frame, self.fps, frame_no)
        tm["captured_at"] = round(captured_at, 6)
        tm["servo"] = None if servo is None else servo.as_dict()
        tm["detections"] = [detection_json(d, comp.pipeline.rect.f) for d in res.detections]
        if step is not None:
            tm["latency_ms"] = round(step.latency_ms, 3)
        return FrameEvent(frame_no, frame, res, step, servo, captured_at, time.time(), tm, self.generation)

    def _between_frames(self, due: float) -> None:
        """Work the pipeline does for the frame just published in the time before the next one is due
        (`due`, time.monotonic s; Pipeline.between_frames), ending BETWEEN_FRAMES_MARGIN_S before it."""
        assert self.comp is not None
        if due - time.monotonic() - BETWEEN_FRAMES_MARGIN_S <= BETWEEN_FRAMES_DELAY_S:
            return
        self._stop.wait(BETWEEN_FRAMES_DELAY_S)
        left = due - time.monotonic() - BETWEEN_FRAMES_MARGIN_S
        if left > 0 and not self._stop.is_set():
            try:
                self.comp.pipeline.between_frames(time.perf_counter() + left)
            except Exception:  # a bug: logged; the next frame is processed all the same
                log.warning("work between frames failed", exc_info=True)

    def _servo_state(self, step: LoopStep | None) -> ServoState | None:
        if step is None or self.servo is None:
            return None
        g = step.frame.gimbal
        pan, tilt = (g.pan_deg, g.tilt_deg) if g is not None else (math.nan, math.nan)
        return ServoState(str(self.servo.mode), pan, tilt, self.servo.goal, step.fault,
                          step.servo_json()["command"])  # type: ignore[arg-type]

    def _skip(self, n: int) -> None:
        comp = self.comp
        assert comp is not None
        self.skipped += n
        sim = comp.sim
        if sim is not None:  # the simulator jumps ahead (a pass that ends meanwhile is rewound at the next read)
            left = sim.scenario.frames - round(sim.scene_t * sim.scenario.fps)
            sim.index += n if sim.scenario.endless or comp.config.loop_source else min(n, left)
        elif comp.config.source == "files":
            for _ in range(n):
                if comp.source.read() is None:
                    break

    def _apply_requests(self) -> None:
        while True:
            try:
                fn, fut = self._requests.get_nowait()
            except queue.Empty:
                return
            if not fut.set_running_or_notify_cancel():
                continue
            try:
                fut.set_result(fn())
            except Exception as exc:
                fut.set_exception(exc)

    def _fail_requests(self) -> None:
        while True:
            try:
                _, fut = self._requests.get_nowait()
            except queue.Empty:
                return
            if fut.set_running_or_notify_cancel():
                fut.set_exception(RuntimeError("the tracker runtime stopped"))

    # --- servo requests ------------------------------------------------------------------------------
    # each servo request's Future holds the mode and goal from before it (servo_restore undoes it)
    def servo_mode(self, mode: ServoMode) -> Future[ServoWish]:
        return self._servo_request(lambda s: s.set_mode(mode))

    def servo_goto(self, pan_deg: float, tilt_deg: float) -> Future[ServoWish]:
        return self._servo_request(lambda s: s.goto(pan_deg, tilt_deg))

    def servo_jog(self, pan_dps: float, tilt_dps: float, duration_s: float) -> Future[ServoWish]:
        return self._servo_request(lambda s: s.jog(pan_dps, tilt_dps, duration_s))

    def servo_restore(self, wish: ServoWish) -> Future[ServoWish]:
        return self._servo_request(lambda s: s.restore(wish))

    def servo_point(self, camera: str, u: float, v: float) -> Future[tuple[float, float, ServoWish]]:
        """Point the mount so that what is seen at raw pixel (u, v) of `camera` comes to its centre: the
        angles, and the mode and goal from before."""
        return self.submit(lambda: self._point(camera, u, v))

    def _servo_request(self, change: Callable[[ServoControl], None]) -> Future[ServoWish]:
        def apply() -> ServoWish:
            servo = self._need_servo()
            before = servo.wish()
            change(servo)
            return before
        return self.submit(apply)

    def select_primary(self, track_id: int) -> Future[PrimaryBefore | None]:
        """Make a living track the primary target; the Future holds None if there is no such track, else
        what `restore_primary` undoes the choice with."""
        def apply() -> PrimaryBefore | None:
            assert self.comp is not None
            return self.comp.pipeline.tracker.select_primary(track_id)  # the loop's predictor starts afresh
        return self.submit(apply)

    def restore_primary(self, before: PrimaryBefore) -> Future[None]:
        """Undo `select_primary` (its audit record was refused): the primary target from before, followed
        afresh (tracker.closedloop.ServoLoop resets its predictor when the primary target changes)."""
        def apply() -> None:
            assert self.comp is not None
            self.comp.pipeline.tracker.restore_primary(before)
        return self.submit(apply)

    def _point(self, camera: str, u: float, v: float) -> tuple[float, float, ServoWish]:
        servo = self._need_servo()
        assert self.comp is not None
        pan, tilt = pixel_angles(self.comp, self.latest, camera, u, v)
        before = servo.wish()
        servo.goto(pan, tilt)
        return pan, tilt, before

    def _need_servo(self) -> ServoControl:
        if self.servo is None:
            raise NoServoError("no servo is configured (start with --servo sim or a driver URL)")
        return self.servo


class NoServoError(RuntimeError):
    """A servo request while the runtime drives no mount."""
