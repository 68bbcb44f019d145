"""Rig file sanity (issue 12 item 5): a bad rig file, or inputs that contradict it, stop `tmeye track`
with exit code 2 and one line naming the file and the field."""

from __future__ import annotations

import json
import subprocess
import sys
from collections.abc import Callable
from fractions import Fraction
from pathlib import Path
from typing import Any

import av
import numpy as np
import pytest

from tracker.geometry import StereoRig, load_rig, save_rig
from tracker.rigcheck import RigError
from tracker.sim.rig import default_rig


def tmeye(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "tmeye", *args], capture_output=True, text=True, timeout=180)


def rig_json(**changes: Callable[[dict[str, Any]], None]) -> dict[str, Any]:
    d = default_rig().to_dict()
    for fn in changes.values():
        fn(d)
    return d


def scale_units(factor: float) -> Callable[[dict[str, Any]], None]:
    def fn(d: dict[str, Any]) -> None:
        for side in ("left", "right"):
            d[side]["c"] = [factor * v for v in d[side]["c"]]
    return fn


def set_field(side: str, key: str, value: Any) -> Callable[[dict[str, Any]], None]:
    def fn(d: dict[str, Any]) -> None:
        d[side][key] = value
    return fn


def k_with(i: int, j: int, value: float) -> Callable[[dict[str, Any]], None]:
    def fn(d: dict[str, Any]) -> None:
        d["left"]["K"][i][j] = value
    return fn


def swap_centres(d: dict[str, Any]) -> None:
    d["left"]["c"], d["right"]["c"] = d["right"]["c"], d["left"]["c"]


def cm_rig_of_a_short_baseline() -> dict[str, Any]:
    """An 8.3 cm rig written in centimetres: b = 8.3 passes the baseline limits, the disparity bound not."""
    d = default_rig(baseline_m=0.083).to_dict()
    scale_units(100.0)(d)
    return d


BAD_RIGS: list[tuple[str, Any, str]] = [
    ("undecodable", b"\xff\xfe\x00garbage", "is unreadable: not UTF-8 JSON text (byte 0xff at offset 0)"),
    ("k2x3", rig_json(k=set_field("left", "K", [[600.0, 0.0, 320.0], [0.0, 600.0, 240.0]])),
     "field left.K: must be 3x3, got 2x3"),
    ("zero_baseline", rig_json(c=set_field("right", "c", [-0.15, 0.0, 0.0])),
     "field right.c: baseline 0 m is outside 0.01 to 10 m"),
    ("nan_focal", rig_json(k=k_with(0, 0, float("nan"))), "field left.K: holds a non-finite number"),
    ("negative_focal", rig_json(k=k_with(1, 1, -600.0)), "field left.K: focal lengths must be positive"),
    ("centimetres", rig_json(u=scale_units(100.0)), "field right.c: baseline 30 m is outside 0.01 to 10 m"),
    ("millimetres", rig_json(u=scale_units(1000.0)), "field right.c: baseline 300 m is outside 0.01 to 10 m"),
    ("centimetres_short", cm_rig_of_a_short_baseline(),
     "field right.c: baseline 8.3 m with f 596.1 px needs disparities up to 1979 px"),
    ("not_rotation", rig_json(r=set_field("right", "R_rc", [[1, 0, 0], [0, 1, 0.2], [0, 0, 1]])),
     "field right.R_rc: not an orthonormal rotation"),
    ("reflection", rig_json(r=set_field("right", "R_rc", [[-1, 0, 0], [0, 1, 0], [0, 0, 1]])),
     "field right.R_rc: a reflection"),
    ("reversed_baseline", rig_json(s=swap_centres), "field right.c: the right camera lies 0.3 m to the left"),
    ("no_dist", rig_json(d=set_field("left", "dist", [0.1, 0.0])), "field left.dist: must be 5, got 2"),
]


def write(path: Path, content: Any) -> Path:
    if isinstance(content, bytes):
        path.write_bytes(content)
    else:
        path.write_text(json.dumps(content))  # NaN is written as the JSON extension NaN
    return path


@pytest.mark.parametrize(("name", "content", "message"), BAD_RIGS, ids=[b[0] for b in BAD_RIGS])
def test_bad_rig_file_stops_track_with_one_line(tmp_path: Path, name: str, content: Any, message: str) -> None:
    rig = write(tmp_path / f"{name}.json", content)
    out = tmeye("track", "--rig", str(rig), "--frames", "1", "--fast")
    assert out.returncode == 2, out.stderr
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1, out.stderr
    assert f"rig file {rig}" in lines[0] and message in lines[0], lines[0]


def test_the_baseline_limits_can_be_widened(tmp_path: Path) -> None:
    """A 5 mm rig is refused by default and accepted with --baseline-limits."""
    d = default_rig(baseline_m=0.005).to_dict()
    rig = write(tmp_path / "small.json", d)
    out = tmeye("track", "--rig", str(rig), "--frames", "1", "--fast")
    assert out.returncode == 2 and "baseline 0.005 m is outside 0.01 to 10 m" in out.stderr
    with pytest.raises(ValueError, match="outside"):
        load_rig(rig)
    assert load_rig(rig, (0.001, 10.0)).baseline == pytest.approx(0.005)


def test_a_good_rig_round_trips() -> None:
    rig = default_rig()
    back = StereoRig.from_dict(json.loads(json.dumps(rig.to_dict())))
    assert np.allclose(back.left.K, rig.left.K) and np.allclose(back.T, rig.T)


def test_the_disparity_search_is_bounded_by_the_nearest_range() -> None:
    """The background search covers f b / near_m (rounded up to 16), so it shrinks as near_m grows."""
    from tracker.detect import DetectorConfig
    from tracker.pipeline import Pipeline

    rig = default_rig()
    n_near = Pipeline(rig, DetectorConfig(near_m=2.5)).bg.num_disparities
    n_far = Pipeline(rig, DetectorConfig(near_m=10.0)).bg.num_disparities
    assert n_near == 80 and n_far == 32  # 600 px x 0.3 m / 2.5 m = 72 -> 80; / 10 m = 18 -> 32
    with pytest.raises(RigError, match=r"more than 320 px \(half the image width"):
        Pipeline(rig, DetectorConfig(near_m=0.5))  # 360 px > 320 px


def write_video(path: Path, frames: list[Any]) -> Path:
    """Lossless grey video (FFV1 in Matroska) of uint8 frames (H, W) at 10 fps."""
    with av.open(str(path), "w") as container:
        stream = container.add_stream("ffv1", rate=10)
        stream.height, stream.width = frames[0].shape
        stream.pix_fmt = "gray"
        stream.codec_context.time_base = Fraction(1, 10)
        for i, img in enumerate(frames):
            frame = av.VideoFrame.from_ndarray(img, format="gray")
            frame.pts, frame.time_base = i, Fraction(1, 10)
            container.mux(stream.encode(frame))
        container.mux(stream.encode())
    return path


def test_exchanged_inputs_are_caught_on_the_first_frames(tmp_path: Path) -> None:
    """The simulated empty scene as two video files: given in order the tracker runs; exchanged, the
    background's disparity is negative and `tmeye track` names the rig file and the field."""
    from tracker.sim.scenarios import SimRig, get_scenario

    sim = SimRig(get_scenario("walk"))
    frames = [sim.background() for _ in range(3)]
    left = write_video(tmp_path / "left.mkv", [f.left for f in frames])
    right = write_video(tmp_path / "right.mkv", [f.right for f in frames])
    rig = tmp_path / "rig.json"
    save_rig(sim.rig, rig)
    ok = tmeye("track", "--source", "files", str(left), str(right), "--rig", str(rig), "--json")
    assert ok.returncode == 0, ok.stderr
    bad = tmeye("track", "--source", "files", str(right), str(left), "--rig", str(rig))
    assert bad.returncode == 2
    lines = bad.stderr.strip().splitlines()
    assert len(lines) == 1, bad.stderr
    assert f"rig file {rig}: " in lines[0] and "disparity is negative" in lines[0]
    assert "left and right inputs are exchanged" in lines[0] and "field right.c" in lines[0]
