"""Identities across frames: several candidate objects, one primary target.

Association in the image by predicted centroid (constant velocity in pixels and disparity), solved as
an assignment problem (scipy's linear_sum_assignment) with a gate. A track is confirmed after
`confirm_hits` associations and dropped after `max_missed` frames without one. The primary target is the
oldest confirmed track, kept while it is seen or coasts (no switching to a newcomer), until it is dropped or has
gone unseen for `primary_hold_s` while another confirmed track is seen: then the oldest seen one takes the role
(a mount's aim gives a lost target up after the same time, tracker.aim). A confirmed track that misses a
frame while a younger track begun within its gate is seen within it takes that track over (`_reunite`): a
part split off its object, or the object seen again beside its prediction, keeps the older identity.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import linear_sum_assignment

F64 = NDArray[np.float64]
NO_STEREO = 1_000_000  # `Track.since_stereo` of a track no stereo sighting vouches for
STEREO_KEPT = 5  # stereo sightings a track keeps for the disparity it holds (MultiTracker.coasting)


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
    since_stereo: int = 0  # updates since its last stereo sighting: sightings by the left camera alone, misses
    stereo: list[tuple[float, float, float]] = field(default_factory=list)  # the last stereo sightings' t, d, σ_d
    born_near: int | None = None  # the confirmed track whose gate its first sighting lay in (MultiTracker._reunite)

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
    primary_hold_s: float | None = 1.5  # a primary unseen this long yields to a seen confirmed track (None: never)


class MultiTracker:
    """`update(t, observations)` with observations (N, 3) of (x, y, disparity) -> assignment of each
    observation to a track id (a new, unconfirmed track for an unmatched one); `primary_id` is the oldest
    confirmed track."""

    def __init__(self, config: TrackerConfig | None = None):
        self.cfg = config or TrackerConfig()
        self.tracks: list[Track] = []
        self._next_id = 1
        self.primary_id: int | None = None

    def update(self, t: float, obs: F64, sigma_d: F64 | None = None, one_camera: NDArray[np.bool_] | None = None
               ) -> list[int]:
        """obs: (N, 3) x, y, disparity; sigma_d: (N,) their disparities' 1-σ (px); one_camera: (N,) which were
        seen by the left camera alone, at a track's held disparity (tracker.one_camera). A track started by
        such a sighting is confirmed only after a stereo sighting and may not live on more of them."""
        sd = np.zeros(len(obs)) if sigma_d is None else sigma_d
        alone = np.zeros(len(obs), bool) if one_camera is None else one_camera
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
            tr.since_stereo = tr.since_stereo + 1 if alone[oi] else 0
            tr.confirmed |= tr.hits >= self.cfg.confirm_hits and tr.since_stereo < NO_STEREO
            if not alone[oi]:
                tr.stereo = [*tr.stereo[1 - STEREO_KEPT:], (t, float(obs[oi, 2]), float(sd[oi]))]
            used.add(ti)
            assigned[oi] = tr.track_id
        for ti, tr in enumerate(self.tracks):
            if ti not in used:
                tr.missed += 1
                tr.since_stereo += 1
        self.tracks = [tr for tr in self.tracks if tr.missed <= self.cfg.max_missed]
        for oi in range(len(obs)):
            if assigned[oi] == -1:
                seen = [] if alone[oi] else [(t, float(obs[oi, 2]), float(sd[oi]))]
                tr = Track(self._next_id, obs[oi].astype(float), t=t, since_stereo=0 if seen else NO_STEREO,
                           confirmed=self.cfg.confirm_hits <= 1 and bool(seen), stereo=seen,
                           born_near=self._gated_by(t, obs[oi]))
                self._next_id += 1
                self.tracks.append(tr)
                assigned[oi] = tr.track_id
        self._reunite(t, assigned)
        self._choose_primary(t)
        return assigned

    def _cost(self, tr: Track, t: float, x: F64) -> float:
        """The association's cost (`_costs`) of state x (x, y, d) for track tr at time t."""
        return float(_costs(tr.predict(t)[None, :], np.asarray(x, np.float64)[None, :])[0, 0])

    def _gate(self, tr: Track) -> float:
        """The largest cost at which tr takes a sighting: it widens while the track coasts, its predicted
        position growing less certain."""
        return self.cfg.gate_px + self.cfg.gate_growth_px * tr.missed

    def _gated_by(self, t: float, x: F64) -> int | None:
        """The oldest confirmed track within whose gate state x lies (a track seen this frame at its sighting;
        with confirm_hits 1 that may be one begun this frame)."""
        return next((tr.track_id for tr in self.tracks if tr.confirmed and self._cost(tr, t, x) <= self._gate(tr)),
                    None)

    def _reunite(self, t: float, assigned: list[int]) -> None:
        """A confirmed track that missed this frame takes over a younger track begun within its gate (a part
        of its object split off and kept while the rest faded, or the object seen again beside where it was
        predicted), when the younger one's sighting this frame lies within its gate: the older identity, the
        primary target's, goes on (with the younger one's state) instead of coasting, "not detected", for up
        to max_missed frames while its object is tracked under another id. Live on the endless scene a part
        of the primary target split off so and the primary coasted 45 frames (2026-12-02)."""
        for old in [tr for tr in self.tracks if tr.confirmed and tr.missed > 0]:
            young = [tr for tr in self.tracks if tr.born_near == old.track_id and tr.missed == 0
                     and self._cost(old, t, tr.state) <= self._gate(old)]
            if not young:
                continue
            new = min(young, key=lambda tr: self._cost(old, t, tr.state))
            old.state, old.velocity, old.t, old.missed = new.state, new.velocity, new.t, 0
            old.hits += new.hits
            old.since_stereo = new.since_stereo
            old.stereo = [*old.stereo, *new.stereo][-STEREO_KEPT:]
            self.tracks.remove(new)
            assigned[:] = [old.track_id if a == new.track_id else a for a in assigned]

    def _associate(self, t: float, obs: F64) -> list[tuple[int, int]]:
        if not self.tracks or len(obs) == 0:
            return []
        cost = _costs(np.array([tr.predict(t) for tr in self.tracks]), obs)
        rows, cols = linear_sum_assignment(cost)
        gate = [self._gate(tr) for tr in self.tracks]
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

    def _choose_primary(self, t: float | None = None) -> None:
        """Keep the primary target while it lives and is seen, or coasts for no longer than primary_hold_s (at
        time t; None: however long) or with no other confirmed track seen; else the oldest confirmed track
        seen this frame, or failing one the oldest confirmed track. Live, a primary that left the view
        had kept the role while a newly confirmed target was seen: 15 frames "not detected", after the aim
        had given it up and sent the mount home (2026-12-02)."""
        alive = {tr.track_id: tr for tr in self.tracks if tr.confirmed}
        seen = [i for i, tr in alive.items() if tr.missed == 0]
        cur = alive.get(self.primary_id) if self.primary_id is not None else None
        hold = self.cfg.primary_hold_s
        if cur is not None and (cur.missed == 0 or not seen or hold is None or t is None or t - cur.t <= hold):
            return
        self.primary_id = min(seen or alive) if alive else None

    def predictions(self, t: float) -> F64:
        """Predicted (x, y, disparity) at time t of the tracks seen in the last few frames, (N, 3)."""
        return np.array([tr.predict(t) for tr in self.tracks if tr.missed <= 2]).reshape(-1, 3)

    def coasting(self, t: float, max_missed: int) -> F64:
        """The confirmed tracks a sighting by the left camera alone may continue (tracker.one_camera), those
        missed in at most `max_missed` frames in a row and seen by stereo since they began, (N, 6): predicted x
        and y at time t; the disparity held from the last STEREO_KEPT stereo sightings, their median (a
        disparity's rate from a few noisy frames drifts further than the object does, and the last sighting
        before an object passes behind a post is the one least seen); its 1-σ (px), the larger of the
        sightings' median 1-σ and their scatter; the updates since the last stereo sighting (one-camera
        sightings and misses); and the age of the sightings (s, from their mean time)."""
        rows = []
        for tr in self.tracks:
            if tr.confirmed and tr.missed <= max_missed and tr.since_stereo < NO_STEREO:
                d, sigma, t_seen = _held(tr.stereo)
                rows.append([*tr.predict(t)[:2], d, tr.since_stereo, sigma, t - t_seen])
        return np.array(rows, np.float64).reshape(-1, 6)

    def held_disparity(self, track_id: int | None) -> float | None:
        """The disparity (px) a track holds from its last STEREO_KEPT stereo sightings, their median (as
        `coasting`); None for no such track or one without a stereo sighting."""
        tr = None if track_id is None else self.get(track_id)
        return None if tr is None or not tr.stereo else _held(tr.stereo)[0]

    def get(self, track_id: int) -> Track | None:
        return next((tr for tr in self.tracks if tr.track_id == track_id), None)


def _costs(pred: F64, obs: F64) -> F64:
    """The association's cost of each observation for each track, (N, M): the image distance (px) from the
    track's predicted (x, y) plus twice the disparities' difference (px), which keeps depth order apart.
    pred: (N, 3) predicted x, y, d; obs: (M, 3)."""
    cost = np.linalg.norm(pred[:, None, :2] - obs[None, :, :2], axis=2)
    return np.asarray(cost + 2.0 * np.abs(pred[:, None, 2] - obs[None, :, 2]), np.float64)


def _held(stereo: list[tuple[float, float, float]]) -> tuple[float, float, float]:
    """From stereo sightings (t, d, σ_d): the median d, max(median σ_d, scatter of d) and the mean t."""
    a = np.array(stereo, np.float64)
    return float(np.median(a[:, 1])), max(float(np.median(a[:, 2])), float(np.std(a[:, 1]))), float(a[:, 0].mean())
