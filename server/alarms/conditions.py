"""Alarm conditions in metres and metres per second, evaluated on one snapshot of the tracker (pure).

A `Snapshot` is what the engine sees at time t (s): the targets of the latest frame (3-D position x, y, z
in the telemetry's frame, metres, y down; range r; metric width and height from the disparity), the
primary target's closing speed −dr/dt from the predictor (m/s), and the device faults of the moment.

Conditions:
- `Zone`: a target inside a box (x, y, z min and max) or a vertical cylinder (centre x, z; radius;
  optional y extent), for at least `dwell_s`;
- `RangeBelow`: a target nearer than `distance_m`;
- `Approach`: the primary closing faster than `speed_mps` for at least `for_s`;
- `Size`: a target whose metric width and height lie inside bounds;
- `Lost`: the primary target not seen for longer than `after_s` (after one was seen);
- `Fault`: a built-in device fault source reports a fault.
Conditions on targets are evaluated per target (per track id): a target counts once its track has been
seen in `MIN_HITS` frames (the tracker's own confirmation), so a single-frame false detection raises
nothing, and its condition once it held in `MIN_HITS` consecutive frames of the track, so a single frame
whose position is off (a disparity outlier near a zone's face) raises nothing either; a track missing from
a frame (a detection gap) keeps the value it had when last seen for
`HOLD_S`, as long as the tracker itself keeps a track without detections, so a person standing in a zone
who is not detected for a second does not clear the alarm and raise it again. The hold ends early when
another track is seen where the missing one could be by now (within `REACQUIRE_M` + `REACQUIRE_MPS`
times the time since it was last seen): the tracker has taken the same target up again under a new id,
or split a part of it off for a few frames. A target seen outside is outside at once. The approach
rule's closing speed is unknown (None) while the predictor coasts or is unsure of it (see
server.alarms.snapshot); an unknown speed keeps the last value for `HOLD_S` (and does not count towards the
rule's for_s). The
approach rule has a deadband (ISA-18.2): it stays true until the speed falls under speed_mps −
deadband_mps, so a target walking at about the threshold does not chatter.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

MIN_HITS = 2
HOLD_S = 2.0  # s: the tracker drops a track after 60 frames without a detection (2 s at 30 fps)
REACQUIRE_M, REACQUIRE_MPS = 1.0, 2.0  # m, m/s: a walking person is under 2 m/s
APPROACH_DEADBAND_MPS = 0.3  # m/s: the default deadband of an approach rule
FAULT_SOURCES = ("camera", "frame_rate", "servo", "recording", "disk", "database")


@dataclass(frozen=True)
class Target:
    """One detection: track id, position (m), range (m), metric width and height (m)."""

    track_id: int
    x: float
    y: float
    z: float
    r: float
    width_m: float = 0.0
    height_m: float = 0.0


@dataclass(frozen=True)
class Snapshot:
    """What the engine evaluates at time t (s). frame: the frame number, or None for a tick without a new
    frame (target conditions then keep their last value); closing_mps: −dr/dt of the primary (m/s) from
    the predictor, None without one; faults: device fault source -> one-line message."""

    t: float
    frame: int | None = None
    targets: tuple[Target, ...] = ()
    primary_id: int | None = None
    closing_mps: float | None = None
    faults: Mapping[str, str] = field(default_factory=dict)
    servo_mode: str | None = None


@dataclass(frozen=True)
class Zone:
    kind = "zone"
    shape: str  # "box" or "cylinder"
    x_min: float = -math.inf
    x_max: float = math.inf
    y_min: float = -math.inf
    y_max: float = math.inf
    z_min: float = -math.inf
    z_max: float = math.inf
    center_x: float = 0.0
    center_z: float = 0.0
    radius: float = 0.0
    dwell_s: float = 0.0

    def contains(self, p: Target) -> bool:
        if not self.y_min <= p.y <= self.y_max:
            return False
        if self.shape == "cylinder":
            return math.hypot(p.x - self.center_x, p.z - self.center_z) <= self.radius
        return self.x_min <= p.x <= self.x_max and self.z_min <= p.z <= self.z_max


@dataclass(frozen=True)
class RangeBelow:
    kind = "range_below"
    distance_m: float


@dataclass(frozen=True)
class Approach:
    kind = "approach"
    speed_mps: float
    for_s: float = 0.0
    deadband_mps: float = APPROACH_DEADBAND_MPS


@dataclass(frozen=True)
class Size:
    kind = "size"
    width_min: float = 0.0
    width_max: float = math.inf
    height_min: float = 0.0
    height_max: float = math.inf

    def fits(self, p: Target) -> bool:
        return self.width_min <= p.width_m <= self.width_max and self.height_min <= p.height_m <= self.height_max


@dataclass(frozen=True)
class Lost:
    kind = "lost"
    after_s: float


@dataclass(frozen=True)
class Fault:
    kind = "fault"
    source: str


Condition = Zone | RangeBelow | Approach | Size | Lost | Fault


def _num(d: Mapping[str, Any], key: str, default: float | None = None, lo: float | None = None) -> float:
    v = d.get(key, default)
    if v is None:
        raise ValueError(f"condition: {key} is required")
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(float(v)):
        raise ValueError(f"condition: {key} must be a finite number, got {v!r}")
    if lo is not None and float(v) < lo:
        raise ValueError(f"condition: {key} must be at least {lo:g}, got {v!r}")
    return float(v)


def _opt(d: Mapping[str, Any], key: str, default: float) -> float:
    return default if d.get(key) is None else _num(d, key)


def _ordered(lo: float, hi: float, name: str) -> None:
    if lo > hi:
        raise ValueError(f"condition: {name}_min {lo:g} is above {name}_max {hi:g}")


def condition_from_dict(d: Mapping[str, Any]) -> Condition:
    """A condition from its JSON form {"kind": ..., ...}; ValueError (one line) when it cannot be used."""
    kind = d.get("kind")
    if kind == "zone":
        shape = d.get("shape", "box")
        y_min, y_max = _opt(d, "y_min", -math.inf), _opt(d, "y_max", math.inf)
        _ordered(y_min, y_max, "y")
        dwell = _num(d, "dwell_s", 0.0, 0.0)
        if shape == "box":
            b = {k: _num(d, k) for k in ("x_min", "x_max", "z_min", "z_max")}
            _ordered(b["x_min"], b["x_max"], "x")
            _ordered(b["z_min"], b["z_max"], "z")
            return Zone("box", y_min=y_min, y_max=y_max, dwell_s=dwell, **b)
        if shape == "cylinder":
            radius = _num(d, "radius", None, 0.0)
            return Zone("cylinder", y_min=y_min, y_max=y_max, center_x=_num(d, "center_x"),
                        center_z=_num(d, "center_z"), radius=radius, dwell_s=dwell)
        raise ValueError(f"condition: zone shape must be box or cylinder, got {shape!r}")
    if kind == "range_below":
        return RangeBelow(_num(d, "distance_m", None, 0.0))
    if kind == "approach":
        speed = _num(d, "speed_mps", None, 0.0)
        band = _num(d, "deadband_mps", APPROACH_DEADBAND_MPS, 0.0)
        if band > speed:
            raise ValueError(f"condition: deadband_mps {band:g} is above speed_mps {speed:g}")
        return Approach(speed, _num(d, "for_s", 0.0, 0.0), band)
    if kind == "size":
        s = Size(_num(d, "width_min", 0.0, 0.0), _opt(d, "width_max", math.inf),
                 _num(d, "height_min", 0.0, 0.0), _opt(d, "height_max", math.inf))
        _ordered(s.width_min, s.width_max, "width")
        _ordered(s.height_min, s.height_max, "height")
        return s
    if kind == "lost":
        return Lost(_num(d, "after_s", None, 0.0))
    raise ValueError(f"condition: kind must be zone, range_below, approach, size or lost, got {kind!r}")


def condition_to_dict(c: Condition) -> dict[str, Any]:
    """The JSON form of a condition (infinite bounds left out)."""
    out: dict[str, Any] = {"kind": c.kind}
    for k, v in vars(c).items():
        if isinstance(v, float) and math.isinf(v):
            continue
        if isinstance(c, Zone) and ((c.shape == "box" and k in ("center_x", "center_z", "radius"))
                                    or (c.shape == "cylinder" and k in ("x_min", "x_max", "z_min", "z_max"))):
            continue
        out[k] = v
    return out


@dataclass
class Memory:
    """A rule's memory across snapshots, per track: frames seen, consecutive frames the condition held, time
    last seen, the condition's value when
    last seen, dwell start; and the time the closing speed went above the threshold (approach), when it
    was last known, the time the primary was last seen (lost)."""

    seen: dict[int, int] = field(default_factory=dict)
    run: dict[int, int] = field(default_factory=dict)
    last_seen: dict[int, float] = field(default_factory=dict)
    held: dict[int, bool] = field(default_factory=dict)
    last_pos: dict[int, tuple[float, float, float]] = field(default_factory=dict)
    inside_since: dict[int, float] = field(default_factory=dict)
    fast_since: float | None = None
    fast: bool = False
    speed_known: float | None = None
    primary_seen: float | None = None
    value: bool = False
    target: int | None = None


def per_target(snap: Snapshot, mem: Memory, test: Callable[[Target], bool]) -> list[int]:
    """Track ids for which a condition holds, oldest holder first: a confirmed target of this frame by its
    own value, a track not seen in this frame by the value it had when last seen, for HOLD_S."""
    for p in snap.targets:
        k = p.track_id
        mem.seen[k] = mem.seen.get(k, 0) + 1
        mem.last_seen[k] = snap.t
        mem.run[k] = mem.run.get(k, 0) + 1 if test(p) else 0
        mem.held[k] = mem.seen[k] >= MIN_HITS and mem.run[k] >= MIN_HITS
        mem.last_pos[k] = (p.x, p.y, p.z)
    for k in [k for k, t in mem.last_seen.items() if t < snap.t and (snap.t - t > HOLD_S or _taken_up(snap, mem, k))]:
        for d in (mem.seen, mem.last_seen, mem.run, mem.held, mem.inside_since, mem.last_pos):
            d.pop(k, None)
    for k, v in mem.held.items():
        if v:
            mem.inside_since.setdefault(k, snap.t)
        else:
            mem.inside_since.pop(k, None)
    return sorted((k for k, v in mem.held.items() if v), key=lambda k: mem.inside_since[k])


def _taken_up(snap: Snapshot, mem: Memory, k: int) -> bool:
    """Whether a track seen in this frame is where the missing track k could be by now."""
    reach = REACQUIRE_M + REACQUIRE_MPS * (snap.t - mem.last_seen[k])
    x, y, z = mem.last_pos[k]
    return any(math.dist((p.x, p.y, p.z), (x, y, z)) <= reach for p in snap.targets)


def evaluate(c: Condition, snap: Snapshot, mem: Memory) -> tuple[bool, int | None]:
    """(condition true, the target that made it true) at the snapshot; a tick without a frame keeps the
    last value of a target condition."""
    if isinstance(c, Fault):
        return c.source in snap.faults, None
    if snap.frame is None:
        return mem.value, mem.target
    mem.value, mem.target = _frame_value(c, snap, mem)
    return mem.value, mem.target


def _frame_value(c: Condition, snap: Snapshot, mem: Memory) -> tuple[bool, int | None]:
    if isinstance(c, Zone):
        inside = per_target(snap, mem, c.contains)
        ok = [k for k in inside if snap.t - mem.inside_since[k] >= c.dwell_s]
        return (True, ok[0]) if ok else (False, None)
    if isinstance(c, RangeBelow):
        near = per_target(snap, mem, lambda p: p.r < c.distance_m)
        return (True, near[0]) if near else (False, None)
    if isinstance(c, Size):
        fit = per_target(snap, mem, c.fits)
        return (True, fit[0]) if fit else (False, None)
    if isinstance(c, Approach):
        return _approach(c, snap, mem)
    assert isinstance(c, Lost)
    if snap.primary_id is not None and any(p.track_id == snap.primary_id for p in snap.targets):
        mem.primary_seen = snap.t
        return False, None
    return mem.primary_seen is not None and snap.t - mem.primary_seen > c.after_s, None


def _approach(c: Approach, snap: Snapshot, mem: Memory) -> tuple[bool, int | None]:
    """Closing faster than speed_mps (until under speed_mps − deadband_mps) for for_s; an unknown speed
    keeps the last value for HOLD_S but does not make for_s pass (a single fast sample followed by unknown
    ones raises nothing)."""
    v = snap.closing_mps
    if v is None:
        if mem.speed_known is None or snap.t - mem.speed_known > HOLD_S:
            mem.fast, mem.fast_since = False, None
            return False, None
        return mem.value, mem.target
    else:
        mem.speed_known = snap.t
        mem.fast = v > c.speed_mps or (mem.fast and v >= c.speed_mps - c.deadband_mps)
        if not mem.fast:
            mem.fast_since = None
        elif mem.fast_since is None:
            mem.fast_since = snap.t
    on = mem.fast_since is not None and snap.t - mem.fast_since >= c.for_s
    return on, snap.primary_id if on else None
