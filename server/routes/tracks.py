"""Tracks recorded by the track writer: list by time, one with its trajectory."""

from __future__ import annotations

from typing import Annotated, Any

from fastapi import APIRouter, Query

from server.deps import Address, CtxDep, DbDep, Operator, RowId, Viewer
from server.schema_base import SQLITE_MAX_INT
from server.schemas import Message, TrackDetail, TrackOut
from server.services import control
from server.services import tracks as track_service

ReplayId = Annotated[int | None, Query(ge=1, le=SQLITE_MAX_INT,
                                       description="a replay's tracks (default: the live ones)")]
router = APIRouter(prefix="/api/tracks", tags=["tracks"])


@router.get("", response_model=list[TrackOut], summary="Tracks seen between start and end (Unix s), newest first")
def list_tracks(_p: Viewer, db: DbDep, start: Annotated[float | None, Query(description="Unix s")] = None,
                end: Annotated[float | None, Query(description="Unix s")] = None,
                limit: Annotated[int, Query(ge=1, le=10000)] = 500,
                replay: ReplayId = None) -> list[Any]:
    return track_service.list_tracks(db, start, end, limit, replay)


@router.post("/{track_id}/primary", status_code=204, responses={404: {"model": Message}, 409: {"model": Message}},
             summary="Make a live track (the telemetry's track_id) the primary target",
             description="The mount follows it until it ends, or until it has gone unseen for the aim's "
                         "`loss_timeout_s` while another confirmed target is in view, which then takes its place.")
def primary(track_id: RowId, ctx: CtxDep, p: Operator, db: DbDep, addr: Address) -> None:
    control.select_primary(db, ctx.runtime, p.user, addr, track_id)


@router.get("/{track_id}", response_model=TrackDetail, responses={404: {"model": Message}},
            summary="One track with its trajectory (x, y, z m; r m; θ, φ deg)")
def get_track(track_id: RowId, _p: Viewer, db: DbDep) -> TrackDetail:
    tr, pts = track_service.get_track(db, track_id)
    return TrackDetail.model_validate({**TrackOut.model_validate(tr).model_dump(), "trajectory": pts},
                                      from_attributes=True)
