"""Replays (operator): the tracker re-run on a recorded range with other settings; a job with progress whose
tracks are listed apart (GET /api/tracks?replay=ID)."""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter
from sqlalchemy import select

from server.db.models import Replay
from server.deps import Address, CtxDep, DbDep, Operator, RowId
from server.recording_schemas import ReplayIn, ReplayOut
from server.schemas import Message
from server.services import audit
from server.services.replays import get_replay, live_setup

router = APIRouter(prefix="/api/replays", tags=["replays"])


@router.post("", response_model=ReplayOut, status_code=202, responses={422: {"model": Message}},
             summary="Re-run the tracker on the recordings of start..end (threshold, rig); its tracks are stored apart")
def create_replay(body: ReplayIn, ctx: CtxDep, p: Operator, db: DbDep, addr: Address) -> Any:
    assert ctx.replays is not None
    row = ctx.replays.create(db, p.user, body.start, body.end, live_setup(ctx.settings, ctx.runtime), body.threshold,
                             body.calibration_id)
    audit.record(db, p.user, addr, "replay", f"replay {row.id}", body.model_dump())
    db.commit()
    return row


@router.get("", response_model=list[ReplayOut], summary="Replays, newest first")
def list_replays(_p: Operator, db: DbDep) -> list[Any]:
    return list(db.scalars(select(Replay).order_by(Replay.id.desc()).limit(200)))


@router.get("/{replay_id}", response_model=ReplayOut, responses={404: {"model": Message}},
            summary="A replay's status, progress and agreement with the live result")
def replay_status(replay_id: RowId, _p: Operator, db: DbDep) -> Any:
    return get_replay(db, replay_id)
