"""The tracks' summaries (server.services.tracks.TrackBook), pure and alone: the peak speed is the speed of
a least-squares line through a second of positions, so the noise of single positions does not make it; and
their writing (flush, on a real SQLite file): a track only once it was seen in MIN_DETECTIONS frames."""

from __future__ import annotations

import asyncio
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from sqlalchemy import select

from server.db.engine import make_engine, session_factory, upgrade
from server.db.models import Track, TrackPoint
from server.services.tracks import MIN_DETECTIONS, TrackBook, fitted_speed, flush

FPS = 30.0


def _feed(book: TrackBook, positions: np.ndarray, t0: float = 1.7e9) -> None:
    """One telemetry message a frame at FPS, one detection (track 1) at each position (x, y, z) m."""
    for i, (x, y, z) in enumerate(positions):
        r = math.sqrt(x * x + y * y + z * z)
        book.add({"captured_at": t0 + i / FPS, "detections": [
            {"track_id": 1, "x": x, "y": y, "z": z, "r": r, "theta_deg": 0.0, "phi_deg": 0.0, "size_m": [0.5, 1.7]}]})


def _walk(speeds: list[tuple[float, float]], sigma: float, seed: int = 0) -> np.ndarray:
    """Positions at FPS of a target 8 m ahead moving along x at each (speed m/s, for s) in turn, with
    Gaussian noise of sigma (m) on every coordinate."""
    v = np.concatenate([np.full(int(round(d * FPS)), s) for s, d in speeds])
    x = np.concatenate([[0.0], np.cumsum(v[1:] / FPS)])
    p = np.stack([x, np.full_like(x, 0.2), np.full_like(x, 8.0)], axis=1)
    return p + np.random.default_rng(seed).normal(0.0, sigma, p.shape)


def test_fitted_speed_of_a_straight_line_and_of_too_few_points() -> None:
    pts = [(t, 1.0 + 3.0 * t, 2.0, 5.0 - 4.0 * t) for t in np.linspace(0.0, 1.0, 7)]
    assert fitted_speed(pts) == pytest.approx(5.0, rel=1e-12)
    assert fitted_speed(pts[:1]) == 0.0
    assert fitted_speed([(1.0, 0.0, 0.0, 0.0), (1.0, 5.0, 0.0, 0.0)]) == 0.0  # no time between them


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_walker_with_noisy_positions_peaks_near_its_walking_speed(seed: int) -> None:
    # 1.4 m/s with 0.1 m of noise a coordinate: differences of positions 2 frames apart made 5 m/s of it
    book = TrackBook(sample_hz=10.0)
    _feed(book, _walk([(1.4, 10.0)], sigma=0.1, seed=seed))
    tr = book.tracks[(0, 1)]
    assert 1.3 <= tr.peak_speed_mps <= 1.8
    assert tr.detections == 300


def test_a_still_target_has_no_speed_to_speak_of() -> None:
    book = TrackBook(sample_hz=10.0)
    _feed(book, _walk([(0.0, 10.0)], sigma=0.1))
    assert book.tracks[(0, 1)].peak_speed_mps < 0.4


def test_a_sprint_of_a_second_and_a_half_is_its_peak() -> None:
    book = TrackBook(sample_hz=10.0)
    _feed(book, _walk([(0.0, 2.0), (6.0, 1.5), (1.0, 3.0)], sigma=0.02))
    assert book.tracks[(0, 1)].peak_speed_mps == pytest.approx(6.0, abs=0.3)


def test_no_speed_before_half_a_second_of_positions() -> None:
    book = TrackBook(sample_hz=10.0)
    _feed(book, _walk([(3.0, 0.4)], sigma=0.0))
    assert book.tracks[(0, 1)].peak_speed_mps == 0.0


def test_a_track_is_written_once_seen_in_enough_frames_and_a_short_one_never(tmp_path: Path) -> None:
    # a real SQLite file built by the migrations
    url = f"sqlite:///{tmp_path / 'tmeye.db'}"
    upgrade(url)
    sessions = session_factory(make_engine(url))
    book = TrackBook(sample_hz=10.0)
    t0 = 1.7e9
    walker = _walk([(1.4, 2.0)], sigma=0.0)

    def frame(i: int, with_blip: bool) -> dict[str, Any]:
        dets = [{"track_id": 1, "x": walker[i][0], "y": 0.2, "z": 8.0, "r": 8.0, "theta_deg": 0.0, "phi_deg": 0.0}]
        if with_blip:  # a blip of noise: track 2, three frames
            dets.append({"track_id": 2, "x": 3.0, "y": 0.0, "z": 20.0, "r": 20.2, "theta_deg": 8.5, "phi_deg": 0.0})
        return {"captured_at": t0 + i / FPS, "detections": dets}

    for i in range(MIN_DETECTIONS - 1):
        book.add(frame(i, with_blip=i < 3))
    assert flush(sessions, "run", book) == 0  # neither was seen in MIN_DETECTIONS frames yet
    for i in range(MIN_DETECTIONS - 1, len(walker)):
        book.add(frame(i, with_blip=False))
    written = flush(sessions, "run", book)
    with sessions() as db:
        rows = list(db.scalars(select(Track)))
        points = list(db.scalars(select(TrackPoint)))
    assert [(r.track_no, r.detections) for r in rows] == [(1, len(walker))]
    assert written == len(points) == 20  # 2 s at 10 Hz, the first frames' samples kept while it waited
    assert points[0].t == pytest.approx(t0)
    book.forget_before(t0 + 100.0)
    assert book.tracks == {}  # the short one too: it would never be written


def test_tracks_wait_in_memory_while_the_database_is_locked_and_are_written_after(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch, caplog: pytest.LogCaptureFixture) -> None:
    # another connection holds the write lock past the busy timeout (shortened here): nothing is written,
    # nothing is lost, the failure is one warning line (a device condition, not a bug), and the next flush
    # writes everything
    import sqlite3

    from server.db import engine as db_engine
    from server.services.tracks import TrackWriter

    monkeypatch.setattr(db_engine, "BUSY_TIMEOUT_MS", 200)
    url = f"sqlite:///{tmp_path / 'tmeye.db'}"
    upgrade(url)
    writer = TrackWriter(None, session_factory(make_engine(url)), sample_hz=10.0, flush_s=1.0)  # type: ignore[arg-type]
    _feed(writer.book, _walk([(1.4, 2.0)], sigma=0.0))
    holder = sqlite3.connect(tmp_path / "tmeye.db")
    holder.execute("BEGIN IMMEDIATE")
    with caplog.at_level("WARNING", logger="tmeye.tracks"):
        asyncio.run(writer._flush())
    assert writer.errors == 1 and writer.written == 0
    assert [r.levelname for r in caplog.records] == ["WARNING"]
    assert caplog.records[0].exc_info is None and "database is locked" in caplog.records[0].getMessage()
    holder.rollback()
    holder.close()
    asyncio.run(writer._flush())
    with session_factory(make_engine(url))() as db:
        assert [t.detections for t in db.scalars(select(Track))] == [60]
        assert len(list(db.scalars(select(TrackPoint)))) == writer.written == 20


def test_a_bug_after_a_locked_database_still_logs_its_traceback(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch, caplog: pytest.LogCaptureFixture) -> None:
    from sqlalchemy.exc import OperationalError

    import server.services.tracks as tracks

    writer = tracks.TrackWriter(None, None, sample_hz=10.0, flush_s=1.0)  # type: ignore[arg-type]
    errors = iter([OperationalError("UPDATE tracks", {}, Exception("database is locked")), ValueError("a bug"),
                   ValueError("the same bug")])

    def failing(*_a: object) -> int:
        raise next(errors)

    monkeypatch.setattr(tracks, "flush", failing)
    with caplog.at_level("WARNING", logger="tmeye.tracks"):
        for _ in range(3):
            asyncio.run(writer._flush())
    assert [(r.levelname, r.exc_info is not None) for r in caplog.records] == [
        ("WARNING", False), ("ERROR", True), ("WARNING", False)]
