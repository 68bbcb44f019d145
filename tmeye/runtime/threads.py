"""Thread priorities: the tracker's frame has a deadline, the work that consumes its results has queues.

On Linux the nice value belongs to each thread, and a thread starts with its creator's. A consumer that
makes its own thread nicer (lower_priority at the top of its loop) leaves the CPU to the tracker's worker
whenever the two compete, on a busy machine or one with few cores; the native threads it starts later
(libx264's encoding threads) are nicer too. Raising a priority needs privileges; lowering one never does."""

from __future__ import annotations

import logging
import os
import threading

log = logging.getLogger(__name__)


def lower_priority(steps: int) -> int | None:
    """Make the calling thread `steps` nicer (at most 19). Returns its nice value then, or None when
    nothing changed (steps <= 0, or the system has no per-thread priorities or refuses)."""
    if steps <= 0 or not hasattr(os, "setpriority"):
        return None
    tid = threading.get_native_id()
    try:
        nice = min(19, os.getpriority(os.PRIO_PROCESS, tid) + steps)
        os.setpriority(os.PRIO_PROCESS, tid, nice)
    except OSError as exc:
        log.warning("could not lower the priority of thread %s: %s", threading.current_thread().name, exc)
        return None
    return nice
