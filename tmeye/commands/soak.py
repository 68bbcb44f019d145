"""`tmeye soak`: run the server under a console's load for a long time and report its health over time."""

from __future__ import annotations

import argparse
import json
import shlex
from typing import Any

from tmeye.errors import UserError


def register(subparsers: Any) -> None:
    p = subparsers.add_parser("soak", help="run the server under load for minutes or hours; report memory, "
                                           "descriptors, threads, stalls, skipped frames, event-loop lag")
    p.add_argument("--minutes", type=float, default=60.0, help="length of the run (default 60)")
    p.add_argument("--webrtc", type=int, default=4, help="WebRTC viewers, both cameras each (default 4)")
    p.add_argument("--ws", type=int, default=10, help="WebSocket telemetry clients (default 10)")
    p.add_argument("--sample-s", type=float, default=10.0, help="seconds between samples (default 10)")
    p.add_argument("--serve-args", default="", help="extra `tmeye serve` arguments")
    p.add_argument("--json", action="store_true", help="print one JSON object (summary and samples)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from tmeye.soak import run_soak

    if not 0.5 <= args.minutes <= 7 * 24 * 60:
        raise UserError(f"--minutes must be 0.5 to 10080, got {args.minutes}")
    if not 0 <= args.webrtc <= 16 or not 0 <= args.ws <= 100:
        raise UserError(f"--webrtc must be 0 to 16 and --ws 0 to 100, got {args.webrtc} and {args.ws}")
    if not 1.0 <= args.sample_s <= args.minutes * 60 / 2:
        raise UserError(f"--sample-s must be 1 to half the run ({args.minutes * 30:g} s), got {args.sample_s}")
    report = run_soak(args.minutes, args.webrtc, args.ws, args.sample_s, shlex.split(args.serve_args))
    if args.json:
        print(json.dumps(report))
        return 0
    for k, v in report["summary"].items():
        print(f"{k:38s}{v}")
    print("\n" + " ".join(f"{k:>10s}" for k in ("t_s", "rss_mb", "fds", "threads", "gap_ms", "lag_p99", "skipped")))
    for s in report["samples"]:
        if "error" in s:
            print(f"{s['t_s']:>10} {s['error']}")
            continue
        vals = (s["t_s"], s["rss_mb"], s["fds"], s["threads"], s["frame_gap_max_ms"], s["loop_lag_p99_ms"],
                s["skipped_in_interval"])
        print(" ".join(f"{'-' if v is None else v:>10}" for v in vals))
    return 0
