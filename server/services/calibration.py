"""Calibration records: uploads checked and stored, `tmeye calibrate` run in a worker process with its
progress lines published as events, the record completed with the rig file and report; activation
switches the runtime's rig without a restart.

Nothing is stored for an upload that fails the checks (board spec, pair counts, files that are not
images, sizes that differ): the images are written to a temporary folder that is renamed into place
only together with the record's commit."""

from __future__ import annotations

import asyncio
import hashlib
import json
import logging
import shutil
import sys
import tempfile
import time
from collections.abc import Sequence
from concurrent.futures import TimeoutError as FutureTimeout
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import cv2
import numpy as np
from sqlalchemy import select, update
from sqlalchemy.orm import Session, sessionmaker

from calibration.board import BoardSpec
from calibration.errors import CalibrationError
from calibration.stereo import MIN_VIEWS
from server.db.models import Calibration, User
from server.services import audit
from server.services.control import Unavailable, commit_or_undo
from server.services.errors import Conflict, Invalid, NotFound
from server.services.events import EventBus
from tmeye.runtime import Runtime
from tracker.geometry import StereoRig

MAX_PAIRS = 200
SWITCH_TIMEOUT_S = 120.0
log = logging.getLogger("tmeye.calibration")


@dataclass(frozen=True)
class Upload:
    name: str
    data: bytes


def check_upload(board: str, square: float, left: Sequence[Upload], right: Sequence[Upload]) -> BoardSpec:
    """The board spec, or Invalid naming the first problem (nothing is stored)."""
    try:
        spec = BoardSpec.parse(board, square)
    except CalibrationError as exc:
        raise Invalid(str(exc)) from None
    if len(left) != len(right):
        raise Invalid(f"{len(left)} left images but {len(right)} right images: upload them in pairs")
    if not MIN_VIEWS <= len(left) <= MAX_PAIRS:
        raise Invalid(f"upload {MIN_VIEWS} to {MAX_PAIRS} image pairs, got {len(left)}")
    size: tuple[int, int] | None = None
    for side, files in (("left", left), ("right", right)):
        for f in files:
            img = cv2.imdecode(np.frombuffer(f.data, np.uint8), cv2.IMREAD_GRAYSCALE) if f.data else None
            if img is None:
                raise Invalid(f"{side} file {f.name!r} is not an image OpenCV can read")
            shape = (img.shape[1], img.shape[0])
            if size is not None and shape != size:
                raise Invalid(f"{side} image {f.name!r} is {shape[0]}x{shape[1]}, the others {size[0]}x{size[1]}")
            size = shape
    return spec


def _ext(name: str) -> str:
    ext = Path(name).suffix.lower()
    return ext if ext in (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff", ".pgm", ".ppm") else ".png"


class CalibrationJobs:
    """Starts and tracks calibration worker processes (one at a time)."""

    def __init__(self, sessions: sessionmaker[Session], data_dir: Path, events: EventBus):
        self.sessions, self.root, self.events = sessions, data_dir / "calibration", events
        self.root.mkdir(parents=True, exist_ok=True)
        self.tasks: set[asyncio.Task[None]] = set()

    def upload(self, user: User, address: str, board: str, square: float, left: Sequence[Upload],
               right: Sequence[Upload]) -> dict[str, Any]:
        """Check an upload and store it as a running record (in a thread: decoding images is CPU work)."""
        spec = check_upload(board, square, left, right)
        with self.sessions() as db:
            return as_json(self.create(db, user, address, spec, left, right))

    def create(self, db: Session, user: User, address: str, spec: BoardSpec, left: Sequence[Upload],
               right: Sequence[Upload]) -> Calibration:
        if self.tasks:
            raise Conflict("a calibration is already running; wait for it to finish")
        tmp = Path(tempfile.mkdtemp(prefix=".upload-", dir=self.root))
        try:
            hashes = []
            for i, (lf, rf) in enumerate(zip(left, right, strict=True)):
                (tmp / f"left_{i:03d}{_ext(lf.name)}").write_bytes(lf.data)
                (tmp / f"right_{i:03d}{_ext(rf.name)}").write_bytes(rf.data)
                hashes.append([hashlib.sha256(lf.data).hexdigest(), hashlib.sha256(rf.data).hexdigest()])
            rec = Calibration(created_at=time.time(), created_by=user.id, status="running", board_cols=spec.cols,
                              board_rows=spec.rows, square_m=spec.square, image_hashes=hashes, image_dir="")
            db.add(rec)
            db.flush()
            final = self.root / f"{rec.id:05d}"
            rec.image_dir = str(final)
            audit.record(db, user, address, "calibration.create", str(rec.id), {"pairs": len(left)})
            tmp.rename(final)
            try:
                db.commit()
            except Exception:
                final.rename(tmp)
                raise
        except BaseException:
            db.rollback()
            shutil.rmtree(tmp, ignore_errors=True)
            raise
        return rec

    def start(self, rec_id: int) -> None:
        task = asyncio.get_running_loop().create_task(self._run(rec_id))
        self.tasks.add(task)
        task.add_done_callback(self.tasks.discard)

    async def _run(self, rec_id: int) -> None:
        folder = await asyncio.to_thread(self._folder_and_board, rec_id)
        d, board, square = folder
        cmd = [sys.executable, "-m", "tmeye", "calibrate", "--left", str(d / "left_*"), "--right",
               str(d / "right_*"), "--board", board, "--square", repr(square), "--out", str(d / "rig.json"), "--json"]
        proc = await asyncio.create_subprocess_exec(*cmd, stdout=asyncio.subprocess.PIPE,
                                                    stderr=asyncio.subprocess.PIPE)
        last = ""
        assert proc.stderr is not None and proc.stdout is not None
        out_task = asyncio.create_task(proc.stdout.read())
        async for raw in proc.stderr:
            last = raw.decode(errors="replace").strip() or last
            self.events.publish("calibration.progress", id=rec_id, message=last)
        out = await out_task
        code = await proc.wait()
        ok = code == 0
        await asyncio.to_thread(self._finish, rec_id, d, ok, out.decode(errors="replace"), last)
        self.events.publish("calibration.done" if ok else "calibration.failed", id=rec_id,
                            message=None if ok else last)

    def _folder_and_board(self, rec_id: int) -> tuple[Path, str, float]:
        with self.sessions() as db:
            rec = get(db, rec_id)
            return Path(rec.image_dir), f"{rec.board_cols}x{rec.board_rows}", rec.square_m

    def _finish(self, rec_id: int, d: Path, ok: bool, stdout: str, last: str) -> None:
        with self.sessions() as db, db.begin():
            rec = get(db, rec_id)
            rec.finished_at = time.time()
            if ok:
                rec.report = json.loads(stdout.strip().splitlines()[-1])
                rec.rig = json.loads((d / "rig.json").read_text())
                rec.status = "done"
            else:
                rec.status, rec.error = "failed", last.removeprefix("tmeye calibrate: error: ") or "calibration failed"

    async def close(self) -> None:
        for t in list(self.tasks):
            t.cancel()


def mark_interrupted(db: Session) -> None:
    """At start-up: records left running by a previous process failed with it."""
    db.execute(update(Calibration).where(Calibration.status == "running")
               .values(status="failed", error="interrupted: the server stopped during the calibration",
                       finished_at=time.time()))
    db.commit()


def get(db: Session, rec_id: int) -> Calibration:
    rec = db.get(Calibration, rec_id)
    if rec is None:
        raise NotFound(f"no calibration record with id {rec_id}")
    return rec


def list_records(db: Session) -> list[Calibration]:
    return list(db.scalars(select(Calibration).order_by(Calibration.id.desc())))


def rig_of(rec: Calibration) -> StereoRig:
    """The record's rig (the rig file's JSON, as `tmeye calibrate` wrote it)."""
    if rec.status != "done" or rec.rig is None:
        raise Conflict(f"calibration {rec.id} is {rec.status}: only a finished calibration can be used")
    try:
        return StereoRig.from_dict(rec.rig)
    except (KeyError, TypeError, AssertionError, ValueError) as exc:
        raise Invalid(f"calibration {rec.id}'s rig is missing or has a malformed field: {exc}") from None


def active_rig(db: Session) -> StereoRig | None:
    rec = db.scalar(select(Calibration).where(Calibration.active.is_(True)))
    return None if rec is None else rig_of(rec)


def activate(db: Session, runtime: Runtime, rec: Calibration, user: User, address: str) -> None:
    """Switch the runtime to the record's rig (the new pipeline learns its background first), then mark
    the record active. Should that commit fail (a disk full at that moment), the runtime is switched back
    to the rig from before: no rig is used without its audit record. (The record is not written first, as
    the other control actions' are: SQLite's write lock, held through a switch of up to 120 s, would stall
    the track writer.)"""
    rig = rig_of(rec)
    assert runtime.comp is not None
    before = runtime.comp.rig
    try:
        runtime.switch_rig(rig).result(timeout=SWITCH_TIMEOUT_S)
    except FutureTimeout:
        raise Unavailable("the tracker did not switch rig in time") from None
    except Exception as exc:
        raise Invalid(f"calibration {rec.id}'s rig cannot be used: {exc}") from None
    db.execute(update(Calibration).values(active=False))
    rec.active = True
    audit.record(db, user, address, "calibration.activate", str(rec.id))
    commit_or_undo(db, lambda: runtime.switch_rig(before), SWITCH_TIMEOUT_S)


def as_json(rec: Calibration, report: bool = False) -> dict[str, Any]:
    return {"id": rec.id, "created_at": rec.created_at, "created_by": rec.created_by, "status": rec.status,
            "board": f"{rec.board_cols}x{rec.board_rows}", "square_m": rec.square_m, "images": len(rec.image_hashes),
            "image_hashes": rec.image_hashes, "error": rec.error, "finished_at": rec.finished_at,
            "active": rec.active, "report": rec.report if report else None}
