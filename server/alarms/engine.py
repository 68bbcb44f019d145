"""The alarm engine (pure, no I/O): rules with on- and off-delays, the ISA-18.2 / IEC 62682 alarm
lifecycle, timed and one-shot shelving, suppression by design, out of service, and the flood state per
operator (server.alarms.flood). `step(snapshot) -> transitions`.

States of a rule's alarm (ISA-18.2 fig. 5): `normal`; `unack` (active, unacknowledged); `ack` (active,
acknowledged); `rtn_unack` (returned to normal, unacknowledged); `shelved` (with a reason: timed, at
most `max_shelve_s`, or one-shot (OPC UA Part 9 OneShotShelve): until the alarm next clears, at most
`max_shelve_s` too); `suppressed` (suppressed by design, see `design_suppression`); `out_of_service`
(an admin took the rule out). An occurrence (one alarm in the list) runs from the activation out of
`normal` until the alarm is `normal` again (acknowledged and cleared), or it is shelved out, suppressed
or taken out of service. Silencing (the console's sound) is not acknowledging and is not the engine's
business.

Suppression by design on this console: a `lost` rule is suppressed while the mount is not in auto mode
(manual, hold or home): the operator, not the tracker, points the cameras then, and a target that
leaves the view is the operator's doing, not an abnormal situation. Its clock starts afresh when the
mount is back in auto.

Delays: the condition must hold for `on_delay_s` before the alarm activates and stay false for
`off_delay_s` before it clears (chattering held back). Flood: more than `flood_on` new alarms in
`flood_window_s` raises the flood state, which ends when fewer than `flood_off` remain in the window.
Times are seconds on the caller's clock (non-decreasing).
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any

from server.alarms.conditions import FAULT_SOURCES, Condition, Fault, Lost, Memory, Snapshot, evaluate
from server.alarms.flood import CONSOLE, FloodMeter

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
    until: float | None = None  # shelved: the time the shelving ends (one-shot: at the latest)
    one_shot: bool = False  # shelved: until the alarm next clears

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
    one_shot: bool = False


def design_suppression(rule: Rule, snap: Snapshot) -> str | None:
    """Why the rule's alarm is suppressed by design at the snapshot (None: it is not)."""
    if isinstance(rule.condition, Lost) and snap.servo_mode not in (None, "auto"):
        return f"the mount is in {snap.servo_mode} mode: the operator points it"
    return None


class AlarmEngine:
    def __init__(self, rules: Iterable[Rule] = (), max_shelve_s: float = 8 * 3600.0, flood_window_s: float = 600.0,
                 flood_on: int = 10, flood_off: int = 5, builtin: bool = True):
        self.max_shelve_s = max_shelve_s
        self.flood_window_s = flood_window_s
        self.floods = FloodMeter(flood_window_s, flood_on, flood_off)
        self.points: dict[str, Point] = {r.key: Point(r) for r in (fault_rules() if builtin else [])}
        self._next = 1
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

    def restore(self, key: str, state: str, shelved_until: float | None = None, reason: str | None = None,
                one_shot: bool = False) -> int | None:
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
        p.one_shot = one_shot and state == "shelved"
        return p.occurrence

    # --- evaluation -----------------------------------------------------------------------------------
    def step(self, snap: Snapshot) -> list[Transition]:
        """Evaluate every rule on the snapshot; the transitions in order."""
        self.t = snap.t
        out: list[Transition] = []
        for p in list(self.points.values()):
            raw, target = evaluate(p.rule.condition, snap, p.memory) if p.rule.enabled else (False, None)
            if p.state == "out_of_service" or self._suppress(p, snap, out):
                continue
            if raw != p.raw or p.raw_since is None:
                p.raw, p.raw_since = raw, snap.t
            if p.state == "shelved":
                self._shelved(p, snap.t, out)
                continue
            self._filter(p, snap, target, out)
        out += self._flood(snap.t)
        return out

    def _suppress(self, p: Point, snap: Snapshot, out: list[Transition]) -> bool:
        """Suppression by design: enter (an open occurrence ends) or leave it; True while suppressed and at
        the snapshot that ends it."""
        why = design_suppression(p.rule, snap)
        if why is not None:
            if p.state != "suppressed":
                out.append(self._close(p, snap.t, "suppressed", "suppressed", None, why))
            return True
        if p.state == "suppressed":
            p.state, p.raw, p.raw_since = "normal", False, None
            if p.memory.primary_seen is not None:
                p.memory.primary_seen = snap.t  # the lost rule's clock starts afresh
            out.append(Transition("unsuppressed", snap.t, p.rule.key, None, "suppressed", "normal",
                                  priority=p.rule.priority))
            return True  # evaluated afresh from the next snapshot
        return False

    def _shelved(self, p: Point, t: float, out: list[Transition]) -> None:
        """A shelved alarm: the timed shelving expires; a one-shot one ends when the alarm clears (the
        condition false for the off-delay) or at the longest shelving."""
        if p.one_shot and p.active and not p.raw and t - (p.raw_since or t) >= p.rule.off_delay_s:
            p.active = False
            out += self._unshelve(p, t, None, "one-shot shelving ended: the alarm cleared")
        elif p.shelved_until is not None and t >= p.shelved_until:
            out += self._unshelve(p, t, None, "shelving expired")

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
            self.floods.alarm(t)
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

    def shelve(self, key: str, t: float, user: str | None, minutes: float | None, reason: str,
               one_shot: bool = False) -> list[Transition]:
        """Timed shelving for `minutes`, or one-shot (minutes None) until the alarm next clears."""
        p = self.point(key)
        if one_shot != (minutes is None):
            raise AlarmStateError("give minutes (timed shelving) or one_shot, not both")
        if minutes is not None and not 0 < minutes * 60.0 <= self.max_shelve_s:
            raise AlarmStateError(f"minutes must be above 0 and at most {self.max_shelve_s / 60:g}")
        if not reason.strip():
            raise AlarmStateError("shelving needs a reason")
        if p.state in ("normal", "out_of_service", "suppressed", "shelved"):
            raise AlarmStateError(f"the alarm is {p.state.replace('_', ' ')}: nothing to shelve")
        if one_shot and not p.active:
            raise AlarmStateError("the alarm has cleared: one-shot shelving lasts until an active alarm clears")
        p.shelved_until = t + (self.max_shelve_s if minutes is None else minutes * 60.0)
        p.shelve_reason, p.one_shot = reason.strip(), one_shot
        old, p.state = p.state, "shelved"
        return [Transition("shelved", t, key, p.occurrence, old, "shelved", user=user, comment=reason.strip(),
                           priority=p.rule.priority, until=p.shelved_until, one_shot=one_shot)]

    def unshelve(self, key: str, t: float, user: str | None) -> list[Transition]:
        p = self.point(key)
        if p.state != "shelved":
            raise AlarmStateError(f"the alarm is {p.state.replace('_', ' ')}, not shelved")
        return self._unshelve(p, t, user, None)

    def _unshelve(self, p: Point, t: float, user: str | None, comment: str | None) -> list[Transition]:
        """Back from shelving: still active -> unacknowledged again; else the occurrence ends (normal)."""
        p.shelved_until = p.shelve_reason = None
        p.one_shot = False
        p.active = p.raw and (t - (p.raw_since or t)) >= p.rule.on_delay_s
        p.state = "unack" if p.active else "normal"
        tr = Transition("unshelved", t, p.rule.key, p.occurrence, "shelved", p.state, user=user, comment=comment,
                        priority=p.rule.priority)
        if p.state == "normal":
            p.occurrence = None
        return [tr]

    def _close(self, p: Point, t: float, kind: str, state: str, user: str | None, message: str | None = None
               ) -> Transition:
        old = p.state
        tr = Transition(kind, t, p.rule.key, p.occurrence, old, state, user=user, priority=p.rule.priority,
                        message=message)
        p.state, p.occurrence, p.active = state, None, False
        p.shelved_until = p.shelve_reason = None
        p.one_shot = False
        return tr

    # --- flood ----------------------------------------------------------------------------------------
    def set_operators(self, since: Mapping[str, float]) -> None:
        """The logged-in operators (username -> login time, s): the flood is counted per operator."""
        self.floods.set_operators(since)

    def _flood(self, t: float) -> list[Transition]:
        return [Transition("flood" if c.flood else "flood_end", t, None, None, None, None,
                           user=c.operator or None, message=f"{c.n} new alarms in {self.flood_window_s / 60:g} min")
                for c in self.floods.step(t)]

    @property
    def flood(self) -> bool:
        """Whether any operator (or the console, without operators) is in flood."""
        return bool(self.floods.flooded)

    def flooded(self, operator: str = CONSOLE) -> bool:
        return operator in self.floods.flooded

    def recent_count(self, operator: str = CONSOLE) -> int:
        return self.floods.count(operator)
