"""server.services.faults.FailureLog: a device fault is one line every time; a bug has its traceback once."""

from __future__ import annotations

import logging

import pytest
from sqlalchemy.exc import OperationalError

from server.services.faults import FailureLog, brief


def _raised(exc: Exception) -> Exception:
    try:
        raise exc
    except Exception as caught:
        return caught


def test_device_faults_are_one_line_and_a_bug_has_its_traceback_once(caplog: pytest.LogCaptureFixture) -> None:
    log = logging.getLogger("tmeye.test-faults")
    failures = FailureLog(log, (OperationalError, OSError))
    locked = OperationalError("UPDATE x", {}, Exception("database is locked\nmore"))
    with caplog.at_level("WARNING", logger="tmeye.test-faults"):
        for exc in (locked, _raised(OSError(28, "No space left on device")), _raised(ValueError("a bug")),
                    _raised(KeyError("the same bug")), locked):
            failures.log(exc, "storing failed: %s", brief(exc))
    assert [(r.levelname, r.exc_info is not None) for r in caplog.records] == [
        ("WARNING", False), ("WARNING", False), ("ERROR", True), ("WARNING", False), ("WARNING", False)]
    assert caplog.records[0].getMessage() == (
        "storing failed: OperationalError: (builtins.Exception) database is locked")
    assert caplog.records[2].exc_info is not None and caplog.records[2].exc_info[0] is ValueError


def test_the_level_of_a_device_fault_is_the_callers(caplog: pytest.LogCaptureFixture) -> None:
    log = logging.getLogger("tmeye.test-faults")
    with caplog.at_level("WARNING", logger="tmeye.test-faults"):
        FailureLog(log, (OSError,), logging.ERROR).log(OSError("disk full"), "recording stopped")
    assert [(r.levelname, r.exc_info) for r in caplog.records] == [("ERROR", None)]


def test_brief_is_one_line() -> None:
    assert brief(ValueError("first\nsecond")) == "ValueError: first"
    assert brief(RuntimeError()) == "RuntimeError: "
