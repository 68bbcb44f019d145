"""The endless simulated scene (scenario `endless`): people come and go for ever, deterministic for a seed.

One episode after another: a person (target id 1, the primary) enters from the side (at azimuth ±36°,
just outside the home view) or from far away (27-30 m, behind the hedge), walks at 0.8-1.8 m/s to one to
three waypoints (3.5-21 m, azimuth ±30°), stops at each for 1-4 s and turns, then leaves by the side or
far away, where it vanishes. The next episode starts 0.5-4 s after the last one ends. In about one
episode in four a second object (id 2) passes as a distractor: a second person, or the round plate of
`two-targets` crossing at 4-10 m. The light drifts in slow ramps (0.75-1.25) with the occasional step
of ±20-30 %. Episodes and light are generated lazily, as far as they are asked for, and kept (asking for
an earlier time again gives the same answer).

World frame of tracker.sim.scene (x right, y down, z forward, metres; the gimbal base at the origin).
Ranges are horizontal distances from the gimbal base; azimuth from +z towards +x.
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from tracker.sim.scene import CAMERA_HEIGHT_M, MovingObject, person_texture, plate_texture

F64 = NDArray[np.float64]

PERSON_HALF_W_M, PERSON_HALF_H_M = 0.25, 0.85  # a person: 0.5 m wide, 1.7 m tall, standing on the ground
PERSON_Y_M = CAMERA_HEIGHT_M - PERSON_HALF_H_M  # the centre's height (y down): 0.85 m above the ground
EDGE_AZ_DEG = 36.0  # side entries and exits
REGION_AZ_DEG = 30.0  # waypoints
REGION_RANGE_M = (3.5, 21.0)  # waypoints: in front of the facade (22 m) and the hedge (24 m)
FAR_RANGE_M = (27.0, 29.9)  # far entries and exits (behind the hedge)
FAR_AZ_DEG = 12.0  # far entries and exits stay clear of the facade (azimuth 14-30° at 22 m)
MIN_RANGE_M = 3.0
SPEED_M_S = (0.8, 1.8)
ACCEL_M_S2 = 1.0
STOP_S = (1.0, 4.0)
GAP_S = (0.5, 4.0)
PLATE_RANGE_M = (4.0, 10.0)
PLATE_Y_M = (0.0, 0.6)  # the plate's centre 0.9-1.5 m above the ground
TILT_SPAN_DEG = 26.0  # mount_range's tilt span: over survey_grid's 24° step, so it surveys two rows


def _polar(az_deg: float, r: float) -> F64:
    """The ground point (x, z) at azimuth az_deg (deg) and range r (m), (2,)."""
    a = math.radians(az_deg)
    return np.array([r * math.sin(a), r * math.cos(a)])


def _closest_range(a: F64, b: F64) -> float:
    """The smallest range (m) on the ground segment a -> b ((2,) each)."""
    d = b - a
    s = float(np.clip(-(a @ d) / max(float(d @ d), 1e-12), 0.0, 1.0))
    return float(np.hypot(*(a + s * d)))


@dataclass(frozen=True)
class _Leg:
    """A straight walk from a to b ((x, z), m) starting at t0 (s): accelerate at ACCEL_M_S2 to v (m/s),
    cruise, decelerate to rest at b."""

    t0: float
    a: F64
    b: F64
    v: float

    @property
    def length(self) -> float:
        return float(np.hypot(*(self.b - self.a)))

    @property
    def peak(self) -> float:
        return min(self.v, math.sqrt(self.length * ACCEL_M_S2))

    @property
    def duration(self) -> float:
        v = self.peak
        return 2.0 * v / ACCEL_M_S2 + (self.length - v * v / ACCEL_M_S2) / v if v > 0 else 0.0

    def at(self, t: float) -> F64:
        """The ground point (x, z) at time t (s) within the leg."""
        big_t, v, length = self.duration, self.peak, self.length
        tau = min(max(t - self.t0, 0.0), big_t)
        t_acc = v / ACCEL_M_S2
        if tau < t_acc:
            s = 0.5 * ACCEL_M_S2 * tau * tau
        elif tau < big_t - t_acc:
            s = 0.5 * v * t_acc + v * (tau - t_acc)
        else:
            s = length - 0.5 * ACCEL_M_S2 * (big_t - tau) ** 2
        return self.a + (self.b - self.a) * (s / length if length > 0 else 0.0)


class WalkPath:
    """A walk through ground points (x, z) (m) starting at t0 (s): a `_Leg` to each point, at speed v
    (m/s), resting `dwell[k]` s at interior point k + 1; at height y (m, down positive). Called with t (s),
    the centre (x, y, z) (3,); before t0 and after t1 it holds its end points."""

    def __init__(self, t0: float, points: list[F64], dwell: list[float], v: float, y: float):
        self.t0, self.y = t0, y
        self.legs: list[_Leg] = []
        t = t0
        for k in range(len(points) - 1):
            leg = _Leg(t, points[k], points[k + 1], v)
            self.legs.append(leg)
            t += leg.duration + (dwell[k] if k < len(dwell) else 0.0)
        self.t1 = self.legs[-1].t0 + self.legs[-1].duration

    def __call__(self, t: float) -> F64:
        k = max(bisect.bisect_right([leg.t0 for leg in self.legs], t) - 1, 0)
        x, z = self.legs[k].at(t)
        return np.array([x, self.y, z])

    def present(self, t: float) -> bool:
        """Whether the walker is in the scene at time t (s): t0 <= t <= t1."""
        return self.t0 <= t <= self.t1


@dataclass(frozen=True)
class Episode:
    """The people and objects of one episode: actors[0] is the primary (id 1); start and end in s."""

    start: float
    end: float
    actors: tuple[MovingObject, ...]


def _waypoint(rng: np.random.Generator, prev: F64) -> F64:
    """A waypoint 2-10 m from prev inside the region, reached without passing nearer than MIN_RANGE_M."""
    for _ in range(200):
        heading = rng.uniform(0.0, 2.0 * math.pi)
        p = prev + rng.uniform(2.0, 10.0) * np.array([math.sin(heading), math.cos(heading)])
        r, az = float(np.hypot(*p)), math.degrees(math.atan2(p[0], p[1]))
        if (REGION_RANGE_M[0] <= r <= REGION_RANGE_M[1] and abs(az) <= REGION_AZ_DEG
                and _closest_range(prev, p) >= MIN_RANGE_M):
            return p
    return _polar(0.0, 10.0)  # practically unreachable; a point every region point sees without passing near


def _route(rng: np.random.Generator) -> list[F64]:
    """A person's ground points (x, z): the entry, 1-3 waypoints, the exit."""
    if rng.random() < 0.6:  # from the side
        pts = [_polar(float(rng.choice([-1.0, 1.0])) * EDGE_AZ_DEG, rng.uniform(4.0, 20.0))]
    else:  # from far away, straight in
        az = rng.uniform(-FAR_AZ_DEG, FAR_AZ_DEG)
        pts = [_polar(az, rng.uniform(*FAR_RANGE_M)), _polar(az, rng.uniform(10.0, 20.0))]
    while len(pts) < 2 + int(rng.integers(0, 3)):
        pts.append(_waypoint(rng, pts[-1]))
    last = pts[-1]
    r, az = float(np.hypot(*last)), math.degrees(math.atan2(last[0], last[1]))
    if abs(az) <= FAR_AZ_DEG and rng.random() < 0.4:  # leave far away, straight out
        pts.append(_polar(az, rng.uniform(*FAR_RANGE_M)))
    else:  # leave by the nearer side, at no less than 4 m
        pts.append(_polar(math.copysign(EDGE_AZ_DEG, az), max(r, 4.0)))
    return pts


def _person(rng: np.random.Generator, tid: int, t0: float) -> tuple[MovingObject, float]:
    """A person walking a random route from t0 (s), and the time (s) it leaves."""
    pts = _route(rng)
    dwell = [float(rng.uniform(*STOP_S)) for _ in pts[1:-1]]
    path = WalkPath(t0, pts, dwell, float(rng.uniform(*SPEED_M_S)), PERSON_Y_M)
    lo = int(rng.integers(100, 126))
    tex = person_texture(rng, lo, lo + 125, 0.01, (2.0 * PERSON_HALF_W_M, 2.0 * PERSON_HALF_H_M))
    return MovingObject(tid, path, PERSON_HALF_W_M, tex, path.present, PERSON_HALF_H_M), path.t1


def _plate(rng: np.random.Generator, tid: int, t0: float) -> tuple[MovingObject, float]:
    """The second-object plate (radius 0.3 m) crossing the scene from side to side from t0 (s)."""
    side = float(rng.choice([-1.0, 1.0]))
    r = rng.uniform(*PLATE_RANGE_M)
    pts = [_polar(side * EDGE_AZ_DEG, r), _polar(-side * EDGE_AZ_DEG, r)]
    path = WalkPath(t0, pts, [], float(rng.uniform(0.5, 1.5)), float(rng.uniform(*PLATE_Y_M)))
    return MovingObject(tid, path, 0.3, plate_texture(rng, 150, 235), path.present), path.t1


def make_episode(rng: np.random.Generator, start: float) -> Episode:
    """One episode from `start` (s): the primary person and, one time in four, a second object entering
    1-8 s later (a person or the plate, even odds). It ends when the last of them leaves."""
    primary, end = _person(rng, 1, start)
    actors = [primary]
    if rng.random() < 0.25:
        t2 = start + float(rng.uniform(1.0, 8.0))
        second, end2 = (_person if rng.random() < 0.5 else _plate)(rng, 2, t2)
        actors.append(second)
        end = max(end, end2)
    return Episode(start, end, tuple(actors))


class LightSchedule:
    """The global illumination gain g(t): holds of 3-10 s, then a ramp over 2-6 s to a level in
    [0.75, 1.25] (two times in three) or a step of ±20-30 % (kept within [0.65, 1.35])."""

    def __init__(self, rng: np.random.Generator):
        self._rng = rng
        self._pieces: list[tuple[float, float, float, float]] = []  # (t0, t1, g0, g1), linear in t
        self._end, self._level = 0.0, 1.0

    def _extend(self) -> None:
        rng = self._rng
        hold = float(rng.uniform(3.0, 10.0))
        self._pieces.append((self._end, self._end + hold, self._level, self._level))
        self._end += hold
        if rng.random() < 2.0 / 3.0:
            new, dur = float(np.clip(self._level + rng.uniform(-0.25, 0.25), 0.75, 1.25)), float(rng.uniform(2, 6))
            self._pieces.append((self._end, self._end + dur, self._level, new))
            self._end += dur
        else:
            delta = float(rng.uniform(0.2, 0.3)) * float(rng.choice([-1.0, 1.0]))
            new = self._level * (1.0 + delta)
            if not 0.65 <= new <= 1.35:
                new = self._level * (1.0 - delta)
        self._level = new

    def __call__(self, t: float) -> float:
        while self._end <= t:
            self._extend()
        k = max(bisect.bisect_right([p[0] for p in self._pieces], t) - 1, 0)
        t0, t1, g0, g1 = self._pieces[k]
        return g0 + (g1 - g0) * min(max((t - t0) / (t1 - t0), 0.0), 1.0) if t1 > t0 else g1


class EndlessScene:
    """The endless scene of one seed: `present(t)` the moving objects in the scene at time t (s), `gain(t)`
    the illumination gain. Deterministic for a seed, whatever order the times are asked in."""

    def __init__(self, seed: int):
        self._rng = np.random.default_rng([seed, 0xE1])
        self.gain = LightSchedule(np.random.default_rng([seed, 0xE2]))
        self.episodes: list[Episode] = []
        self._starts: list[float] = []

    def episodes_until(self, t: float) -> list[Episode]:
        """The episodes starting at or before time t (s) (generating them as needed), in order."""
        while not self.episodes or self.episodes[-1].start <= t:
            start = self.episodes[-1].end if self.episodes else 0.0
            ep = make_episode(self._rng, start + float(self._rng.uniform(*GAP_S)))
            self.episodes.append(ep)
            self._starts.append(ep.start)
        return self.episodes[:bisect.bisect_right(self._starts, t)]

    def present(self, t: float) -> list[MovingObject]:
        """The objects in the scene at time t (s): the current episode's actors that have entered and not
        yet left; none between episodes."""
        eps = self.episodes_until(t)
        if not eps or t > eps[-1].end:
            return []
        return [a for a in eps[-1].actors if a.visible(t)]


def mount_range(margin_deg: float = 4.0) -> tuple[tuple[float, float], tuple[float, float]]:
    """(pan, tilt) ranges (deg) for the mount following an endless scene's objects: pan ±(EDGE_AZ_DEG +
    margin_deg); tilt from a person's centre at MIN_RANGE_M (-12.2°) minus margin_deg up to margin_deg
    above the horizon, then widened symmetrically to a span of TILT_SPAN_DEG, so that
    `tracker.closedloop.survey_grid` (one tilt row at the middle of a span under its 24° step) surveys two
    rows, at the ends: one middle row leaves the top and bottom of the view unsurveyed at the range's
    ends, and unknown background there gives false targets that pull the mount further out."""
    el_min = min(-math.degrees(math.atan2(PERSON_Y_M, MIN_RANGE_M)),
                 -math.degrees(math.atan2(PLATE_Y_M[1], PLATE_RANGE_M[0]))) - margin_deg
    el_max = margin_deg
    pad = max(TILT_SPAN_DEG - (el_max - el_min), 0.0) / 2.0
    return ((-EDGE_AZ_DEG - margin_deg, EDGE_AZ_DEG + margin_deg), (el_min - pad, el_max + pad))
