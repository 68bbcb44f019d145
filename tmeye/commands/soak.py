"""`tmeye soak --minutes N`: run the server under WebRTC, WebSocket and REST load and report its health."""

from __future__ import annotations

import argparse
import shlex
from typing import Any

from tmeye.errors import UserError
from tmeye.output import emit


def register(subparsers: Any) -> None:
    p = subparsers.add_parser("soak", help="run `tmeye serve` under steady load (WebRTC, WebSocket, REST) and "
                                           "report skipped frames, loop lag, stalls, memory, fds and threads")
    p.add_argument("--minutes", type=float, default=60.0, help="how long (default 60)")
    p.add_argument("--viewers", type=int, default=4, help="WebRTC viewers (default 4)")
    p.add_argument("--clients", type=int, default=10, help="WebSocket telemetry clients (default 10)")
    p.add_argument("--serve-args", default="", help="extra `tmeye serve` arguments, e.g. '--servo none'")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from tmeye.soak import run_soak

    if not 0.25 <= args.minutes <= 24 * 60:
        raise UserError(f"--minutes must be 0.25 to 1440, got {args.minutes}")
    if not 0 <= args.viewers <= 16 or not 1 <= args.clients <= 100:
        raise UserError("--viewers must be 0 to 16 and --clients 1 to 100")
    report = run_soak(args.minutes, args.viewers, args.clients, shlex.split(args.serve_args))
    if not args.json:
        report = {k: v for k, v in report.items() if k != "samples"}
    emit(report, args.json)
    return 0
