"""Users (admin) and the audit log (admin)."""

from __future__ import annotations

from typing import Annotated, Any

from fastapi import APIRouter, Query

from server.deps import Address, Admin, DbDep, RowId
from server.schemas import AuditOut, Message, UserIn, UserOut, UserPatch
from server.services import audit
from server.services import users as user_service

router = APIRouter(prefix="/api", tags=["users"])


@router.get("/users", response_model=list[UserOut], summary="All users")
def list_users(_p: Admin, db: DbDep) -> list[Any]:
    return user_service.list_users(db)


@router.post("/users", response_model=UserOut, status_code=201, responses={409: {"model": Message}},
             summary="Create a user (password 12 to 128 characters)")
def create_user(body: UserIn, p: Admin, db: DbDep, addr: Address) -> Any:
    return user_service.add_by_admin(db, p.user, addr, body.username, body.password, body.role)


@router.patch("/users/{user_id}", response_model=UserOut, responses={404: {"model": Message}, 409: {"model": Message}},
              summary="Change password (ends the user's sessions), role or disabled")
def patch_user(user_id: RowId, body: UserPatch, p: Admin, db: DbDep, addr: Address) -> Any:
    return user_service.change_by_admin(db, p.user, addr, user_id, body.password, body.role, body.disabled)


@router.delete("/users/{user_id}", status_code=204, responses={404: {"model": Message}, 409: {"model": Message}},
               summary="Delete a user")
def delete_user(user_id: RowId, p: Admin, db: DbDep, addr: Address) -> None:
    user_service.remove_by_admin(db, p.user, addr, user_id)


@router.get("/audit", response_model=list[AuditOut], summary="Audit log, newest first")
def list_audit(_p: Admin, db: DbDep, start: Annotated[float | None, Query(description="Unix s")] = None,
               end: Annotated[float | None, Query(description="Unix s")] = None,
               action: Annotated[str | None, Query(max_length=64)] = None,
               limit: Annotated[int, Query(ge=1, le=10000)] = 500) -> list[Any]:
    return audit.list_entries(db, start, end, action, limit)
