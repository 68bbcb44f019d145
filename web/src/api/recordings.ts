// The recording, playback, evidence and export calls (types from the OpenAPI document).
import { request } from "./client";
import type { components } from "./schema";

type S = components["schemas"];
export type Segment = S["SegmentOut"];
export type Bookmark = S["BookmarkOut"];
export type Lock = S["LockOut"];
export type ExportJob = S["ExportOut"];
export type Camera = "left" | "right";
/** One recorded frame's telemetry (the live message: frame, captured_at, detections, servo, ...). */
export interface FrameTelemetry {
  frame: number;
  captured_at: number;
  detections?: { track_id: number; r: number; theta_deg: number; phi_deg: number }[];
  servo?: { mode: string; pan_deg: number; tilt_deg: number } | null;
  r?: number | null;
  theta_deg?: number | null;
  phi_deg?: number | null;
  track_id?: number | null;
}

/** A decoded frame from /api/playback/frame: the JPEG (object URL) and its headers. */
export interface PlaybackFrame {
  url: string;
  frame: number;
  capturedAt: number;
}

const get = <T>(path: string, query?: Record<string, string | number | undefined>) =>
  request<T>("GET", path, { query });

export const rec = {
  segments: (camera: Camera, start: number, end: number) =>
    get<Segment[]>("/api/recordings", { camera, start, end, limit: 100000 }),
  telemetry: (start: number, end: number) => get<FrameTelemetry[]>("/api/telemetry", { start, end }),
  playlistUrl: (camera: Camera, start: number, end: number) =>
    `/api/playback/${camera}.m3u8?start=${start.toFixed(3)}&end=${end.toFixed(3)}`,
  bookmarks: (start: number, end: number) => get<Bookmark[]>("/api/bookmarks", { start, end }),
  addBookmark: (t: number, note: string) => request<Bookmark>("POST", "/api/bookmarks", { body: { t, note } }),
  locks: (start: number, end: number) => get<Lock[]>("/api/locks", { start, end }),
  addLock: (start: number, end: number, note: string) =>
    request<Lock>("POST", "/api/locks", { body: { start, end, note } }),
  unlock: (id: number) => request<void>("DELETE", `/api/locks/${id}`),
  exportRange: (start: number, end: number) =>
    request<ExportJob>("POST", "/api/exports", { body: { start, end, cameras: ["left", "right"] } }),
  exportJob: (id: number) => get<ExportJob>(`/api/exports/${id}`),
  exportUrl: (id: number) => `/api/exports/${id}/download`,
  tracks: (start: number, end: number) =>
    get<{ id: number; first_seen: number; last_seen: number }[]>("/api/tracks", { start, end, limit: 2000 }),
};

/** The exact frame of `camera` captured last at or before t (Unix s). */
export async function playbackFrame(camera: Camera, t: number, signal?: AbortSignal): Promise<PlaybackFrame> {
  const res = await fetch(`/api/playback/frame?camera=${camera}&t=${t.toFixed(6)}`,
    { credentials: "same-origin", signal });
  if (!res.ok) {
    let detail = `${res.status}`;
    try {
      detail = ((await res.json()) as { detail: string }).detail;
    } catch { /* not JSON */ }
    throw new Error(detail);
  }
  const blob = await res.blob();
  return { url: URL.createObjectURL(blob), frame: Number(res.headers.get("X-Frame-Index")),
    capturedAt: Number(res.headers.get("X-Captured-At")) };
}
