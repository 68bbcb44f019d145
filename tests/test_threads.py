"""Per-thread priorities: a consumer thread made nicer leaves the tracker's thread as it was, and the
threads it starts afterwards (libx264's) inherit its nice value."""

from __future__ import annotations

import os
import threading

import pytest

from tmeye.runtime.threads import lower_priority

pytestmark = pytest.mark.skipif(not hasattr(os, "setpriority"), reason="no per-thread priorities here")


def _nice(tid: int) -> int:
    return os.getpriority(os.PRIO_PROCESS, tid)


def test_a_thread_made_nicer_alone_and_its_children_inherit() -> None:
    main = _nice(threading.get_native_id())
    seen: dict[str, int | None] = {}

    def child() -> None:
        seen["child"] = _nice(threading.get_native_id())

    def consumer() -> None:
        seen["returned"] = lower_priority(3)
        seen["self"] = _nice(threading.get_native_id())
        t = threading.Thread(target=child)
        t.start()
        t.join()

    t = threading.Thread(target=consumer)
    t.start()
    t.join()
    want = min(19, main + 3)
    assert seen == {"returned": want, "self": want, "child": want}
    assert _nice(threading.get_native_id()) == main  # the caller's thread (the tracker's) is untouched


def test_zero_steps_change_nothing() -> None:
    before = _nice(threading.get_native_id())
    assert lower_priority(0) is None
    assert _nice(threading.get_native_id()) == before
