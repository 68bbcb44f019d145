"""`tmeye eval --alarms`: alarm rules run on the tracker's output over the endless simulated scene (closed
loop on the simulated gimbal, as `tmeye serve` runs by default), compared with the same rules applied to
the scene's true target positions.

Per rule, the truth is the rule's condition on the true objects of each frame (every object in the scene:
world position, range about the origin, closing speed −dr/dt by differences between frames, the approach
rule's deadband), with the rule's own delays: an expected alarm starts at the first frame the condition
holds (plus the on-delay, or the approach rule's `for_s`) and ends `off_delay_s` after the last frame it
holds (runs closer than the
off-delay merge). `entries` counts the raw runs (e.g. true zone entries). An alarm matches an expected one
when their intervals overlap; misses and false alarms are the unmatched ones; activation and clear errors
are alarm minus expected times (s) of the matched pairs (a positive activation error is a late alarm).
`out_of_view` counts the misses during which the condition never held for an object seen by both cameras
(its pixels in both images: no camera saw what would raise the alarm) and the late activations (over 0.1 s)
whose condition held for a seen object only later than 0.1 s after the expected start.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from server.alarms.conditions import Approach, RangeBelow, Target, Zone, condition_to_dict
from server.alarms.engine import AlarmEngine, Rule
from server.alarms.snapshot import snapshot_from
from tmeye.runtime.compose import compose
from tmeye.runtime.config import RuntimeConfig
from tmeye.runtime.telemetry import detection_json, telemetry
from tracker.sim.render import FrameTruth

F = np.float64
Interval = tuple[float, float]

RULES = (
    Rule("rule:1", "zone 6 x 6 m at 8-14 m", "critical", Zone("box", x_min=-3, x_max=3, z_min=8, z_max=14),
         0.0, 1.0),
    Rule("rule:2", "range below 6 m", "high", RangeBelow(6.0), 0.0, 1.0),
    Rule("rule:3", "approach above 0.8 m/s for 0.5 s", "medium", Approach(0.8, 0.5), 0.0, 1.0),
)


@dataclass
class RuleRecord:
    """Per rule: the truth per frame and the alarm intervals the engine produced."""

    rule: Rule
    truth: list[tuple[float, bool]] = field(default_factory=list)
    in_view: list[tuple[float, bool]] = field(default_factory=list)  # the condition on objects both cameras see
    alarms: list[list[float]] = field(default_factory=list)  # [activated, cleared (nan while active)]


def truth_value(rule: Rule, tr: FrameTruth, closing: dict[int, float], origin: np.ndarray, was: bool = False
                ) -> bool:
    """The rule's condition on the true objects of a frame; was: its value at the frame before (the
    approach rule's deadband)."""
    c = rule.condition
    if isinstance(c, Zone):
        return any(c.contains(Target(t.target_id, float(t.world[0]), float(t.world[1]), float(t.world[2]), 0.0))
                   for t in tr.targets)
    if isinstance(c, RangeBelow):
        return any(float(np.linalg.norm(t.world - origin)) < c.distance_m for t in tr.targets)
    if isinstance(c, Approach):
        return any(v > c.speed_mps or (was and v >= c.speed_mps - c.deadband_mps) for v in closing.values())
    raise ValueError(f"no truth for {c.kind}")


def runs(truth: list[tuple[float, bool]], dt: float) -> list[Interval]:
    """Raw runs of the truth: (first frame time, last frame time + dt)."""
    out: list[Interval] = []
    start = None
    for t, v in truth:
        if v and start is None:
            start = t
        elif not v and start is not None:
            out.append((start, t))
            start = None
    if start is not None:
        out.append((start, truth[-1][0] + dt))
    return out


def expected(rule: Rule, raw: list[Interval]) -> list[Interval]:
    """Expected alarms from raw runs, as the engine's delays make them: a condition's own hold (the approach
    rule's for_s) shortens each run from its start (a shorter run never holds); runs closer than the
    off-delay merge; the alarm starts on_delay_s after its first run starts (a first run shorter than the
    on-delay raises nothing) and clears off_delay_s after its last run ends."""
    hold = rule.condition.for_s if isinstance(rule.condition, Approach) else 0.0
    held = [(s + hold, e) for s, e in raw if e - s >= hold - 1e-9]
    out: list[list[float]] = []
    for s, e in held:
        if out and s - out[-1][1] < rule.off_delay_s:
            out[-1][1] = e
        elif e - s >= rule.on_delay_s - 1e-9:
            out.append([s + rule.on_delay_s, e])
    return [(s, e + rule.off_delay_s) for s, e in out]


def compare(exp: list[Interval], got: list[Interval], end: float,
            in_view: list[tuple[float, bool]] | None = None, hold: float = 0.0) -> dict[str, Any]:
    """Expected against produced alarm intervals; `end`: the run's end (s): a clear expected after it is not
    timed; in_view: the condition on the objects both cameras see, per frame; hold: the condition's own hold
    (s, before the expected start)."""
    def overlaps(a: Interval, b: Interval) -> bool:
        return a[0] <= b[1] and b[0] <= a[1]

    matched = [(e, next(g for g in got if overlaps(e, g))) for e in exp if any(overlaps(e, g) for g in got)]
    on = [g[0] - e[0] for e, g in matched]
    off = [g[1] - e[1] for e, g in matched if math.isfinite(g[1]) and e[1] < end]
    false = [g for g in got if not any(overlaps(g, e) for e in exp)]
    split = sum(max(0, sum(overlaps(e, g) for g in got) - 1) for e in exp)

    def stats(v: list[float]) -> dict[str, float | None]:
        a = np.abs(np.array(v, F))
        return {"mean_s": round(float(np.mean(v)), 4) if v else None,
                "p50_abs_s": round(float(np.median(a)), 4) if v else None,
                "max_abs_s": round(float(a.max()), 4) if v else None,
                "within_0.1s": int((a <= 0.1 + 1e-9).sum())}

    def seen_from(e: Interval) -> float:
        return next((t for t, v in in_view or () if v and e[0] - hold - 1e-9 <= t <= e[1]), math.inf)

    missed = [e for e in exp if all(not overlaps(e, g) for g in got)]
    unseen = {"misses": sum(seen_from(e) == math.inf for e in missed),
              "late": sum(g[0] - e[0] > 0.1 + 1e-9 and seen_from(e) > e[0] - hold + 0.1 + 1e-9 for e, g in matched)}
    return {"expected": len(exp), "alarms": len(got), "matched": len(matched), "misses": len(exp) - len(matched),
            "false_alarms": len(false), "split": split, "activation_error": stats(on), "clear_error": stats(off),
            "out_of_view": unseen if in_view is not None else None,
            "false_alarm_times": [round(g[0], 2) for g in false][:20],
            "missed_times": [round(e[0], 2) for e in exp if all(not overlaps(e, g) for g in got)][:20]}


def evaluate_alarms(minutes: float = 10.0, seed: int = 0, rules: tuple[Rule, ...] = RULES,
                    progress: Callable[[int, int], None] | None = None, start_s: float = 0.0) -> dict[str, Any]:
    """`minutes` of the scene from scene time `start_s` (s; the tracker starts afresh there, so a long run
    can be measured in parts that run side by side)."""
    cfg = RuntimeConfig(source="sim", scenario="endless", seed=seed, servo="sim", realtime=False)
    comp = compose(cfg)
    assert comp.sim is not None and comp.loop is not None
    comp.sim.index = first = int(round(start_s * comp.fps))
    origin = np.asarray(cfg.origin, F)
    engine = AlarmEngine(rules, builtin=False)
    recs = {r.key: RuleRecord(r) for r in rules}
    n = int(round(minutes * 60.0 * comp.fps))
    dt = 1.0 / comp.fps
    last_r: dict[int, float] = {}
    try:
        for k in range(n):
            frame = comp.source.read()
            truth = comp.sim.last_truth
            assert frame is not None and truth is not None
            step = comp.loop.step(frame)
            tm = telemetry(step.result, frame, comp.fps, first + k)
            tm["detections"] = [detection_json(d, comp.pipeline.rect.f) for d in step.result.detections]
            ranges = {t.target_id: float(np.linalg.norm(t.world - origin)) for t in truth.targets}
            closing = {i: (last_r[i] - r) / dt for i, r in ranges.items() if i in last_r}
            last_r = ranges
            seen = ({int(k) for k in np.unique(truth.ids_left)} & {int(k) for k in np.unique(truth.ids_right)}) - {0}
            visible = dataclasses.replace(truth, targets=tuple(t for t in truth.targets if t.target_id in seen))
            for rec in recs.values():
                was = bool(rec.truth) and rec.truth[-1][1]
                rec.truth.append((frame.t, truth_value(rec.rule, truth, closing, origin, was)))
                was = bool(rec.in_view) and rec.in_view[-1][1]
                rec.in_view.append((frame.t, truth_value(rec.rule, visible, {i: v for i, v in closing.items()
                                                                             if i in seen}, origin, was)))
            for tr in engine.step(snapshot_from(frame.t, first + k, tm, step, cfg.origin)):
                rec = recs[str(tr.rule)]
                if tr.kind == "activated":
                    rec.alarms.append([tr.t, math.nan])
                elif tr.kind == "cleared":
                    rec.alarms[-1][1] = tr.t
            if progress is not None:
                progress(k + 1, n)
    finally:
        comp.close()
    out: dict[str, Any] = {"scenario": "endless", "seed": seed, "start_s": start_s, "frames": n,
                           "simulated_s": round(n * dt, 2), "fps": comp.fps, "rules": []}
    for rec in recs.values():
        raw = runs(rec.truth, dt)
        got = [(a, c if math.isfinite(c) else math.inf) for a, c in rec.alarms]  # inf: still active at the end
        res = {"name": rec.rule.name, "condition": condition_to_dict(rec.rule.condition),
               "on_delay_s": rec.rule.on_delay_s, "off_delay_s": rec.rule.off_delay_s, "entries": len(raw)}
        hold = rec.rule.condition.for_s if isinstance(rec.rule.condition, Approach) else 0.0
        res.update(compare(expected(rec.rule, raw), got, rec.truth[-1][0], rec.in_view, hold))
        out["rules"].append(res)
    return out
