"""Live tracker settings: read, and change from the next frame on (admin)."""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter

from server.deps import Address, Admin, CtxDep, DbDep, Viewer
from server.schemas import Message
from server.services import control
from server.settings_schemas import TrackerSettings, TrackerSettingsPatch

router = APIRouter(prefix="/api/tracker", tags=["tracker"])


@router.get("/config", response_model=TrackerSettings, summary="Detection, identity and aiming settings")
def get_config(ctx: CtxDep, _p: Viewer) -> dict[str, Any]:
    return ctx.runtime.tuning.as_dict()


@router.patch("/config", response_model=TrackerSettings, responses={422: {"model": Message}},
              summary="Change some settings; applied from the next frame, kept across restarts")
def patch_config(body: TrackerSettingsPatch, ctx: CtxDep, p: Admin, db: DbDep, addr: Address) -> dict[str, Any]:
    return control.patch_tuning(db, ctx.runtime, p.user, addr, body)
