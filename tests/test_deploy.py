"""Deployment files: docker-compose.yml is valid for Debian's docker-compose (as shipped and with its
commented device pass-through switched on); the Dockerfile is Debian-based, runs as a non-root user, keeps
/data as a volume and checks /api/health. No Docker engine runs here: the image is not built or run."""

from __future__ import annotations

import re
import shutil
import subprocess
from pathlib import Path

import pytest
from server_helpers import ROOT

COMPOSE = shutil.which("docker-compose")


def _config(path: Path) -> subprocess.CompletedProcess[str]:
    assert COMPOSE is not None
    return subprocess.run([COMPOSE, "-f", str(path), "config"], capture_output=True, text=True, timeout=60,
                          cwd=path.parent)


@pytest.mark.skipif(COMPOSE is None, reason="docker-compose is not installed (apt-get install -y docker-compose)")
def test_compose_file_is_valid_as_shipped_and_with_devices(tmp_path: Path) -> None:
    shipped = _config(ROOT / "docker-compose.yml")
    assert shipped.returncode == 0, shipped.stderr
    assert "tmeye-data:/data" in shipped.stdout and "8080" in shipped.stdout
    text = (ROOT / "docker-compose.yml").read_text()
    on = re.sub(r"^(\s*)# (devices:|group_add:|  - /dev/|  - video|  - dialout)", r"\1\2", text, flags=re.M)
    assert on.count("/dev/video0:/dev/video0") == 1 and "# devices:" not in on
    (tmp_path / "Dockerfile").write_text("FROM scratch\n")
    (tmp_path / "docker-compose.yml").write_text(on)
    devices = _config(tmp_path / "docker-compose.yml")
    assert devices.returncode == 0, devices.stderr
    assert "/dev/ttyACM0" in devices.stdout and "dialout" in devices.stdout


def test_dockerfile_is_debian_non_root_with_volume_and_health_check() -> None:
    lines = [ln.strip() for ln in (ROOT / "Dockerfile").read_text().splitlines()]
    froms = [ln for ln in lines if ln.startswith("FROM ")]
    assert froms and all("bookworm" in ln for ln in froms), froms  # Debian 12 images
    users = [ln.split()[1] for ln in lines if ln.startswith("USER ")]
    assert users and users[-1] not in ("root", "0"), users
    assert 'VOLUME ["/data"]' in lines and any("TMEYE_DATA_DIR=/data" in ln for ln in lines)
    health = " ".join(lines[lines.index(next(ln for ln in lines if ln.startswith("HEALTHCHECK"))):][:2])
    assert "/api/health" in health and "'ok'" in health
    # a wheel install, not -e, of the versions CI passed with
    assert any(ln.startswith("RUN pip install --no-cache-dir -c constraints.txt . ") for ln in lines)
