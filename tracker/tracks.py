"""Identities across frames: several candidate objects, one primary target.

Association in the image by predicted centroid (constant velocity in pixels and disparity), solved as
an assignment problem (scipy's linear_sum_assignment) with a gate. A track is confirmed after
`confirm_hits` associations and dropped after `max_missed` frames without one. The primary target is the
oldest confirmed track, kept until it is dropped (no switching to a newcomer).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import linear_sum_assignment

F64 = NDArray[np.float64]


@dataclass
class Track:
    """A tracked object: id, last image state (x, y, d), velocity per second, age and misses."""

    track_id: int
    state: F64
    velocity: F64 = field(default_factory=lambda: np.zeros(3))
    t: float = 0.0
    hits: int = 1
    missed: int = 0
    confirmed: bool = False

    def predict(self, t: float) -> F64:
        return np.asarray(self.state + self.velocity * (t - self.t))


@dataclass(frozen=True)
class PrimaryBefore:
    """What an operator's choice of primary target changed: the primary from before and the track the choice
    confirmed (None: it was confirmed already)."""

    primary_id: int | None
    confirmed_id: int | None


@dataclass(frozen=True)
class TrackerConfig:
    gate_px: float = 40.0
    gate_growth_px: float = 4.0  # per frame without a detection
    confirm_hits: int = 2
    max_missed: int = 60


class MultiTracker:
    """`update(t, observations)` with observations (N, 3) of (x, y, disparity) -> assignment of each
    observation to a track id (a new, unconfirmed track for an unmatched one); `primary_id` is the oldest
    confirmed track."""

    def __init__(self, config: TrackerConfig | None = None):
        self.cfg = config or TrackerConfig()
        self.tracks: list[Track] = []
        self._next_id = 1
        self.primary_id: int | None = None

    def update(self, t: float, obs: F64) -> list[int]:
        assigned = [-1] * len(obs)
        pairs = self._associate(t, obs)
        used = set()
        for ti, oi in pairs:
            tr = self.tracks[ti]
            dt = max(t - tr.t, 1e-3)
            new_v = (obs[oi] - tr.state) / dt
            tr.velocity = new_v if tr.hits == 1 else 0.5 * tr.velocity + 0.5 * new_v
            tr.state, tr.t = obs[oi].astype(float), t
            tr.hits += 1
            tr.missed = 0
            tr.confirmed |= tr.hits >= self.cfg.confirm_hits
            used.add(ti)
            assigned[oi] = tr.track_id
        for ti, tr in enumerate(self.tracks):
            if ti not in used:
                tr.missed += 1
        self.tracks = [tr for tr in self.tracks if tr.missed <= self.cfg.max_missed]
        for oi in range(len(obs)):
            if assigned[oi] == -1:
                tr = Track(self._next_id, obs[oi].astype(float), t=t, confirmed=self.cfg.confirm_hits <= 1)
                self._next_id += 1
                self.tracks.append(tr)
                assigned[oi] = tr.track_id
        self._choose_primary()
        return assigned

    def _associate(self, t: float, obs: F64) -> list[tuple[int, int]]:
        if not self.tracks or len(obs) == 0:
            return []
        pred = np.array([tr.predict(t) for tr in self.tracks])
        cost = np.linalg.norm(pred[:, None, :2] - obs[None, :, :2], axis=2)
        cost += 2.0 * np.abs(pred[:, None, 2] - obs[None, :, 2])  # disparity keeps depth order apart
        rows, cols = linear_sum_assignment(cost)
        # the gate widens while a track coasts: its predicted position grows less certain
        gate = [self.cfg.gate_px + self.cfg.gate_growth_px * tr.missed for tr in self.tracks]
        return [(int(r), int(c)) for r, c in zip(rows, cols, strict=True) if cost[r, c] <= gate[r]]

    def select_primary(self, track_id: int) -> PrimaryBefore | None:
        """Make a living track the primary target (an operator's choice); None if there is no such track,
        else what `restore_primary` needs to undo the choice."""
        tr = self.get(track_id)
        if tr is None:
            return None
        before = PrimaryBefore(self.primary_id, None if tr.confirmed else track_id)
        tr.confirmed = True
        self.primary_id = track_id
        return before

    def restore_primary(self, before: PrimaryBefore) -> None:
        """Undo `select_primary`: the primary target from before (the oldest confirmed track if it has
        ended since), and the chosen track unconfirmed again if the choice had confirmed it."""
        chosen = None if before.confirmed_id is None else self.get(before.confirmed_id)
        if chosen is not None:
            chosen.confirmed = chosen.hits >= self.cfg.confirm_hits
        self.primary_id = before.primary_id
        self._choose_primary()

    def _choose_primary(self) -> None:
        alive = {tr.track_id: tr for tr in self.tracks if tr.confirmed}
        if self.primary_id in alive:
            return
        self.primary_id = min(alive) if alive else None

    def predictions(self, t: float) -> F64:
        """Predicted (x, y, disparity) at time t of the tracks seen in the last few frames, (N, 3)."""
        return np.array([tr.predict(t) for tr in self.tracks if tr.missed <= 2]).reshape(-1, 3)

    def get(self, track_id: int) -> Track | None:
        return next((tr for tr in self.tracks if tr.track_id == track_id), None)
