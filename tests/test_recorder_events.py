"""The recorder in events mode, fed real H.264 packets (libx264, stamped frames) and telemetry with detections
at known frames, writing to a real SQLite database made by the migrations: footage from the pre-roll (from
the packet ring, starting on a keyframe) to the post-roll after the last detection, nothing else; frames
decode with their stamps and have their telemetry."""

from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np
from sqlalchemy import select

from server.db.engine import make_engine, session_factory, upgrade
from server.db.models import RecordedFrame, Segment
from server.services.recorder import Recorder, RecorderConfig
from tmeye.media.encoder import EncodedFrame, H264Encoder, pts_of, stamp
from tmeye.media.pipeline import CAMERAS
from tmeye.recordcheck import decode_stamps
from tmeye.runtime.publish import Hub

T0 = 1_795_000_000.0
FPS, GOP = 30.0, 15  # keyframes every 0.5 s
EVENTS = set(range(150, 180)) | set(range(400, 411))  # frames with a detection


class Media:
    """The media pipeline's side the recorder uses: packet hubs, the recorder count, keyframe requests."""

    def __init__(self) -> None:
        self.packets: dict[str, Hub[EncodedFrame]] = {c: Hub() for c in CAMERAS}
        self.recorders = 0
        self.key = {c: True for c in CAMERAS}

    def request_keyframe(self, camera: str) -> None:
        self.key[camera] = True


def feed(media: Media, runtime: Any, frames: int, events: set[int] = EVENTS,
         hook: Callable[[int, float], None] | None = None) -> None:
    enc = {c: H264Encoder(160, 128, FPS, 300_000, GOP) for c in CAMERAS}
    base = (np.random.default_rng(0).random((128, 160)) * 80).astype(np.uint8)
    for i in range(frames):
        t = T0 + i / FPS
        tm = {"frame": i, "captured_at": round(t, 6), "detections": [{"track_id": 1}] if i in events else []}
        if hook is not None:
            hook(i, t)
        runtime.hub.publish(SimpleNamespace(frame_no=i, captured_at=t, telemetry=tm))
        for c in CAMERAS:
            key, media.key[c] = media.key[c], False
            for data, pts, is_key in enc[c].encode(stamp(base, i), pts_of(t), key):
                media.packets[c].publish(EncodedFrame(c, data, pts, is_key, i, t))
        time.sleep(1 / 120)


def events_recorder(tmp_path: Path) -> tuple[Media, Any, Any, Recorder]:
    """A started recorder in events mode (2 s pre- and post-roll) on a migrated database in tmp_path."""
    url = f"sqlite:///{tmp_path}/tmeye.db"
    upgrade(url)
    sessions = session_factory(make_engine(url))
    media, runtime = Media(), SimpleNamespace(hub=Hub())
    rec = Recorder(media, runtime, sessions, tmp_path,  # type: ignore[arg-type]
                   RecorderConfig(mode="events", segment_s=10.0, preroll_s=2.0, postroll_s=2.0, min_free_mb=0))
    rec.start()
    return media, runtime, sessions, rec


def test_events_mode_records_pre_and_post_roll_only(tmp_path: Path) -> None:
    media, runtime, sessions, rec = events_recorder(tmp_path)
    assert media.recorders == 1
    feed(media, runtime, 520)
    time.sleep(0.5)
    rec.stop()
    with sessions() as db:
        segs = list(db.scalars(select(Segment).order_by(Segment.start, Segment.camera)))
        stored = set(db.scalars(select(RecordedFrame.frame_no)))
    assert [s.camera for s in segs] == ["left", "right", "left", "right"]
    assert all(s.kind == "event" and s.status == "closed" for s in segs)
    for s in segs:
        nos = s.frame_nos
        assert nos == list(range(nos[0], nos[-1] + 1))  # no frame lost inside a segment
        stamps, err = decode_stamps((tmp_path / s.path).read_bytes())
        assert err is None and [v for _, v in stamps] == nos and s.keyframes[0] == 0.0
        assert stored >= set(nos)
    first, second = segs[0].frame_nos, segs[2].frame_nos
    # pre-roll: from the newest keyframe at least 2 s (60 frames) before the first detection
    assert first[0] % GOP == 0 and 150 - 60 - GOP < first[0] <= 150 - 60
    assert first[-1] == 179 + 60  # post-roll: 2 s after the last detection
    assert second[0] % GOP == 0 and 400 - 60 - GOP < second[0] <= 400 - 60 and second[-1] == 410 + 60
    assert stored == set(first) | set(second)  # telemetry only of recorded frames


def test_an_alarm_activation_is_recorded_in_events_mode(tmp_path: Path) -> None:
    """No detection at all: the activation (Recorder.event, what the alarm service calls) alone keeps the
    pre-roll before it and the post-roll after it."""
    media, runtime, sessions, rec = events_recorder(tmp_path)
    feed(media, runtime, 420, events=set(), hook=lambda i, t: rec.event(t) if i == 300 else None)
    time.sleep(0.5)
    rec.stop()
    with sessions() as db:
        segs = list(db.scalars(select(Segment).order_by(Segment.start, Segment.camera)))
    assert [s.camera for s in segs] == ["left", "right"] and all(s.kind == "event" for s in segs)
    nos = segs[0].frame_nos
    assert nos[0] % GOP == 0 and 300 - 60 - GOP < nos[0] <= 300 - 60 and nos[-1] == 300 + 60
