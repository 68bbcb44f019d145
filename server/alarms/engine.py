"""The alarm engine (pure, no I/O): rules with on- and off-delays, the ISA-18.2 / IEC 62682 alarm
lifecycle, timed shelving, out of service, and the flood state. `step(snapshot) -> transitions`.

States of a rule's alarm (ISA-18.2 fig. 5): `normal`; `unack` (active, unacknowledged); `ack` (active,
acknowledged); `rtn_unack` (returned to normal, unacknowledged); `shelved` (timed, with a reason, at
most `max_shelve_s`); `out_of_service` (an admin took the rule out). An occurrence (one alarm in the
list) runs from the activation out of `normal` until the alarm is `normal` again (acknowledged and
cleared), or it is shelved or taken out of service. Silencing (the console's sound) is not
acknowledging and is not the engine's business.

Delays: the condition must hold for `on_delay_s` before the alarm activates and stay false for
`off_delay_s` before it clears (chattering held back). Flood: more than `flood_on` new alarms in
`flood_window_s` raises the flood state, which ends when fewer than `flood_off` remain in the window.
Times are seconds on the caller's clock (non-decreasing).
"""

from __future__ import annotations

from collections import deque
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any

from server.alarms.conditions import FAULT_SOURCES, Condition, Fault, Memory, Snapshot, evaluate

PRIORITIES = ("critical", "high", "medium", "low")
FAULT_PRIORITY = {"camera": "critical", "frame_rate": "medium", "servo": "high", "recording": "high",
                  "disk": "high", "database": "high"}
FAULT_NAMES = {"camera": "Camera stalled or gone", "frame_rate": "Frame rate under the floor",
               "servo": "Servo fault", "recording": "Recording failure", "disk": "Disk space low",
               "database": "Database errors"}


class AlarmStateError(ValueError):
    """An operation that the alarm's state does not allow (ack of an acknowledged alarm, ...)."""


@dataclass(frozen=True)
class Rule:
    """key: the rule's id ("rule:<n>" for stored rules, "fault:<source>" for the built-in ones)."""

    key: str
    name: str
    priority: str
    condition: Condition
    on_delay_s: float = 0.0
    off_delay_s: float = 0.0
    enabled: bool = True
    out_of_service: bool = False


def fault_rules() -> list[Rule]:
    """The built-in, always-on device fault rules."""
    return [Rule(f"fault:{s}", FAULT_NAMES[s], FAULT_PRIORITY[s], Fault(s)) for s in FAULT_SOURCES]


@dataclass(frozen=True)
class Transition:
    """One state change of a rule's alarm. occurrence: the engine's number of the alarm (a new one when
    `opened`); kind: activated, cleared, acknowledged, shelved, unshelved, out_of_service, in_service,
    removed, flood or flood_end (those two have no rule); frame and target_id: what triggered it."""

    kind: str
    t: float
    rule: str | None
    occurrence: int | None
    state_from: str | None
    state_to: str | None
    opened: bool = False
    user: str | None = None
    comment: str | None = None
    frame: int | None = None
    target_id: int | None = None
    message: str | None = None
    priority: str | None = None
    until: float | None = None  # shelved: the time the shelving ends

    def as_dict(self) -> dict[str, Any]:
        return dict(vars(self))


@dataclass
class Point:
    """A rule's alarm point: the filtered condition and the lifecycle state."""

    rule: Rule
    memory: Memory = field(default_factory=Memory)
    raw: bool = False
    raw_since: float | None = None
    active: bool = False
    state: str = "normal"
    occurrence: int | None = None
    shelved_until: float | None = None
    shelve_reason: str | None = None


class AlarmEngine:
    def __init__(self, rules: Iterable[Rule] = (), max_shelve_s: float = 8 * 3600.0, flood_window_s: float = 600.0,
                 flood_on: int = 10, flood_off: int = 5, builtin: bool = True):
        self.max_shelve_s = max_shelve_s
        self.flood_window_s, self.flood_on, self.flood_off = flood_window_s, flood_on, flood_off
        self.points: dict[str, Point] = {r.key: Point(r) for r in (fault_rules() if builtin else [])}
        self._next = 1
        self._new: deque[float] = deque()  # activation times inside the flood window
        self.flood = False
        self.t = 0.0
        for r in rules:
            self.points[r.key] = Point(r)

    # --- rules ----------------------------------------------------------------------------------------
    def set_rule(self, rule: Rule, t: float, user: str | None = None) -> list[Transition]:
        """Add or replace a rule; a changed condition starts its memory afresh. Taking it out of service
        (or back) is a transition."""
        p = self.points.get(rule.key)
        if p is None:
            self.points[rule.key] = p = Point(rule)
        elif p.rule.condition != rule.condition:
            p.memory, p.raw, p.raw_since = Memory(), False, None
        old, p.rule = p.rule, rule
        out: list[Transition] = []
        if rule.out_of_service and p.state != "out_of_service":
            out.append(self._close(p, t, "out_of_service", "out_of_service", user))
        elif not rule.out_of_service and old.out_of_service and p.state == "out_of_service":
            p.state, p.active, p.raw, p.raw_since = "normal", False, False, None
            out.append(Transition("in_service", t, rule.key, None, "out_of_service", "normal", user=user,
                                  priority=rule.priority))
        return out

    def remove_rule(self, key: str, t: float, user: str | None = None) -> list[Transition]:
        p = self.points.pop(key, None)
        if p is None or p.occurrence is None:
            return []
        return [self._close(p, t, "removed", "normal", user)]

    def restore(self, key: str, state: str, shelved_until: float | None = None, reason: str | None = None
                ) -> int | None:
        """Take back an open alarm kept from an earlier run (unack, ack, rtn_unack or shelved): its new
        occurrence number, or None when the rule is gone or the state is not an open one. The condition is
        evaluated afresh: an alarm whose condition no longer holds clears after its off-delay."""
        p = self.points.get(key)
        if p is None or state not in ("unack", "ack", "rtn_unack", "shelved") or p.state == "out_of_service":
            return None
        p.occurrence, self._next = self._next, self._next + 1
        p.state, p.active = state, state != "rtn_unack"
        p.raw, p.raw_since = p.active, None
        p.shelved_until, p.shelve_reason = (shelved_until, reason) if state == "shelved" else (None, None)
        return p.occurrence

    # --- evaluation -----------------------------------------------------------------------------------
    def step(self, snap: Snapshot) -> list[Transition]:
        """Evaluate every rule on the snapshot; the transitions in order."""
        self.t = snap.t
        out: list[Transition] = []
        for p in list(self.points.values()):
            raw, target = evaluate(p.rule.condition, snap, p.memory) if p.rule.enabled else (False, None)
            if p.state == "out_of_service":
                continue
            if raw != p.raw or p.raw_since is None:
                p.raw, p.raw_since = raw, snap.t
            if p.state == "shelved":
                if p.shelved_until is not None and snap.t >= p.shelved_until:
                    out += self._unshelve(p, snap.t, None, "shelving expired")
                continue
            self._filter(p, snap, target, out)
        out += self._flood(snap.t)
        return out

    def _filter(self, p: Point, snap: Snapshot, target: int | None, out: list[Transition]) -> None:
        held = snap.t - (p.raw_since if p.raw_since is not None else snap.t)
        if p.raw and not p.active and held >= p.rule.on_delay_s:
            p.active = True
            out.append(self._activate(p, snap.t, snap.frame, target, snap.faults))
        elif not p.raw and p.active and held >= p.rule.off_delay_s:
            p.active = False
            out.append(self._clear(p, snap.t, snap.frame))

    def _activate(self, p: Point, t: float, frame: int | None, target: int | None,
                  faults: Mapping[str, str]) -> Transition:
        opened = p.state == "normal"
        if opened:
            p.occurrence = self._next
            self._next += 1
            self._new.append(t)
        old, p.state = p.state, "unack" if p.state in ("normal", "rtn_unack") else p.state
        msg = faults.get(p.rule.condition.source) if isinstance(p.rule.condition, Fault) else None
        return Transition("activated", t, p.rule.key, p.occurrence, old, p.state, opened, frame=frame,
                          target_id=target, message=msg, priority=p.rule.priority)

    def _clear(self, p: Point, t: float, frame: int | None) -> Transition:
        old = p.state
        p.state = "rtn_unack" if old == "unack" else "normal"
        tr = Transition("cleared", t, p.rule.key, p.occurrence, old, p.state, frame=frame, priority=p.rule.priority)
        if p.state == "normal":
            p.occurrence = None
        return tr

    # --- operator actions -----------------------------------------------------------------------------
    def point(self, key: str) -> Point:
        try:
            return self.points[key]
        except KeyError:
            raise AlarmStateError(f"no alarm rule {key}") from None

    def ack(self, key: str, t: float, user: str | None, comment: str | None = None) -> list[Transition]:
        p = self.point(key)
        if p.state not in ("unack", "rtn_unack"):
            raise AlarmStateError(f"the alarm is {p.state.replace('_', ' ')}: nothing to acknowledge")
        old = p.state
        p.state = "ack" if old == "unack" else "normal"
        tr = Transition("acknowledged", t, key, p.occurrence, old, p.state, user=user, comment=comment,
                        priority=p.rule.priority)
        if p.state == "normal":
            p.occurrence = None
        return [tr]

    def shelve(self, key: str, t: float, user: str | None, minutes: float, reason: str) -> list[Transition]:
        p = self.point(key)
        if not 0 < minutes * 60.0 <= self.max_shelve_s:
            raise AlarmStateError(f"minutes must be above 0 and at most {self.max_shelve_s / 60:g}")
        if not reason.strip():
            raise AlarmStateError("shelving needs a reason")
        if p.state in ("normal", "out_of_service"):
            raise AlarmStateError(f"the alarm is {p.state.replace('_', ' ')}: nothing to shelve")
        p.shelved_until, p.shelve_reason = t + minutes * 60.0, reason.strip()
        old, p.state = p.state, "shelved"
        return [Transition("shelved", t, key, p.occurrence, old, "shelved", user=user, comment=reason.strip(),
                           priority=p.rule.priority, until=p.shelved_until)]

    def unshelve(self, key: str, t: float, user: str | None) -> list[Transition]:
        p = self.point(key)
        if p.state != "shelved":
            raise AlarmStateError(f"the alarm is {p.state.replace('_', ' ')}, not shelved")
        return self._unshelve(p, t, user, None)

    def _unshelve(self, p: Point, t: float, user: str | None, comment: str | None) -> list[Transition]:
        """Back from shelving: still active -> unacknowledged again; else the occurrence ends (normal)."""
        p.shelved_until = p.shelve_reason = None
        p.active = p.raw and (t - (p.raw_since or t)) >= p.rule.on_delay_s
        p.state = "unack" if p.active else "normal"
        tr = Transition("unshelved", t, p.rule.key, p.occurrence, "shelved", p.state, user=user, comment=comment,
                        priority=p.rule.priority)
        if p.state == "normal":
            p.occurrence = None
        return [tr]

    def _close(self, p: Point, t: float, kind: str, state: str, user: str | None) -> Transition:
        old = p.state
        tr = Transition(kind, t, p.rule.key, p.occurrence, old, state, user=user, priority=p.rule.priority)
        p.state, p.occurrence, p.active = state, None, False
        p.shelved_until = p.shelve_reason = None
        return tr

    # --- flood ----------------------------------------------------------------------------------------
    def _flood(self, t: float) -> list[Transition]:
        while self._new and self._new[0] <= t - self.flood_window_s:
            self._new.popleft()
        n = len(self._new)
        if not self.flood and n > self.flood_on:
            self.flood = True
            return [Transition("flood", t, None, None, None, None, message=f"{n} new alarms in "
                               f"{self.flood_window_s / 60:g} min")]
        if self.flood and n < self.flood_off:
            self.flood = False
            return [Transition("flood_end", t, None, None, None, None, message=f"{n} new alarms in "
                               f"{self.flood_window_s / 60:g} min")]
        return []

    @property
    def recent_count(self) -> int:
        return len(self._new)
