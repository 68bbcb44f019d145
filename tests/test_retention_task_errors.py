"""The retention task (server.services.storage.RetentionTask) when a run fails: the database failing
(OperationalError: locked past its busy timeout, read-only, full) is a device condition, one warning line,
tried again at the next interval; anything else is a bug and logs its traceback."""

from __future__ import annotations

import asyncio
from pathlib import Path

import pytest
from sqlalchemy.exc import OperationalError

from server.services import storage
from server.services.retention import Policy


def _one_failing_run(monkeypatch: pytest.MonkeyPatch, tmp_path: Path, exc: Exception) -> storage.RetentionTask:
    calls = []

    def failing(*_a: object, **_k: object) -> list[int]:
        calls.append(1)
        raise exc

    monkeypatch.setattr(storage, "apply_retention", failing)
    task = storage.RetentionTask(None, tmp_path, Policy({}), interval_s=60.0)  # type: ignore[arg-type]

    async def run_once() -> None:
        t = asyncio.create_task(task.run())
        while not calls or task.last_run is None:
            await asyncio.sleep(0.01)
        t.cancel()

    asyncio.run(run_once())
    return task


def test_a_locked_database_is_one_warning_line(monkeypatch: pytest.MonkeyPatch, tmp_path: Path,
                                               caplog: pytest.LogCaptureFixture) -> None:
    locked = OperationalError("DELETE FROM segments", {}, Exception("database is locked"))
    with caplog.at_level("WARNING", logger="tmeye.retention"):
        task = _one_failing_run(monkeypatch, tmp_path, locked)
    assert task.errors == 1
    assert [(r.levelname, r.exc_info) for r in caplog.records] == [("WARNING", None)]
    assert "database is locked" in caplog.records[0].getMessage()


def test_anything_else_logs_its_traceback(monkeypatch: pytest.MonkeyPatch, tmp_path: Path,
                                          caplog: pytest.LogCaptureFixture) -> None:
    with caplog.at_level("WARNING", logger="tmeye.retention"):
        task = _one_failing_run(monkeypatch, tmp_path, ValueError("a bug"))
    assert task.errors == 1
    assert [r.levelname for r in caplog.records] == ["ERROR"] and caplog.records[0].exc_info is not None
