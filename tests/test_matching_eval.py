"""`tmeye eval --matching`: match_point and OpenCV StereoSGBM measured at the same textured points of the
Middlebury pairs in ../shared/data/stereo-gt (issue 12 item 7; figures, not a target, are asserted)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path


def test_matching_eval_reports_both_methods_on_every_pair(shared_data: Path, tmp_path: Path) -> None:
    root = shared_data / "stereo-gt"
    out = subprocess.run([sys.executable, "-m", "tmeye", "eval", "--matching", str(root), "--json"],
                         capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    res = json.loads(out.stdout)
    names = sorted(f.name for f in root.iterdir() if (f / "im2.png").exists())
    assert sorted(k for k in res if isinstance(res[k], dict)) == names
    for name in names:
        r = res[name]
        assert r["points"] > 1000
        for method in ("match_point", "sgbm"):
            m = r[method]
            assert 0.5 < m["answered"] <= 1.0 and 0.0 < m["median_err_px"] < 0.5 and 0.0 <= m["over_1px"] < 0.2
    assert isinstance(res["match_point_beats_sgbm_on_every_pair"], bool)


def test_matching_eval_names_a_missing_folder(tmp_path: Path) -> None:
    out = subprocess.run([sys.executable, "-m", "tmeye", "eval", "--matching", str(tmp_path / "none")],
                         capture_output=True, text=True, timeout=60)
    assert out.returncode == 2 and "is not a directory" in out.stderr
    out = subprocess.run([sys.executable, "-m", "tmeye", "eval", "--matching", str(tmp_path)],
                         capture_output=True, text=True, timeout=60)
    assert out.returncode == 2 and "no stereo pairs" in out.stderr
    assert len(out.stderr.strip().splitlines()) == 1
