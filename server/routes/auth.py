"""Login (OAuth2 password form; bearer token plus an HttpOnly SameSite=Strict cookie) and logout."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Depends, HTTPException, Request, Response
from fastapi.security import OAuth2PasswordRequestForm

from server.deps import COOKIE, CSRF_COOKIE, Address, CtxDep, DbDep, PrincipalDep
from server.schemas import LoginAnswer, Me, Message
from server.services import auth as auth_service

router = APIRouter(prefix="/api/auth", tags=["auth"])


@router.post("/login", response_model=LoginAnswer, summary="Log in with username and password",
             responses={401: {"model": Message}, 429: {"model": Message, "description": "too many failures"}})
def login(form: Annotated[OAuth2PasswordRequestForm, Depends()], request: Request, response: Response, ctx: CtxDep,
          db: DbDep, address: Address) -> LoginAnswer:
    wait = ctx.throttle.retry_after(form.username, address)
    if wait:
        raise HTTPException(429, f"too many failed logins: try again in {wait} s", headers={"Retry-After": str(wait)})
    answer = auth_service.login(db, ctx, form.username, form.password, address)
    if answer is None:
        ctx.throttle.failed(form.username, address)
        raise HTTPException(401, "wrong username or password", headers={"WWW-Authenticate": "Bearer"})
    ctx.throttle.succeeded(form.username)
    secure = ctx.settings.cookie_secure or request.url.scheme == "https"  # https: directly or via a trusted proxy
    response.set_cookie(COOKIE, answer.access_token, max_age=answer.expires_in, httponly=True, samesite="strict",
                        secure=secure, path="/")
    response.set_cookie(CSRF_COOKIE, answer.csrf_token, max_age=answer.expires_in, httponly=False,
                        samesite="strict", secure=secure, path="/")
    return answer


@router.get("/me", response_model=Me, summary="Who is logged in: username and role")
def me(p: PrincipalDep) -> Me:
    return Me(username=p.user.username, role=p.user.role)


@router.post("/logout", status_code=204, summary="End this session: its token stops working at once")
def logout(p: PrincipalDep, response: Response, ctx: CtxDep, db: DbDep, address: Address) -> Response:
    auth_service.logout(db, p.user, p.session_id, address)
    ctx.idle.forget(p.session_id)
    response.status_code = 204
    response.delete_cookie(COOKIE, path="/")
    response.delete_cookie(CSRF_COOKIE, path="/")
    return response
