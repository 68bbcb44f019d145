// The HTTP client: same-origin fetch with the session cookie; every unsafe request carries the CSRF
// header (the readable tmeye_csrf cookie, or the csrf_token of the login answer). Errors become ApiError
// with the server's one-line `detail`; a 401 also tells the app that the session is gone.
import type {
  AlarmDetail, AlarmOut, AlarmRuleIn, AlarmRuleOut, AlarmRulePatch, AlarmSummary, AuditOut, CalibrationOut, GotoRequest, Health, JogRequest, LoginAnswer, PointRequest, Preset, PresetIn,
  ServoMode, ServoStatus, SessionDescription, Status, Telemetry, TrackDetail, TrackOut, TrackerSettings,
  TrackerSettingsPatch, UserIn, UserOut, UserPatch, WebRtcConfig,
} from "./types";

export class ApiError extends Error {
  constructor(readonly status: number, readonly detail: string, readonly retryAfter?: number) {
    super(detail);
  }
  /** Network failure (server down or restarting) rather than an answer. */
  get offline(): boolean {
    return this.status === 0;
  }
}

/** What went wrong, in one line: an API error's detail, else the error's message. */
export function errorText(e: unknown): string {
  return e instanceof ApiError ? e.detail : e instanceof Error ? e.message : String(e);
}

const UNSAFE = new Set(["POST", "PUT", "PATCH", "DELETE"]);
let csrfFromLogin: string | null = sessionStorage.getItem("tmeye.csrf");

export function readCookie(name: string): string | null {
  for (const part of document.cookie.split(";")) {
    const [k, ...v] = part.trim().split("=");
    if (k === name) return decodeURIComponent(v.join("="));
  }
  return null;
}

export function csrfToken(): string | null {
  return readCookie("tmeye_csrf") ?? csrfFromLogin;
}

export function setCsrfToken(token: string | null): void {
  csrfFromLogin = token;
  if (token) sessionStorage.setItem("tmeye.csrf", token);
  else sessionStorage.removeItem("tmeye.csrf");
}

type Listener = (err: ApiError) => void;
const unauthorizedListeners = new Set<Listener>();
export function onUnauthorized(fn: Listener): () => void {
  unauthorizedListeners.add(fn);
  return () => unauthorizedListeners.delete(fn);
}

export interface RequestOptions {
  body?: unknown;
  form?: FormData | URLSearchParams;
  query?: Record<string, string | number | undefined | null>;
  signal?: AbortSignal;
  /** Do not announce a 401 (the login form and probes handle it themselves). */
  quiet401?: boolean;
  timeoutMs?: number;
}

export async function request<T>(method: string, path: string, opts: RequestOptions = {}): Promise<T> {
  const headers: Record<string, string> = { Accept: "application/json" };
  let body: BodyInit | undefined;
  if (opts.form) body = opts.form;
  else if (opts.body !== undefined) {
    body = JSON.stringify(opts.body);
    headers["Content-Type"] = "application/json";
  }
  if (UNSAFE.has(method)) {
    const t = csrfToken();
    if (t) headers["X-CSRF-Token"] = t;
  }
  let url = path;
  if (opts.query) {
    const q = new URLSearchParams();
    for (const [k, v] of Object.entries(opts.query)) if (v !== undefined && v !== null && v !== "") q.set(k, String(v));
    const s = q.toString();
    if (s) url += `?${s}`;
  }
  const ctrl = new AbortController();
  const timer = setTimeout(() => ctrl.abort(), opts.timeoutMs ?? 20000);
  opts.signal?.addEventListener("abort", () => ctrl.abort());
  let res: Response;
  try {
    res = await fetch(url, { method, headers, body, credentials: "same-origin", signal: ctrl.signal });
  } catch (e) {
    throw new ApiError(0, opts.signal?.aborted ? "cancelled" : "the server cannot be reached");
  } finally {
    clearTimeout(timer);
  }
  if (res.status === 204) return undefined as T;
  const text = await res.text();
  let data: unknown = undefined;
  if (text) {
    try {
      data = JSON.parse(text);
    } catch {
      data = text;
    }
  }
  if (!res.ok) {
    const detail =
      data && typeof data === "object" && "detail" in data
        ? typeof (data as { detail: unknown }).detail === "string"
          ? (data as { detail: string }).detail
          : JSON.stringify((data as { detail: unknown }).detail)
        : `${res.status} ${res.statusText}`;
    const ra = Number(res.headers.get("Retry-After"));
    const err = new ApiError(res.status, detail, Number.isFinite(ra) && ra > 0 ? ra : undefined);
    if (res.status === 401 && !opts.quiet401) unauthorizedListeners.forEach((fn) => fn(err));
    throw err;
  }
  return data as T;
}

const get = <T>(path: string, opts?: RequestOptions) => request<T>("GET", path, opts);
const post = <T>(path: string, body?: unknown, opts?: RequestOptions) => request<T>("POST", path, { ...opts, body });

/** Every call the console makes, typed by the OpenAPI schemas. */
export const api = {
  health: () => get<Health>("/api/health", { quiet401: true, timeoutMs: 4000 }),
  login: (username: string, password: string) =>
    request<LoginAnswer>("POST", "/api/auth/login", {
      form: new URLSearchParams({ username, password }),
      quiet401: true,
    }),
  logout: () => request<void>("POST", "/api/auth/logout", { quiet401: true }),
  me: () => get<{ username: string; role: string }>("/api/auth/me", { quiet401: true }),
  status: () => get<Status>("/api/status", { timeoutMs: 5000 }),
  telemetryLatest: () => get<Telemetry>("/api/telemetry/latest"),

  servo: () => get<ServoStatus>("/api/servo"),
  setMode: (mode: ServoMode) => request<ServoStatus>("PUT", "/api/servo/mode", { body: { mode } }),
  goto: (b: GotoRequest) => post<ServoStatus>("/api/servo/goto", b),
  jog: (b: JogRequest) => post<ServoStatus>("/api/servo/jog", b, { timeoutMs: 3000 }),
  point: (b: PointRequest) => post<ServoStatus>("/api/servo/point", b),
  presets: () => get<Preset[]>("/api/servo/presets"),
  createPreset: (b: PresetIn) => post<Preset>("/api/servo/presets", b),
  gotoPreset: (id: number) => post<ServoStatus>(`/api/servo/presets/${id}/goto`),
  deletePreset: (id: number) => request<void>("DELETE", `/api/servo/presets/${id}`),

  makePrimary: (trackId: number) => post<void>(`/api/tracks/${trackId}/primary`),
  tracks: (start?: number, end?: number, limit?: number) =>
    get<TrackOut[]>("/api/tracks", { query: { start, end, limit } }),
  track: (id: number) => get<TrackDetail>(`/api/tracks/${id}`),

  trackerConfig: () => get<TrackerSettings>("/api/tracker/config"),
  patchTrackerConfig: (p: TrackerSettingsPatch) =>
    request<TrackerSettings>("PATCH", "/api/tracker/config", { body: p }),

  calibrations: () => get<CalibrationOut[]>("/api/calibrations"),
  calibration: (id: number) => get<CalibrationOut>(`/api/calibrations/${id}`),
  uploadCalibration: (form: FormData) =>
    request<CalibrationOut>("POST", "/api/calibrations", { form, timeoutMs: 300000 }),
  activateCalibration: (id: number) => post<CalibrationOut>(`/api/calibrations/${id}/activate`),
  rigUrl: (id: number) => `/api/calibrations/${id}/rig`,

  users: () => get<UserOut[]>("/api/users"),
  createUser: (b: UserIn) => post<UserOut>("/api/users", b),
  patchUser: (id: number, b: UserPatch) => request<UserOut>("PATCH", `/api/users/${id}`, { body: b }),
  deleteUser: (id: number) => request<void>("DELETE", `/api/users/${id}`),
  audit: (q: { start?: number; end?: number; action?: string; limit?: number }) =>
    get<AuditOut[]>("/api/audit", { query: q }),

  alarms: (state?: string, since?: number, limit?: number) =>
    get<AlarmOut[]>("/api/alarms", { query: { state, since, limit } }),
  alarm: (id: number) => get<AlarmDetail>(`/api/alarms/${id}`),
  alarmSummary: () => get<AlarmSummary>("/api/alarms/summary"),
  ackAlarm: (id: number, comment: string | null) => post<AlarmOut>(`/api/alarms/${id}/ack`, { comment }),
  shelveAlarm: (id: number, minutes: number, reason: string) =>
    post<AlarmOut>(`/api/alarms/${id}/shelve`, { minutes, reason }),
  /** One-shot shelving: until the (active) alarm next clears. */
  shelveAlarmOneShot: (id: number, reason: string) =>
    post<AlarmOut>(`/api/alarms/${id}/shelve`, { one_shot: true, reason }),
  unshelveAlarm: (id: number) => post<AlarmOut>(`/api/alarms/${id}/unshelve`),
  alarmRules: () => get<AlarmRuleOut[]>("/api/alarm-rules"),
  createAlarmRule: (b: AlarmRuleIn) => post<AlarmRuleOut>("/api/alarm-rules", b),
  patchAlarmRule: (id: number, b: AlarmRulePatch) =>
    request<AlarmRuleOut>("PATCH", `/api/alarm-rules/${id}`, { body: b }),
  deleteAlarmRule: (id: number) => request<void>("DELETE", `/api/alarm-rules/${id}`),

  webrtcConfig: () => get<WebRtcConfig>("/api/webrtc/config", { timeoutMs: 5000 }),
  webrtcOffer: (offer: SessionDescription) =>
    post<SessionDescription>("/api/webrtc/offer", offer, { timeoutMs: 15000 }),
};
