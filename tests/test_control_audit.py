"""Control actions and their audit records (server.services.control) on a real runtime (simulated rig and
gimbal) and a real SQLite file built by the migrations: an action whose audit record cannot be stored is
not done. A refused commit (a disk full at that moment) undoes the runtime request it followed: the mode and
goal, or the tracker settings, are those from before, and no audit row is stored; a refused request stores
nothing either."""

from __future__ import annotations

import time
from collections.abc import Iterator
from pathlib import Path

import pytest
from sqlalchemy import func, select
from sqlalchemy.exc import OperationalError
from sqlalchemy.orm import Session

from server.db.engine import make_engine, session_factory, upgrade
from server.db.models import AuditEntry, SettingsChange, User
from server.services import control
from server.services.errors import Invalid
from tmeye.runtime import Runtime, RuntimeConfig, ServoMode


class DiskFullAtCommit(Session):
    """A session whose commits fail as SQLite's do when the disk fills while the WAL is written."""

    def commit(self) -> None:
        raise OperationalError("COMMIT", {}, Exception("database or disk is full"))


@pytest.fixture(scope="module")
def rt() -> Iterator[Runtime]:
    runtime = Runtime(RuntimeConfig(scenario="walk", servo="sim", realtime=True, loop_source=True))
    runtime.start()
    yield runtime
    runtime.stop()


@pytest.fixture
def db_url(tmp_path: Path) -> str:
    url = f"sqlite:///{tmp_path / 'tmeye.db'}"
    upgrade(url)
    with session_factory(make_engine(url))() as db:
        db.add(User(username="olga", password_hash="x", role="operator", created_at=time.time(),
                    password_changed_at=time.time()))
        db.commit()
    return url


def _rows(url: str) -> tuple[int, int]:
    with session_factory(make_engine(url))() as db:
        return (int(db.scalar(select(func.count()).select_from(AuditEntry)) or 0),
                int(db.scalar(select(func.count()).select_from(SettingsChange)) or 0))


def _user(db: Session) -> User:
    user = db.scalar(select(User).where(User.username == "olga"))
    assert user is not None
    return user


def test_a_servo_action_whose_audit_cannot_be_committed_is_undone(rt: Runtime, db_url: str) -> None:
    assert rt.servo is not None
    with Session(make_engine(db_url)) as db:
        control.set_mode(db, rt, _user(db), "10.0.0.9", "auto")
    assert rt.servo.wish() == (ServoMode.AUTO, None) and _rows(db_url) == (1, 0)
    with DiskFullAtCommit(make_engine(db_url)) as db:
        user = _user(db)
        with pytest.raises(OperationalError):
            control.goto(db, rt, user, "10.0.0.9", 25.0, 6.0)
        assert rt.servo.wish() == (ServoMode.AUTO, None)  # back to following the target
        with pytest.raises(OperationalError):
            control.jog(db, rt, user, "10.0.0.9", 20.0, 0.0, 1.0)
        assert rt.servo.wish() == (ServoMode.AUTO, None)
    with Session(make_engine(db_url)) as db:
        control.goto(db, rt, _user(db), "10.0.0.9", -10.0, 2.0)
    assert rt.servo.wish() == (ServoMode.MANUAL, (-10.0, 2.0)) and _rows(db_url) == (2, 0)
    with DiskFullAtCommit(make_engine(db_url)) as db, pytest.raises(OperationalError):
        control.set_mode(db, rt, _user(db), "10.0.0.9", "home")
    assert rt.servo.wish() == (ServoMode.MANUAL, (-10.0, 2.0))  # the goal from before, not home
    with Session(make_engine(db_url)) as db, pytest.raises(Invalid):  # refused by the runtime: nothing stored
        control.goto(db, rt, _user(db), "10.0.0.9", 400.0, 0.0)
    assert rt.servo.wish() == (ServoMode.MANUAL, (-10.0, 2.0)) and _rows(db_url) == (2, 0)
    with Session(make_engine(db_url)) as db:
        control.set_mode(db, rt, _user(db), "10.0.0.9", "auto")


def test_tracker_settings_whose_record_cannot_be_committed_are_undone(rt: Runtime, db_url: str) -> None:
    eps = rt.tuning.as_dict()["detector"]["epsilon"]
    with DiskFullAtCommit(make_engine(db_url)) as db, pytest.raises(OperationalError):
        control.update_tuning(db, rt, _user(db), "10.0.0.9", {"detector": {"epsilon": eps + 3}})
    assert rt.tuning.as_dict()["detector"]["epsilon"] == eps and _rows(db_url) == (0, 0)
    with Session(make_engine(db_url)) as db:
        control.update_tuning(db, rt, _user(db), "10.0.0.9", {"detector": {"epsilon": eps + 3}})
    assert rt.tuning.as_dict()["detector"]["epsilon"] == eps + 3 and _rows(db_url) == (1, 1)
    with Session(make_engine(db_url)) as db:
        control.update_tuning(db, rt, _user(db), "10.0.0.9", {"detector": {"epsilon": eps}})


def _other_live_track(runtime: Runtime) -> tuple[int, int]:
    """The primary target and another track seen in the last frame, once the scene has two."""
    assert runtime.comp is not None
    deadline = time.monotonic() + 20.0
    while time.monotonic() < deadline:
        tracker = runtime.comp.pipeline.tracker
        primary, live = tracker.primary_id, [tr.track_id for tr in list(tracker.tracks) if tr.missed == 0]
        others = [t for t in live if t != primary]
        if primary in live and others:
            return primary, others[0]
        time.sleep(0.05)
    raise AssertionError("the two-targets scene never showed two tracks")


def test_a_primary_choice_whose_audit_cannot_be_committed_is_undone(db_url: str) -> None:
    runtime = Runtime(RuntimeConfig(scenario="two-targets", realtime=True, loop_source=True))
    runtime.start()
    try:
        assert runtime.comp is not None
        primary, other = _other_live_track(runtime)
        with DiskFullAtCommit(make_engine(db_url)) as db, pytest.raises(OperationalError):
            control.select_primary(db, runtime, _user(db), "10.0.0.9", other)
        assert runtime.comp.pipeline.tracker.primary_id == primary and _rows(db_url) == (0, 0)
        with Session(make_engine(db_url)) as db:
            control.select_primary(db, runtime, _user(db), "10.0.0.9", other)
        assert runtime.comp.pipeline.tracker.primary_id == other and _rows(db_url) == (1, 0)
    finally:
        runtime.stop()


def test_a_rig_switch_whose_audit_cannot_be_committed_is_switched_back(rt: Runtime, db_url: str) -> None:
    from server.db.models import Calibration
    from server.services import calibration

    assert rt.comp is not None
    before = rt.comp.rig
    new = before.to_dict()
    for side in ("left", "right"):  # the lens centres 1 % farther apart: another rig
        new[side]["c"] = [float(v) * 1.01 for v in new[side]["c"]]  # type: ignore[index]
    new["baseline_m"] = 1.01 * before.baseline
    with Session(make_engine(db_url)) as db:
        db.add(Calibration(created_at=time.time(), status="done", board_cols=9, board_rows=6, square_m=0.025,
                           image_hashes=[], image_dir="", rig=new, active=False))
        db.commit()
    with DiskFullAtCommit(make_engine(db_url)) as db, pytest.raises(OperationalError):
        rec = db.scalars(select(Calibration)).one()
        calibration.activate(db, rt, rec, _user(db), "10.0.0.9")
    assert rt.comp.rig.baseline == pytest.approx(before.baseline) and _rows(db_url) == (0, 0)
    with Session(make_engine(db_url)) as db:
        rec = db.scalars(select(Calibration)).one()
        calibration.activate(db, rt, rec, _user(db), "10.0.0.9")
        assert rec.active
    assert rt.comp.rig.baseline == pytest.approx(1.01 * before.baseline) and _rows(db_url) == (1, 0)
    rt.switch_rig(before).result(120)

