"""Alarm persistence: rules CRUD rows <-> engine rules, transitions stored as alarm rows and their
history, and the queries behind /api/alarms and /api/alarm-rules."""

from __future__ import annotations

import time
from typing import Any

from sqlalchemy import select
from sqlalchemy.orm import Session

from server.alarms.conditions import FAULT_SOURCES, Fault, condition_from_dict, condition_to_dict
from server.alarms.engine import FAULT_NAMES, FAULT_PRIORITY, PRIORITIES, Rule, Transition
from server.db.models import Alarm, AlarmEvent, AlarmRule, User
from server.services.errors import Conflict, Invalid, NotFound

OPEN_STATES = ("unack", "ack", "rtn_unack", "shelved")
STATES = (*OPEN_STATES, "suppressed", "out_of_service", "normal")
RULE_FIELDS = ("name", "priority", "condition", "on_delay_s", "off_delay_s", "enabled", "out_of_service")


def engine_rule(row: AlarmRule) -> Rule:
    if row.builtin is not None:
        return Rule(f"fault:{row.builtin}", row.name, row.priority, Fault(row.builtin),
                    out_of_service=row.out_of_service)
    return Rule(f"rule:{row.id}", row.name, row.priority, condition_from_dict(row.condition), row.on_delay_s,
                row.off_delay_s, row.enabled, row.out_of_service)


def rule_key(row: AlarmRule) -> str:
    return f"fault:{row.builtin}" if row.builtin is not None else f"rule:{row.id}"


def rule_json(row: AlarmRule) -> dict[str, Any]:
    return {"id": row.id, "name": row.name, "priority": row.priority, "condition": row.condition,
            "on_delay_s": row.on_delay_s, "off_delay_s": row.off_delay_s, "enabled": row.enabled,
            "out_of_service": row.out_of_service, "created_at": row.created_at, "updated_at": row.updated_at,
            "built_in": row.builtin is not None}


def ensure_builtin_rules(db: Session) -> None:
    """A row for each built-in device fault rule that has none yet (always on; an admin may take one out of
    service)."""
    have = set(db.scalars(select(AlarmRule.builtin).where(AlarmRule.builtin.is_not(None))))
    now = time.time()
    for src in FAULT_SOURCES:
        if src not in have:
            db.add(AlarmRule(name=FAULT_NAMES[src], priority=FAULT_PRIORITY[src],
                             condition={"kind": "fault", "source": src}, on_delay_s=0.0, off_delay_s=0.0,
                             enabled=True, out_of_service=False, created_at=now, updated_at=now, builtin=src))
    db.flush()


def not_builtin(row: AlarmRule, what: str) -> None:
    """Conflict when a built-in rule is asked for more than going out of service or back."""
    if row.builtin is not None:
        raise Conflict(f"rule {row.id} ({row.name}) is built in: {what}")


def _checked(values: dict[str, Any]) -> dict[str, Any]:
    """Validate and normalise rule fields (ValueError -> Invalid, one line)."""
    out = dict(values)
    if "priority" in out and out["priority"] not in PRIORITIES:
        raise Invalid(f"priority must be one of {', '.join(PRIORITIES)}")
    if "condition" in out:
        try:
            out["condition"] = condition_to_dict(condition_from_dict(out["condition"]))
        except ValueError as exc:
            raise Invalid(str(exc)) from None
    return out


def list_rules(db: Session) -> list[AlarmRule]:
    return list(db.scalars(select(AlarmRule).order_by(AlarmRule.id)))


def get_rule(db: Session, rule_id: int) -> AlarmRule:
    row = db.get(AlarmRule, rule_id)
    if row is None:
        raise NotFound(f"no alarm rule with id {rule_id}")
    return row


def add_rule(db: Session, user: User, values: dict[str, Any]) -> AlarmRule:
    v = _checked(values)
    now = time.time()
    row = AlarmRule(created_at=now, updated_at=now, created_by=user.id, **{k: v[k] for k in RULE_FIELDS})
    db.add(row)
    db.flush()
    return row


def patch_rule(db: Session, rule_id: int, values: dict[str, Any]) -> AlarmRule:
    row = get_rule(db, rule_id)
    if set(values) - {"out_of_service"}:
        not_builtin(row, "only out_of_service can change")
    for k, val in _checked(values).items():
        setattr(row, k, val)
    row.updated_at = time.time()
    db.flush()
    return row


def alarm_json(row: Alarm) -> dict[str, Any]:
    return {k: getattr(row, k) for k in ("id", "rule_id", "rule_key", "name", "priority", "state", "activated_at",
                                         "cleared_at", "acked_at", "acked_by", "updated_at", "frame", "target_id",
                                         "run_id", "message", "shelved_until", "shelve_reason",
                                         "shelved_one_shot")}


def event_json(ev: AlarmEvent) -> dict[str, Any]:
    return {k: getattr(ev, k) for k in ("id", "at", "kind", "state_from", "state_to", "username", "comment",
                                        "frame", "target_id", "message")}


def store(db: Session, tr: Transition, alarm: Alarm | None, user: User | None, name: str, run_id: str | None
          ) -> Alarm | None:
    """Store one transition: a new alarm row when it opens an occurrence, else an update of `alarm`, and
    its history entry. None for a transition without an alarm row (nothing stored)."""
    if tr.opened:
        rule_id = int(tr.rule.split(":")[1]) if tr.rule and tr.rule.startswith("rule:") else None
        alarm = Alarm(rule_id=rule_id, rule_key=tr.rule, name=name, priority=tr.priority or "high",
                      state=tr.state_to, activated_at=tr.t, updated_at=tr.t, frame=tr.frame, target_id=tr.target_id,
                      run_id=run_id if tr.target_id is not None else None, message=tr.message)
        db.add(alarm)
        db.flush()
    if alarm is None:
        return None
    alarm.state, alarm.updated_at = tr.state_to or alarm.state, tr.t
    if tr.kind == "activated" and not tr.opened:
        alarm.cleared_at, alarm.message = None, tr.message or alarm.message
    elif tr.kind == "cleared":
        alarm.cleared_at = tr.t
    elif tr.kind == "acknowledged":
        alarm.acked_at, alarm.acked_by = tr.t, None if user is None else user.username
    elif tr.kind == "shelved":
        alarm.shelve_reason, alarm.shelved_until, alarm.shelved_one_shot = tr.comment, tr.until, tr.one_shot
    if tr.kind in ("unshelved", "out_of_service", "removed", "suppressed"):
        alarm.shelved_until, alarm.shelved_one_shot = None, False
    db.add(AlarmEvent(alarm_id=alarm.id, at=tr.t, kind=tr.kind, state_from=tr.state_from, state_to=tr.state_to,
                      user_id=None if user is None else user.id, username=None if user is None else user.username,
                      comment=tr.comment, frame=tr.frame, target_id=tr.target_id, message=tr.message))
    return alarm


def list_alarms(db: Session, states: list[str], since: float | None, limit: int) -> list[Alarm]:
    bad = [s for s in states if s not in (*STATES, "open")]
    if bad:
        raise Invalid(f"unknown state {bad[0]!r}; use open or any of {', '.join(STATES)}")
    wanted = {x for s in states for x in (OPEN_STATES if s == "open" else (s,))}
    q = select(Alarm).order_by(Alarm.activated_at.desc()).limit(limit)
    if wanted:
        q = q.where(Alarm.state.in_(sorted(wanted)))
    if since is not None:
        q = q.where(Alarm.updated_at >= since)
    rows = list(db.scalars(q))
    return sorted(rows, key=lambda a: (PRIORITIES.index(a.priority) if a.priority in PRIORITIES else 9,
                                       -a.activated_at))


def get_alarm(db: Session, alarm_id: int) -> tuple[Alarm, list[AlarmEvent]]:
    row = db.get(Alarm, alarm_id)
    if row is None:
        raise NotFound(f"no alarm with id {alarm_id}")
    hist = list(db.scalars(select(AlarmEvent).where(AlarmEvent.alarm_id == alarm_id).order_by(AlarmEvent.at,
                                                                                               AlarmEvent.id)))
    return row, hist


def open_alarms(db: Session) -> list[Alarm]:
    return list(db.scalars(select(Alarm).where(Alarm.state.in_(OPEN_STATES))))


def detail(db: Session, alarm_id: int, preroll_s: float) -> dict[str, Any]:
    """An alarm with its history, the id of its track once written, and the playback link (pre-roll)."""
    from server.db.models import Track

    row, hist = get_alarm(db, alarm_id)
    track = None
    if row.run_id is not None and row.target_id is not None:
        track = db.scalar(select(Track.id).where(Track.run_id == row.run_id, Track.track_no == row.target_id))
    return {**alarm_json(row), "history": [event_json(e) for e in hist], "track_id": track,
            "playback_url": f"#/playback?t={row.activated_at - preroll_s:.3f}&alarm={row.id}"}
