"""Servo control: state, mode, go-to, jog, presets. Viewers may look; operators drive."""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter

from server.deps import Address, CtxDep, DbDep, Operator, RowId, Viewer
from server.schemas import GotoRequest, JogRequest, Message, ModeRequest, PointRequest, Preset, PresetIn, ServoStatus
from server.services import control

router = APIRouter(prefix="/api/servo", tags=["servo"])
ERRORS: dict[int | str, dict[str, Any]] = {409: {"model": Message, "description": "no servo configured"},
                                           422: {"model": Message}, 503: {"model": Message}}


@router.get("", response_model=ServoStatus, summary="Mode, angles (deg), goal and fault of the mount")
def get_servo(ctx: CtxDep, _p: Viewer) -> dict[str, Any]:
    return control.servo_state(ctx.runtime)


@router.put("/mode", response_model=ServoStatus, responses=ERRORS, summary="auto, manual, hold or home")
def put_mode(body: ModeRequest, ctx: CtxDep, p: Operator, db: DbDep, addr: Address) -> dict[str, Any]:
    return control.set_mode(db, ctx.runtime, p.user, addr, body.mode)


@router.post("/goto", response_model=ServoStatus, responses=ERRORS, summary="Go to angles (switches to manual)")
def goto(body: GotoRequest, ctx: CtxDep, p: Operator, db: DbDep, addr: Address) -> dict[str, Any]:
    return control.goto(db, ctx.runtime, p.user, addr, body.pan_deg, body.tilt_deg)


@router.post("/jog", response_model=ServoStatus, responses=ERRORS, summary="Move at a rate for a while (manual)")
def jog(body: JogRequest, ctx: CtxDep, p: Operator, db: DbDep, addr: Address) -> dict[str, Any]:
    return control.jog(db, ctx.runtime, p.user, addr, body.pan_dps, body.tilt_dps, body.duration_s)


@router.post("/point", response_model=ServoStatus, responses=ERRORS,
             summary="Bring what is seen at a pixel to the image centre (through the calibrated camera; manual)")
def point(body: PointRequest, ctx: CtxDep, p: Operator, db: DbDep, addr: Address) -> dict[str, Any]:
    return control.point(db, ctx.runtime, p.user, addr, body.camera, body.u, body.v)


@router.get("/presets", response_model=list[Preset], summary="Named positions")
def list_presets(_p: Viewer, db: DbDep) -> list[Any]:
    return control.list_presets(db)


@router.post("/presets", response_model=Preset, status_code=201, responses=ERRORS, summary="Store a position")
def create_preset(body: PresetIn, ctx: CtxDep, p: Operator, db: DbDep, addr: Address) -> Any:
    return control.create_preset(db, ctx.runtime, p.user, addr, body.name, body.pan_deg, body.tilt_deg)


@router.post("/presets/{preset_id}/goto", response_model=ServoStatus, responses={404: {"model": Message}, **ERRORS},
             summary="Go to a preset (switches to manual)")
def goto_preset(preset_id: RowId, ctx: CtxDep, p: Operator, db: DbDep, addr: Address) -> dict[str, Any]:
    pr = control.get_preset(db, preset_id)
    return control.goto(db, ctx.runtime, p.user, addr, pr.pan_deg, pr.tilt_deg, "preset.goto", pr.name)


@router.delete("/presets/{preset_id}", status_code=204, responses={404: {"model": Message}}, summary="Delete a preset")
def delete_preset(preset_id: RowId, p: Operator, db: DbDep, addr: Address) -> None:
    control.delete_preset(db, p.user, addr, preset_id)
