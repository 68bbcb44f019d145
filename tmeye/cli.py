"""`tmeye` entry point: parses the sub-command and turns expected failures into one-line errors."""

from __future__ import annotations

import argparse
import importlib
import os
import sys

import cv2

from tmeye.errors import UserError

__all__ = ["UserError", "build_parser", "main"]

# Sub-command modules, each with register(subparsers) setting `func` on its parser.
COMMANDS = ("track", "eval", "bench", "calibrate", "serve", "user", "soak")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="tmeye", description="Real-time stereo tracker (simulated rig by default)")
    sub = parser.add_subparsers(dest="command", required=True)
    for name in COMMANDS:
        try:
            module = importlib.import_module(f"tmeye.commands.{name}")
        except ModuleNotFoundError as exc:
            if exc.name == f"tmeye.commands.{name}":
                continue  # that command is not part of this build yet
            raise
        module.register(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        code = args.func(args)
    except BrokenPipeError:  # the reader went away (`tmeye track --json | head`): stop quietly, as on SIGPIPE
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())  # no second error at exit's flush
        return 128 + 13
    except (UserError, ValueError, FileNotFoundError, OSError) as exc:
        print(f"tmeye {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except cv2.error as exc:  # a backstop: inputs OpenCV refused that no check above caught
        reason = str(exc).strip().splitlines()[-1] if str(exc).strip() else type(exc).__name__
        print(f"tmeye {args.command}: error: OpenCV refused the input: {reason}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        return 130
    return int(code or 0)
