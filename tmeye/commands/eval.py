"""`tmeye eval`: accuracy against the simulated rig's ground truth, one JSON object per run."""

from __future__ import annotations

import argparse
import json
import os
from pathlib import Path
from typing import Any

from tmeye.errors import UserError
from tmeye.output import emit
from tmeye.progress import Progress

SPECIAL = {
    "calibration": "calibrate from rendered board views of the simulated rig and compare with its truth",
}


def register(subparsers: Any) -> None:
    p = subparsers.add_parser("eval", help="measure accuracy on a simulated scenario")
    p.add_argument("--scenario", help="scenario name (see --list): its targets are solid bodies; NAME:plate draws "
                   "them as flat plates")
    p.add_argument("--all", action="store_true", help="every scenario, as bodies and as plates, each checked "
                   "against the acceptance lines (with --frames, --seed, --json)")
    p.add_argument("--list", action="store_true", help="list the scenarios and exit")
    p.add_argument("--frames", type=int, help="number of frames (default: the scenario's length)")
    p.add_argument("--seed", type=int, default=0, help="random seed of the simulated scene (default 0)")
    p.add_argument("--rig", help="rig file the tracker uses instead of the simulator's true rig")
    p.add_argument("--epsilon", type=int, help="eq. (9) threshold ε in grey levels (default 12)")
    p.add_argument("--alarms", action="store_true", help="alarm rules (zone, range, approach) on the endless "
                   "scene against its true target positions (with --minutes, --seed)")
    p.add_argument("--minutes", type=float, default=10.0, help="simulated minutes of --alarms (default 10)")
    p.add_argument("--start", type=float, default=0.0, help="--alarms: scene time (s) to start at (default 0)")
    p.add_argument("--matching", metavar="DIR",
                   help="instead: point matching (tracker.point_match.match_point) against OpenCV StereoSGBM on the "
                        "rectified pairs with known disparity under DIR (NAME/im2.png, im6.png, disp2.png, disp6.png)")
    p.add_argument("--near-wall", action="store_true",
                   help="instead: a person walking 0.05, 0.1, 0.2 and 0.5 m in front of a wall at 7 m, cameras still "
                        "(and 0.1 m with light steps): detection, false targets, range error per gap, MOG2 beside")
    p.add_argument("--startup", action="store_true",
                   help="instead: frames lost when a target stands in view from frame 0 and then walks, with the "
                        "first pair as the background, with the background learnt from the stream, and surveyed")
    p.add_argument("--exposure", action="store_true",
                   help="instead: pan:body and walk:body with the right camera's exposure stepped to 0.8 and 1.2 "
                        "times the left's at 2 s, with the exposures matched and without, beside the cameras alike")
    p.add_argument("--frames-out", metavar="FILE",
                   help="with --scenario: also write one JSON line per frame the target is visible in to FILE "
                        "(what was reported and its 1-sigma, the truth, the errors and normalised errors, the blob)")
    p.add_argument("--edge-samples", type=int, default=1, metavar="N",
                   help="with --scenario or --all: the simulator draws each pixel a body's edge crosses as the mean of "
                        "N x N rays over it, as a camera integrates light (default 1: each pixel's centre)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=run)


def _scenarios() -> dict[str, str]:
    from tracker.sim.scenarios import SCENARIOS

    out = {name: s.description for name, s in SCENARIOS.items()}
    out.update(SPECIAL)
    out["NAME:body"] = ("any scenario above but calibration (the default): its targets are textured, lit 3-D "
                        "bodies (sphere, walking person, vehicle), truth their volume centroid")
    out["NAME:plate"] = "any scenario above but calibration with its targets as flat plates facing the cameras"
    return out


def scenario_name(name: str) -> str:
    """The scenario `--scenario NAME` runs: NAME:body (solid bodies, the default), NAME:plate as given;
    calibration as it is. Raises UserError for an unknown name."""
    from tracker.sim.scenarios import BODY_SUFFIX, split_name

    if name in SPECIAL:
        return name
    try:
        _, suffix = split_name(name)
    except ValueError:
        raise UserError(f"unknown scenario {name!r}; known: {', '.join(_scenarios())}") from None
    return name if suffix else name + BODY_SUFFIX


def _instead(args: argparse.Namespace) -> int:
    """--matching, --near-wall, --startup or --exposure: an evaluation of its own instead of a scenario's."""
    if args.matching:
        if args.frames_out:
            raise UserError("--frames-out writes the frames of one tracking scenario: give it with --scenario NAME")
        emit(_matching(args.matching), args.json)
        return 0
    if args.scenario or args.rig or args.epsilon is not None or args.alarms or args.all or args.frames_out or (
            args.near_wall + args.startup + args.exposure > 1):
        raise UserError("--near-wall, --startup and --exposure run their own scenes: give one, and only --seed, "
                        "--frames and --json with it")
    if args.frames is not None and args.frames < 1:
        raise UserError(f"--frames must be at least 1, got {args.frames}")
    emit(_near_wall(args) if args.near_wall else _startup(args) if args.startup else _exposure(args), args.json)
    return 0


def _alarms(args: argparse.Namespace) -> int:
    """--alarms: the alarm rules on the endless scene against its true target positions."""
    if args.scenario or args.frames is not None or args.rig or args.epsilon is not None or args.all or \
            args.frames_out:
        raise UserError("--alarms runs the endless scene: give only --minutes, --seed and --json with it")
    if not 0 < args.minutes <= 600:
        raise UserError(f"--minutes must be above 0 and at most 600, got {args.minutes:g}")
    from tmeye.alarm_eval import evaluate_alarms

    if args.start < 0:
        raise UserError(f"--start must be at least 0, got {args.start:g}")
    emit(evaluate_alarms(args.minutes, args.seed, progress=Progress("eval alarms"), start_s=args.start), True)
    return 0


def run(args: argparse.Namespace) -> int:
    if args.seed < 0:  # numpy's generators refuse it, naming no option
        raise UserError(f"--seed must be 0 or more, got {args.seed}")
    names = _scenarios()
    if not 1 <= args.edge_samples <= 8:
        raise UserError(f"--edge-samples must be 1 to 8, got {args.edge_samples}")
    if args.edge_samples != 1 and not (args.scenario or args.all) or args.edge_samples != 1 and (
            args.matching or args.near_wall or args.startup or args.exposure or args.alarms):
        raise UserError("--edge-samples goes with --scenario NAME or --all")
    if args.matching or args.near_wall or args.startup or args.exposure:
        return _instead(args)
    if args.list:
        for name, desc in names.items():
            print(f"{name:14s} {desc}")
        return 0
    if args.alarms:
        return _alarms(args)
    if args.frames is not None and args.frames < 1:
        raise UserError(f"--frames must be at least 1, got {args.frames}")
    if args.frames_out and (args.all or not args.scenario or scenario_name(args.scenario) == "calibration"):
        raise UserError("--frames-out writes the frames of one tracking scenario: give it with --scenario NAME")
    if args.all:
        if args.scenario or args.rig or args.epsilon is not None:
            raise UserError("--all runs every scenario: give only --frames, --seed and --json with it")
        return _all(args)
    if not args.scenario:
        raise UserError("give --scenario NAME, --all, --alarms or --list")
    args.scenario = scenario_name(args.scenario)
    if args.edge_samples != 1 and (args.scenario in SPECIAL or not args.scenario.endswith(":body")):
        raise UserError(f"--edge-samples changes how bodies are drawn: {args.scenario!r} has none")
    if args.scenario == "calibration":
        from calibration.scenario import run_calibration_scenario

        result: dict[str, object] = run_calibration_scenario(seed=args.seed).to_json()
    else:
        out = None if args.frames_out is None else FramesOut(args.frames_out)  # checked before the run
        result = _tracking(args, None if out is None else out.rows)
        if out is not None:
            out.write()
    emit(result, args.json)
    return 0


class FramesOut:
    """`--frames-out FILE`: checked before the run (its directory exists and can be written, FILE is not a
    directory), its rows gathered by the run (tracker.evaluation.frame_row), written after it whole, through
    a file beside it renamed over FILE: an interrupted run leaves FILE as it was."""

    def __init__(self, path: str):
        p = Path(path)
        if p.is_dir():
            raise UserError(f"--frames-out {path!r} is a directory")
        if not p.parent.is_dir():
            raise UserError(f"--frames-out {path!r}: no such directory {str(p.parent)!r}")
        if not os.access(p.parent, os.W_OK) or (p.exists() and not os.access(p, os.W_OK)):
            raise UserError(f"--frames-out {path!r} cannot be written")
        self.path = p
        self.rows: list[dict[str, object]] = []

    def write(self) -> None:
        tmp = self.path.with_name(f".{self.path.name}.{os.getpid()}.tmp")
        try:
            with tmp.open("w", encoding="utf-8") as f:
                f.writelines(json.dumps(r) + "\n" for r in self.rows)
            os.replace(tmp, self.path)
        except OSError as e:
            tmp.unlink(missing_ok=True)
            raise UserError(f"--frames-out {str(self.path)!r}: {e.strerror or e}") from None


def _tracking(args: argparse.Namespace, rows: list[dict[str, object]] | None = None) -> dict[str, object]:
    from tracker.detect import DetectorConfig
    from tracker.evaluation import run_scenario
    from tracker.geometry import load_rig
    from tracker.sim.scenarios import get_scenario

    if get_scenario(args.scenario).closed_loop:
        return _closed_loop(args, rows)

    rig = load_rig(args.rig) if args.rig else None
    det = DetectorConfig(epsilon=args.epsilon) if args.epsilon is not None else None
    report = run_scenario(args.scenario, frames=args.frames, seed=args.seed, rig=rig, detector=det,
                          progress=Progress(f"eval {args.scenario}"), rows=rows, edge_samples=args.edge_samples)
    return {**report.to_json(), "edge_samples": args.edge_samples}


def _all(args: argparse.Namespace) -> int:
    from tmeye.eval_all import run_all, summary_lines

    bar = Progress("eval --all")
    result = run_all(args.frames, args.seed, done=lambda _name, n, total: bar(n, total),
                     edge_samples=args.edge_samples)
    result["edge_samples"] = args.edge_samples
    if args.json:
        emit(result, True)
    else:
        print("\n".join(summary_lines(result)))
        if args.edge_samples != 1:
            print(f"bodies' edges drawn as the mean of {args.edge_samples} x {args.edge_samples} rays a pixel")
    return 0


def _closed_loop(args: argparse.Namespace, rows: list[dict[str, object]] | None = None) -> dict[str, object]:
    """A closed-loop scenario: the predictive loop and the reactive baseline drive the simulated gimbal."""
    from tracker.closedloop_eval import evaluate_closed_loop

    if args.rig or args.epsilon is not None:
        raise UserError(f"--rig and --epsilon are not supported by the closed-loop scenario {args.scenario!r}")
    report = evaluate_closed_loop(args.scenario, frames=args.frames, seed=args.seed,
                                  progress=Progress(f"eval {args.scenario}"), rows=rows,
                                  edge_samples=args.edge_samples)
    return {**report.to_json(), "edge_samples": args.edge_samples}


def _near_wall(args: argparse.Namespace) -> dict[str, object]:
    from tracker.nearwall_eval import near_wall_table

    return near_wall_table(seed=args.seed, frames=args.frames)


def _exposure(args: argparse.Namespace) -> dict[str, object]:
    from tracker.exposure_eval import exposure_table

    return exposure_table(seed=args.seed, frames=args.frames)


def _startup(args: argparse.Namespace) -> dict[str, object]:
    from tracker.startup_eval import METHODS, run_startup

    return {m: run_startup(m, frames=args.frames, seed=args.seed).to_json() for m in METHODS}


def _matching(root: str) -> dict[str, object]:
    """Per pair: points, and for match_point and SGBM the answered share, median error, share > 1 px."""
    from pathlib import Path

    from tracker.matching_eval import evaluate_matching

    if not Path(root).is_dir():
        raise UserError(f"--matching {root!r} is not a directory")
    pairs = evaluate_matching(Path(root))
    out: dict[str, object] = {p.name: p.to_json() for p in pairs}
    out["match_point_beats_sgbm_on_every_pair"] = all(p.beats_sgbm for p in pairs)
    return out
