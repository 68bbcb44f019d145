"""Which way a tracked body walks, against the cameras' line of sight (issue 12 item 1).

A walking person swings its arms and legs in the plane it walks in. Seen from the side (walking across
the line of sight) the swing moves the outline's limbs across the image and the silhouette's centroid
off the body's volume centre; seen from the front or back (walking towards or away from the cameras) it
moves them along the line of sight, which the image does not show. A person standing still does not
swing them at all. `swing_share` is that share of the swing seen across the image,

    s = |v_⊥| / max(|v|, v_0)

with v the body's horizontal velocity (m/s, world x and z; y is down), v_⊥ its part across the line of
sight from the rig's origin, and v_0 a walking speed (m/s) below which the limbs are taken to swing less
in proportion (a person standing has v ≈ 0 and s ≈ 0). v is the least-squares slope of the track's last
`frames` world positions against time; its noise lies mostly along the line of sight (the range's), which
only moves s towards 0 where the body hardly moves across it. `gait_share`, m = min(|v| / v_0, 1) with |v|²
less the fit's own variance, says how fully it walks (a standing body's range noise would have it walk).
tracker.solid_prior.SolidPrior turns s and m into the upright body's centroid 1-σ along x.

Measured on the simulator's walkers (frames not cut by the image's edge or by another object), the azimuth
error against the volume centre in units of the seen height h, Gaussian-equivalent (median |error| / 0.674),
by the true sin of the heading against the line of sight: walk 0.31, 0.32, 0.46, 0.69 % of h at sin 0-0.3,
0.3-0.6, 0.6-0.85, 0.85-1; illumination 0.35, 0.40, 0.37, 0.77 %; foliage 0.30, 0.30, 0.49, 0.68 %; pan
0.24, 0.53, 0.59, 0.63 %; endless 0.23, 0.42, 0.41, 0.40 %; two-targets 0.25, 0.25, 0.36, 0.25 %.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

F64 = NDArray[np.float64]


class HeadingHistory:
    """The last `frames` world positions of each track (frames at most max_gap apart), for `swing_share`."""

    def __init__(self, frames: int = 15, min_frames: int = 5, max_gap: int = 3, walk_mps: float = 0.5):
        if not (2 <= min_frames <= frames and max_gap >= 1 and walk_mps > 0):
            raise ValueError(f"heading history needs 2 <= min_frames <= frames, max_gap >= 1 and walk_mps > 0, "
                             f"got {min_frames}, {frames}, {max_gap}, {walk_mps}")
        self.frames, self.min_frames, self.max_gap, self.walk_mps = frames, min_frames, max_gap, walk_mps
        self._kept: dict[int, tuple[int, list[tuple[float, F64]]]] = {}  # id -> (last index, [(t, world)])

    def add(self, track_id: int, index: int, t: float, world: F64) -> None:
        """Keep the track's world position (m, (3,)) at frame `index`, time t (s)."""
        last, seen = self._kept.get(track_id, (index, []))
        if index - last > self.max_gap or index < last:
            seen = []
        self._kept[track_id] = (index, [*seen[1 - self.frames:], (t, np.asarray(world, np.float64))])

    def shares(self, track_id: int, index: int, origin: F64) -> tuple[float | None, float | None]:
        """(s, m) from one fit of the positions kept before frame `index` (`swing_share`, `gait_share`);
        (None, None) with fewer than min_frames of them or the last more than max_gap frames old."""
        fit = self._velocity(track_id, index)
        if fit is None:
            return None, None
        return self._swing(fit, origin), self._gait(fit)

    def swing_share(self, track_id: int, index: int, origin: F64) -> float | None:
        """s (see the module's docstring) from the positions kept before frame `index`; None with fewer than
        min_frames of them or the last more than max_gap frames old."""
        return self.shares(track_id, index, origin)[0]

    def gait_share(self, track_id: int, index: int) -> float | None:
        """m = min(|v| / v_0, 1): how fully the body walks (0 standing still, 1 at a walking speed or
        faster), from the same fit as swing_share, |v|² less the fit's own variance (the positions' scatter
        about the line: a standing body's range noise of 0.1 m at 10 m made it walk at 0.2 m/s); None where
        that fit has none."""
        fit = self._velocity(track_id, index)
        return None if fit is None else self._gait(fit)

    def _swing(self, fit: tuple[F64, F64, float], origin: F64) -> float | None:
        v_h, last, _ = fit
        los = last - origin
        u = np.array([los[0], los[2]])
        n = float(np.hypot(*u))
        if n <= 0.0:
            return None
        across = abs(float(v_h[0] * u[1] - v_h[1] * u[0])) / n  # |v_⊥| (m/s)
        return min(across / max(float(np.hypot(*v_h)), self.walk_mps), 1.0)

    def _gait(self, fit: tuple[F64, F64, float]) -> float:
        v_h, _, var_v = fit
        return min(float(np.sqrt(max(float(v_h @ v_h) - var_v, 0.0))) / self.walk_mps, 1.0)

    def _velocity(self, track_id: int, index: int) -> tuple[F64, F64, float] | None:
        """The horizontal velocity (m/s, world x and z: the least-squares slope of the kept positions against
        time), the last position (3,) and the slope's variance summed over x and z ((m/s)²: the residuals'
        variance over Σ (t - t̄)²), from the positions kept before frame `index`."""
        last, seen = self._kept.get(track_id, (index, []))
        if len(seen) < self.min_frames or index - last > self.max_gap:
            return None
        t = np.array([s[0] for s in seen])
        X = np.array([s[1] for s in seen])[:, [0, 2]]  # (n, 2) horizontal: world y is down
        tc = t - t.mean()
        stt = float(tc @ tc)
        if stt <= 0.0:
            return None
        Xc = X - X.mean(axis=0)
        v = (tc @ Xc) / stt  # m/s, (2,)
        resid = Xc - np.outer(tc, v)
        var_v = float(np.sum(resid * resid)) / max(len(t) - 2, 1) / stt
        return v, np.asarray(seen[-1][1]), var_v

    def keep_only(self, track_ids: list[int]) -> None:
        """Forget the positions of tracks not in track_ids (ended)."""
        live = set(track_ids)
        self._kept = {i: v for i, v in self._kept.items() if i in live}
