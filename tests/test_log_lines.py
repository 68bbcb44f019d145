"""`tmeye serve` logs one line per event: a traceback joins its message's line (tmeye.commands.serve)."""

from __future__ import annotations

import io
import logging

from tmeye.commands.serve import LOG_FORMAT, OneLineFormatter


def test_an_exception_is_logged_on_one_line() -> None:
    out = io.StringIO()
    handler = logging.StreamHandler(out)
    handler.setFormatter(OneLineFormatter(LOG_FORMAT))
    log = logging.getLogger("tmeye.test.lines")
    log.addHandler(handler)
    log.propagate = False
    try:
        try:
            {}["camera"]
        except KeyError:
            log.exception("track writer failed\nwhile flushing")
        log.warning("disk at %d %%", 97)
    finally:
        log.removeHandler(handler)
    lines = out.getvalue().splitlines()
    assert len(lines) == 2, lines
    assert "ERROR tmeye.test.lines: track writer failed | while flushing | Traceback" in lines[0]
    assert lines[0].endswith("KeyError: 'camera'")
    assert lines[1].endswith("WARNING tmeye.test.lines: disk at 97 %")
