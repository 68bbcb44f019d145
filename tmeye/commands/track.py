"""`tmeye track`: run the tracker on a source and print live telemetry (r, θ, φ, fps) per frame."""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from typing import Any

from tmeye.errors import UserError


def register(subparsers: Any) -> None:
    p = subparsers.add_parser("track", help="track a target and print per-frame telemetry")
    p.add_argument("--source", default="sim", choices=("sim", "files", "usb", "rtsp"),
                   help="frame source (default: the simulated rig)")
    p.add_argument("inputs", nargs="*", help="LEFT RIGHT: video files, camera indices/devices or RTSP URLs")
    p.add_argument("--scenario", default="walk", help="simulated scenario (with --source sim)")
    p.add_argument("--seed", type=int, default=0, help="simulated scene seed")
    p.add_argument("--rig", help="rig file (tmeye calibrate); required for real sources")
    p.add_argument("--frames", type=int, help="stop after this many frames")
    p.add_argument("--origin", default="0,0,0",
                   help="X,Y,Z (m, gimbal-base frame) about which r, θ and φ are given (default 0,0,0)")
    p.add_argument("--json", action="store_true", help="one JSON line per frame")
    p.add_argument("--fast", action="store_true",
                   help="simulated source: run as fast as possible instead of at the scenario's frame rate")
    p.add_argument("--servo", metavar="URL",
                   help="close the loop: drive a pan/tilt mount (sim, maestro:/dev/ttyACM0, ascii:/dev/ttyUSB0)")
    p.set_defaults(func=run)


def _open(args: argparse.Namespace) -> tuple[Any, Any, list[Any]]:
    """(source, rig, background pairs to learn from)."""
    from tracker.geometry import load_rig

    rig = load_rig(args.rig) if args.rig else None
    if args.source == "sim":
        from tracker.evaluation import survey_poses
        from tracker.sim.scenarios import SimRig, get_scenario

        if args.inputs:
            raise UserError("--source sim takes no LEFT RIGHT inputs")
        sim = SimRig(get_scenario(args.scenario), seed=args.seed)
        if args.servo:  # the mount follows the target: learn the background over its range
            from tracker.closedloop import survey_grid
            from tracker.closedloop_eval import mount_range

            return sim, rig or sim.rig, [sim.background(g) for g in survey_grid(*mount_range(sim.scenario))]
        return sim, rig or sim.rig, [sim.background(g) for g in survey_poses(sim.scenario)]
    from tracker.sources import open_source

    if rig is None:
        raise UserError(f"--source {args.source} needs --rig RIG.json (make one with `tmeye calibrate`)")
    src = open_source(args.source, list(args.inputs))
    first = src.read()
    if first is None:
        src.close()
        raise UserError(f"{args.source} source gave no frames")
    return src, rig, [first]  # the first pair is taken as the empty background


def _servo_loop(args: argparse.Namespace, source: Any, pipe: Any) -> tuple[Any, Any]:
    """(frame source, ServoLoop) for --servo URL: the driver is opened first, so a bad URL, a missing
    port or a silent device is a one-line error before any tracking."""
    from tracker.aim import AimConfig, AimController
    from tracker.closedloop import LoopConfig, ServoLoop, ServoSimSource, background_range, widen_background
    from tracker.closedloop_eval import closed_loop_imm, mount_range
    from tracker.servo import ServoError, SimulatedGimbal, open_servo

    try:
        driver = open_servo(args.servo)
    except ServoError as exc:
        raise UserError(str(exc)) from None
    ctrl = AimController(AimConfig(frame_width_px=pipe.rig.left.size[0], focal_px=pipe.rect.f))
    lead = 0.09
    if isinstance(driver, SimulatedGimbal):
        if args.source != "sim":
            driver.close()
            raise UserError("--servo sim drives the simulated rig: use it with --source sim")
        lead = driver.config.latency_s + driver.config.time_constant_s
    if args.source == "sim":
        widen_background(pipe, *background_range(*mount_range(source.scenario), pipe.rig.left.size,
                                                 pipe.rect.f))
        source = ServoSimSource(source, driver, lambda: ctrl.setpoint)
    latency = 0.005 if isinstance(driver, SimulatedGimbal) else None  # simulated time: the budget
    return source, ServoLoop(pipe, ctrl, closed_loop_imm(), driver, LoopConfig(lead_s=lead, latency_s=latency))


def telemetry(res: Any, frame: Any, fps: float) -> dict[str, object]:
    """One frame's telemetry as a JSON-ready mapping (angles in degrees, lengths in metres)."""
    out: dict[str, object] = {"frame": frame.index, "t": round(frame.t, 6), "offset_s": round(frame.offset_s, 6),
                              "detected": res.primary is not None, "track_id": res.primary_id,
                              "objects": len(res.detections), "fps": round(fps, 1),
                              "step_ms": round(sum(res.stage_ms.values()), 3)}
    if res.primary is not None:
        loc = res.primary.loc
        out.update({"x": round(float(loc.world[0]), 4), "y": round(float(loc.world[1]), 4),
                    "z": round(float(loc.world[2]), 4), "r": round(loc.r, 4),
                    "theta_deg": round(math.degrees(loc.theta), 4), "phi_deg": round(math.degrees(loc.phi), 4),
                    "sigma_r": round(loc.sigma_r, 4), "sigma_theta_deg": round(math.degrees(loc.sigma_theta), 5),
                    "sigma_phi_deg": round(math.degrees(loc.sigma_phi), 5)})
    return out


def _line(tm: dict[str, object]) -> str:
    if not tm["detected"]:
        return f"frame {tm['frame']:>6}  no target{'':52s} {tm['fps']:6.1f} fps"
    return (f"frame {tm['frame']:>6}  track {tm['track_id']:>3}  r {tm['r']:7.3f} ± {tm['sigma_r']:.3f} m  "
            f"θ {tm['theta_deg']:+8.3f}°  φ {tm['phi_deg']:+7.3f}°  {tm['fps']:6.1f} fps")


def run(args: argparse.Namespace) -> int:
    from tracker.pipeline import Pipeline

    if args.frames is not None and args.frames < 1:
        raise UserError(f"--frames must be at least 1, got {args.frames}")
    source, rig, background = _open(args)
    loop = None
    live = sys.stdout.isatty() and not args.json
    try:
        pipe = Pipeline(rig, origin=_origin(args.origin))
        if args.servo:
            source, loop = _servo_loop(args, source, pipe)
        for bg in background:
            pipe.learn_background(bg)
        _run_frames(args, source, pipe, loop, live)
    finally:
        source.close()
        if loop is not None and loop.driver is not None:
            loop.driver.close()
        if live:
            print()
    return 0


def _origin(text: str) -> Any:
    import numpy as np

    try:
        xyz = [float(v) for v in text.split(",")]
    except ValueError:
        xyz = []
    if len(xyz) != 3 or not all(np.isfinite(xyz)):
        raise UserError(f"--origin must be three numbers X,Y,Z in metres, got {text!r}")
    return np.array(xyz)


def _run_frames(args: argparse.Namespace, source: Any, pipe: Any, loop: Any, live: bool) -> None:
    """Track frame by frame until the source ends or --frames, printing telemetry."""
    n, t_last, fps = 0, time.perf_counter(), 0.0
    period = 1.0 / source.scenario.fps if args.source == "sim" and not args.fast else 0.0
    t_start = time.perf_counter()
    while args.frames is None or n < args.frames:
        if period:
            time.sleep(max(0.0, t_start + n * period - time.perf_counter()))
        frame = source.read()
        if frame is None:
            break
        step = loop.step(frame) if loop is not None else None
        res = step.result if step is not None else pipe.step(frame)
        now = time.perf_counter()
        fps = 0.9 * fps + 0.1 / max(now - t_last, 1e-6) if n else 1.0 / max(now - t_last, 1e-6)
        t_last = now
        tm = telemetry(res, frame, fps)
        if step is not None:
            tm["servo"] = step.servo_json()
            tm["latency_ms"] = round(step.latency_ms, 3)
        if args.json:
            print(json.dumps(tm), flush=True)
        elif live:
            sys.stdout.write("\r" + _line(tm))
            sys.stdout.flush()
        else:
            print(_line(tm))
        n += 1
