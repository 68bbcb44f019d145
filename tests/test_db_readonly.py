"""A read-only database or data directory at start-up (a real read-only mount made with `unshare -rm`):
`tmeye serve` exits non-zero with one line naming the problem, before it listens or prints its URL.

A database turning read-only under a running server cannot be staged here: the kernel refuses to remount a
filesystem read-only while files on it are open for writing (EBUSY), and a read-only bind mount or chmod does
not affect the descriptors SQLite already holds. The running server's answer to a database that stops taking
writes (503 with one line, reads on, the database alarm, recovery) is tested with a full disk instead
(test_disk_full.py), which fails SQLite writes the same way."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
from fault_helpers import unshare_refused

from server.db.engine import upgrade

ROOT = Path(__file__).resolve().parents[1]
CASES = {
    "mount": ("cp -a {src}/. {mnt}/ && mount -o remount,ro {mnt}", "{mnt}",
              "the data directory {mnt} is not writable: Read-only file system"),
    "empty": ("mount -o remount,ro {mnt}", "{mnt}/data",
              "the data directory {mnt}/data is not writable: Read-only file system"),
    "db-file": ("cp -a {src}/. {mnt}/ && mount --bind {mnt}/tmeye.db {mnt}/tmeye.db && "
                "mount -o remount,bind,ro {mnt}/tmeye.db", "{mnt}",
                "the database {mnt}/tmeye.db cannot be written: attempt to write a readonly database"),
}


@pytest.mark.parametrize("case", sorted(CASES))
def test_read_only_storage_at_start_up_is_one_line_and_non_zero(tmp_path: Path, case: str) -> None:
    why = unshare_refused(tmp_path)
    if why:
        pytest.skip(why)
    src, mnt = tmp_path / "src", tmp_path / "mnt"
    src.mkdir()
    mnt.mkdir()
    upgrade(f"sqlite:///{src / 'tmeye.db'}")  # an existing database at head
    setup, data, needle = (x.format(src=src, mnt=mnt) for x in CASES[case])
    script = f"mount -t tmpfs -o size=8m tmpfs {mnt} && {setup} && exec \"$@\""
    p = subprocess.run(["unshare", "-rm", "sh", "-c", script, "sh", sys.executable, "-m", "tmeye", "serve",
                        "--port", "0", "--data-dir", data], cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert p.returncode == 2, (p.returncode, p.stdout, p.stderr)
    assert p.stderr.strip().splitlines() == [f"tmeye serve: error: {needle}"], p.stderr
    assert p.stdout == ""  # it did not get as far as listening
