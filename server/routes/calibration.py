"""Calibration records: upload image pairs (admin), list, get, activate (admin), download the rig file."""

from __future__ import annotations

import asyncio
from typing import Annotated, Any

from fastapi import APIRouter, File, Form, UploadFile
from fastapi.responses import JSONResponse

from server.deps import Address, Admin, CtxDep, DbDep, RowId, Viewer
from server.schemas import CalibrationOut, Message
from server.services import calibration as cal

router = APIRouter(prefix="/api/calibrations", tags=["calibration"])
NOT_FOUND: dict[int | str, dict[str, Any]] = {404: {"model": Message}}


@router.post("", response_model=CalibrationOut, status_code=202, responses={409: {"model": Message},
             422: {"model": Message}}, summary="Upload image pairs and start a calibration (progress on /ws/events)")
async def create(ctx: CtxDep, p: Admin, addr: Address, left: Annotated[list[UploadFile], File()],
                 right: Annotated[list[UploadFile], File()],
                 board: Annotated[str, Form(description="inner corners COLSxROWS", examples=["9x6"])],
                 square: Annotated[float, Form(gt=0, le=10, description="square size (m)", examples=[0.025])]
                 ) -> dict[str, Any]:
    lefts = [cal.Upload(f.filename or f"left{i}", await f.read()) for i, f in enumerate(left)]
    rights = [cal.Upload(f.filename or f"right{i}", await f.read()) for i, f in enumerate(right)]
    rec = await asyncio.to_thread(ctx.calibrations.upload, p.user, addr, board, square, lefts, rights)
    ctx.calibrations.start(rec["id"])
    return rec


@router.get("", response_model=list[CalibrationOut], summary="All calibration records, newest first")
def list_records(_p: Viewer, db: DbDep) -> list[dict[str, Any]]:
    return [cal.as_json(r) for r in cal.list_records(db)]


@router.get("/{rec_id}", response_model=CalibrationOut, responses=NOT_FOUND, summary="One record with its report")
def get_record(rec_id: RowId, _p: Viewer, db: DbDep) -> dict[str, Any]:
    return cal.as_json(cal.get(db, rec_id), report=True)


@router.post("/{rec_id}/activate", response_model=CalibrationOut, responses={**NOT_FOUND, 409: {"model": Message}},
             summary="Make this rig the tracker's (switches without a restart)")
def activate(rec_id: RowId, ctx: CtxDep, p: Admin, db: DbDep, addr: Address) -> dict[str, Any]:
    rec = cal.get(db, rec_id)
    cal.activate(db, ctx.runtime, rec, p.user, addr)
    return cal.as_json(rec)


@router.get("/{rec_id}/rig", responses={**NOT_FOUND, 409: {"model": Message}},
            summary="The rig file (JSON) this calibration produced")
def download_rig(rec_id: RowId, _p: Viewer, db: DbDep) -> JSONResponse:
    rec = cal.get(db, rec_id)
    if rec.rig is None:
        return JSONResponse({"detail": f"calibration {rec_id} is {rec.status}: it has no rig file"}, 409)
    return JSONResponse(rec.rig, headers={"Content-Disposition": f'attachment; filename="rig-{rec_id}.json"'})
