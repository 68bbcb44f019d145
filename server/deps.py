"""FastAPI dependencies: the context, a database session, the current user (bearer token or session
cookie, with a CSRF check for cookie-authenticated unsafe requests) and role requirements."""

from __future__ import annotations

import hmac
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Annotated
from urllib.parse import urlsplit

from fastapi import Depends, HTTPException, Path, Request, WebSocket, status
from sqlalchemy.orm import Session

from server.context import AppContext
from server.db.models import User
from server.schema_base import SQLITE_MAX_INT
from server.security import csrf_token, read_token
from server.services import users as user_service

COOKIE = "tmeye_session"
CSRF_COOKIE = "tmeye_csrf"
CSRF_HEADER = "X-CSRF-Token"
SAFE_METHODS = frozenset({"GET", "HEAD", "OPTIONS"})

# A row id in a path: SQLite's INTEGER range (a larger number would fail in the driver, not be "not found").
RowId = Annotated[int, Path(ge=1, le=SQLITE_MAX_INT, description="row id")]


def get_ctx(request: Request) -> AppContext:
    ctx: AppContext = request.app.state.ctx
    return ctx


CtxDep = Annotated[AppContext, Depends(get_ctx)]


def get_db(ctx: CtxDep) -> Iterator[Session]:
    with ctx.sessions() as db:
        yield db


DbDep = Annotated[Session, Depends(get_db)]


@dataclass(frozen=True)
class Principal:
    """The authenticated caller: the user row, the session id and how it authenticated."""

    user: User
    session_id: str
    via_cookie: bool


def _unauthorized(msg: str) -> HTTPException:
    return HTTPException(status.HTTP_401_UNAUTHORIZED, msg, headers={"WWW-Authenticate": "Bearer"})


def token_from(headers: dict[str, str] | None, cookies: dict[str, str]) -> tuple[str | None, bool]:
    """(token, came from the cookie) from an Authorization: Bearer header or the session cookie."""
    auth = (headers or {}).get("authorization", "")
    if auth:
        scheme, _, value = auth.partition(" ")
        if scheme.lower() != "bearer" or not value.strip():
            raise _unauthorized("Authorization header must be 'Bearer <token>'")
        return value.strip(), False
    return cookies.get(COOKIE), True


def authenticate(ctx: AppContext, db: Session, token: str | None, via_cookie: bool) -> Principal:
    if not token:
        raise _unauthorized("not logged in")
    claims = read_token(ctx.key, token)
    if claims is None:
        raise _unauthorized("invalid or expired token")
    user = user_service.session_user(db, claims.session_id)
    if user is None:
        raise _unauthorized("session ended (logged out, expired or password changed)")
    if not ctx.idle.touch(claims.session_id):
        user_service.revoke(db, claims.session_id)
        db.commit()
        raise _unauthorized(f"session ended after {ctx.settings.session_idle_s} s without a request")
    return Principal(user, claims.session_id, via_cookie)


def get_principal(request: Request, ctx: CtxDep, db: DbDep) -> Principal:
    token, via_cookie = token_from(dict(request.headers), dict(request.cookies))
    p = authenticate(ctx, db, token, via_cookie)
    if via_cookie and request.method not in SAFE_METHODS:
        sent = request.headers.get(CSRF_HEADER, "")
        if not hmac.compare_digest(sent, csrf_token(ctx.key, p.session_id)):
            raise HTTPException(status.HTTP_403_FORBIDDEN, f"missing or wrong {CSRF_HEADER} header "
                                "(cookie-authenticated requests that change state need it)")
    return p


PrincipalDep = Annotated[Principal, Depends(get_principal)]


def require(role: str) -> Callable[[Principal], Principal]:
    rank = user_service.RANK[role]

    def check(p: PrincipalDep) -> Principal:
        if user_service.RANK.get(p.user.role, -1) < rank:
            raise HTTPException(status.HTTP_403_FORBIDDEN, f"needs the {role} role (you are {p.user.role})")
        return p
    return check


Viewer = Annotated[Principal, Depends(require("viewer"))]
Operator = Annotated[Principal, Depends(require("operator"))]
Admin = Annotated[Principal, Depends(require("admin"))]


def client_address(request: Request) -> str:
    return request.client.host if request.client else "unknown"


Address = Annotated[str, Depends(client_address)]


def same_origin(origin: str, host: str) -> bool:
    """Whether a browser's Origin header names the host the request was sent to."""
    return urlsplit(origin).netloc.lower() == host.lower()


def websocket_principal(ws: WebSocket, ctx: AppContext, role: str = "viewer") -> Principal:
    """Authenticate a WebSocket handshake (cookie or Authorization: Bearer); HTTPException otherwise.
    A cookie-authenticated handshake must come from the console's own origin (browsers send the cookie
    with a handshake that another site's page starts: cross-site WebSocket hijacking)."""
    token, via_cookie = token_from(dict(ws.headers), dict(ws.cookies))
    origin = ws.headers.get("origin")
    if via_cookie and token and origin and not same_origin(origin, ws.headers.get("host", "")):
        raise HTTPException(status.HTTP_403_FORBIDDEN, f"cross-origin WebSocket from {origin[:60]} refused")
    with ctx.sessions() as db:
        p = authenticate(ctx, db, token, via_cookie)
    if user_service.RANK.get(p.user.role, -1) < user_service.RANK[role]:
        raise HTTPException(status.HTTP_403_FORBIDDEN, f"needs the {role} role")
    return p
