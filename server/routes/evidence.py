"""Evidence locks (operators lock, only admins unlock) and bookmarks with a note."""

from __future__ import annotations

from typing import Annotated, Any

from fastapi import APIRouter, Query

from server.deps import Address, Admin, CtxDep, DbDep, Operator, RowId, Viewer
from server.recording_schemas import BookmarkIn, BookmarkOut, LockIn, LockOut
from server.schemas import Message
from server.services import evidence

router = APIRouter(prefix="/api", tags=["evidence"])
Time = Annotated[float | None, Query(description="Unix s")]
NOT_FOUND: dict[int | str, dict[str, Any]] = {404: {"model": Message}}


@router.get("/locks", response_model=list[LockOut], summary="Evidence locks overlapping start..end")
def list_locks(_p: Viewer, db: DbDep, start: Time = None, end: Time = None) -> list[Any]:
    return evidence.list_locks(db, start, end)


@router.post("/locks", response_model=LockOut, status_code=201, responses={**NOT_FOUND, 422: {"model": Message}},
             summary="Keep a time range, or a track's or an alarm's footage (widened by the pre- and post-roll), "
                     "from retention")
def add_lock(body: LockIn, ctx: CtxDep, p: Operator, db: DbDep, addr: Address) -> Any:
    margin = max(ctx.settings.preroll_s, ctx.settings.postroll_s)
    roll = (margin, margin) if body.track_id is not None else (ctx.settings.preroll_s, ctx.settings.postroll_s)
    return evidence.add_lock(db, p.user, addr, body.start, body.end, body.track_id, body.note, roll, body.alarm_id)


@router.delete("/locks/{lock_id}", status_code=204, responses=NOT_FOUND, summary="Unlock (admin)")
def remove_lock(lock_id: RowId, p: Admin, db: DbDep, addr: Address) -> None:
    evidence.remove_lock(db, p.user, addr, lock_id)


@router.get("/bookmarks", response_model=list[BookmarkOut], summary="Bookmarks in start..end")
def list_bookmarks(_p: Viewer, db: DbDep, start: Time = None, end: Time = None) -> list[Any]:
    return evidence.list_bookmarks(db, start, end)


@router.post("/bookmarks", response_model=BookmarkOut, status_code=201, responses={422: {"model": Message}},
             summary="Bookmark a moment with a note")
def add_bookmark(body: BookmarkIn, p: Operator, db: DbDep, addr: Address) -> Any:
    return evidence.add_bookmark(db, p.user, addr, body.t, body.note)


@router.delete("/bookmarks/{bookmark_id}", status_code=204, responses=NOT_FOUND, summary="Delete a bookmark")
def remove_bookmark(bookmark_id: RowId, p: Operator, db: DbDep, addr: Address) -> None:
    evidence.remove_bookmark(db, p.user, addr, bookmark_id)
