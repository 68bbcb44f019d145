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
Targets count once their track has been seen in `MIN_HITS` consecutive frames (the tracker's own
confirmation), so a single-frame false detection raises nothing.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

MIN_HITS = 2
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
        return Approach(_num(d, "speed_mps", None, 0.0), _num(d, "for_s", 0.0, 0.0))
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
    """A rule's memory across snapshots: consecutive frames per track, dwell start per track, the time the
    closing speed went above the threshold, the time the primary was last seen."""

    hits: dict[int, int] = field(default_factory=dict)
    inside_since: dict[int, float] = field(default_factory=dict)
    fast_since: float | None = None
    primary_seen: float | None = None
    value: bool = False
    target: int | None = None


def confirmed(snap: Snapshot, mem: Memory) -> list[Target]:
    """The snapshot's targets whose tracks were seen in MIN_HITS consecutive frames (updates mem.hits)."""
    mem.hits = {p.track_id: mem.hits.get(p.track_id, 0) + 1 for p in snap.targets}
    return [p for p in snap.targets if mem.hits[p.track_id] >= MIN_HITS]


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
    targets = confirmed(snap, mem)
    if isinstance(c, Zone):
        inside = [p.track_id for p in targets if c.contains(p)]
        mem.inside_since = {k: mem.inside_since.get(k, snap.t) for k in inside}
        ok = [k for k in inside if snap.t - mem.inside_since[k] >= c.dwell_s]
        return (True, ok[0]) if ok else (False, None)
    if isinstance(c, RangeBelow):
        near = [p for p in targets if p.r < c.distance_m]
        return (True, min(near, key=lambda p: p.r).track_id) if near else (False, None)
    if isinstance(c, Size):
        fit = [p.track_id for p in targets if c.fits(p)]
        return (True, fit[0]) if fit else (False, None)
    if isinstance(c, Approach):
        fast = snap.closing_mps is not None and snap.closing_mps > c.speed_mps
        mem.fast_since = (mem.fast_since if mem.fast_since is not None else snap.t) if fast else None
        on = mem.fast_since is not None and snap.t - mem.fast_since >= c.for_s
        return on, snap.primary_id if on else None
    assert isinstance(c, Lost)
    if snap.primary_id is not None and any(p.track_id == snap.primary_id for p in targets):
        mem.primary_seen = snap.t
        return False, None
    return mem.primary_seen is not None and snap.t - mem.primary_seen > c.after_s, None
