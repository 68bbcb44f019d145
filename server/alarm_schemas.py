"""Pydantic models of the alarm API (rules, alarms, their history, operator actions). Lengths in metres,
speeds in m/s, times in Unix seconds, delays and durations in seconds unless named otherwise."""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import BaseModel, ConfigDict, Field, JsonValue

from server.schema_base import Strict

Priority = Literal["critical", "high", "medium", "low"]
AlarmState = Literal["unack", "ack", "rtn_unack", "shelved", "suppressed", "out_of_service", "normal"]


class ZoneCondition(Strict):
    """A target inside a box (x, y, z min and max) or a vertical cylinder (centre_x, centre_z, radius,
    optional y_min / y_max), in the telemetry's frame (x right, y down, z forward, m); dwell_s: how long
    it must stay inside."""

    model_config = ConfigDict(json_schema_extra={"examples": [
        {"kind": "zone", "shape": "box", "x_min": -2.0, "x_max": 2.0, "z_min": 5.0, "z_max": 12.0, "dwell_s": 2.0},
        {"kind": "zone", "shape": "cylinder", "center_x": 0.0, "center_z": 10.0, "radius": 3.0}]})

    kind: Literal["zone"]
    shape: Literal["box", "cylinder"] = "box"
    x_min: float | None = None
    x_max: float | None = None
    y_min: float | None = None
    y_max: float | None = None
    z_min: float | None = None
    z_max: float | None = None
    center_x: float | None = None
    center_z: float | None = None
    radius: float | None = Field(None, gt=0)
    dwell_s: float = Field(0.0, ge=0, le=3600)


class RangeBelowCondition(Strict):
    model_config = ConfigDict(json_schema_extra={"examples": [
        {"kind": "range_below", "distance_m": 8.0}]})

    kind: Literal["range_below"]
    distance_m: float = Field(gt=0, le=1000)


class ApproachCondition(Strict):
    """Closing speed −dr/dt of the primary target (from the predictor) above speed_mps for for_s; it stays
    true until the speed falls under speed_mps − deadband_mps (ISA-18.2 deadband, against chattering)."""

    model_config = ConfigDict(json_schema_extra={"examples": [
        {"kind": "approach", "speed_mps": 1.5, "for_s": 1.0, "deadband_mps": 0.3}]})

    kind: Literal["approach"]
    speed_mps: float = Field(gt=0, le=100)
    for_s: float = Field(0.0, ge=0, le=600)
    deadband_mps: float = Field(0.3, ge=0, le=100)


class SizeCondition(Strict):
    """A target whose metric width and height (m, from its disparity) lie inside the bounds."""

    model_config = ConfigDict(json_schema_extra={"examples": [
        {"kind": "size", "width_min": 1.5, "height_max": 2.5}]})

    kind: Literal["size"]
    width_min: float = Field(0.0, ge=0)
    width_max: float | None = Field(None, gt=0)
    height_min: float = Field(0.0, ge=0)
    height_max: float | None = Field(None, gt=0)


class LostCondition(Strict):
    """The primary target not seen for longer than after_s. Suppressed by design while the mount is not in
    auto mode (manual, hold or home: the operator points it)."""

    model_config = ConfigDict(json_schema_extra={"examples": [
        {"kind": "lost", "after_s": 5.0}]})

    kind: Literal["lost"]
    after_s: float = Field(gt=0, le=3600)


Condition = Annotated[ZoneCondition | RangeBelowCondition | ApproachCondition | SizeCondition | LostCondition,
                      Field(discriminator="kind")]


class AlarmRuleIn(Strict):
    model_config = ConfigDict(extra="forbid", json_schema_extra={"examples": [
        {"name": "Gate zone", "priority": "critical", "on_delay_s": 0, "off_delay_s": 2,
         "condition": {"kind": "zone", "shape": "box", "x_min": -3, "x_max": 3, "z_min": 8, "z_max": 14}}]})

    name: str = Field(min_length=1, max_length=128)
    priority: Priority
    condition: Condition
    on_delay_s: float = Field(0.0, ge=0, le=3600)
    off_delay_s: float = Field(0.0, ge=0, le=3600)
    enabled: bool = True
    out_of_service: bool = False


class AlarmRulePatch(Strict):
    model_config = ConfigDict(json_schema_extra={"examples": [
        {"priority": "high", "on_delay_s": 1.0}, {"enabled": False}]})

    name: str | None = Field(None, min_length=1, max_length=128)
    priority: Priority | None = None
    condition: Condition | None = None
    on_delay_s: float | None = Field(None, ge=0, le=3600)
    off_delay_s: float | None = Field(None, ge=0, le=3600)
    enabled: bool | None = None
    out_of_service: bool | None = Field(None, description="take the rule out of service (true) or back (false)")


class AlarmRuleOut(BaseModel):
    model_config = ConfigDict(json_schema_extra={"examples": [
        {"id": 1, "name": "Gate zone", "priority": "critical", "condition": {"kind": "zone", "shape": "box",
         "x_min": -2.0, "x_max": 2.0, "z_min": 5.0, "z_max": 12.0, "dwell_s": 2.0}, "on_delay_s": 0.5,
         "off_delay_s": 2.0, "enabled": True, "out_of_service": False, "created_at": 1795000000.1,
         "updated_at": 1795000000.1, "built_in": False, "state": "normal"}]})

    id: int
    name: str
    priority: Priority
    condition: dict[str, Any]
    on_delay_s: float
    off_delay_s: float
    enabled: bool
    out_of_service: bool
    created_at: float
    updated_at: float
    built_in: bool = Field(description="a built-in device fault rule: read-only but for out_of_service, not deletable")
    state: AlarmState | None = Field(description="the state of the rule's alarm now (suppressed: by design)")


class AlarmOut(BaseModel):
    model_config = ConfigDict(json_schema_extra={"examples": [
        {"id": 7, "rule_id": 1, "rule_key": "rule:1", "name": "Gate zone", "priority": "critical",
         "state": "unack", "activated_at": 1795000000.1, "cleared_at": None, "acked_at": None, "acked_by": None,
         "updated_at": 1795000000.1, "frame": 1234, "target_id": 3, "run_id": "20261122T220000-123.0",
         "message": None, "shelved_until": None, "shelve_reason": None, "shelved_one_shot": False}]})

    id: int
    rule_id: int | None
    rule_key: str = Field(description="rule:<id> for a stored rule, fault:<source> for a device fault")
    name: str
    priority: Priority
    state: AlarmState
    activated_at: float
    cleared_at: float | None
    acked_at: float | None
    acked_by: str | None
    updated_at: float
    frame: int | None = Field(description="the frame that triggered it")
    target_id: int | None = Field(description="the track number (of run_id) that triggered it")
    run_id: str | None
    message: str | None
    shelved_until: float | None = Field(description="when the shelving ends (one-shot: at the latest)")
    shelve_reason: str | None
    shelved_one_shot: bool = Field(description="shelved until the alarm next clears (OPC UA one-shot shelving)")


_EVENT_EXAMPLE: dict[str, JsonValue] = {
    "id": 31, "at": 1795000000.1, "kind": "activated", "state_from": "normal", "state_to": "unack", "username": None,
    "comment": None, "frame": 1234, "target_id": 3, "message": None}


class AlarmEventOut(BaseModel):
    model_config = ConfigDict(json_schema_extra={"examples": [_EVENT_EXAMPLE]})

    id: int
    at: float
    kind: str = Field(description="activated, cleared, acknowledged, shelved, unshelved, suppressed, "
                                  "out_of_service, removed")
    state_from: str | None
    state_to: str | None
    username: str | None = Field(description="who did it; null for the engine")
    comment: str | None
    frame: int | None
    target_id: int | None
    message: str | None


class AlarmDetail(AlarmOut):
    model_config = ConfigDict(json_schema_extra={"examples": [
        {"id": 7, "rule_id": 1, "rule_key": "rule:1", "name": "Gate zone", "priority": "critical", "state": "unack",
         "activated_at": 1795000000.1, "cleared_at": None, "acked_at": None, "acked_by": None,
         "updated_at": 1795000000.1, "frame": 1234, "target_id": 3, "run_id": "20261122T220000-123.0",
         "message": None, "shelved_until": None, "shelve_reason": None, "shelved_one_shot": False,
         "history": [_EVENT_EXAMPLE], "track_id": 12, "playback_url": "#/playback?t=1794999990.100&alarm=7"}]})

    history: list[AlarmEventOut]
    track_id: int | None = Field(description="id of the triggering track in /api/tracks, once written")
    playback_url: str = Field(description="the console's playback at the alarm, pre-roll included")


class AckRequest(Strict):
    model_config = ConfigDict(json_schema_extra={"examples": [
        {"comment": "gardener, expected"}]})

    comment: str | None = Field(None, max_length=1000)


class ShelveRequest(Strict):
    model_config = ConfigDict(json_schema_extra={"examples": [
        {"minutes": 30, "reason": "maintenance at the gate"}, {"one_shot": True, "reason": "known visitor"}]})

    minutes: float | None = Field(None, gt=0, description="timed shelving: how long; at most the server's limit "
                                  "(8 h by default)")
    reason: str = Field(min_length=1, max_length=500)
    one_shot: bool = Field(False, description="instead of minutes: shelved until the alarm next clears (an active "
                           "alarm), at most the server's limit")


class AlarmSummary(BaseModel):
    model_config = ConfigDict(json_schema_extra={"examples": [
        {"open": {"critical": 1, "high": 0, "medium": 2, "low": 0}, "unacknowledged": {"critical": 1, "high": 0,
         "medium": 1, "low": 0}, "flood": False, "new_in_window": 3, "window_s": 600.0, "flooded_operators": []}]})

    open: dict[str, int] = Field(description="alarms in the list (unack, ack, rtn_unack) per priority")
    unacknowledged: dict[str, int]
    flood: bool = Field(description="the caller's flood: more than 10 new alarms in 10 minutes since they logged in "
                        "(ends below 5)")
    new_in_window: int = Field(description="new alarms in the window since the caller logged in")
    window_s: float
    flooded_operators: list[str] = Field(description="the logged-in operators in flood")
