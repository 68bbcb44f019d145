"""`tmeye calibrate`: stereo calibration from chessboard image pairs (issue 3) -> rig file for the tracker."""

from __future__ import annotations

import argparse
import json
import sys
from typing import Any

import numpy as np

from calibration.board import BoardSpec
from calibration.holdout import compare_models, split
from calibration.output import summary, write_report, write_rig
from calibration.stereo import MIN_VIEWS, calibrate_stereo
from calibration.views import detect_pairs, expand


def register(subparsers: Any) -> None:
    """Add the `calibrate` sub-command (sets func=run)."""
    p = subparsers.add_parser("calibrate", help="calibrate the stereo rig from chessboard image pairs")
    p.add_argument("--left", required=True, help="glob of the left camera's images, e.g. 'left/*.png'")
    p.add_argument("--right", required=True, help="glob of the right camera's images (sorted, paired)")
    p.add_argument("--board", required=True, help="inner corners COLSxROWS, e.g. 9x6")
    p.add_argument("--square", required=True, type=float, help="square size (metres; sets the unit of T)")
    p.add_argument("--model", choices=("pinhole", "polynomial"), default="pinhole",
                   help="lens model recorded as chosen (the tracker always uses the Brown-Conrady cameras)")
    p.add_argument("--out", required=True, help="rig file to write (JSON, tmeye-rig format)")
    p.add_argument("--json", action="store_true", help="print one JSON object instead of the summary")
    p.add_argument("--report", help="write a PNG report (per-view error bars, corner residuals)")
    p.add_argument("--fix-k3", action="store_true", help="hold k3 at 0 (4-coefficient lens)")
    p.add_argument("--compare-opencv", action="store_true",
                   help="also calibrate the same corners with OpenCV's stereoCalibrate and report its figures")
    p.set_defaults(func=run)


def _progress(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


def run(args: argparse.Namespace) -> int:
    board = BoardSpec.parse(args.board, args.square)
    left, right = expand(args.left, "left"), expand(args.right, "right")
    _progress(f"detecting a {board.cols}x{board.rows} board in {len(left)} image pairs ...")
    views = detect_pairs(left, right, board, _progress)
    train, held = split(views, MIN_VIEWS)
    cal = calibrate_stereo(train, board, fix_k3=args.fix_k3, progress=_progress)
    out = summary(cal, args.model)
    if held is not None:
        cmp = compare_models(cal, held)
        out["held_out"] = {"views": cmp.views, "board_rms": cmp.board_rms, "better_model": cmp.best}
    if args.compare_opencv:
        from calibration.compare import opencv_stereo

        out["opencv"] = opencv_stereo(train.subset(np.isin(train.names, cal.names))).to_json()
    write_rig(cal, args.out, args.model)
    if args.report:
        write_report(cal, args.report)
    if args.json:
        print(json.dumps(out))
    else:
        print(_readable(out, args.out))
    return 0


def _readable(s: dict[str, Any], path: str) -> str:
    K_l, K_r = s["K_left"], s["K_right"]
    lines = [
        f"views used {s['views_used']}, rejected {len(s['views_rejected'])}, "
        f"images skipped {len(s['images_skipped'])}",
        f"RMS reprojection {s['rms_px']:.3f} px (stereo pairs {s['stereo_rms_px']:.3f} px)",
        f"left  f {K_l[0][0]:.2f} {K_l[1][1]:.2f}  c {K_l[0][2]:.2f} {K_l[1][2]:.2f}  dist "
        + " ".join(f"{x:+.4f}" for x in s["dist_left"]),
        f"right f {K_r[0][0]:.2f} {K_r[1][1]:.2f}  c {K_r[0][2]:.2f} {K_r[1][2]:.2f}  dist "
        + " ".join(f"{x:+.4f}" for x in s["dist_right"]),
        f"baseline {s['baseline']:.5f}  Euler (δ, φ, γ) " + " ".join(f"{a:+.4f}°" for a in s["euler_deg"]),
        f"rectified row error mean {s['rectified_row_error_mean_px']:.3f} px, "
        f"RMS {s['rectified_row_error_rms_px']:.3f} px",
        f"board coverage left {100 * s['coverage']['left']:.0f}%, right {100 * s['coverage']['right']:.0f}%",
    ]
    for r in s["views_rejected"]:
        lines.append(f"rejected {r['view']}: {r['reason']}")
    for r in s["images_skipped"]:
        lines.append(f"skipped {r['image']}: {r['reason']}")
    if "held_out" in s:
        h = s["held_out"]
        figs = ", ".join(f"{k} {v:.5f}" for k, v in h["board_rms"].items())
        lines.append(f"held-out views {h['views']}: board-shape RMS {figs} -> {h['better_model']} is better")
    if "opencv" in s:
        o = s["opencv"]
        lines.append(f"OpenCV stereoCalibrate on the same corners: rectified row error mean "
                     f"{o['rectified_row_error_mean_px']:.3f} px, RMS {o['rectified_row_error_rms_px']:.3f} px; "
                     f"RMS reprojection {o['stereo_rms_px']:.3f} px")
    lines.append(f"wrote {path}")
    return "\n".join(lines)
