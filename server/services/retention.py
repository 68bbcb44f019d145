"""Retention decisions, pure (no I/O): which finished segments to delete by age per kind and by a disk
quota, oldest unlocked first, never a locked one and never one still being written."""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass

DAY_S = 86400.0


@dataclass(frozen=True)
class SegmentInfo:
    """id; kind continuous or event; start / end Unix s (end None: still open); size in bytes."""

    id: int
    kind: str
    start: float
    end: float | None
    size: int


@dataclass(frozen=True)
class Policy:
    """max_age_days per kind; quota_bytes: the recordings' disk budget (0: none)."""

    max_age_days: dict[str, float]
    quota_bytes: int = 0


def locked(seg: SegmentInfo, locks: Sequence[tuple[float, float]]) -> bool:
    """Whether any lock range [start, end] (Unix s) overlaps the segment."""
    end = seg.end if seg.end is not None else float("inf")
    return any(lo <= end and seg.start <= hi for lo, hi in locks)


def to_delete(segments: Iterable[SegmentInfo], locks: Sequence[tuple[float, float]], policy: Policy,
              now: float) -> list[int]:
    """Ids to delete, oldest first: first every unlocked finished segment older than its kind's age limit, then,
    while the total size is above the quota, the oldest unlocked finished ones left."""
    segs = sorted(segments, key=lambda s: (s.start, s.id))
    total = sum(s.size for s in segs)
    free = [s for s in segs if s.end is not None and not locked(s, locks)]
    out: list[int] = []
    for s in free:
        limit = policy.max_age_days.get(s.kind)
        if limit is not None and s.end is not None and now - s.end > limit * DAY_S:
            out.append(s.id)
            total -= s.size
    if policy.quota_bytes > 0:
        gone = set(out)
        for s in free:
            if total <= policy.quota_bytes:
                break
            if s.id not in gone:
                out.append(s.id)
                total -= s.size
    order = {s.id: i for i, s in enumerate(segs)}
    return sorted(out, key=order.__getitem__)
