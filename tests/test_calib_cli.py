"""`tmeye calibrate` end to end on rendered simulator images, and every bad input named in issue 3."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import cv2
import numpy as np
import pytest
from calib_helpers import write_sim_pairs

from calibration.board import BoardSpec
from calibration.errors import (
    BoardSizeError,
    CalibrationError,
    ImageMismatchError,
    TooFewViewsError,
    UnreadableImageError,
)
from calibration.views import detect_pairs
from tmeye.cli import main
from tracker.geometry import load_rig
from tracker.sim.rig import default_rig

BOARD = BoardSpec(9, 6, 0.05)


@pytest.fixture(scope="module")
def sim(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("calib_sim")
    write_sim_pairs(folder, 8, seed=3)
    return folder


def _copy(sim: Path, dst: Path, n: int) -> tuple[list[Path], list[Path]]:
    out: tuple[list[Path], list[Path]] = ([], [])
    for k, side in enumerate(("left", "right")):
        (dst / side).mkdir(parents=True)
        for p in sorted((sim / side).glob("*.png"))[:n]:
            shutil.copy(p, dst / side / p.name)
            out[k].append(dst / side / p.name)
    return out


def test_cli_writes_rig_json_and_report(sim: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    d = tmp_path / "imgs"
    left, right = _copy(sim, d, 8)
    cv2.imwrite(str(left[0]), np.full((480, 640), 200, np.uint8))  # a left image without the board
    out, rep = tmp_path / "rig.json", tmp_path / "report.png"
    code = main(["calibrate", "--left", str(d / "left/*.png"), "--right", str(d / "right/*.png"),
                 "--board", "9x6", "--square", "0.05", "--out", str(out), "--json", "--report", str(rep)])
    assert code == 0
    cap = capsys.readouterr()
    s = json.loads(cap.out)
    for key in ("rms_px", "stereo_rms_px", "per_view_rms_px", "baseline", "euler_deg", "T", "K_left",
                "K_right", "dist_left", "dist_right", "rectified_row_error_mean_px",
                "rectified_row_error_rms_px", "views_used", "views_rejected"):
        assert key in s, key
    assert "[1/8]" in cap.err  # progress on stderr
    assert [x["image"] for x in s["images_skipped"]] == [str(left[0])]  # named and counted
    assert s["rms_px"] < 0.2 and s["rectified_row_error_rms_px"] < 0.2
    assert s["baseline"] == pytest.approx(0.30, rel=2e-3)
    rig = load_rig(out)  # what the tracker loads
    assert rig.baseline == pytest.approx(0.30, rel=2e-3)
    np.testing.assert_allclose(rig.left.K, default_rig().left.K, rtol=3e-3, atol=1.5)
    assert json.loads(out.read_text())["calibration"]["model"] == "pinhole"
    # the disparity offset's σ, through the joint covariance: well below what the yaw's marginal σ alone
    # would say (yaw and the right principal point move the right image alike; their sum is well known)
    f = float(rig.left.K[0, 0])
    assert 0.0 < s["disparity_offset_std_px"] < 0.5 * f * np.radians(s["euler_std_deg"][1])
    assert rig.sigma.disparity_px == s["disparity_offset_std_px"] and rig.sigma.principal_px[0] > 0
    img = cv2.imread(str(rep))
    assert img is not None and img.shape[1] == 1200


def _cli_error(args: list[str], capsys: pytest.CaptureFixture[str]) -> str:
    assert main(["calibrate", *args]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    return err[-1]


def test_cli_bad_board_size_is_one_line_error(sim: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    d = tmp_path / "i"
    _copy(sim, d, 5)
    msg = _cli_error(["--left", str(d / "left/*.png"), "--right", str(d / "right/*.png"), "--board", "8x5",
                      "--square", "0.05", "--out", str(tmp_path / "r.json")], capsys)
    assert msg.startswith("tmeye calibrate: error: no 8x5 inner-corner chessboard found")
    assert not (tmp_path / "r.json").exists()


def test_too_few_views_gives_the_minimum(sim: Path, tmp_path: Path) -> None:
    left, right = _copy(sim, tmp_path, 3)
    with pytest.raises(TooFewViewsError, match="need at least 4"):
        detect_pairs(left, right, BOARD)


def test_left_right_count_mismatch(sim: Path, tmp_path: Path) -> None:
    left, right = _copy(sim, tmp_path, 5)
    with pytest.raises(ImageMismatchError, match="5 left images but 4 right images"):
        detect_pairs(left, right[:4], BOARD)


def test_image_size_mismatch(sim: Path, tmp_path: Path) -> None:
    left, right = _copy(sim, tmp_path, 5)
    small = cv2.resize(cv2.imread(str(right[2]), cv2.IMREAD_GRAYSCALE), (320, 240))
    cv2.imwrite(str(right[2]), small)
    with pytest.raises(ImageMismatchError, match="is 320x240, the others 640x480"):
        detect_pairs(left, right, BOARD)


def test_unreadable_file(sim: Path, tmp_path: Path) -> None:
    left, right = _copy(sim, tmp_path, 5)
    left[1].write_bytes(b"not a png")
    with pytest.raises(UnreadableImageError, match=str(left[1].name)):
        detect_pairs(left, right, BOARD)


def test_board_size_not_matching(sim: Path, tmp_path: Path) -> None:
    left, right = _copy(sim, tmp_path, 4)
    with pytest.raises(BoardSizeError, match="no 7x6 inner-corner chessboard"):
        detect_pairs(left, right, BoardSpec(7, 6, 0.05))


def test_image_without_board_is_named_skip(sim: Path, tmp_path: Path) -> None:
    left, right = _copy(sim, tmp_path, 6)
    blank = np.full((480, 640), 128, np.uint8)
    cv2.imwrite(str(left[0]), blank)
    cv2.imwrite(str(right[0]), blank)
    views = detect_pairs(left, right, BOARD)
    assert {s.name for s in views.skipped} == {str(left[0]), str(right[0])}
    assert all("no 9x6 board found" in s.reason for s in views.skipped)
    assert len(views.names) == 5  # the pair with no board at all is left out


def test_malformed_board_argument() -> None:
    with pytest.raises(CalibrationError, match="COLSxROWS"):
        BoardSpec.parse("9by6", 0.05)
    with pytest.raises(CalibrationError, match="positive"):
        BoardSpec.parse("9x6", 0.0)
    with pytest.raises(CalibrationError, match="too large: at most 100 inner corners"):
        BoardSpec.parse("99999999999999999999x6", 0.05)
    with pytest.raises(CalibrationError, match="at least 0.0001 and finite"):
        BoardSpec.parse("9x6", 1e-300)
    with pytest.raises(CalibrationError, match="at least 0.0001 and finite"):
        BoardSpec.parse("9x6", float("inf"))


def test_missing_glob_is_one_line_error(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    msg = _cli_error(["--left", str(tmp_path / "none/*.png"), "--right", str(tmp_path / "x/*.png"),
                      "--board", "9x6", "--square", "0.05", "--out", str(tmp_path / "r.json")], capsys)
    assert "matches no files" in msg
