"""Shared test fixtures: the path of ../shared/data (tests skip with a reason when it is absent), one
headless chromium per browser-test module (Debian's, driven by Playwright; skipped with a reason without it),
and the simulator's people at the one stature the situation tests were written around."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from web_helpers import browser, require_browser

SHARED_DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data"


@pytest.fixture
def shared_data() -> Path:
    if not SHARED_DATA.is_dir():
        pytest.skip(f"shared test data not found at {SHARED_DATA} (clone with ../shared beside the repo)")
    return SHARED_DATA


@pytest.fixture(autouse=True)
def people_as_written(request: pytest.FixtureRequest) -> Iterator[None]:
    """Every simulated person PERSON_STATURE_M (1.69 m) tall, as every one was when the tests that name a
    scene's frames (a walker's legs before a wall at frame 1320, ...) were written: the situations they
    reproduce are that person's. `tmeye eval` draws people's statures (tracker.sim.bodies.draw_stature),
    and so do the `tmeye` processes tests start; a test marked `drawn_statures` gets them too. Its own
    MonkeyPatch: a test's `monkeypatch.undo()` (tests/test_growth.py's `_outline` calls it between two
    runs) must not undo it."""
    if request.node.get_closest_marker("drawn_statures") is not None:
        yield
        return
    import tracker.sim.scenarios as scenarios
    from tracker.sim.bodies import PERSON_STATURE_M

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(scenarios, "draw_stature", lambda rng: PERSON_STATURE_M)
        yield


@pytest.fixture(scope="module")
def chromium() -> Iterator[Any]:
    require_browser()
    with browser() as b:
        yield b
