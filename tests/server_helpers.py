"""A real `tmeye serve` on 127.0.0.1 in a subprocess for the server tests, with login helpers."""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import httpx

from tmeye.benchserver import end_with_parent

ROOT = Path(__file__).resolve().parents[1]


@dataclass
class Server:
    proc: subprocess.Popen[str]
    url: str
    data_dir: Path
    log: Path
    tokens: dict[str, str] = field(default_factory=dict)

    @property
    def admin_password(self) -> str:
        return (self.data_dir / "initial-admin-password").read_text().strip()

    def login(self, username: str = "admin", password: str | None = None) -> str:
        r = httpx.post(f"{self.url}/api/auth/login",
                       data={"username": username, "password": password or self.admin_password})
        r.raise_for_status()
        token: str = r.json()["access_token"]
        return token

    def client(self, token: str | None = None) -> httpx.Client:
        headers = {"Authorization": f"Bearer {token}"} if token else {}
        return httpx.Client(base_url=self.url, headers=headers, timeout=30.0)

    def as_admin(self) -> httpx.Client:
        if "admin" not in self.tokens:
            self.tokens["admin"] = self.login()
        return self.client(self.tokens["admin"])

    def add_user(self, name: str, role: str, password: str = "correct horse battery") -> str:
        with self.as_admin() as c:
            r = c.post("/api/users", json={"username": name, "password": password, "role": role})
            assert r.status_code in (201, 409), r.text
        return self.login(name, password)

    def stop(self, sig: int = signal.SIGTERM, timeout: float = 10.0) -> int:
        if self.proc.poll() is None:
            self.proc.send_signal(sig)
        return self.proc.wait(timeout)

    def log_text(self) -> str:
        return self.log.read_text(errors="replace")


def start_server(data_dir: Path, *args: str, env: dict[str, str] | None = None, wait_s: float = 120.0) -> Server:
    """`tmeye serve --port 0 --data-dir DATA ARGS` until /api/health says ok."""
    data_dir.mkdir(parents=True, exist_ok=True)
    cmd = [sys.executable, "-m", "tmeye", "serve", "--port", "0", "--data-dir", str(data_dir), *args]
    return launch(cmd, data_dir, data_dir / "server.log", env, wait_s)


def launch(cmd: list[str], data_dir: Path, log: Path, env: dict[str, str] | None = None,
           wait_s: float = 120.0) -> Server:
    """Run `cmd` (a `tmeye serve` that prints its URL first) until /api/health says ok."""
    proc = subprocess.Popen(cmd, cwd=ROOT, stdout=subprocess.PIPE, stderr=log.open("w"), text=True,
                            preexec_fn=end_with_parent,  # no server outlives a failed or killed test run
                            env={**os.environ, **(env or {})})
    assert proc.stdout is not None
    line = proc.stdout.readline()
    m = re.search(r"(https?://127\.0\.0\.1:\d+)/", line)
    if not m:
        proc.kill()
        raise AssertionError(f"no URL printed: {line!r}\n{log.read_text()}")
    server = Server(proc, m.group(1), data_dir, log)
    deadline = time.monotonic() + wait_s
    while time.monotonic() < deadline:
        if proc.poll() is not None:
            raise AssertionError(f"server exited with {proc.returncode}:\n{server.log_text()}")
        try:
            if httpx.get(f"{server.url}/api/health", timeout=2, verify=False).json().get("status") == "ok":
                return server
        except httpx.HTTPError:
            pass
        time.sleep(0.2)
    server.stop(signal.SIGKILL)
    raise AssertionError(f"server not healthy within {wait_s} s:\n{server.log_text()}")


def openapi_routes(spec: dict[str, Any]) -> list[tuple[str, str]]:
    """(method, path) of every operation in an OpenAPI document."""
    return [(m.upper(), p) for p, ops in spec["paths"].items() for m in ops if m in ("get", "post", "put", "patch",
                                                                                    "delete")]
