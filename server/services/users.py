"""Users and their sessions: create, change, delete, authenticate, log in and out, the initial admin."""

from __future__ import annotations

import logging
import os
import secrets
import time
from pathlib import Path
from typing import Any

from sqlalchemy import func, select, update
from sqlalchemy.orm import Session

from server.db.models import AuthSession, User
from server.security import check_password_rules, dummy_verify, hash_password, new_session_id, verify_password
from server.services import audit
from server.services.errors import Conflict, Invalid, NotFound

ROLES = ("viewer", "operator", "admin")
RANK = {r: i for i, r in enumerate(ROLES)}
log = logging.getLogger("tmeye.auth")


def _check_role(role: str) -> None:
    if role not in RANK:
        raise Invalid(f"unknown role {role!r}; use viewer, operator or admin")


def create_user(db: Session, username: str, password: str, role: str) -> User:
    _check_role(role)
    try:
        check_password_rules(password)
    except ValueError as exc:
        raise Invalid(str(exc)) from None
    if db.scalar(select(User).where(func.lower(User.username) == username.lower())) is not None:
        raise Conflict(f"user {username!r} already exists")
    now = time.time()
    user = User(username=username, password_hash=hash_password(password), role=role, created_at=now,
                password_changed_at=now, disabled=False)
    db.add(user)
    db.flush()
    return user


def get_user(db: Session, user_id: int) -> User:
    user = db.get(User, user_id)
    if user is None:
        raise NotFound(f"no user with id {user_id}")
    return user


def list_users(db: Session) -> list[User]:
    return list(db.scalars(select(User).order_by(User.id)))


def _admins(db: Session) -> int:
    return int(db.scalar(select(func.count()).select_from(User).where(User.role == "admin", User.disabled.is_(False)))
               or 0)


def update_user(db: Session, user: User, password: str | None, role: str | None, disabled: bool | None) -> User:
    """Change the password (ends the user's sessions), the role or the disabled flag; the last active admin
    cannot be demoted or disabled."""
    if role is not None:
        _check_role(role)
    demoting = (role is not None and role != "admin") or bool(disabled)
    if user.role == "admin" and not user.disabled and demoting and _admins(db) <= 1:
        raise Conflict("the last admin cannot be demoted or disabled")
    if password is not None:
        try:
            user.password_hash = hash_password(password)
        except ValueError as exc:
            raise Invalid(str(exc)) from None
        user.password_changed_at = time.time()
        revoke_all(db, user.id)
    if role is not None:
        user.role = role
    if disabled is not None:
        user.disabled = disabled
        if disabled:
            revoke_all(db, user.id)
    return user


def delete_user(db: Session, user: User) -> None:
    if user.role == "admin" and not user.disabled and _admins(db) <= 1:
        raise Conflict("the last admin cannot be deleted")
    db.delete(user)


def add_by_admin(db: Session, admin: User, address: str, username: str, password: str, role: str) -> User:
    """An admin's new user, recorded in the audit log, committed."""
    user = create_user(db, username, password, role)
    audit.record(db, admin, address, "user.create", username, {"role": role})
    db.commit()
    return user


def change_by_admin(db: Session, admin: User, address: str, user_id: int, password: str | None, role: str | None,
                    disabled: bool | None) -> User:
    """An admin's change of a user (`update_user`), recorded without the password itself, committed."""
    user = update_user(db, get_user(db, user_id), password, role, disabled)
    detail: dict[str, Any] = {k: v for k, v in (("role", role), ("disabled", disabled)) if v is not None}
    if password:
        detail["password"] = "changed"
    audit.record(db, admin, address, "user.update", user.username, detail)
    db.commit()
    return user


def remove_by_admin(db: Session, admin: User, address: str, user_id: int) -> None:
    """An admin's deletion of a user, recorded in the audit log, committed."""
    user = get_user(db, user_id)
    delete_user(db, user)
    audit.record(db, admin, address, "user.delete", user.username)
    db.commit()


def authenticate(db: Session, username: str, password: str) -> User | None:
    user = db.scalar(select(User).where(func.lower(User.username) == username.lower()))
    if user is None:
        dummy_verify()
        return None
    if not verify_password(user.password_hash, password) or user.disabled:
        return None
    return user


def open_session(db: Session, user: User, ttl_s: float, address: str | None) -> AuthSession:
    now = time.time()
    s = AuthSession(id=new_session_id(), user_id=user.id, created_at=now, expires_at=now + ttl_s, address=address)
    db.add(s)
    return s


def session_user(db: Session, session_id: str) -> User | None:
    """The user of a live session (not revoked, not expired, user not disabled), else None."""
    s = db.get(AuthSession, session_id)
    if s is None or s.revoked_at is not None or s.expires_at <= time.time():
        return None
    user = db.get(User, s.user_id)
    return None if user is None or user.disabled else user


def revoke(db: Session, session_id: str) -> None:
    db.execute(update(AuthSession).where(AuthSession.id == session_id, AuthSession.revoked_at.is_(None))
               .values(revoked_at=time.time()))


def revoke_all(db: Session, user_id: int) -> None:
    db.execute(update(AuthSession).where(AuthSession.user_id == user_id, AuthSession.revoked_at.is_(None))
               .values(revoked_at=time.time()))


def ensure_initial_admin(db: Session, data_dir: Path) -> Path | None:
    """With no users: create `admin` with a random password written to DATA/initial-admin-password
    (mode 0600) and return that path; otherwise None."""
    if db.scalar(select(func.count()).select_from(User)):
        return None
    password = secrets.token_urlsafe(18)
    create_user(db, "admin", password, "admin")
    path = data_dir / "initial-admin-password"
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
    with os.fdopen(fd, "w") as f:
        f.write(password + "\n")
    os.chmod(path, 0o600)
    db.commit()
    return path
