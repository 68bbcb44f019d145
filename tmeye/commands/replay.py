"""`tmeye track --source recording`: the tracker re-run on a server's recordings of a range (tmeye.replay),
one telemetry line per frame on stdout, and at the end how the replay agrees with the live detections
recorded for the same frames (stderr). Nothing is written to the data directory."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

from tmeye.errors import UserError


def run_recording(args: argparse.Namespace) -> int:
    from tmeye.commands.track import line
    from tmeye.replay import replay_config, run_replay
    from tmeye.runtime import ComposeError, FrameEvent
    from tracker.geometry import load_rig

    if args.inputs or args.servo or args.frames is not None:
        raise UserError("--source recording takes no LEFT RIGHT inputs, --servo or --frames")
    if not args.data_dir or args.start is None or args.end is None:
        raise UserError("--source recording needs --data-dir DIR, --start T0 and --end T1 (Unix s)")
    if not Path(args.data_dir).is_dir():
        raise UserError(f"--data-dir {args.data_dir} is not a directory")
    scenario = "" if args.background == "first" else (args.scenario or "endless")
    try:
        cfg = replay_config(args.data_dir, args.start, args.end, scenario, args.seed, args.targets)
        rig = load_rig(args.rig) if args.rig else None
    except (OSError, ValueError, KeyError) as exc:
        raise UserError(str(exc).splitlines()[0]) from None

    def show(ev: FrameEvent, _progress: float) -> None:
        tm: dict[str, Any] = {k: v for k, v in ev.telemetry.items() if k not in ("detections", "servo")}
        print(json.dumps(tm) if args.json else line(tm), flush=True)

    try:
        agreement = run_replay(cfg, None, rig, show)
    except ComposeError as exc:
        raise UserError(str(exc)) from None
    except RuntimeError as exc:
        raise UserError(str(exc).splitlines()[0]) from None
    print(f"tmeye track: replayed {agreement.frames} frames; agreement with the live result: "
          f"{json.dumps(agreement.summary())}", file=sys.stderr)
    return 0
