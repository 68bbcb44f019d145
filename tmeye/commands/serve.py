"""`tmeye serve`: the operator console server (FastAPI under uvicorn) on a rig runtime."""

from __future__ import annotations

import argparse
import logging
import socket
import sys
from typing import Any

from tmeye.commands.track import TARGET_CHOICES, TARGETS_HELP
from tmeye.errors import UserError

LOG_FORMAT = "%(asctime)s %(levelname)s %(name)s: %(message)s"


class OneLineFormatter(logging.Formatter):
    """Every event on one line: a traceback (or a multi-line message) follows its message with its lines
    joined by " | ", so a log reader or grep sees one event per line."""

    def format(self, record: logging.LogRecord) -> str:
        return " | ".join(line for line in super().format(record).splitlines() if line.strip())


def one_line_logging(level: str) -> None:
    handler = logging.StreamHandler(sys.stderr)
    handler.setFormatter(OneLineFormatter(LOG_FORMAT))
    logging.basicConfig(level=level.upper(), handlers=[handler], force=True)


def register(subparsers: Any) -> None:
    p = subparsers.add_parser("serve", help="run the operator console server (REST, WebSocket, browser console)")
    p.add_argument("--host", help="address to listen on (default 127.0.0.1)")
    p.add_argument("--port", type=int, help="TCP port (default 8080; 0: any free port)")
    p.add_argument("--data-dir", help="database, keys and uploads (default ./tmeye-data)")
    p.add_argument("--source", choices=("sim", "files", "usb", "rtsp"), help="frame source (default sim)")
    p.add_argument("inputs", nargs="*", help="LEFT RIGHT of a real source")
    p.add_argument("--scenario", help="simulated scene (default endless; finite scenarios repeat)")
    p.add_argument("--seed", type=int, help="simulated scene seed")
    p.add_argument("--rig", help="rig file (default: the active calibration record, else the simulator's rig)")
    p.add_argument("--servo", help="sim, none, or a driver URL (maestro:/dev/ttyACM0, ascii:/dev/ttyUSB0); "
                   "default: sim with the simulated source, none with a real one")
    p.add_argument("--targets", choices=TARGET_CHOICES,
                   help=TARGETS_HELP)
    p.add_argument("--log-level", choices=("debug", "info", "warning", "error"))
    p.add_argument("--stamp-frames", action="store_true", default=None,
                   help="measurement mode: the video carries the frame index in its top-left corner")
    p.add_argument("--tls-cert", help="PEM certificate: serve HTTPS directly (with --tls-key)")
    p.add_argument("--tls-key", help="PEM private key of --tls-cert")
    p.add_argument("--trusted-proxy", action="append", metavar="ADDR",
                   help="reverse proxy address or network whose X-Forwarded-For/-Proto are believed (repeatable)")
    p.set_defaults(func=run)


def settings_from(args: argparse.Namespace) -> Any:
    from pydantic import ValidationError

    from server.services.errors import one_line
    from server.settings import Settings

    given = {k: v for k, v in {"host": args.host, "port": args.port, "data_dir": args.data_dir,
                               "source": args.source, "scenario": args.scenario, "seed": args.seed,
                               "rig": args.rig, "servo": args.servo, "targets": args.targets,
                               "log_level": args.log_level,
                               "stamp_frames": args.stamp_frames, "tls_cert": args.tls_cert,
                               "tls_key": args.tls_key, "trusted_proxies": args.trusted_proxy}.items()
             if v is not None}
    if args.inputs:
        given["inputs"] = list(args.inputs)
    try:
        return Settings(**given)
    except ValidationError as exc:
        raise UserError(f"bad setting: {one_line(exc)}") from None


def tls_and_proxies(settings: Any) -> dict[str, Any]:
    """uvicorn options: the TLS certificate and key, and X-Forwarded-* honoured only from trusted proxies."""
    opts: dict[str, Any] = {"proxy_headers": bool(settings.trusted_proxies),
                            "forwarded_allow_ips": list(settings.trusted_proxies)}
    if settings.tls_cert:
        for what, path in (("certificate", settings.tls_cert), ("key", settings.tls_key)):
            if not path.is_file():
                raise UserError(f"TLS {what} {path} is not a readable file")
        opts.update(ssl_certfile=str(settings.tls_cert), ssl_keyfile=str(settings.tls_key))
    return opts


def run(args: argparse.Namespace) -> int:
    import uvicorn

    from server.app import create_app
    from server.db.engine import storage_problem

    settings = settings_from(args)
    problem = storage_problem(settings.data_dir, settings.db_path)
    if problem:
        raise UserError(problem)
    # The tracker's worker thread and the event loop share the GIL: hand it over within 1 ms (Python's
    # default 5 ms delayed WebSocket sends by up to that while the worker ran Python code).
    sys.setswitchinterval(0.001)
    one_line_logging(settings.log_level)
    try:
        sock = socket.create_server((settings.host, settings.port), reuse_port=False)
    except OSError as exc:
        raise UserError(f"cannot listen on {settings.host}:{settings.port}: {exc.strerror or exc}") from None
    port = sock.getsockname()[1]
    scheme = "https" if settings.tls_cert else "http"
    url = f"{scheme}://{settings.host}:{port}/"
    pw = settings.data_dir / "initial-admin-password"
    print(f"TMEye console: {url}  (API docs {url}api/docs)", flush=True)
    print(f"log in as 'admin'; on first start its password is written to {pw.resolve()}", flush=True)
    config = uvicorn.Config(create_app(settings), log_config=None, log_level=settings.log_level,
                            timeout_graceful_shutdown=2, ws_ping_interval=settings.ws_ping_s,
                            ws_ping_timeout=settings.ws_ping_s, ws_per_message_deflate=False, access_log=False,
                            **tls_and_proxies(settings))
    server = uvicorn.Server(config)
    server.run(sockets=[sock])
    if not server.started:
        raise UserError("the server did not start (see the log above)")
    return 0
