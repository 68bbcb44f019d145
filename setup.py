"""Build hook (the metadata is in pyproject.toml): a wheel carries the built console (web/dist) as
server/web_dist and the Alembic migrations (alembic/) as server/migrations, so that `pip install` of the
wheel serves the whole console and makes its database. An editable install uses the checkout's own."""

from __future__ import annotations

import shutil
from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py

ROOT = Path(__file__).resolve().parent


class BuildWithConsole(build_py):
    def run(self) -> None:
        super().run()
        if getattr(self, "editable_mode", False):
            return
        dist = ROOT / "web" / "dist"
        if not (dist / "index.html").is_file():
            raise SystemExit("web/dist is not built: run `cd web && npm ci && npm run build` before building the wheel")
        target = Path(self.build_lib) / "server"
        shutil.copytree(dist, target / "web_dist", dirs_exist_ok=True)
        shutil.copytree(ROOT / "alembic", target / "migrations", dirs_exist_ok=True,
                        ignore=shutil.ignore_patterns("__pycache__", "*.pyc", "README*"))


setup(cmdclass={"build_py": BuildWithConsole})
