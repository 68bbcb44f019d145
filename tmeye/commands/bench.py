"""`tmeye bench`: per-stage and whole-step timing on one thread, against OpenCV's MOG2."""

from __future__ import annotations

import argparse
from typing import Any

from tmeye.errors import UserError
from tmeye.output import emit


def parse_size(text: str) -> tuple[int, int]:
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise UserError(f"--size must look like 640x480, got {text!r}") from None
    if not (64 <= w <= 4096 and 48 <= h <= 4096):
        raise UserError(f"--size {w}x{h} is out of range (64x48 to 4096x4096)")
    return w, h


def register(subparsers: Any) -> None:
    p = subparsers.add_parser("bench", help="time the pipeline per stage and against MOG2")
    p.add_argument("--size", default="640x480", help="image size WxH (default 640x480)")
    p.add_argument("--frames", type=int, default=300, help="frames to time (default 300)")
    p.add_argument("--scenario", default="walk",
                   help="open-loop simulated scenario whose frames are timed (default walk; pan moves the cameras)")
    p.add_argument("--repeats", type=int, default=5,
                   help="passes per measurement; each figure is the best of them (default 5)")
    p.add_argument("--edge-samples", type=int, default=1, metavar="N",
                   help="a :body scenario's edges drawn as the mean of N x N rays a pixel (tmeye eval --edge-samples; "
                        "default 1)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--server", action="store_true",
                   help="measure `tmeye serve` under load instead: WebSocket telemetry clients, skipped frames, "
                        "event-loop lag, capture-to-send latency, CPU")
    p.add_argument("--seconds", type=float, default=30.0, help="--server: measurement window (default 30)")
    p.add_argument("--clients", type=int, default=10, help="--server: WebSocket clients (default 10)")
    p.add_argument("--webrtc", metavar="N,N", help="measure WebRTC viewers instead (aiortc clients; e.g. 1,4): decoded "
                   "fps, capture-to-decoded latency, server CPU per number of clients")
    p.add_argument("--browser", action="store_true",
                   help="measure the console's Live page in headless chromium instead: frames shown per second per "
                        "camera (requestVideoFrameCallback), frames received/decoded/dropped, server CPU")
    p.add_argument("--recording", action="store_true",
                   help="measure recording instead: frames in exactly one segment per camera over --seconds, "
                        "stamps against telemetry, /api/playback/frame at --probes random times, the worker's "
                        "frame-time cost of recording, --kills SIGKILL restarts")
    p.add_argument("--crash", action="store_true",
                   help="measure crash safety instead: an alarm acknowledged, --kills SIGKILLs at random moments "
                        "(integrity_check, committed rows and the acknowledgement kept, recordings decode), then "
                        "SIGTERM (stop time, segments closed)")
    p.add_argument("--probes", type=int, default=100, help="--recording: random playback times (default 100)")
    p.add_argument("--kills", type=int, default=20,
                   help="--recording, --crash: SIGKILLs at random moments (default 20)")
    p.add_argument("--cost-seconds", type=float, default=20.0,
                   help="--recording: seconds per with/without-recorder round of the worker cost (0: skip)")
    p.add_argument("--serve-args", default="", help="--server: extra `tmeye serve` arguments, e.g. '--servo none'")
    p.set_defaults(func=run)


def run_webrtc(args: argparse.Namespace) -> int:
    import shlex

    from tmeye.benchserver import run_webrtc_bench

    try:
        counts = [int(v) for v in args.webrtc.split(",")]
    except ValueError:
        counts = []
    if not counts or not all(1 <= n <= 16 for n in counts):
        raise UserError(f"--webrtc takes client counts 1 to 16 separated by commas, got {args.webrtc!r}")
    emit(run_webrtc_bench(args.seconds, counts, shlex.split(args.serve_args)), args.json)
    return 0


def run_browser(args: argparse.Namespace) -> int:
    import shlex

    from tmeye.benchbrowser import run_browser_bench

    if not 5 <= args.seconds <= 3600:
        raise UserError(f"--seconds must be 5 to 3600, got {args.seconds}")
    try:
        emit(run_browser_bench(args.seconds, shlex.split(args.serve_args)), args.json)
    except (RuntimeError, ImportError) as exc:
        raise UserError(f"--browser: {exc}") from None
    return 0


def run_server(args: argparse.Namespace) -> int:
    import shlex

    from tmeye.benchserver import run_server_bench

    if not 1 <= args.clients <= 100:
        raise UserError(f"--clients must be 1 to 100, got {args.clients}")
    if not 5 <= args.seconds <= 7200:
        raise UserError(f"--seconds must be 5 to 7200, got {args.seconds}")
    emit(run_server_bench(args.seconds, args.clients, 5.0, shlex.split(args.serve_args)), args.json)
    return 0


def run_recording(args: argparse.Namespace) -> int:
    import shlex

    from tmeye.benchrecording import run_recording_bench

    if not (args.seconds == 0 or 10 <= args.seconds <= 7200):
        raise UserError(f"--seconds must be 0 (no coverage run) or 10 to 7200 for --recording, got {args.seconds}")
    if not 1 <= args.probes <= 10000 or not 0 <= args.kills <= 1000 or not 0 <= args.cost_seconds <= 600:
        raise UserError("--probes must be 1 to 10000, --kills 0 to 1000, --cost-seconds 0 to 600")
    emit(run_recording_bench(args.seconds, args.probes, args.kills, args.cost_seconds, shlex.split(args.serve_args)),
         args.json)
    return 0


def run_crash(args: argparse.Namespace) -> int:
    import shlex
    import tempfile
    from pathlib import Path

    from tmeye.crashcheck import run as crash_run

    if not 1 <= args.kills <= 1000:
        raise UserError(f"--kills must be 1 to 1000 for --crash, got {args.kills}")
    with tempfile.TemporaryDirectory(prefix="tmeye-bench-crash-") as tmp:
        emit(crash_run(Path(tmp), args.kills, shlex.split(args.serve_args)), args.json)
    return 0


def run(args: argparse.Namespace) -> int:
    if args.crash:
        return run_crash(args)
    if args.recording:
        return run_recording(args)
    if args.webrtc:
        return run_webrtc(args)
    if args.server:
        return run_server(args)
    if args.browser:
        return run_browser(args)
    from tracker.bench import run_bench
    from tracker.sim.scenarios import get_scenario

    size = parse_size(args.size)
    if args.frames < 10:
        raise UserError(f"--frames must be at least 10, got {args.frames}")
    if not 1 <= args.repeats <= 20:
        raise UserError(f"--repeats must be 1 to 20, got {args.repeats}")
    try:
        sc = get_scenario(args.scenario)
    except ValueError as e:
        raise UserError(str(e)) from None
    if sc.closed_loop:
        raise UserError(f"scenario {sc.name!r} is closed-loop (its frames depend on the servo loop): time it "
                        f"with tmeye eval --scenario {sc.name}")
    if not 1 <= args.edge_samples <= 8:
        raise UserError(f"--edge-samples must be 1 to 8, got {args.edge_samples}")
    if args.edge_samples != 1 and not sc.bodies:
        raise UserError(f"--edge-samples changes how bodies are drawn: {sc.name!r} has none")
    report = run_bench(size, args.frames, sc.name, repeats=args.repeats, edge_samples=args.edge_samples).to_json()
    emit(report, args.json)
    return 0
