"""Alarm rules (admin), alarms and their history (viewer), acknowledge and shelve (operator)."""

from __future__ import annotations

from typing import Annotated, Any

from fastapi import APIRouter, Query

from server.alarm_schemas import (
    AckRequest,
    AlarmDetail,
    AlarmOut,
    AlarmRuleIn,
    AlarmRuleOut,
    AlarmRulePatch,
    AlarmSummary,
    ShelveRequest,
)
from server.deps import Address, Admin, CtxDep, DbDep, Operator, RowId, Viewer
from server.schemas import Message
from server.services import alarm_store as store
from server.services.errors import Invalid

router = APIRouter(prefix="/api", tags=["alarms"])
E404: dict[int | str, dict[str, Any]] = {404: {"model": Message}}
EACT: dict[int | str, dict[str, Any]] = {404: {"model": Message}, 409: {"model": Message}, 422: {"model": Message}}


@router.get("/alarm-rules", response_model=list[AlarmRuleOut],
            summary="Alarm rules, the built-in device fault rules with them, and the state of each one's alarm")
def list_rules(ctx: CtxDep, _p: Viewer, db: DbDep) -> list[dict[str, Any]]:
    return [ctx.alarms.rule_out(r) for r in store.list_rules(db)]


@router.post("/alarm-rules", response_model=AlarmRuleOut, status_code=201, responses={422: {"model": Message}},
             summary="Create a rule (zone, range_below, approach, size or lost)")
def create_rule(body: AlarmRuleIn, ctx: CtxDep, p: Admin, db: DbDep, addr: Address) -> dict[str, Any]:
    return ctx.alarms.create_rule(db, p.user, addr, body.model_dump(exclude_none=True))


@router.patch("/alarm-rules/{rule_id}", response_model=AlarmRuleOut, responses=EACT,
              summary="Change a rule; out_of_service takes it out of service or back")
def patch_rule(rule_id: RowId, body: AlarmRulePatch, ctx: CtxDep, p: Admin, db: DbDep, addr: Address) -> dict[str, Any]:
    return ctx.alarms.update_rule(db, p.user, addr, rule_id, body.model_dump(exclude_none=True))


@router.delete("/alarm-rules/{rule_id}", status_code=204, responses=E404 | {409: {"model": Message}},
               summary="Delete a rule (not a built-in one)")
def delete_rule(rule_id: RowId, ctx: CtxDep, p: Admin, db: DbDep, addr: Address) -> None:
    ctx.alarms.delete_rule(db, p.user, addr, rule_id)


@router.get("/alarms", response_model=list[AlarmOut], responses={422: {"model": Message}},
            summary="Alarms by priority then time, newest first")
def list_alarms(_p: Viewer, db: DbDep,
                state: Annotated[str | None, Query(description="comma-separated states, or open (unack, ack, "
                                                   "rtn_unack, shelved)")] = None,
                since: Annotated[float | None, Query(description="changed at or after (Unix s)")] = None,
                limit: Annotated[int, Query(ge=1, le=1000)] = 200) -> list[dict[str, Any]]:
    states = [s.strip() for s in state.split(",") if s.strip()] if state else []
    return [store.alarm_json(a) for a in store.list_alarms(db, states, since, limit)]


@router.get("/alarms/summary", response_model=AlarmSummary, summary="Open alarms per priority, flood state")
def summary(ctx: CtxDep, p: Viewer) -> dict[str, Any]:
    return ctx.alarms.summary(p.user.username)


@router.get("/alarms/{alarm_id}", response_model=AlarmDetail, responses=E404, summary="An alarm with its history")
def get_alarm(alarm_id: RowId, ctx: CtxDep, _p: Viewer, db: DbDep) -> dict[str, Any]:
    return store.detail(db, alarm_id, ctx.settings.alarm_preroll_s)


@router.post("/alarms/{alarm_id}/ack", response_model=AlarmOut, responses=EACT, summary="Acknowledge, with a comment")
def ack(alarm_id: RowId, body: AckRequest, ctx: CtxDep, p: Operator, db: DbDep, addr: Address) -> dict[str, Any]:
    return ctx.alarms.ack(db, p.user, addr, alarm_id, body.comment)


@router.post("/alarms/{alarm_id}/shelve", response_model=AlarmOut, responses=EACT,
             summary="Shelve for some minutes (at most 8 h by default) or one-shot (until it clears), with a reason")
def shelve(alarm_id: RowId, body: ShelveRequest, ctx: CtxDep, p: Operator, db: DbDep, addr: Address) -> dict[str, Any]:
    if body.one_shot == (body.minutes is not None):
        raise Invalid("give minutes (timed shelving) or one_shot true, one of the two")
    if body.minutes is not None and body.minutes * 60.0 > ctx.settings.alarm_max_shelve_h * 3600.0:
        raise Invalid(f"minutes: at most {ctx.settings.alarm_max_shelve_h * 60:g} (the longest shelving)")
    return ctx.alarms.shelve(db, p.user, addr, alarm_id, body.minutes, body.reason, body.one_shot)


@router.post("/alarms/{alarm_id}/unshelve", response_model=AlarmOut, responses=EACT, summary="End the shelving")
def unshelve(alarm_id: RowId, ctx: CtxDep, p: Operator, db: DbDep, addr: Address) -> dict[str, Any]:
    return ctx.alarms.unshelve(db, p.user, addr, alarm_id)
