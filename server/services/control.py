"""Servo control and live tracker settings: requests to the runtime (applied by its worker between
frames), presets and settings changes in the database, every action audited."""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from concurrent.futures import Future
from concurrent.futures import TimeoutError as FutureTimeout
from typing import Any, TypeVar

from pydantic import ValidationError
from sqlalchemy import select
from sqlalchemy.exc import OperationalError
from sqlalchemy.orm import Session

from server.db.models import ServoPreset, SettingsChange, User
from server.services import audit
from server.services.errors import Conflict, Invalid, NotFound, one_line
from server.settings_schemas import TrackerSettings, TrackerSettingsPatch
from tmeye.runtime import NoServoError, Runtime, ServoMode, ServoRequestError, TrackerTuning
from tmeye.runtime.servo import ServoWish

T = TypeVar("T")
REQUEST_TIMEOUT_S = 2.0
log = logging.getLogger("tmeye.control")


class Unavailable(RuntimeError):
    """503: the runtime cannot take the request now."""


def wait(fut: Future[T]) -> T:
    """The request's result; service errors for a missing servo, bad angles or a stopped runtime."""
    try:
        return fut.result(timeout=REQUEST_TIMEOUT_S)
    except NoServoError as exc:
        raise Conflict(str(exc)) from None
    except ServoRequestError as exc:
        raise Invalid(str(exc)) from None
    except FutureTimeout:
        raise Unavailable("the tracker did not take the request in time") from None
    except RuntimeError as exc:
        raise Unavailable(str(exc)) from None


def servo_state(rt: Runtime) -> dict[str, Any]:
    ev = rt.latest
    if rt.servo is None:
        return {"configured": False}
    out: dict[str, Any] = {}
    if ev is not None and ev.servo is not None:
        out = ev.servo.as_dict()  # the angles at the last capture
    goal = rt.servo.goal  # the operator's wishes as they are now (the frame may predate them)
    out.update(mode=str(rt.servo.mode), goal=None if goal is None else {"pan_deg": goal[0], "tilt_deg": goal[1]})
    pan, tilt = rt.servo.limits
    out.update(configured=True,
               limits={"pan_deg": [pan.min_deg, pan.max_deg], "tilt_deg": [tilt.min_deg, tilt.max_deg]})
    return out


def _written_first(db: Session) -> None:
    """Write an action's rows (its audit record) before the runtime is asked: a locked or read-only database
    refuses the action (503) before anything is done."""
    db.flush()


def commit_or_undo(db: Session, undo: Callable[[], Future[Any]], timeout_s: float = REQUEST_TIMEOUT_S) -> None:
    """Commit an action's rows, written before the runtime took the request. Should the commit itself fail
    (a disk full at that moment), the request is undone first (waiting up to timeout_s), so the 503
    ("nothing was changed") holds and no control action goes unaudited."""
    try:
        db.commit()
    except OperationalError:
        try:
            undo().result(timeout=timeout_s)
        except Exception as exc:  # the 503 still goes out; the log says what stands
            log.warning("a request whose audit record was refused could not be undone: %s", exc)
        raise


def _servo_action(db: Session, rt: Runtime, request: Callable[[], Future[ServoWish]]) -> dict[str, Any]:
    """A servo request whose audit record the session holds: written first, the request made, committed
    (or the request undone); the servo's state after it."""
    _written_first(db)
    before = wait(request())
    commit_or_undo(db, lambda: rt.servo_restore(before))
    return servo_state(rt)


def set_mode(db: Session, rt: Runtime, user: User, address: str, mode: str) -> dict[str, Any]:
    audit.record(db, user, address, "servo.mode", mode)
    return _servo_action(db, rt, lambda: rt.servo_mode(ServoMode(mode)))


def goto(db: Session, rt: Runtime, user: User, address: str, pan_deg: float, tilt_deg: float,
         action: str = "servo.goto", target: str | None = None) -> dict[str, Any]:
    audit.record(db, user, address, action, target, {"pan_deg": pan_deg, "tilt_deg": tilt_deg})
    return _servo_action(db, rt, lambda: rt.servo_goto(pan_deg, tilt_deg))


def point(db: Session, rt: Runtime, user: User, address: str, camera: str, u: float, v: float) -> dict[str, Any]:
    entry = audit.record(db, user, address, "servo.point", camera, {"u": u, "v": v})
    _written_first(db)
    pan, tilt, before = wait(rt.servo_point(camera, u, v))
    entry.detail = {"u": u, "v": v, "pan_deg": round(pan, 4), "tilt_deg": round(tilt, 4)}
    commit_or_undo(db, lambda: rt.servo_restore(before))
    return servo_state(rt)


def select_primary(db: Session, rt: Runtime, user: User, address: str, track_id: int) -> None:
    audit.record(db, user, address, "track.primary", str(track_id))
    _written_first(db)
    before = wait(rt.select_primary(track_id))
    if before is None:
        raise NotFound(f"no live track {track_id} (it may have ended)")
    commit_or_undo(db, lambda: rt.restore_primary(before))


def jog(db: Session, rt: Runtime, user: User, address: str, pan_dps: float, tilt_dps: float,
        duration_s: float) -> dict[str, Any]:
    audit.record(db, user, address, "servo.jog", None,
                 {"pan_dps": pan_dps, "tilt_dps": tilt_dps, "duration_s": duration_s})
    return _servo_action(db, rt, lambda: rt.servo_jog(pan_dps, tilt_dps, duration_s))


def list_presets(db: Session) -> list[ServoPreset]:
    return list(db.scalars(select(ServoPreset).order_by(ServoPreset.name)))


def get_preset(db: Session, preset_id: int) -> ServoPreset:
    p = db.get(ServoPreset, preset_id)
    if p is None:
        raise NotFound(f"no preset with id {preset_id}")
    return p


def create_preset(db: Session, rt: Runtime, user: User, address: str, name: str, pan: float | None,
                  tilt: float | None) -> ServoPreset:
    if db.scalar(select(ServoPreset).where(ServoPreset.name == name)) is not None:
        raise Conflict(f"a preset named {name!r} already exists")
    if pan is None or tilt is None:
        st = servo_state(rt)
        if not st.get("configured") or st.get("pan_deg") is None:
            raise Conflict("no servo position to store: give pan_deg and tilt_deg")
        pan = st["pan_deg"] if pan is None else pan
        tilt = st["tilt_deg"] if tilt is None else tilt
    assert pan is not None and tilt is not None
    if rt.servo is not None:
        from tmeye.runtime.servo import check_angles

        try:
            check_angles(pan, tilt, *rt.servo.limits)
        except ServoRequestError as exc:
            raise Invalid(str(exc)) from None
    p = ServoPreset(name=name, pan_deg=pan, tilt_deg=tilt, created_at=time.time(), created_by=user.id)
    db.add(p)
    audit.record(db, user, address, "preset.create", name, {"pan_deg": pan, "tilt_deg": tilt})
    db.commit()
    return p


def delete_preset(db: Session, user: User, address: str, preset_id: int) -> None:
    p = get_preset(db, preset_id)
    db.delete(p)
    audit.record(db, user, address, "preset.delete", p.name)
    db.commit()


def tuning_from_dict(base: TrackerTuning, d: dict[str, dict[str, Any]]) -> TrackerTuning:
    try:
        return base.updated(d)
    except (ValueError, TypeError) as exc:
        raise Invalid(str(exc)) from None


def saved_tuning(db: Session) -> dict[str, dict[str, Any]] | None:
    row = db.scalar(select(SettingsChange).where(SettingsChange.section == "tracker")
                    .order_by(SettingsChange.id.desc()).limit(1))
    return None if row is None else row.after


def patch_tuning(db: Session, rt: Runtime, user: User, address: str, patch: TrackerSettingsPatch
                 ) -> dict[str, dict[str, Any]]:
    """Some tracker settings changed (the others as they are): checked whole (ranges, types, unknown names;
    Invalid, nothing changed), then `update_tuning` with the ones the patch names."""
    merged = rt.tuning.as_dict()
    named = patch.model_dump(exclude_none=True)
    for section, values in named.items():
        merged[section].update(values)
    try:
        checked = TrackerSettings.model_validate(merged).model_dump()
    except ValidationError as exc:
        raise Invalid(one_line(exc)) from None
    return update_tuning(db, rt, user, address,
                         {s: {k: v for k, v in checked[s].items() if k in named.get(s, {})} for s in checked})


def update_tuning(db: Session, rt: Runtime, user: User, address: str, new: dict[str, dict[str, Any]]
                  ) -> dict[str, dict[str, Any]]:
    old = rt.tuning
    before = old.as_dict()
    tuning = tuning_from_dict(old, new)
    after = tuning.as_dict()
    db.add(SettingsChange(at=time.time(), user_id=user.id, section="tracker", before=before, after=after))
    changed = {s: {k: v for k, v in after[s].items() if before[s][k] != v} for s in after}
    audit.record(db, user, address, "tracker.config", None, {s: c for s, c in changed.items() if c})
    _written_first(db)
    wait(rt.set_tuning(tuning))
    commit_or_undo(db, lambda: rt.set_tuning(old))
    return after
