"""Exports of recorded ranges (operator): a job with progress, then a zip to download."""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter, HTTPException
from fastapi.responses import FileResponse
from sqlalchemy import select

from server.db.models import Export
from server.deps import Address, CtxDep, DbDep, Operator, RowId
from server.recording_schemas import ExportIn, ExportOut
from server.schemas import Message
from server.services import audit
from server.services.exports import get_export

router = APIRouter(prefix="/api/exports", tags=["exports"])


@router.post("", response_model=ExportOut, status_code=202, responses={422: {"model": Message}},
             summary="Export start..end: one MP4 per camera (not encoded again) and the telemetry, zipped")
def create_export(body: ExportIn, ctx: CtxDep, p: Operator, db: DbDep, addr: Address) -> Any:
    assert ctx.exports is not None
    row = ctx.exports.create(db, p.user, body.start, body.end, list(body.cameras))
    audit.record(db, p.user, addr, "export", f"export {row.id}", body.model_dump())
    db.commit()
    return row


@router.get("", response_model=list[ExportOut], summary="Exports, newest first")
def list_exports(_p: Operator, db: DbDep) -> list[Any]:
    return list(db.scalars(select(Export).order_by(Export.id.desc()).limit(200)))


@router.get("/{export_id}", response_model=ExportOut, responses={404: {"model": Message}},
            summary="An export's status and progress")
def export_status(export_id: RowId, _p: Operator, db: DbDep) -> Any:
    return get_export(db, export_id)


@router.get("/{export_id}/download", response_class=FileResponse,
            responses={404: {"model": Message}, 409: {"model": Message}}, summary="The finished export (zip)")
def download(export_id: RowId, ctx: CtxDep, _p: Operator, db: DbDep) -> FileResponse:
    row = get_export(db, export_id)
    if row.status != "done" or row.path is None:
        raise HTTPException(409, f"export {export_id} is {row.status}, not done")
    return FileResponse(ctx.settings.data_dir / row.path, media_type="application/zip",
                        filename=f"tmeye-export-{export_id}.zip")
