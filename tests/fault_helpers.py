"""A real `tmeye serve` whose data directory is a small tmpfs of its own (a private mount namespace made
by `unshare -rm`, no root needed): disk-full and read-only faults on a real filesystem. The test reaches
the files through /proc/PID/root (the server's view of the mounts)."""

from __future__ import annotations

import errno
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Any

from server_helpers import Server, launch


def unshare_refused(tmp: Path) -> str | None:
    """Why a private tmpfs cannot be mounted here (None: it can)."""
    d = tmp / "probe-mnt"
    d.mkdir(parents=True, exist_ok=True)
    try:
        p = subprocess.run(["unshare", "-rm", "sh", "-c", f"mount -t tmpfs -o size=1m tmpfs {d}"],
                           capture_output=True, text=True, timeout=20)
    except FileNotFoundError:
        return "unshare(1) is not installed"
    return None if p.returncode == 0 else f"unshare -rm with a tmpfs mount is not permitted: {p.stderr.strip()}"


def start_on_tmpfs(mnt: Path, size_mb: int, *args: str, env: dict[str, str] | None = None,
                   setup: str = "") -> Server:
    """`tmeye serve` with DATA = MNT/data on a tmpfs of size_mb MiB mounted at MNT in the server's own mount
    namespace; `setup`: shell commands run after the mount, before the server (for example a remount).
    The log goes beside MNT (outside the tmpfs); Server.data_dir is the /proc/PID/root view of DATA."""
    mnt.mkdir(parents=True, exist_ok=True)
    data = mnt / "data"
    script = f"mount -t tmpfs -o size={size_mb}m tmpfs {mnt} && mkdir -p {data} && {setup or 'true'} && exec \"$@\""
    cmd = ["unshare", "-rm", "sh", "-c", script, "sh", sys.executable, "-m", "tmeye", "serve", "--port", "0",
           "--data-dir", str(data), *args]
    s = launch(cmd, mnt, mnt.parent / f"{mnt.name}.log", env)
    s.data_dir = Path(f"/proc/{s.proc.pid}/root{data}")
    return s


def integrity_check(server: Server) -> str:
    """PRAGMA integrity_check of a running tmpfs server's database, run inside its mount namespace (SQLite
    resolves the /proc/PID/root link to a path that only exists there)."""
    inside = str(server.data_dir).split("/root", 1)[1] + "/tmeye.db"
    code = f"import sqlite3; print(sqlite3.connect({inside!r}).execute('PRAGMA integrity_check').fetchone()[0])"
    p = subprocess.run(["nsenter", "-t", str(server.proc.pid), "-U", "-m", "--preserve-credentials",
                        sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    return p.stdout.strip() or p.stderr.strip()


def fill(path: Path, leave_bytes: int = 0) -> int:
    """Append to `path` until its filesystem has about leave_bytes free (0: until ENOSPC); bytes written."""
    n = 0
    with path.open("ab", buffering=0) as f:
        while True:
            want = shutil.disk_usage(path.parent).free - leave_bytes if leave_bytes else 1 << 16
            if want <= 0:
                return n
            try:
                n += f.write(b"\0" * min(want, 1 << 20)) or 0
            except OSError as exc:
                if exc.errno != errno.ENOSPC:
                    raise
                return n


def open_alarms(client: Any, rule_key: str) -> list[dict[str, Any]]:
    """The open alarms of one rule (e.g. "fault:servo"), as the API lists them."""
    alarms: list[dict[str, Any]] = client.get("/api/alarms", params={"state": "open"}).json()
    return [a for a in alarms if a["rule_key"] == rule_key]
