"""`tmeye user add NAME --role ROLE [--data-dir DIR]`: add a console user (password from stdin when it is
not a terminal, else asked twice)."""

from __future__ import annotations

import argparse
import getpass
import sys
from pathlib import Path
from typing import Any

from tmeye.errors import UserError


def register(subparsers: Any) -> None:
    p = subparsers.add_parser("user", help="manage console users")
    sub = p.add_subparsers(dest="action", required=True)
    add = sub.add_parser("add", help="add a user")
    add.add_argument("name")
    add.add_argument("--role", required=True, choices=("viewer", "operator", "admin"))
    add.add_argument("--data-dir", default=None, help="default ./tmeye-data (or TMEYE_DATA_DIR)")
    add.set_defaults(func=run_add)


def _password() -> str:
    if not sys.stdin.isatty():
        return sys.stdin.readline().rstrip("\r\n")
    first = getpass.getpass("password: ")
    if getpass.getpass("again: ") != first:
        raise UserError("the passwords differ")
    return first


def run_add(args: argparse.Namespace) -> int:
    from server.db.engine import make_engine, session_factory, upgrade
    from server.services import users
    from server.services.errors import Conflict, Invalid
    from server.settings import Settings

    settings = Settings(data_dir=Path(args.data_dir)) if args.data_dir else Settings()
    password = _password()
    settings.data_dir.mkdir(parents=True, exist_ok=True)
    upgrade(settings.db_url)
    engine = make_engine(settings.db_url)
    try:
        with session_factory(engine)() as db:
            users.create_user(db, args.name, password, args.role)
            db.commit()
    except (Conflict, Invalid) as exc:
        raise UserError(str(exc)) from None
    finally:
        engine.dispose()
    print(f"added {args.role} {args.name!r} to {settings.db_path}")
    return 0
