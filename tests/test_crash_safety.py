"""Crash safety on a real `tmeye serve` (issue #13 section 3), a short version of `tmeye bench --crash`: an
alarm acknowledged through the API, then SIGKILL at random moments, 3 times here (20 in the bench): after each
restart integrity_check is ok, no row the API showed before the kill is lost, the acknowledgement is kept with
its user and comment, every segment row's file decodes and none is missing. Then SIGTERM: stopped within 5 s
with every segment closed (no open row; the next start reconciles nothing) and playable."""

from __future__ import annotations

from pathlib import Path

import pytest

from tmeye.crashcheck import run

KILLS = 3


def test_sigkill_keeps_committed_rows_and_the_acknowledgement_then_sigterm_closes(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("TMEYE_SEGMENT_S", "3")  # segments close within a round
    res = run(tmp_path / "data", KILLS, seed=3, moment_s=(2.0, 5.0))
    print(res)
    assert res["kills"] == res["integrity_ok"] == res["restarts"] == KILLS
    assert res["rows_compared"] > 0 and res["rows_lost"] == 0, res["lost"]
    assert res["ack_kept"] == KILLS
    assert res["segments_checked"] > 0 and res["rows_missing_file"] == res["segments_not_decoding"] == 0
    st = res["sigterm"]
    assert st["stop_s"] <= 5.0 and st["open_rows"] == 0 and st["integrity"] == "ok", st
    assert st["segments_checked"] > 0 and st["rows_missing_file"] == st["segments_not_decoding"] == 0, st
    assert not st["reconciled_after"], st
