"""`tmeye track`: run the tracker on a source and print live telemetry (r, θ, φ, fps) per frame.

The rig is composed and run by the same runtime as `tmeye serve` (tmeye.runtime): a worker thread
publishes each frame, and this command prints what it receives."""

from __future__ import annotations

import argparse
import json
import sys
from typing import Any

from tmeye.errors import UserError

TARGET_CHOICES = ("auto", "solid", "flat")  # RuntimeConfig.targets (kept light: no runtime import here)
TARGETS_HELP = ("what the range is measured to: solid (a body's centre, half its assumed depth behind the "
                "seen face), flat (the seen face: boards) or auto (default: solid, except the simulator's flat plates)")


def register(subparsers: Any) -> None:
    p = subparsers.add_parser("track", help="track a target and print per-frame telemetry")
    p.add_argument("--source", default="sim", choices=("sim", "files", "usb", "rtsp", "recording"),
                   help="frame source (default: the simulated rig; recording: a server's recordings of "
                        "--start..--end in --data-dir, replayed as fast as possible)")
    p.add_argument("--data-dir", help="with --source recording: the server's data directory")
    p.add_argument("--start", type=float, help="with --source recording: the range's start (Unix s)")
    p.add_argument("--end", type=float, help="with --source recording: the range's end (Unix s)")
    p.add_argument("--background", choices=("scene", "first"), default="scene",
                   help="with --source recording: learn the background from the simulated --scenario (default "
                        "endless, as `tmeye serve`) or from the first recorded pair, then the stream (real cameras)")
    p.add_argument("inputs", nargs="*", help="LEFT RIGHT: video files, camera indices/devices or RTSP URLs")
    p.add_argument("--scenario", help="simulated scenario (with --source sim, default walk; with --source "
                                      "recording, default endless)")
    p.add_argument("--seed", type=int, default=0, help="simulated scene seed")
    p.add_argument("--rig", help="rig file (tmeye calibrate); required for real sources")
    p.add_argument("--frames", type=int, help="stop after this many frames")
    p.add_argument("--origin", default="0,0,0",
                   help="X,Y,Z (m, gimbal-base frame) about which r, θ and φ are given (default 0,0,0)")
    p.add_argument("--baseline-limits", metavar="MIN,MAX",
                   help="plausible rig baselines in metres the rig file is checked against (default 0.01,10)")
    p.add_argument("--json", action="store_true", help="one JSON line per frame")
    p.add_argument("--targets", choices=TARGET_CHOICES, default="auto",
                   help=TARGETS_HELP)
    p.add_argument("--fast", action="store_true",
                   help="simulated source: run as fast as possible instead of at the scenario's frame rate")
    p.add_argument("--loop", action="store_true", help="simulated source: repeat a finite scenario")
    p.add_argument("--servo", metavar="URL",
                   help="close the loop: drive a pan/tilt mount (sim, maestro:/dev/ttyACM0, ascii:/dev/ttyUSB0)")
    p.set_defaults(func=run)


def parse_origin(text: str) -> tuple[float, float, float]:
    """"X,Y,Z" in metres -> a finite 3-tuple; UserError otherwise."""
    import math

    try:
        xyz = [float(v) for v in text.split(",")]
    except ValueError:
        xyz = []
    if len(xyz) != 3 or not all(math.isfinite(v) for v in xyz):
        raise UserError(f"--origin must be three numbers X,Y,Z in metres, got {text!r}")
    return xyz[0], xyz[1], xyz[2]


def parse_limits(text: str | None) -> tuple[float, float] | None:
    """"MIN,MAX" baseline limits in metres -> (min, max) with 0 < min < max; UserError otherwise."""
    if text is None:
        return None
    try:
        lo, hi = (float(v) for v in text.split(","))
    except ValueError:
        lo = hi = float("nan")
    if not 0 < lo < hi < float("inf"):
        raise UserError(f"--baseline-limits must be MIN,MAX metres with 0 < MIN < MAX, got {text!r}")
    return lo, hi


def line(tm: dict[str, Any]) -> str:
    if not tm["detected"]:
        return f"frame {tm['frame']:>6}  no target{'':52s} {tm['fps']:6.1f} fps"
    return (f"frame {tm['frame']:>6}  track {tm['track_id']:>3}  r {tm['r']:7.3f} ± {tm['sigma_r']:.3f} m  "
            f"θ {tm['theta_deg']:+8.3f}°  φ {tm['phi_deg']:+7.3f}°  {tm['fps']:6.1f} fps")


def run(args: argparse.Namespace) -> int:
    from tmeye.runtime import ComposeError, Runtime, RuntimeConfig

    if args.source == "recording":
        from tmeye.commands.replay import run_recording

        return run_recording(args)
    if args.frames is not None and args.frames < 1:
        raise UserError(f"--frames must be at least 1, got {args.frames}")
    if args.seed < 0:  # numpy's generators refuse it, naming no option
        raise UserError(f"--seed must be 0 or more, got {args.seed}")
    if args.source == "sim" and args.inputs:
        raise UserError("--source sim takes no LEFT RIGHT inputs")
    if args.source != "sim" and not args.rig:
        raise UserError(f"--source {args.source} needs --rig RIG.json (make one with `tmeye calibrate`)")
    try:
        cfg = RuntimeConfig(source=args.source, inputs=tuple(args.inputs), scenario=args.scenario or "walk",
                            seed=args.seed,
                            rig=args.rig, servo=args.servo, realtime=not args.fast and args.source == "sim",
                            loop_source=args.loop, max_frames=args.frames, origin=parse_origin(args.origin),
                            baseline_limits_m=parse_limits(args.baseline_limits), targets=args.targets)
        runtime = Runtime(cfg)
        sub = runtime.hub.subscribe(maxsize=1024, name="track")
        runtime.start()
    except ComposeError as exc:
        raise UserError(str(exc)) from None
    live = sys.stdout.isatty() and not args.json
    try:
        _print_frames(args, sub, live)
    finally:
        runtime.stop()
        if live:
            print()
    if sub.dropped:
        print(f"tmeye track: {sub.dropped} frames were processed but not printed (output too slow)", file=sys.stderr)
    if runtime.error:
        raise UserError(runtime.error)
    return 0


def _print_frames(args: argparse.Namespace, sub: Any, live: bool) -> None:
    while True:
        ev = sub.get(timeout=0.5)
        if ev is None:
            if sub.closed:
                return
            continue
        tm = dict(ev.telemetry)
        tm.pop("detections", None)
        tm.pop("captured_at", None)
        if tm.get("servo") is None:
            tm.pop("servo", None)
        if args.json:
            print(json.dumps(tm), flush=True)
        elif live:
            sys.stdout.write("\r" + line(tm))
            sys.stdout.flush()
        else:
            print(line(tm))
