"""The browser console's tests: Debian's chromium driven by the Python playwright package against a real
`tmeye serve` (tests/server_helpers.py) serving web/dist. Tests skip with a reason when playwright,
/usr/bin/chromium or web/dist is missing (build it with `npm ci && npm run build` in web/)."""

from __future__ import annotations

import contextlib
import socket
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import httpx
import pytest
from server_helpers import ROOT, Server

from tmeye.benchbrowser import CHROMIUM, CHROMIUM_ARGS

DIST = ROOT / "web" / "dist"
ARTIFACTS = ROOT / "test-artifacts" / "web"
PASSWORD = "correct horse battery"


def skip_reason() -> str | None:
    """Why the browser tests cannot run here, or None."""
    try:
        import playwright.sync_api  # noqa: F401
    except ImportError:
        return "the Python package playwright is not installed (pip install playwright; no browser download needed)"
    if not CHROMIUM.exists():
        return f"{CHROMIUM} is missing (apt-get install -y chromium)"
    if not (DIST / "index.html").exists():
        return f"{DIST} is not built (cd web && npm ci && npm run build)"
    return None


def require_browser() -> None:
    reason = skip_reason()
    if reason:
        pytest.skip(reason)


@contextlib.contextmanager
def browser() -> Iterator[Any]:
    from playwright.sync_api import sync_playwright

    with sync_playwright() as p:
        b = p.chromium.launch(executable_path=str(CHROMIUM), args=CHROMIUM_ARGS)
        try:
            yield b
        finally:
            b.close()


def new_page(b: Any, server: Server, width: int = 1280, height: int = 720, init_script: str | None = None) -> Any:
    """A fresh context (no cookies) on the server; camera and microphone granted so that Chromium offers
    127.0.0.1 ICE candidates."""
    ctx = b.new_context(viewport={"width": width, "height": height}, base_url=server.url,
                        permissions=["camera", "microphone"])
    ctx.set_default_timeout(20000)
    if init_script:
        ctx.add_init_script(init_script)
    page = ctx.new_page()
    page.console_lines = []  # type: ignore[attr-defined]
    page.on("console", lambda m: page.console_lines.append(f"{m.type}: {m.text}"))  # type: ignore[attr-defined]
    page.on("pageerror", lambda e: page.console_lines.append(f"pageerror: {e}"))  # type: ignore[attr-defined]
    return page


def login(page: Any, username: str, password: str) -> None:
    """Log in through the form (its fields are labelled Username and Password, its button Log in)."""
    page.goto("/")
    page.get_by_label("Username").fill(username)
    page.get_by_label("Password").fill(password)
    page.get_by_role("button", name="Log in").click()
    page.get_by_role("navigation", name="Pages").wait_for()


def user(server: Server, name: str, role: str) -> tuple[str, str]:
    """(name, password) of a user with `role`, created through the API."""
    server.add_user(name, role, PASSWORD)
    return name, PASSWORD


def admin(server: Server) -> tuple[str, str]:
    return "admin", server.admin_password


def wait_for(fn: Callable[[], Any], timeout: float = 20.0, every: float = 0.2, what: str = "condition") -> Any:
    deadline = time.monotonic() + timeout
    last: Any = None
    while time.monotonic() < deadline:
        last = fn()
        if last:
            return last
        time.sleep(every)
    raise AssertionError(f"{what} not met within {timeout} s (last value {last!r})")


def debug(page: Any) -> dict[str, Any]:
    """The Live page's window.__tmeye (source, frame counts, sync, servo, stamps)."""
    d: dict[str, Any] = page.evaluate("() => JSON.parse(JSON.stringify(window.__tmeye || {}))")
    return d


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port: int = s.getsockname()[1]
        return port


def has_route(server: Server, method: str, path: str) -> bool:
    spec = httpx.get(f"{server.url}/api/openapi.json", timeout=10).json()
    return method.lower() in spec.get("paths", {}).get(path, {})


def require_route(server: Server, method: str, path: str) -> None:
    if not has_route(server, method, path):
        pytest.skip(f"the server has no {method} {path} yet")


def screenshot(page: Any, name: str, full_page: bool = False) -> Path:
    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    path = ARTIFACTS / f"{name}.png"
    page.screenshot(path=str(path), full_page=full_page)
    return path
