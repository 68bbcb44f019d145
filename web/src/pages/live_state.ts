// What the Live page's parts share (live.ts composes them): the session's right to drive the mount, the
// source's size and field of view, the aim's dead band, the mount's last state, the telemetry buffer, and
// the debug record tests read as window.__tmeye.
import type { ServoStatus } from "../api/types";
import { atLeast, roleReason, type Session } from "../lib/session";
import { TelemetryBuffer } from "../lib/telemetry";

export type Camera = "left" | "right";
export type Source = "webrtc" | "mjpeg" | "none";

/** What tests and the curious can read: window.__tmeye. */
export interface Debug {
  source: Source;
  frames: Record<Camera, number>;
  sync: Record<Camera, { rtp: number; frame: number | null; offsetTicks: number | null; matched: string } | null>;
  telemetryMessages: number;
  socketOpens: number;
  lastError: string | null;
  servo: ServoStatus | null;
  /** the detections drawn over the left picture now, and the picture's size in source pixels */
  shown: { track_id: number; box: number[] }[];
  primary: number | null;
  size: [number, number];
  /** with window.__tmeyeVerifyStamps (tests, server --stamp-frames): the frame index stamped in the left
   * picture on screen and the frame of the telemetry drawn over it */
  stamps: { camera: Camera; stamp: number; frame: number | null; offsetTicks: number | null }[];
}

export interface LiveState {
  readonly canDrive: boolean;
  /** why this session may not drive the mount ("" when it may) */
  readonly driveReason: string;
  readonly buffer: TelemetryBuffer;
  readonly debug: Debug;
  /** the source's image size (px) */
  srcW: number;
  srcH: number;
  /** the left camera's field of view (degrees) from the rig in use; null until the status gives it */
  fovDeg: [number, number] | null;
  /** the aim's dead band, a fraction of the image width (the overlay draws it) */
  deadbandFrac: number;
  servo: ServoStatus | null;
  disposed: boolean;
}

export function liveState(session: Session): LiveState {
  const canDrive = atLeast(session, "operator");
  const debug: Debug = { source: "none", frames: { left: 0, right: 0 }, sync: { left: null, right: null },
    telemetryMessages: 0, socketOpens: 0, lastError: null, servo: null, stamps: [],
    shown: [], primary: null, size: [640, 480] };
  (window as unknown as { __tmeye: Debug }).__tmeye = debug;
  return { canDrive, driveReason: canDrive ? "" : roleReason(session, "operator", "Driving the mount"),
    buffer: new TelemetryBuffer(3, 1500), debug, srcW: 640, srcH: 480, fovDeg: null, deadbandFrac: 0.02,
    servo: null, disposed: false };
}
