"""The built wheel carries the whole console: web/dist as server/web_dist and the Alembic migrations as
server/migrations. The wheel is built from a copy of the sources, installed (without dependencies) into
a directory of its own, and `tmeye serve` run from there, away from the checkout, serves the console and
makes its database."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
import time
import zipfile
from pathlib import Path

import httpx
import pytest
from server_helpers import ROOT

DIST = ROOT / "web" / "dist"
SOURCES = ("tracker", "calibration", "tmeye", "server", "alembic", "alembic.ini", "pyproject.toml", "setup.py",
           "README.md")


def _build_wheel(tmp: Path) -> Path:
    src = tmp / "src"
    for name in SOURCES:
        p = ROOT / name
        if p.is_dir():
            shutil.copytree(p, src / name, ignore=shutil.ignore_patterns("__pycache__", "*.pyc", "web_dist",
                                                                         "migrations"))
        else:
            shutil.copy2(p, src / name)
    shutil.copytree(DIST, src / "web" / "dist")
    out = tmp / "wheels"
    proc = subprocess.run([sys.executable, "-m", "pip", "wheel", "--quiet", "--no-deps", "--no-build-isolation",
                           "--wheel-dir", str(out), str(src)], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr[-3000:]
    (wheel,) = out.glob("tmeye-*.whl")
    return wheel


def test_the_wheel_serves_the_whole_console(tmp_path: Path) -> None:
    if not (DIST / "index.html").is_file():
        pytest.skip(f"{DIST} is not built (cd web && npm ci && npm run build)")
    pytest.importorskip("wheel", reason="the wheel package builds wheels without build isolation (pip install wheel)")
    wheel = _build_wheel(tmp_path)
    names = set(zipfile.ZipFile(wheel).namelist())
    web_files = {f"server/web_dist/{p.relative_to(DIST).as_posix()}" for p in DIST.rglob("*") if p.is_file()}
    assert web_files and web_files <= names, sorted(web_files - names)[:5]
    migrations = {f"server/migrations/versions/{p.name}" for p in (ROOT / "alembic" / "versions").glob("*.py")}
    assert {"server/migrations/env.py", "server/migrations/script.py.mako"} | migrations <= names

    site = tmp_path / "site"
    subprocess.run([sys.executable, "-m", "pip", "install", "--quiet", "--no-deps", "--target", str(site),
                    str(wheel)], check=True, timeout=300)
    env = {**os.environ, "PYTHONPATH": str(site)}
    where = subprocess.run([sys.executable, "-c", "import server, tmeye; print(server.__file__, tmeye.__file__)"],
                           cwd=tmp_path, env=env, capture_output=True, text=True, check=True).stdout
    assert str(ROOT) not in where and where.count(str(site)) == 2, where
    log = (tmp_path / "server.log").open("w")
    proc = subprocess.Popen([sys.executable, "-m", "tmeye", "serve", "--port", "0", "--data-dir",
                             str(tmp_path / "data")], cwd=tmp_path, env=env, stdout=subprocess.PIPE,
                            stderr=log, text=True)
    try:
        assert proc.stdout is not None
        m = re.search(r"(http://127\.0\.0\.1:\d+)/", proc.stdout.readline())
        assert m, (tmp_path / "server.log").read_text()
        url = m.group(1)
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline:
            try:
                if httpx.get(f"{url}/api/health", timeout=2).json().get("status") == "ok":
                    break
            except httpx.HTTPError:
                pass
            assert proc.poll() is None, (tmp_path / "server.log").read_text()
            time.sleep(0.3)
        index = httpx.get(f"{url}/")
        assert index.status_code == 200 and index.text == (DIST / "index.html").read_text()
        for asset in re.findall(r'(?:src|href)="/?(assets/[^"]+)"', index.text):
            r = httpx.get(f"{url}/{asset}")
            assert r.status_code == 200 and r.content == (DIST / asset).read_bytes(), asset
        assert (tmp_path / "data" / "tmeye.db").is_file()  # made by the packaged migrations
        r = httpx.post(f"{url}/api/auth/login", data={"username": "admin", "password": (
            tmp_path / "data" / "initial-admin-password").read_text().strip()})
        assert r.status_code == 200
    finally:
        proc.terminate()
        proc.wait(20)
        log.close()
