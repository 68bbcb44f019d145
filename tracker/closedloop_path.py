"""Piecewise target paths for closed-loop scenarios: straight legs with acceleration, coordinated turns and
stop-start reversals, integrated once and then interpolated (a `Trajectory`: t -> world point).

World frame of tracker.geometry (x right, y down, z forward, metres). The horizontal heading ψ is measured
from +z towards +x, so a positive turn rate turns a target heading right (+x) towards the rig (-z).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

F64 = NDArray[np.float64]


@dataclass(frozen=True)
class Leg:
    """One leg of a path: duration_s (s), tangential acceleration accel (m/s², speed floored at 0), turn
    rate turn_deg_s (deg/s, heading rate of a coordinated turn). reverse: turn the heading by 180° at the
    start of the leg (only sensible when the target is at rest: a stop-start reversal)."""

    duration_s: float
    accel: float = 0.0
    turn_deg_s: float = 0.0
    reverse: bool = False


class LegPath:
    """A horizontal path of `Leg`s from `start` (x, z) in metres with initial heading `heading_deg` and
    speed 0, at height y(t) (m, down positive). Integrated with step `dt_s`; evaluation interpolates
    linearly (error < 1 mm at the default step). Beyond the last leg the target keeps its last position."""

    def __init__(self, legs: Sequence[Leg], start: tuple[float, float], heading_deg: float,
                 height: Callable[[float], float], dt_s: float = 1e-3):
        self.legs = tuple(legs)
        self.height = height
        ts, xs, zs, turns = [0.0], [start[0]], [start[1]], []
        x, z, v, psi, t = start[0], start[1], 0.0, math.radians(heading_deg), 0.0
        for leg in self.legs:
            if leg.reverse:
                psi += math.pi
            w = math.radians(leg.turn_deg_s)
            for _ in range(max(round(leg.duration_s / dt_s), 0)):
                turns.append(w)
                v = max(v + leg.accel * dt_s, 0.0)  # dv/dt = a
                psi += w * dt_s  # dψ/dt = ω
                x += v * math.sin(psi) * dt_s
                z += v * math.cos(psi) * dt_s
                t += dt_s
                ts.append(t)
                xs.append(x)
                zs.append(z)
        turns.append(0.0)
        self._t = np.array(ts)
        self._x = np.array(xs)
        self._z = np.array(zs)
        self._w = np.array(turns)  # turn rate (rad/s) over [t_k, t_k+1)

    @property
    def duration_s(self) -> float:
        return float(self._t[-1])

    def __call__(self, t: float) -> F64:
        """World position (3,) in metres at time t (s)."""
        return np.array([float(np.interp(t, self._t, self._x)), self.height(t),
                         float(np.interp(t, self._t, self._z))])

    def turn_rate(self, t: float) -> float:
        """The commanded heading rate (rad/s) at time t (s); 0 on straight legs and outside the path."""
        if t < 0.0 or t >= self._t[-1]:
            return 0.0
        k = int(np.searchsorted(self._t, t, side="right")) - 1
        return float(self._w[k])

    def turning(self, t0: float, t1: float) -> bool:
        """True if the target turns at any time in [t0, t1] (s)."""
        k0 = max(int(np.searchsorted(self._t, t0, side="right")) - 1, 0)
        k1 = int(np.searchsorted(self._t, t1, side="right"))
        return bool(np.any(self._w[k0:k1] != 0.0))


def _manoeuvre_height(t: float) -> float:
    """Height of the manoeuvre target: 1.2 m above the ground ± 0.2 m (y = 0.3 ± 0.2 m, down positive)."""
    return 0.3 + 0.2 * math.sin(2.0 * math.pi * t / 6.0)


# Starts 10 m ahead at azimuth 0 heading right; the azimuth swings from +38.5° to -19.5° (58°, more than
# the 56° horizontal field of view; further left the target would pass behind the simulated scene's post),
# range 9.6-11.2 m, speeds up to 3.6 m/s, accelerations of ±6 m/s², coordinated turns of 25-30°/s (38 % of
# the time), line-of-sight rates up to 21°/s, two stop-start reversals; 9.8 s.
MANOEUVRE = LegPath(
    (
        Leg(0.6, accel=6.0),  # accelerate to the right
        Leg(0.4),
        Leg(1.0, turn_deg_s=25.0),  # turn towards the rig
        Leg(0.6, accel=-6.0),  # stop
        Leg(0.4),
        Leg(0.6, accel=6.0, reverse=True),  # start back to the left
        Leg(0.4),
        Leg(1.2, turn_deg_s=-30.0),  # turn away
        Leg(0.8),
        Leg(0.6, accel=-6.0),  # stop
        Leg(0.3),
        Leg(0.6, accel=6.0, reverse=True),  # start back to the right
        Leg(0.3),
        Leg(1.5, turn_deg_s=30.0),  # turn towards the rig
        Leg(0.5),
    ),
    start=(0.0, 10.0),
    heading_deg=90.0,
    height=_manoeuvre_height,
)
