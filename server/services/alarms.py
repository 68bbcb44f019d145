"""The alarm service: runs the pure engine (server.alarms.engine) on the runtime's published frames and on
a periodic tick (device faults show even when no frame comes) in its own thread, off the event loop;
stores every transition (alarm rows, their history, the audit log for operator actions) and pushes it to
`/ws/events` clients as {"type": "alarm", "alarm": ..., "transition": ...}; an operator's flood state goes
out as {"type": "alarm_flood", "flood", "message", "operator"}. The flood is counted per logged-in
operator (server.alarms.flood): the users of role operator or admin with a live session, each from their
earliest live login, looked up every probe_s. Operator actions (ack, shelve, unshelve) and rule changes come
from the routers' threads; one lock keeps the engine and the alarm rows in step. While the database cannot
store (full, read-only, locked), evaluated transitions wait in memory and are stored, with their own times,
once it can; an operator action or rule change that cannot be stored is undone in the engine (the API
answers 503)."""

from __future__ import annotations

import contextlib
import copy
import logging
import shutil
import threading
import time
from collections import deque
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from sqlalchemy import select, text
from sqlalchemy.orm import Session, sessionmaker

from server.alarms.conditions import Snapshot
from server.alarms.engine import PRIORITIES, AlarmEngine, AlarmStateError, Rule, Transition
from server.alarms.faults import FaultThresholds, Health, device_faults
from server.alarms.snapshot import snapshot_from
from server.db.models import Alarm, AlarmRule, AuthSession, User
from server.services import alarm_store as store
from server.services import audit
from server.services.errors import Conflict, NotFound
from server.services.events import EventBus
from server.services.faults import FailureLog, brief
from tmeye.runtime import FrameEvent, Runtime

log = logging.getLogger("tmeye.alarms")
MAX_UNSTORED = 10_000  # transitions kept while the database cannot store them (the oldest go first)
STORE_RETRY_S = 1.0  # how often storing them is tried again (s)
Probe = Callable[[], "str | None"]


@dataclass
class AlarmOptions:
    """tick_s: how often device faults are evaluated without frames (s); probe_s: how often the disk and
    the database are probed (s); max_shelve_s: the longest shelving (s)."""

    thresholds: FaultThresholds = field(default_factory=FaultThresholds)
    tick_s: float = 0.2
    probe_s: float = 2.0
    max_shelve_s: float = 8 * 3600.0


class AlarmService:
    def __init__(self, runtime: Runtime, sessions: sessionmaker[Session], events: EventBus | None,
                 data_dir: Path, options: AlarmOptions | None = None, run_id: Callable[[], str | None] = lambda: None):
        self.runtime, self.sessions, self.events, self.data_dir = runtime, sessions, events, data_dir
        self.opt = options or AlarmOptions()
        self.run_id = run_id
        self.engine = AlarmEngine(max_shelve_s=self.opt.max_shelve_s)
        self.lock = threading.Lock()
        self.rows: dict[int, int] = {}  # engine occurrence -> alarm row id
        self.probes: dict[str, Probe] = {}  # fault source (recording, database, ...) -> current fault or None
        self.on_activated: list[Callable[[float], None]] = []  # called with each activation's time (Unix s)
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._started = time.time()
        self._rates: deque[tuple[float, int]] = deque()
        self._probed_at = -1e9
        self._disk: int | None = None
        self._db_fault: str | None = None
        self._write_fault: str | None = None
        self._unstored: list[Transition] = []
        self._store_at = 0.0
        self._failures = FailureLog(log)
        self._operators: dict[str, float] | None = None
        self._last_t = 0.0

    # --- life cycle ----------------------------------------------------------------------------------
    def start(self) -> None:
        """Load the rules and the open alarms of an earlier run, then start evaluating."""
        with self.sessions() as db:
            store.ensure_builtin_rules(db)
            for row in store.list_rules(db):
                self.engine.set_rule(store.engine_rule(row), time.time())
            self.engine.set_operators(self._logged_in(db, time.time()))
            for a in store.open_alarms(db):
                occ = self.engine.restore(a.rule_key, a.state, a.shelved_until, a.shelve_reason, a.shelved_one_shot)
                if occ is None:
                    a.state, a.updated_at = "normal", time.time()
                else:
                    self.rows[occ] = a.id
            db.commit()
        self._started = time.time()
        self._thread = threading.Thread(target=self._run, name="tmeye-alarms", daemon=True)
        self._thread.start()

    def stop(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(3.0)

    def _run(self) -> None:
        sub = self.runtime.hub.subscribe(maxsize=256, name="alarms")
        try:
            while not self._stop.is_set():
                ev = sub.get(timeout=self.opt.tick_s)
                if ev is None and sub.closed:
                    self._stop.wait(self.opt.tick_s)
                try:
                    self._evaluate(ev)
                except Exception:  # a bug must not end alarm evaluation: logged, next frame goes on
                    log.exception("alarm evaluation failed")
        finally:
            self.runtime.hub.unsubscribe(sub)

    # --- evaluation ----------------------------------------------------------------------------------
    def health(self, now: float) -> Health:
        rt, latest = self.runtime, self.runtime.latest
        self._rates.append((now, rt.frames))
        w = self.opt.thresholds.fps_window_s
        while len(self._rates) > 2 and self._rates[1][0] <= now - w:
            self._rates.popleft()
        t0, n0 = self._rates[0]
        rate = (rt.frames - n0) / (now - t0) if now - t0 >= w * 0.9 else None
        if now - self._probed_at >= self.opt.probe_s:
            self._probed_at = now
            self._disk = _free_bytes(self.data_dir)
            self._db_fault = self._probe_db()
            if self._db_fault is None:
                with self.sessions() as session:
                    self._operators = self._logged_in(session, now)
        db = self._write_fault or self._db_fault or _probe(self.probes.get("database"))
        return Health(now, rt.state, rt.error, rt.source_fault, None if latest is None else latest.done_at,
                      now - self._started, rate, None if latest is None or latest.servo is None else latest.servo.fault,
                      _probe(self.probes.get("recording")), db, self._disk)

    @staticmethod
    def _logged_in(db: Session, now: float) -> dict[str, float]:
        """Operators (role operator or admin, not disabled) with a live session -> their earliest login."""
        rows = db.execute(select(User.username, AuthSession.created_at)
                          .join(AuthSession, AuthSession.user_id == User.id)
                          .where(AuthSession.revoked_at.is_(None), AuthSession.expires_at > now,
                                 User.role.in_(("operator", "admin")), User.disabled.is_(False)))
        out: dict[str, float] = {}
        for name, at in rows:
            out[name] = min(at, out.get(name, at))
        return out

    def _evaluate(self, ev: FrameEvent | None) -> None:
        now = time.time()
        faults = device_faults(self.health(now), self.opt.thresholds)
        latest = self.runtime.latest if ev is None else ev
        mode = None if latest is None or latest.servo is None else latest.servo.mode
        if ev is not None:
            snap = snapshot_from(max(ev.captured_at, self._last_t), ev.frame_no, ev.telemetry, ev.step,
                                 self.runtime.config.origin, faults, mode)
        else:
            snap = Snapshot(max(now, self._last_t), None, faults=faults, servo_mode=mode)
        self._last_t = snap.t
        with self.lock:
            if self._operators is not None:
                self.engine.set_operators(self._operators)
                self._operators = None
            trs = self.engine.step(snap)
            self._unstored = (self._unstored + trs)[-MAX_UNSTORED:]
            if self._unstored and time.monotonic() >= self._store_at:
                try:
                    self._commit(self._unstored, None, None)
                    self._unstored = []
                except Exception as exc:  # kept; tried again in a second (a full, read-only or locked
                    # database is a device fault, the database alarm's)
                    self._store_at = time.monotonic() + STORE_RETRY_S
                    self._failures.log(exc, "storing %d alarm transitions failed (kept, retried): %s",
                                       len(self._unstored), brief(exc))
        for tr in trs:
            if tr.kind == "activated":
                for hook in self.on_activated:
                    hook(tr.t)

    def _commit(self, trs: list[Transition], user: User | None, address: str | None,
                db: Session | None = None) -> list[dict[str, Any]]:
        """Store transitions (under the lock) and publish them once committed; the alarm rows touched."""
        own = db is None
        session = self.sessions() if db is None else db
        pushed: list[tuple[dict[str, Any], dict[str, Any] | None]] = []
        rows = dict(self.rows)
        try:
            for tr in trs:
                if tr.kind in ("flood", "flood_end"):
                    audit.record(session, None, None, f"alarm.{tr.kind}", tr.user and f"operator {tr.user}",
                                 {"message": tr.message})
                    pushed.append((tr.as_dict(), None))
                    continue
                row = self._row(session, tr)
                alarm = store.store(session, tr, row, user, self._name(tr), self.run_id())
                if alarm is None:
                    continue
                if tr.occurrence is not None and tr.state_to in ("normal", "out_of_service", "suppressed"):
                    self.rows.pop(tr.occurrence, None)  # the occurrence ended: its row no longer changes
                elif tr.occurrence is not None:
                    self.rows[tr.occurrence] = alarm.id
                if user is not None:
                    audit.record(session, user, address, f"alarm.{tr.kind}", f"alarm {alarm.id}",
                                 {"comment": tr.comment} if tr.comment else None)
                pushed.append((tr.as_dict(), store.alarm_json(alarm)))
            session.commit()
            self._write_fault = None
        except Exception as exc:
            session.rollback()
            self.rows = rows  # as they were: the rows this attempt added or ended were not stored
            self._write_fault = f"storing alarms failed: {type(exc).__name__}: {exc}".splitlines()[0]
            raise
        finally:
            if own:
                session.close()
        for tr_json, alarm_json in pushed:
            self._publish(tr_json, alarm_json)
        return [a for _, a in pushed if a is not None]

    def _row(self, db: Session, tr: Transition) -> Alarm | None:
        rid = None if tr.opened or tr.occurrence is None else self.rows.get(tr.occurrence)
        return None if rid is None else db.get(Alarm, rid)

    def _name(self, tr: Transition) -> str:
        p = self.engine.points.get(tr.rule or "")
        return p.rule.name if p is not None else str(tr.rule)

    def _publish(self, tr: dict[str, Any], alarm: dict[str, Any] | None) -> None:
        if self.events is None:
            return
        if alarm is None:
            self.events.publish_threadsafe("alarm_flood", flood=tr["kind"] == "flood", message=tr["message"],
                                           operator=tr["user"])
        else:
            self.events.publish_threadsafe("alarm", alarm=alarm, transition=tr)

    def _probe_db(self) -> str | None:
        try:
            with self.sessions() as db:
                db.execute(text("SELECT 1"))
        except Exception as exc:
            return f"database unavailable: {type(exc).__name__}: {exc}".splitlines()[0]
        return None

    @contextlib.contextmanager
    def _undo_on_failure(self) -> Iterator[None]:
        """Under the lock: an engine change whose transitions cannot be stored is undone."""
        saved = copy.deepcopy(self.engine)
        try:
            yield
        except Exception:
            self.engine = saved
            raise

    # --- operator actions ----------------------------------------------------------------------------
    def act(self, db: Session, user: User, address: str, alarm_id: int,
            action: Callable[[str, float], list[Transition]]) -> dict[str, Any]:
        """Run an engine action on the current occurrence of alarm `alarm_id`; its row afterwards."""
        with self.lock:
            row = db.get(Alarm, alarm_id)
            if row is None:
                raise NotFound(f"no alarm with id {alarm_id}")
            occ = next((o for o, r in self.rows.items() if r == alarm_id), None)
            point = self.engine.points.get(row.rule_key)
            if occ is None or point is None or point.occurrence != occ:
                raise Conflict(f"alarm {alarm_id} is {row.state.replace('_', ' ')}: it can no longer change")
            with self._undo_on_failure():
                try:
                    trs = action(row.rule_key, time.time())
                except AlarmStateError as exc:
                    raise Conflict(str(exc)) from None
                self._commit(trs, user, address, db)
        db.refresh(row)
        return store.alarm_json(row)

    def ack(self, db: Session, user: User, address: str, alarm_id: int, comment: str | None) -> dict[str, Any]:
        return self.act(db, user, address, alarm_id, lambda k, t: self.engine.ack(k, t, user.username, comment))

    def shelve(self, db: Session, user: User, address: str, alarm_id: int, minutes: float | None,
               reason: str, one_shot: bool = False) -> dict[str, Any]:
        return self.act(db, user, address, alarm_id,
                        lambda k, t: self.engine.shelve(k, t, user.username, minutes, reason, one_shot))

    def unshelve(self, db: Session, user: User, address: str, alarm_id: int) -> dict[str, Any]:
        return self.act(db, user, address, alarm_id, lambda k, t: self.engine.unshelve(k, t, user.username))

    # --- rules ---------------------------------------------------------------------------------------
    def rule_changed(self, db: Session, rule: Rule, user: User | None, address: str | None) -> None:
        """After a rule row was added or changed in `db` (not yet committed): update the engine, store the
        transitions (taking out of service, back in service) and commit."""
        with self.lock, self._undo_on_failure():
            trs = self.engine.set_rule(rule, time.time(), None if user is None else user.username)
            self._commit(trs, user, address, db)

    def rule_removed(self, db: Session, key: str, user: User, address: str) -> None:
        with self.lock, self._undo_on_failure():
            self._commit(self.engine.remove_rule(key, time.time(), user.username), user, address, db)

    def create_rule(self, db: Session, user: User, address: str, values: dict[str, Any]) -> dict[str, Any]:
        row = store.add_rule(db, user, values)
        audit.record(db, user, address, "alarm_rule.create", f"rule {row.id}", {"name": row.name})
        self.rule_changed(db, store.engine_rule(row), user, address)
        return self.rule_out(row)

    def update_rule(self, db: Session, user: User, address: str, rule_id: int, values: dict[str, Any]
                    ) -> dict[str, Any]:
        row = store.patch_rule(db, rule_id, values)
        audit.record(db, user, address, "alarm_rule.update", f"rule {row.id}", values)
        self.rule_changed(db, store.engine_rule(row), user, address)
        return self.rule_out(row)

    def delete_rule(self, db: Session, user: User, address: str, rule_id: int) -> None:
        row = store.get_rule(db, rule_id)
        store.not_builtin(row, "it cannot be deleted; take it out of service instead")
        audit.record(db, user, address, "alarm_rule.delete", f"rule {row.id}", {"name": row.name})
        with self.lock, self._undo_on_failure():
            trs = self.engine.remove_rule(f"rule:{rule_id}", time.time(), user.username)
            db.delete(row)
            self._commit(trs, user, address, db)

    def rule_out(self, row: AlarmRule) -> dict[str, Any]:
        """A rule's JSON with the state of its alarm."""
        return {**store.rule_json(row), "state": self.rule_state(store.rule_key(row))}

    def rule_state(self, row_key: str) -> str | None:
        """The state of a rule's alarm in the engine (normal, unack, ..., suppressed, out_of_service)."""
        with self.lock:
            p = self.engine.points.get(row_key)
            return None if p is None else p.state

    def summary(self, operator: str) -> dict[str, Any]:
        """Open alarms by priority, unacknowledged ones by priority, and `operator`'s flood state."""
        counts = dict.fromkeys(PRIORITIES, 0)
        unack = dict.fromkeys(PRIORITIES, 0)
        with self.lock:
            for p in self.engine.points.values():
                if p.occurrence is None or p.state in ("shelved", "normal", "out_of_service"):
                    continue
                counts[p.rule.priority] += 1
                if p.state in ("unack", "rtn_unack"):
                    unack[p.rule.priority] += 1
            return {"open": counts, "unacknowledged": unack, "flood": self.engine.flooded(operator),
                    "new_in_window": self.engine.recent_count(operator), "window_s": self.engine.flood_window_s,
                    "flooded_operators": sorted(self.engine.floods.flooded)}


def counter_probe(count: Callable[[], int], what: str, hold_s: float = 10.0) -> Probe:
    """A probe that reports a fault for hold_s seconds after an error counter went up."""
    state = {"n": count(), "at": -1e18}

    def probe() -> str | None:
        n = count()
        if n != state["n"]:
            state["n"], state["at"] = n, time.monotonic()
        return f"{what} ({n} times so far)" if time.monotonic() - state["at"] < hold_s else None
    return probe


def _probe(fn: Probe | None) -> str | None:
    if fn is None:
        return None
    try:
        return fn()
    except Exception as exc:  # a broken probe is itself a fault of what it watches
        return f"probe failed: {type(exc).__name__}: {exc}".splitlines()[0]


def _free_bytes(path: Path) -> int | None:
    try:
        return shutil.disk_usage(path).free
    except OSError:
        return None
