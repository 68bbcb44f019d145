"""Logging in and out: a session row, a signed token, the audit entries."""

from __future__ import annotations

from sqlalchemy.orm import Session

from server.context import AppContext
from server.db.models import User
from server.schemas import LoginAnswer
from server.security import csrf_token, make_token
from server.services import audit
from server.services import users as user_service


def login(db: Session, ctx: AppContext, username: str, password: str, address: str) -> LoginAnswer | None:
    user = user_service.authenticate(db, username, password)
    if user is None:
        audit.record(db, None, address, "auth.login_failed", username[:64])
        db.commit()
        return None
    ttl = ctx.settings.token_ttl_s
    s = user_service.open_session(db, user, ttl, address)
    audit.record(db, user, address, "auth.login")
    db.commit()
    return LoginAnswer(access_token=make_token(ctx.key, s.id, s.expires_at), role=user.role,
                       expires_in=ttl, csrf_token=csrf_token(ctx.key, s.id))


def logout(db: Session, user: User, session_id: str, address: str) -> None:
    user_service.revoke(db, session_id)
    audit.record(db, user, address, "auth.logout")
    db.commit()
