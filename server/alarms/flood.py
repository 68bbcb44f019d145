"""The alarm flood, per operator (pure): ISA-18.2 / IEC 62682 call it a flood when more than 10 alarms
are annunciated to one operator in 10 minutes, and it ends when fewer than 5 remain in the window.

What "per operator" means on this console: every operator sees every alarm (one rig, one alarm list;
there are no areas of responsibility to split), so the alarms annunciated to an operator are the new
alarms raised while that operator is logged in, from the start of their login: an operator who logs in
during a burst is not in flood for the alarms raised before (they see them as a standing list, not as a
stream of annunciations). Viewers do not handle alarms and are not operators here. Alarms that are
shelved, suppressed by design or out of service raise nothing and count for nobody.

Without a list of logged-in operators (`operators` never set, as in `tmeye eval --alarms`) the console is
one operator position, named `CONSOLE`, manned from the start.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Mapping
from dataclasses import dataclass

CONSOLE = ""


@dataclass(frozen=True)
class FloodChange:
    """An operator's flood state changed at time t (s): flood True (raised) or False (ended); n: the
    alarms annunciated to them in the window at t."""

    t: float
    operator: str
    flood: bool
    n: int


class FloodMeter:
    def __init__(self, window_s: float = 600.0, on: int = 10, off: int = 5):
        self.window_s, self.on, self.off = window_s, on, off
        self.annunciated: deque[float] = deque()  # times of new alarms inside the window
        self.operators: dict[str, float] = {CONSOLE: -float("inf")}  # operator -> logged in since (s)
        self.flooded: set[str] = set()

    def alarm(self, t: float) -> None:
        """A new alarm was annunciated at t."""
        self.annunciated.append(t)

    def set_operators(self, since: Mapping[str, float]) -> None:
        """The logged-in operators and when each logged in (s); one who left is out of flood silently."""
        self.operators = dict(since)
        self.flooded &= set(self.operators)

    def count(self, operator: str = CONSOLE) -> int:
        """Alarms annunciated to `operator` inside the window (0 for one not logged in)."""
        since = self.operators.get(operator)
        return 0 if since is None else sum(1 for a in self.annunciated if a >= since)

    def step(self, t: float) -> list[FloodChange]:
        """Drop what left the window; the operators whose flood state changed at t."""
        while self.annunciated and self.annunciated[0] <= t - self.window_s:
            self.annunciated.popleft()
        out = []
        for op in sorted(self.operators):
            n = self.count(op)
            if op not in self.flooded and n > self.on:
                self.flooded.add(op)
                out.append(FloodChange(t, op, True, n))
            elif op in self.flooded and n < self.off:
                self.flooded.discard(op)
                out.append(FloodChange(t, op, False, n))
        return out
