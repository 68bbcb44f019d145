"""Exports: a time range of recordings as a zip of one MP4 per camera (the segments' packets remuxed, not
encoded again: the clip starts on the keyframe at or before `start`) and the telemetry of the range as
CSV and JSON. Jobs run one at a time in a worker thread; the row carries status and progress."""

from __future__ import annotations

import csv
import io
import json
import logging
import time
import zipfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

import av
from sqlalchemy import select, update
from sqlalchemy.orm import Session, sessionmaker

from server.db.models import Export, Segment, User
from server.services.errors import Invalid, NotFound
from server.services.segments import list_segments, telemetry_range
from tmeye.media.encoder import CLOCK_HZ

log = logging.getLogger("tmeye.exports")
MAX_RANGE_S = 24 * 3600.0
CSV_FIELDS = ("frame", "captured_at", "detected", "track_id", "objects", "x", "y", "z", "r", "theta_deg", "phi_deg",
              "sigma_r", "sigma_theta_deg", "sigma_phi_deg", "servo_mode", "pan_deg", "tilt_deg")


def mark_interrupted(db: Session) -> None:
    db.execute(update(Export).where(Export.status.in_(("queued", "running")))
               .values(status="failed", error="interrupted by a server stop", finished_at=time.time()))
    db.commit()


def get_export(db: Session, export_id: int) -> Export:
    row = db.get(Export, export_id)
    if row is None:
        raise NotFound(f"no export with id {export_id}")
    return row


def first_key(segs: list[Segment], t0: int) -> int:
    """The absolute pts of the keyframe at or before t0 (90 kHz ticks), or the first frame after it."""
    seg = segs[0]
    keys = [seg.start_pts + round(k * CLOCK_HZ) for k in seg.keyframes] or [seg.start_pts]
    before = [k for k in keys if k <= t0]
    return int(before[-1] if before else keys[0])


def remux(segs: list[Segment], data_dir: Path, out_path: Path, start: float, end: float) -> dict[int, float]:
    """Write the packets of `segs` (one camera, in time order) from the keyframe at or before `start` to the
    last frame at or before `end` into one MP4; returns {absolute pts: time in the clip (s)} of its frames."""
    t1 = round(end * CLOCK_HZ)
    base = first_key(segs, round(start * CLOCK_HZ))
    times: dict[int, float] = {}
    with av.open(str(out_path), "w", format="mp4", options={"movflags": "+faststart"}) as out:
        ost = None
        for seg in segs:
            with av.open(str(data_dir / seg.path)) as src:
                ist = src.streams.video[0]
                ost = ost or out.add_stream_from_template(ist)
                try:
                    for pkt in src.demux(ist):
                        pts = None if pkt.pts is None or pkt.size == 0 else seg.start_pts + int(pkt.pts)
                        if pts is None or pts < base or pts in times:
                            continue
                        if pts > t1:
                            break
                        pkt.pts = pkt.dts = pts - base
                        pkt.stream = ost
                        out.mux(pkt)
                        times[pts] = (pts - base) / CLOCK_HZ
                except av.error.InvalidDataError:
                    pass  # a segment cut by a crash ends at its last complete fragment
    return times


def telemetry_files(rows: list[dict[str, Any]], times: dict[str, dict[int, float]]) -> tuple[str, str]:
    """CSV (one line per frame: the primary target and the servo, and each clip's time of the frame) and JSON
    (every message whole, with the clips' times)."""
    buf = io.StringIO()
    cams = sorted(times)
    w = csv.writer(buf)
    w.writerow([*CSV_FIELDS, *(f"{c}_clip_t" for c in cams)])
    out = []
    for tm in rows:
        pts = round(float(tm["captured_at"]) * CLOCK_HZ)
        clip = {c: times[c].get(pts) for c in cams}
        servo = tm.get("servo") or {}
        line = [tm.get(k) for k in CSV_FIELDS[:14]] + [servo.get("mode"), servo.get("pan_deg"), servo.get("tilt_deg")]
        w.writerow(["" if v is None else v for v in line] + ["" if clip[c] is None else f"{clip[c]:.6f}"
                                                            for c in cams])
        out.append({**tm, "clip_t": clip})
    return buf.getvalue(), json.dumps(out, separators=(",", ":"))


class ExportJobs:
    def __init__(self, sessions: sessionmaker[Session], data_dir: Path):
        self.sessions, self.data_dir = sessions, data_dir
        self.pool = ThreadPoolExecutor(1, thread_name_prefix="tmeye-export")

    def create(self, db: Session, user: User, start: float, end: float, cameras: list[str]) -> Export:
        if not end > start:
            raise Invalid("end must be after start")
        if end - start > MAX_RANGE_S:
            raise Invalid(f"an export spans at most {MAX_RANGE_S / 3600:.0f} h")
        if not list_segments(db, None, start, end, 1):
            raise Invalid(f"nothing was recorded between {start:.3f} and {end:.3f}")
        row = Export(status="queued", progress=0.0, start=start, end=end, cameras=sorted(set(cameras)),
                     created_at=time.time(), created_by=user.id)
        db.add(row)
        db.commit()
        self.pool.submit(self._run, row.id)
        return row

    def close(self) -> None:
        self.pool.shutdown(wait=True, cancel_futures=True)

    def _set(self, export_id: int, **values: Any) -> None:
        with self.sessions() as db, db.begin():
            db.execute(update(Export).where(Export.id == export_id).values(**values))

    def _run(self, export_id: int) -> None:
        try:
            size = self._build(export_id)
            self._set(export_id, status="done", progress=1.0, path=f"exports/{export_id}.zip", bytes=size,
                      finished_at=time.time())
        except Exception as exc:
            log.exception("export %d failed", export_id)
            self._set(export_id, status="failed", error=str(exc).splitlines()[0] if str(exc) else type(exc).__name__,
                      finished_at=time.time())

    def _build(self, export_id: int) -> int:
        self._set(export_id, status="running")
        with self.sessions() as db:
            job = get_export(db, export_id)
            plan = {c: list(db.scalars(select(Segment).where(Segment.camera == c, Segment.status != "open",
                                                             Segment.start <= job.end, Segment.end >= job.start)
                                       .order_by(Segment.start))) for c in job.cameras}
            rows = telemetry_range(db, job.start, job.end, 10_000_000)
        work = self.data_dir / "exports" / str(export_id)
        work.mkdir(parents=True, exist_ok=True)
        times: dict[str, dict[int, float]] = {}
        for i, (cam, segs) in enumerate(plan.items()):
            if segs:
                times[cam] = remux(segs, self.data_dir, work / f"{cam}.mp4", job.start, job.end)
            self._set(export_id, progress=round(0.9 * (i + 1) / len(plan), 3))
        csv_text, json_text = telemetry_files(rows, times)
        zpath = self.data_dir / "exports" / f"{export_id}.zip"
        with zipfile.ZipFile(zpath, "w") as z:
            for cam in times:
                z.write(work / f"{cam}.mp4", f"{cam}.mp4", compress_type=zipfile.ZIP_STORED)
                (work / f"{cam}.mp4").unlink()
            z.writestr("telemetry.csv", csv_text, compress_type=zipfile.ZIP_DEFLATED)
            z.writestr("telemetry.json", json_text, compress_type=zipfile.ZIP_DEFLATED)
        work.rmdir()
        return zpath.stat().st_size
