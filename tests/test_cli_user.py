"""`tmeye user add`: password from stdin, one-line errors, and the user can log in to a server."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from server_helpers import ROOT


def _add(data: Path, *args: str, password: str = "a strong password 1") -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "tmeye", "user", "add", *args, "--data-dir", str(data)],
                          input=password + "\n", capture_output=True, text=True, cwd=ROOT, timeout=120)


def test_user_add_reads_stdin_and_refuses_bad_input(tmp_path: Path) -> None:
    ok = _add(tmp_path, "carol", "--role", "operator")
    assert ok.returncode == 0 and "added operator 'carol'" in ok.stdout
    dup = _add(tmp_path, "carol", "--role", "viewer")
    assert dup.returncode == 2 and dup.stderr.strip() == "tmeye user: error: user 'carol' already exists"
    short = _add(tmp_path, "dave", "--role", "viewer", password="short")
    assert short.returncode == 2 and "12 to 128 characters" in short.stderr and short.stderr.count("\n") == 1
    role = _add(tmp_path, "erin", "--role", "king")
    assert role.returncode == 2 and "invalid choice" in role.stderr

    from server.db.engine import make_engine, session_factory
    from server.services import users

    engine = make_engine(f"sqlite:///{tmp_path / 'tmeye.db'}")
    with session_factory(engine)() as db:
        assert users.authenticate(db, "carol", "a strong password 1") is not None
        assert [u.username for u in users.list_users(db)] == ["carol"]
    engine.dispose()
