// Types of the API's requests and answers, taken from the OpenAPI document (schema.d.ts is generated from
// web/openapi.json by `npm run gen:api`; refresh openapi.json from a running server's /api/openapi.json).
import type { components } from "./schema";

type S = components["schemas"];

export type Role = S["UserOut"]["role"];
export type LoginAnswer = S["LoginAnswer"];
export type Status = S["Status"];
export type ServoStatus = S["ServoStatus"];
export type ServoMode = NonNullable<S["ModeRequest"]["mode"]>;
export type Telemetry = S["Telemetry"];
export type Detection = S["Detection"];
export type GotoRequest = S["GotoRequest"];
export type JogRequest = S["JogRequest"];
export type Preset = S["Preset"];
export type PresetIn = S["PresetIn"];
export type TrackOut = S["TrackOut"];
export type TrackDetail = S["TrackDetail"];
export type TrackPoint = S["TrackPointOut"];
export type TrackerSettings = S["TrackerSettings"];
export type TrackerSettingsPatch = S["TrackerSettingsPatch"];
export type CalibrationOut = S["CalibrationOut"];
export type UserOut = S["UserOut"];
export type UserIn = S["UserIn"];
export type UserPatch = S["UserPatch"];
export type AuditOut = S["AuditOut"];
export type Health = S["Health"];
export type AlarmOut = S["AlarmOut"];
export type AlarmDetail = S["AlarmDetail"];
export type AlarmEvent = S["AlarmEventOut"];
export type AlarmRuleOut = S["AlarmRuleOut"];
export type AlarmRuleIn = S["AlarmRuleIn"];
export type AlarmRulePatch = S["AlarmRulePatch"];
export type AlarmSummary = S["AlarmSummary"];
export type Priority = AlarmOut["priority"];

/** `/ws/events` messages. */
export interface ServerEvent {
  type: string;
  at: number;
  id?: number;
  message?: string | null;
  [k: string]: unknown;
}

export type WebRtcConfig = S["WebRTCConfig"];
export type SessionDescription = S["SessionDescription"];
export type PointRequest = S["PointRequest"];
