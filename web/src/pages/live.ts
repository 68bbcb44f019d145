// The Live page: both cameras with the overlay of the frame on screen (telemetry matched by RTP
// timestamp), readouts of the primary target, plan and side views of the last minute's tracks with the
// cameras' field of view, and the mount's controls (mode, jog by keys / pad / gamepad, go-to, click to
// point, click a detection to make it primary, presets).
import { api, ApiError } from "../api/client";
import type { Preset, ServoMode, ServoStatus, Status, Telemetry } from "../api/types";
import { field, h, notice } from "../lib/dom";
import { num } from "../lib/format";
import { JogController, type Vec } from "../lib/jog";
import { MetricView, type Wedge, type XY } from "../lib/plots";
import { atLeast, roleReason } from "../lib/session";
import { ReconnectingSocket, type SocketState } from "../lib/socket";
import { zoneOutlines } from "../lib/zones";
import { motionOf, TelemetryBuffer, type Match } from "../lib/telemetry";
import { detectionAt, drawOverlay } from "../video/overlay";
import { mjpegAvailable, startWebRtc, VideoUnavailable, type RtcVideo } from "../video/webrtc";
import type { Page, PageContext } from "./types";

type Camera = "left" | "right";
type VideoMode = "auto" | "webrtc" | "mjpeg" | "off";
type Source = "webrtc" | "mjpeg" | "none";

interface CamView {
  camera: Camera;
  fig: HTMLElement;
  frame: HTMLElement;
  video: HTMLVideoElement;
  img: HTMLImageElement;
  /** the right camera's picture over WebRTC: each frame the video presents, painted (see PAINTED) */
  picture: HTMLCanvasElement | null;
  canvas: HTMLCanvasElement;
  state: HTMLElement;
  frames: number;
  shown: Telemetry | null;
  lastSync: string;
}

/** The cameras whose WebRTC video is shown by painting each presented frame into a canvas, the video
 * element itself kept invisible (opacity 0: decoded, presented and called back, not composited). Chromium
 * takes a page with more than one visible video layer for a video conference: unless the page draws faster
 * than 30 frames per second it halves the compositor's rate to 30 Hz (cc::FrameRateEstimator), and two
 * 30 fps streams whose frames arrive with some jitter then lose one frame in five or six (measured: 24 to 25
 * shown per second of 30 decoded, against 28 with one visible video layer). */
const PAINTED: ReadonlySet<Camera> = new Set<Camera>(["right"]);

/** What tests and the curious can read: window.__tmeye. */
interface Debug {
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

const STAMP_BITS = 16, STAMP_CELL = 8;
let stampCanvas: HTMLCanvasElement | null = null;

/** Paint the frame a video presents now into a canvas of the video's own size (CSS scales it like the video). */
function paint(picture: HTMLCanvasElement, video: HTMLVideoElement): void {
  const w = video.videoWidth, h = video.videoHeight;
  if (!w || !h) return;
  if (picture.width !== w || picture.height !== h) {
    picture.width = w;
    picture.height = h;
  }
  picture.getContext("2d", { alpha: false })?.drawImage(video, 0, 0, w, h);
}

/** The frame index the server's measurement mode (--stamp-frames) draws in the top-left corner: 16 cells of
 * 8x8 px, most significant bit first, white for 1. */
function readStamp(video: HTMLVideoElement | HTMLCanvasElement, srcW: number): number | null {
  const width = video instanceof HTMLVideoElement ? video.videoWidth : video.width;
  const scale = width > 0 ? width / srcW : 1;
  const w = STAMP_BITS * STAMP_CELL;
  stampCanvas ??= document.createElement("canvas");
  stampCanvas.width = w;
  stampCanvas.height = STAMP_CELL;
  const c = stampCanvas.getContext("2d", { willReadFrequently: true });
  if (!c) return null;
  c.drawImage(video, 0, 0, w * scale, STAMP_CELL * scale, 0, 0, w, STAMP_CELL);
  const px = c.getImageData(0, 0, w, STAMP_CELL).data;
  let v = 0;
  for (let k = 0; k < STAMP_BITS; k++) {
    const i = ((STAMP_CELL / 2) * w + k * STAMP_CELL + STAMP_CELL / 2) * 4;
    const grey = (px[i] + px[i + 1] + px[i + 2]) / 3;
    v = (v << 1) | (grey > 127 ? 1 : 0);
  }
  return v;
}

const HISTORY_S = 60;
const MODES: ServoMode[] = ["auto", "manual", "hold", "home"];
const MODE_HELP: Record<ServoMode, string> = {
  auto: "Auto: follow the primary target",
  manual: "Manual: stay at the operator's angles",
  hold: "Hold: stop where it is",
  home: "Home: go to the home position",
};

export function livePage(ctx: PageContext): Page {
  const { session, root, status } = ctx;
  const canDrive = atLeast(session, "operator");
  const driveReason = canDrive ? "" : roleReason(session, "operator", "Driving the mount");
  const buffer = new TelemetryBuffer(3, 1500);
  const debug: Debug = { source: "none", frames: { left: 0, right: 0 }, sync: { left: null, right: null },
    telemetryMessages: 0, socketOpens: 0, lastError: null, servo: null, stamps: [],
    shown: [], primary: null, size: [640, 480] };
  (window as unknown as { __tmeye: Debug }).__tmeye = debug;
  let srcW = 640, srcH = 480;
  let deadbandFrac = 0.02;
  let servo: ServoStatus | null = null;
  let disposed = false;
  const cleanups: (() => void)[] = [];

  // ---------------------------------------------------------------- cameras
  const makeCam = (camera: Camera, title: string): CamView => {
    const video = h("video", { muted: true, autoplay: true, playsInline: true, disablePictureInPicture: true,
      "aria-hidden": "true" });
    video.muted = true;
    const img = h("img", { alt: "", hidden: true });
    const picture = PAINTED.has(camera) ? h("canvas", { class: "picture", hidden: true, "aria-hidden": "true" }) : null;
    const canvas = h("canvas", { class: "overlay", "aria-hidden": "true" });
    const frame = h("div", {
      class: "cam-frame", role: "img",
      "aria-label": `${title}. ${canDrive ? (camera === "left"
        ? "Click to point the mount there; click a detection box to make it the primary target " +
          "(from the keyboard: Go to, and Make primary in the detections list)."
        : "Click to point the mount there (from the keyboard: Go to).") : ""}`,
    }, video, img, picture, canvas);
    const state = h("span", { class: "cam-state", "data-testid": `cam-${camera}-state` }, "connecting…");
    const fig = h("figure", { class: "cam", "data-camera": camera }, frame,
      h("figcaption", null, h("span", null, title), state));
    return { camera, fig, frame, video, img, picture, canvas, state, frames: 0, shown: null, lastSync: "" };
  };
  const cams: Record<Camera, CamView> = { left: makeCam("left", "Left camera"), right: makeCam("right", "Right camera") };

  const videoSelect = h("select", { name: "video" },
    h("option", { value: "auto" }, "Auto (WebRTC, else MJPEG)"), h("option", { value: "webrtc" }, "WebRTC"),
    h("option", { value: "mjpeg" }, "MJPEG"), h("option", { value: "off" }, "Off (overlay only)"));
  videoSelect.value = (localStorage.getItem("tmeye.video") as VideoMode | null) ?? "auto";
  const layoutSelect = h("select", { name: "layout" },
    h("option", { value: "side" }, "Side by side"), h("option", { value: "large" }, "Left large, right small"));
  layoutSelect.value = localStorage.getItem("tmeye.layout") ?? "side";
  const videos = h("div", { class: `videos layout-${layoutSelect.value}`, role: "group", "aria-label": "Cameras" },
    cams.left.fig, cams.right.fig);
  layoutSelect.addEventListener("change", () => {
    videos.className = `videos layout-${layoutSelect.value}`;
    localStorage.setItem("tmeye.layout", layoutSelect.value);
  });
  const videoNote = h("span", { class: "muted", "data-testid": "video-note" });
  const toolbar = h("div", { class: "toolbar" }, field("Video", videoSelect), field("Layout", layoutSelect), videoNote);

  // ---------------------------------------------------------------- readouts
  const ro = (label: string, key: string) => {
    const dd = h("dd", { "data-testid": `ro-${key}` }, "—");
    return { row: [h("dt", null, label), dd], dd };
  };
  const R = {
    frame: ro("Frame", "frame"), target: ro("Primary", "target"), r: ro("r", "r"), theta: ro("θ", "theta"),
    phi: ro("φ", "phi"), speed: ro("Speed", "speed"), heading: ro("Heading", "heading"), xyz: ro("x, y, z", "xyz"),
    servo: ro("Mount", "servo"),
  };
  const detList = h("ul", { class: "det-list", "aria-label": "Detections" });
  const readouts = h("section", { class: "panel readouts", "aria-labelledby": "ro-title" },
    h("h2", { id: "ro-title" }, "Target"),
    h("dl", null, ...Object.values(R).map((x) => x.row)),
    h("h3", null, "Detections"), detList);

  // ---------------------------------------------------------------- plots
  const planEl = h("div", { class: "plot-box" });
  const sideEl = h("div", { class: "plot-box" });
  const plots = h("div", { class: "plots" },
    h("section", { class: "panel plot", "aria-label": "Plan view of the last minute (metres)" }, planEl),
    h("section", { class: "panel plot", "aria-label": "Side view of the last minute (metres)" }, sideEl));
  const plan = new MetricView(planEl, { title: "Plan view (last minute)", xLabel: "x (m, right)",
    yLabel: "z (m, ahead)", minSpan: 6, include: [[0, 0], [0, 6]],
    series: [{ label: "primary", stroke: "#ffb020" }, { label: "other targets", stroke: "#4fd1ff", width: 1.5 },
      { label: "alarm zones", stroke: "#ff6b6b", width: 1.5 }] });
  let zones: XY = [[], []];
  const loadZones = () => api.alarmRules().then((r) => { zones = zoneOutlines(r); }, () => undefined);
  void loadZones();
  const zoneTimer = window.setInterval(() => void loadZones(), 5000);
  const side = new MetricView(sideEl, { title: "Side view (last minute)", xLabel: "ground range (m)",
    yLabel: "height (m, up)", minSpan: 3, include: [[0, 0], [6, 0]],
    series: [{ label: "primary", stroke: "#ffb020" }, { label: "other targets", stroke: "#4fd1ff", width: 1.5 }] });
  cleanups.push(() => plan.destroy(), () => side.destroy(), () => window.clearInterval(zoneTimer));
  const history = new Map<number, { t: number; x: number; y: number; z: number }[]>();
  let primaryId: number | null = null;

  // ---------------------------------------------------------------- controls
  const ctlMsg = notice("status");
  const modeButtons = MODES.map((m) => h("button", { type: "button", class: "mode", "aria-pressed": "false",
    title: MODE_HELP[m], "data-mode": m, onclick: () => void drive(() => api.setMode(m), `Mode ${m}`) },
    m[0].toUpperCase() + m.slice(1)));
  const speed = h("input", { type: "range", min: 1, max: 90, step: 1, name: "jog-speed" });
  speed.value = localStorage.getItem("tmeye.jogspeed") ?? "15";
  const speedOut = h("output", { for: "" }, `${speed.value}°/s`);
  speed.addEventListener("input", () => {
    speedOut.textContent = `${speed.value}°/s`;
    localStorage.setItem("tmeye.jogspeed", speed.value);
  });
  const rate = () => Number(speed.value) || 15;
  const jog = new JogController((e) => showError(e, "Jog"));
  const padDirs: [string, string, Vec][] = [
    ["up", "Tilt up", { pan: 0, tilt: 1 }], ["left", "Pan left", { pan: -1, tilt: 0 }],
    ["right", "Pan right", { pan: 1, tilt: 0 }], ["down", "Tilt down", { pan: 0, tilt: -1 }],
  ];
  const glyph: Record<string, string> = { up: "▲", down: "▼", left: "◀", right: "▶" };
  const padButtons = padDirs.map(([name, label, v]) => {
    const b = h("button", { type: "button", class: `pad-${name}`, "aria-label": label, title: `${label} (hold)` },
      glyph[name]);
    const start = (ev: PointerEvent) => {
      ev.preventDefault();
      b.setPointerCapture?.(ev.pointerId);
      jog.set(`pad`, { pan: v.pan * rate(), tilt: v.tilt * rate() });
    };
    const stop = () => jog.set("pad", null);
    b.addEventListener("pointerdown", start);
    b.addEventListener("pointerup", stop);
    b.addEventListener("pointercancel", stop);
    b.addEventListener("lostpointercapture", stop);
    b.addEventListener("keydown", (ev) => {
      if (ev.key === "Enter" || ev.key === " ") {
        ev.preventDefault();
        if (!ev.repeat) void jog.pulse({ pan: v.pan * rate(), tilt: v.tilt * rate() });
      }
    });
    return b;
  });
  const stopBtn = h("button", { type: "button", class: "pad-stop", "aria-label": "Stop", title: "Stop jogging",
    onclick: () => void drive(() => api.setMode("hold"), "Hold") }, "■");
  const pad = h("div", { class: "pad", role: "group", "aria-label": "Jog pad" },
    padButtons[0], padButtons[1], stopBtn, padButtons[2], padButtons[3]);
  const gamepadState = h("p", { class: "muted small", "data-testid": "gamepad" }, "Gamepad: none connected");

  const panIn = h("input", { type: "number", step: 0.1, min: -360, max: 360, name: "pan", required: true, value: "0" });
  const tiltIn = h("input", { type: "number", step: 0.1, min: -90, max: 90, name: "tilt", required: true, value: "0" });
  const gotoForm = h("form", { class: "row-form" }, field("Pan (°)", panIn), field("Tilt (°)", tiltIn),
    h("button", { type: "submit" }, "Go to"));
  gotoForm.addEventListener("submit", (ev) => {
    ev.preventDefault();
    void drive(() => api.goto({ pan_deg: Number(panIn.value), tilt_deg: Number(tiltIn.value) }), "Go to");
  });

  const presetList = h("ul", { class: "preset-list", "aria-label": "Presets" });
  const presetName = h("input", { name: "preset-name", maxLength: 64, pattern: "[\\w .\\-]+", required: true });
  const presetForm = h("form", { class: "row-form" }, field("Preset name", presetName),
    h("button", { type: "submit" }, "Save current position"));
  presetForm.addEventListener("submit", (ev) => {
    ev.preventDefault();
    void drive(() => api.createPreset({ name: presetName.value.trim() }), "Save preset").then((ok) => {
      if (ok) {
        presetName.value = "";
        void loadPresets();
      }
    });
  });

  const reasonId = "drive-reason";
  const fieldset = h("fieldset", { class: "controls-set", disabled: !canDrive,
    "aria-describedby": canDrive ? undefined : reasonId },
    h("legend", { class: "sr-only" }, "Mount control"),
    h("div", { class: "ctl-block" }, h("h3", null, "Mode"),
      h("div", { class: "modes", role: "group", "aria-label": "Servo mode" }, ...modeButtons)),
    h("div", { class: "ctl-block" }, h("h3", null, "Jog"), field("Jog speed", speed), speedOut, pad,
      h("p", { class: "muted small" }, "Arrow keys jog while held (not in a text field); Shift doubles the speed."),
      gamepadState),
    h("div", { class: "ctl-block" }, h("h3", null, "Go to"), gotoForm),
    h("div", { class: "ctl-block" }, h("h3", null, "Presets"), presetList, presetForm));
  const controls = h("aside", { class: "panel controls", "aria-labelledby": "ctl-title" },
    h("h2", { id: "ctl-title" }, "Mount"),
    canDrive ? null : h("p", { class: "reason", id: reasonId, role: "note", "data-testid": "drive-reason" }, driveReason),
    ctlMsg, fieldset);

  root.replaceChildren(h("section", { class: "live" },
    h("h1", { class: "sr-only" }, "Live"),
    h("div", { class: "live-main" }, toolbar, videos, h("div", { class: "live-lower" }, readouts, plots)),
    controls));

  // ---------------------------------------------------------------- actions
  function showError(e: unknown, what: string): void {
    const err = e instanceof ApiError ? e : new ApiError(0, String(e));
    debug.lastError = `${what}: ${err.status} ${err.detail}`;
    const text = err.status === 403 ? `${what} refused: ${err.detail}` :
      err.status === 404 ? `${what}: not available on this server (${err.detail})` :
      err.offline ? `${what}: the server cannot be reached` : `${what} failed: ${err.detail}`;
    ctlMsg.show(text, "bad");
  }

  async function act(fn: () => Promise<unknown>, what: string): Promise<boolean> {
    if (!canDrive) {
      ctlMsg.show(driveReason, "warn");
      return false;
    }
    try {
      const r = await fn();
      if (r && typeof r === "object" && "mode" in r) updateServo(r as ServoStatus);
      ctlMsg.show(`${what}: done`, "ok");
      return true;
    } catch (e) {
      showError(e, what);
      return false;
    }
  }

  /** act() for a command that moves the mount or sets its mode: jogging stops first, and the command is sent
   * once the server has answered the last jog (a stop still in flight would otherwise arrive after the
   * command and switch the mount back to manual). */
  async function drive(fn: () => Promise<unknown>, what: string): Promise<boolean> {
    if (canDrive) await jog.halt();
    return act(fn, what);
  }

  async function loadPresets(): Promise<void> {
    let list: Preset[];
    try {
      list = await api.presets();
    } catch (e) {
      if (!(e instanceof ApiError && e.status === 401)) presetList.replaceChildren(h("li", { class: "muted" }, "Presets could not be loaded"));
      return;
    }
    presetList.replaceChildren(...(list.length ? list.map((p) => h("li", null,
      h("span", { class: "preset-name" }, `${p.name}`), h("span", { class: "muted" }, ` ${num(p.pan_deg, 1)}°, ${num(p.tilt_deg, 1)}°`),
      h("span", { class: "preset-actions" },
        h("button", { type: "button", "aria-label": `Go to preset ${p.name}`,
          onclick: () => void drive(() => api.gotoPreset(p.id), `Preset ${p.name}`) }, "Go"),
        h("button", { type: "button", class: "danger", "aria-label": `Delete preset ${p.name}`,
          onclick: () => void act(() => api.deletePreset(p.id), `Delete ${p.name}`).then(() => loadPresets()) }, "Delete"))))
      : [h("li", { class: "muted" }, "No presets yet")]));
  }

  function updateServo(s: ServoStatus | null | undefined): void {
    if (!s) return;
    servo = { ...servo, ...s };
    debug.servo = servo;
    for (const b of modeButtons) b.setAttribute("aria-pressed", String(b.dataset.mode === servo.mode));
    R.servo.dd.textContent = servo.mode
      ? `${servo.mode}, pan ${num(servo.pan_deg, 2)}°, tilt ${num(servo.tilt_deg, 2)}°${servo.fault ? `, fault: ${servo.fault}` : ""}`
      : "no servo";
  }

  // ---------------------------------------------------------------- keyboard and gamepad
  const keysDown = new Set<string>();
  const KEYS: Record<string, Vec> = { ArrowUp: { pan: 0, tilt: 1 }, ArrowDown: { pan: 0, tilt: -1 },
    ArrowLeft: { pan: -1, tilt: 0 }, ArrowRight: { pan: 1, tilt: 0 } };
  let shift = false;
  const typing = (t: EventTarget | null) => t instanceof HTMLElement &&
    (t.isContentEditable || ["INPUT", "SELECT", "TEXTAREA"].includes(t.tagName));
  const keyVec = (): Vec | null => {
    if (!keysDown.size) return null;
    const k = shift ? 2 : 1;
    let pan = 0, tilt = 0;
    for (const key of keysDown) {
      pan += KEYS[key].pan;
      tilt += KEYS[key].tilt;
    }
    return { pan: pan * rate() * k, tilt: tilt * rate() * k };
  };
  const onKeyDown = (ev: KeyboardEvent) => {
    shift = ev.shiftKey;
    if (!(ev.key in KEYS) || typing(ev.target) || ev.altKey || ev.ctrlKey || ev.metaKey) return;
    ev.preventDefault();
    if (!canDrive) {
      ctlMsg.show(driveReason, "warn");
      return;
    }
    if (ev.repeat && keysDown.has(ev.key)) return;
    keysDown.add(ev.key);
    jog.set("keys", keyVec());
  };
  const onKeyUp = (ev: KeyboardEvent) => {
    shift = ev.shiftKey;
    if (!keysDown.delete(ev.key)) return;
    jog.set("keys", keyVec());
  };
  const onBlur = () => {
    keysDown.clear();
    jog.set("keys", null);
  };
  window.addEventListener("keydown", onKeyDown);
  window.addEventListener("keyup", onKeyUp);
  window.addEventListener("blur", onBlur);
  cleanups.push(() => {
    window.removeEventListener("keydown", onKeyDown);
    window.removeEventListener("keyup", onKeyUp);
    window.removeEventListener("blur", onBlur);
    jog.stopAll();
  });

  let gpRaf = 0;
  const pollGamepad = () => {
    gpRaf = 0;
    const pads = (navigator.getGamepads?.() ?? []).filter((g): g is Gamepad => !!g && g.connected);
    if (!pads.length) {
      gamepadState.textContent = "Gamepad: none connected";
      jog.set("gamepad", null);
      return;
    }
    const g = pads[0];
    gamepadState.textContent = `Gamepad: ${g.id.slice(0, 40)} (left stick or d-pad jogs)`;
    const dz = (x: number) => (Math.abs(x) < 0.15 ? 0 : x);
    let pan = dz(g.axes[0] ?? 0), tilt = -dz(g.axes[1] ?? 0);
    const pressed = (i: number) => !!g.buttons[i]?.pressed;
    if (pressed(12)) tilt = 1;
    if (pressed(13)) tilt = -1;
    if (pressed(14)) pan = -1;
    if (pressed(15)) pan = 1;
    if (canDrive) jog.set("gamepad", { pan: pan * rate() * 2, tilt: tilt * rate() * 2 });
    gpRaf = requestAnimationFrame(pollGamepad);
  };
  const onPad = () => {
    if (!gpRaf) gpRaf = requestAnimationFrame(pollGamepad);
  };
  window.addEventListener("gamepadconnected", onPad);
  window.addEventListener("gamepaddisconnected", onPad);
  onPad();
  cleanups.push(() => {
    window.removeEventListener("gamepadconnected", onPad);
    window.removeEventListener("gamepaddisconnected", onPad);
    cancelAnimationFrame(gpRaf);
  });

  // ---------------------------------------------------------------- click on the video
  const pixelOf = (cam: CamView, ev: MouseEvent): [number, number] | null => {
    const r = cam.frame.getBoundingClientRect();
    const s = Math.min(r.width / srcW, r.height / srcH);
    const ox = (r.width - srcW * s) / 2, oy = (r.height - srcH * s) / 2;
    const u = (ev.clientX - r.left - ox) / s, v = (ev.clientY - r.top - oy) / s;
    return u >= 0 && v >= 0 && u <= srcW && v <= srcH ? [u, v] : null;
  };
  for (const cam of Object.values(cams)) {
    cam.frame.addEventListener("click", (ev) => {
      const px = pixelOf(cam, ev);
      if (!px) return;
      const [u, v] = px;
      if (!canDrive) {
        ctlMsg.show(driveReason, "warn");
        return;
      }
      const d = cam.camera === "left" ? detectionAt(cam.shown ?? buffer.latest, u, v) : null;
      if (d) void act(() => api.makePrimary(d.track_id), `Primary target #${d.track_id}`);
      else void drive(() => api.point({ camera: cam.camera, u: Math.round(u * 10) / 10, v: Math.round(v * 10) / 10 }),
        `Point ${cam.camera} camera at (${u.toFixed(0)}, ${v.toFixed(0)})`);
    });
    if (canDrive) cam.frame.classList.add("clickable");
  }

  // ---------------------------------------------------------------- telemetry
  let lastDom = 0;
  let telemetryAt = 0;
  const onTelemetry = (msg: Telemetry) => {
    debug.telemetryMessages += 1;
    telemetryAt = performance.now();
    buffer.push(msg);
    if (msg.servo) updateServo(msg.servo);
    primaryId = msg.track_id;
    for (const d of msg.detections ?? []) {
      let pts = history.get(d.track_id);
      if (!pts) history.set(d.track_id, (pts = []));
      const last = pts[pts.length - 1];
      if (!last || msg.captured_at - last.t >= 0.1) pts.push({ t: msg.captured_at, x: d.x, y: d.y, z: d.z });
    }
    if (source !== "webrtc") {
      const now = performance.now();
      if (now - lastDom > 100) {
        lastDom = now;
        renderReadouts(msg, source === "mjpeg" ? "latest (MJPEG has no frame timestamps)" : "latest");
      }
    }
  };
  const onSocketState = (s: SocketState, info: { attempts: number }) => {
    debug.socketOpens = socket ? socket.opens : 0;
    const text = s === "open" ? "Telemetry: connected" : s === "connecting" ? "Telemetry: connecting…" :
      s === "unauthorized" ? "Telemetry: not logged in" : `Telemetry: disconnected, reconnecting (${info.attempts})`;
    status.slot("telemetry", text, s === "open" ? "ok" : s === "connecting" ? "info" : "bad");
    if (s === "open" && socket && socket.opens > 1) {
      // the server came back: start the video again, reload presets and settings
      buffer.clear();
      void restartVideo("reconnected");
      void loadPresets();
      void loadConfig();
    }
  };
  let socket: ReconnectingSocket<Telemetry> | null = null;
  socket = new ReconnectingSocket<Telemetry>({ path: "/ws/telemetry", onMessage: onTelemetry, onState: onSocketState });
  cleanups.push(() => socket?.close());

  function renderReadouts(tel: Telemetry, sync: string): void {
    const win = buffer.before(tel, 0.6);
    const m = motionOf(win);
    R.frame.dd.textContent = `${tel.frame} · ${sync}`;
    R.target.dd.textContent = tel.detected && tel.track_id !== null ? `#${tel.track_id}` : "none";
    R.r.dd.textContent = tel.r != null ? `${num(tel.r, 2)} ± ${num(tel.sigma_r, 3)} m` : "—";
    R.theta.dd.textContent = tel.theta_deg != null ? `${num(tel.theta_deg, 2)} ± ${num(tel.sigma_theta_deg, 3)}°` : "—";
    R.phi.dd.textContent = tel.phi_deg != null ? `${num(tel.phi_deg, 2)} ± ${num(tel.sigma_phi_deg, 3)}°` : "—";
    R.speed.dd.textContent = m ? `${num(m.speed, 2)} m/s` : "—";
    R.heading.dd.textContent = m && m.speed > 0.1 ? `${num(m.heading, 0)}° (0° = away from the rig, 90° = right)` : "—";
    R.xyz.dd.textContent = tel.x != null ? `${num(tel.x, 2)}, ${num(tel.y, 2)}, ${num(tel.z, 2)} m` : "—";
    const ids = (tel.detections ?? []).map((d) => `${d.track_id}:${tel.track_id === d.track_id}`).join(",");
    if (detList.dataset.ids !== ids) {
      detList.dataset.ids = ids;
      detList.replaceChildren(...((tel.detections ?? []).length ? tel.detections!.map((d) => h("li", null,
        h("span", null, `#${d.track_id}${d.track_id === tel.track_id ? " (primary)" : ""} `),
        h("span", { class: "muted" }, `${num(d.r, 1)} m`),
        d.track_id !== tel.track_id && canDrive
          ? h("button", { type: "button", class: "small", onclick: () => void act(() => api.makePrimary(d.track_id),
            `Primary target #${d.track_id}`) }, "Make primary") : null))
        : [h("li", { class: "muted" }, "none")]));
    }
  }

  // ---------------------------------------------------------------- overlays and video
  let source: Source = "none";
  let rtc: RtcVideo | null = null;
  let videoGen = 0;
  let retryTimer: number | undefined;

  const drawCam = (cam: CamView, tel: Telemetry | null, sync: string) => {
    cam.shown = tel;
    if (cam.camera === "left") {
      debug.shown = (tel?.detections ?? []).map((d) => ({ track_id: d.track_id, box: d.box }));
      debug.primary = tel?.track_id ?? null;
    }
    const motion = tel ? motionOf(buffer.before(tel, 0.6)) : null;
    drawOverlay(cam.canvas, { camera: cam.camera, srcW, srcH, tel, motion, deadbandFrac, sync });
  };

  const onVideoFrame = (cam: CamView, gen: number) => {
    const v = cam.video;
    if (!("requestVideoFrameCallback" in v)) return;
    const cb = (_now: number, meta: VideoFrameCallbackMetadata) => {
      if (disposed || gen !== videoGen) return;
      cam.frames += 1;
      debug.frames[cam.camera] = cam.frames;
      const rtp = meta.rtpTimestamp;
      let m: Match | null = null;
      let sync: string;
      if (rtp !== undefined) {
        m = buffer.match(rtp);
        sync = m ? (m.offsetTicks === 0 ? "in sync" : `±${Math.round(Math.abs(m.offsetTicks) / 90)} ms`) : "no telemetry for this frame";
      } else sync = "no RTP timestamp";
      debug.sync[cam.camera] = { rtp: rtp ?? -1, frame: m?.msg.frame ?? null, offsetTicks: m?.offsetTicks ?? null,
        matched: m ? (m.offsetTicks === 0 ? "exact" : "near") : "none" };
      const tel = m?.msg ?? null;
      if (cam.picture) paint(cam.picture, v);
      if ((window as unknown as { __tmeyeVerifyStamps?: boolean }).__tmeyeVerifyStamps) {
        const st = readStamp(cam.picture ?? v, srcW); // what is on screen: the painted picture where there is one
        if (st !== null) {
          debug.stamps.push({ camera: cam.camera, stamp: st, frame: tel?.frame ?? null, offsetTicks: m?.offsetTicks ?? null });
          if (debug.stamps.length > 1200) debug.stamps.shift();
        }
      }
      drawCam(cam, tel, sync);
      if (cam.camera === "left" && tel) {
        const now = performance.now();
        if (now - lastDom > 100) {
          lastDom = now;
          renderReadouts(tel, sync);
        }
      }
      v.requestVideoFrameCallback(cb);
    };
    v.requestVideoFrameCallback(cb);
  };

  // without frame timestamps (MJPEG, no video) the overlay shows the latest telemetry, drawn at the display's
  // rate; with WebRTC the video's frame callbacks draw it, and no idle animation frames are asked for
  let raf = 0;
  const drawLatest = () => {
    raf = 0;
    if (source === "webrtc" || disposed) return;
    raf = requestAnimationFrame(drawLatest);
    const sync = source === "mjpeg" ? "latest (MJPEG)" : "latest (no video)";
    drawCam(cams.left, buffer.latest, sync);
    drawCam(cams.right, buffer.latest, sync);
  };
  const setSource = (s: Source) => {
    source = s;
    debug.source = s;
    if (s !== "webrtc" && !raf) raf = requestAnimationFrame(drawLatest);
  };
  setSource("none");
  cleanups.push(() => cancelAnimationFrame(raf));

  const setCamState = (text: string, tone = "info") => {
    for (const c of Object.values(cams)) {
      c.state.textContent = text;
      c.state.dataset.tone = tone;
    }
  };

  const stopVideo = () => {
    videoGen += 1;
    window.clearTimeout(retryTimer);
    rtc?.close();
    rtc = null;
    for (const c of Object.values(cams)) {
      c.video.srcObject = null;
      c.video.hidden = true;
      c.video.classList.remove("painted");
      if (c.picture) c.picture.hidden = true;
      c.img.removeAttribute("src");
      c.img.hidden = true;
      c.frame.classList.remove("has-video");
    }
    setSource("none");
  };

  const useMjpeg = async (gen: number, why: string): Promise<boolean> => {
    setCamState("MJPEG: connecting…");
    const ok = await mjpegAvailable("left");
    if (gen !== videoGen || disposed) return false;
    if (!ok) return false;
    for (const c of Object.values(cams)) {
      c.img.hidden = false;
      c.img.onerror = () => {
        if (gen !== videoGen) return;
        c.state.textContent = "MJPEG: stream ended, retrying…";
        c.state.dataset.tone = "bad";
        window.clearTimeout(retryTimer);
        retryTimer = window.setTimeout(() => void restartVideo("mjpeg error"), 3000);
      };
      c.img.src = `/api/live/${c.camera}.mjpeg?t=${Date.now()}`;
      c.frame.classList.add("has-video");
    }
    setSource("mjpeg");
    setCamState("MJPEG", "ok");
    videoNote.textContent = why;
    status.slot("video", "Video: MJPEG", "ok");
    return true;
  };

  async function restartVideo(reason: string): Promise<void> {
    stopVideo();
    const gen = videoGen;
    const mode = videoSelect.value as VideoMode;
    videoNote.textContent = "";
    if (mode === "off") {
      setCamState("video off");
      status.slot("video", "Video: off", "info");
      videoNote.textContent = "Video off: the overlay shows the latest telemetry.";
      return;
    }
    let why = "";
    if (mode === "auto" || mode === "webrtc") {
      setCamState("WebRTC: connecting…");
      status.slot("video", "Video: connecting…", "info");
      try {
        const r = await startWebRtc((st) => {
          if (gen !== videoGen) return;
          if (st === "failed" || st === "closed" || st === "disconnected") {
            setCamState(`WebRTC ${st}`, "bad");
            status.slot("video", `Video: WebRTC ${st}, reconnecting`, "bad");
            window.clearTimeout(retryTimer);
            retryTimer = window.setTimeout(() => void restartVideo(`WebRTC ${st}`), st === "disconnected" ? 3000 : 1000);
          }
        });
        if (gen !== videoGen || disposed) {
          r.close();
          return;
        }
        rtc = r;
        cams.left.video.srcObject = r.left;
        cams.right.video.srcObject = r.right;
        for (const c of Object.values(cams)) {
          c.video.hidden = false;
          if (c.picture) {
            c.video.classList.add("painted");
            c.picture.hidden = false;
          }
          c.frame.classList.add("has-video");
          void c.video.play().catch(() => undefined);
          onVideoFrame(c, gen);
        }
        setSource("webrtc");
        setCamState("WebRTC", "ok");
        status.slot("video", "Video: WebRTC", "ok");
        return;
      } catch (e) {
        if (gen !== videoGen || disposed) return;
        why = e instanceof VideoUnavailable ? e.message : `WebRTC failed: ${e instanceof Error ? e.message : String(e)}`;
        if (e instanceof ApiError && e.status === 401) return;
        if (mode === "webrtc") {
          setCamState(why, "bad");
          status.slot("video", "Video: none", "bad");
          videoNote.textContent = `${why}; retrying in 10 s.`;
          retryTimer = window.setTimeout(() => void restartVideo("retry"), 10000);
          return;
        }
      }
    }
    if (await useMjpeg(gen, why ? `${why}: using MJPEG.` : "")) return;
    if (gen !== videoGen || disposed) return;
    const msg = `${why ? `${why}; ` : ""}no MJPEG stream either`;
    setCamState("no video", "bad");
    status.slot("video", "Video: none", "bad");
    videoNote.textContent = `${msg}: the overlay shows the latest telemetry. Retrying in 30 s.`;
    retryTimer = window.setTimeout(() => void restartVideo(`retry after ${reason}`), 30000);
  }
  videoSelect.addEventListener("change", () => {
    localStorage.setItem("tmeye.video", videoSelect.value);
    void restartVideo("selected");
  });
  cleanups.push(stopVideo);

  // ---------------------------------------------------------------- status, config, plots
  const onStatus = (s: Status | null, online: boolean) => {
    if (!s || !online) return;
    const w = Number(s.source?.width), hh = Number(s.source?.height);
    if (w > 0 && hh > 0 && (w !== srcW || hh !== srcH)) {
      srcW = w;
      srcH = hh;
      debug.size = [w, hh];
      for (const c of Object.values(cams)) c.frame.style.aspectRatio = `${srcW} / ${srcH}`;
    }
    // the telemetry carries the servo state of every frame; the status fills in when it does not flow
    if (performance.now() - telemetryAt > 2000) updateServo(s.servo);
    else if (s.servo.limits) updateServo({ limits: s.servo.limits } as ServoStatus);
  };
  cleanups.push(status.subscribe(onStatus));
  for (const c of Object.values(cams)) c.frame.style.aspectRatio = `${srcW} / ${srcH}`;

  async function loadConfig(): Promise<void> {
    try {
      const cfg = await api.trackerConfig();
      deadbandFrac = cfg.aim.deadband_frac ?? deadbandFrac;
    } catch {
      /* keep the default */
    }
  }

  const plotTimer = window.setInterval(() => {
    const latest = buffer.latest;
    const now = latest?.captured_at ?? Date.now() / 1000;
    const prim: XY = [[], []], others: XY = [[], []];
    const sPrim: XY = [[], []], sOthers: XY = [[], []];
    const headsPlan: { x: number; y: number; color: string; label: string }[] = [];
    const headsSide: typeof headsPlan = [];
    for (const [id, pts] of history) {
      while (pts.length && pts[0].t < now - HISTORY_S) pts.shift();
      if (!pts.length) {
        history.delete(id);
        continue;
      }
      const isPrim = id === primaryId;
      const [pp, ss] = isPrim ? [prim, sPrim] : [others, sOthers];
      for (const p of pts) {
        pp[0].push(p.x); pp[1].push(p.z);
        ss[0].push(Math.hypot(p.x, p.z)); ss[1].push(-p.y);
      }
      pp[0].push(null); pp[1].push(null); ss[0].push(null); ss[1].push(null);
      const last = pts[pts.length - 1];
      if (now - last.t < 1.0) {
        const color = isPrim ? "#ffb020" : "#4fd1ff";
        headsPlan.push({ x: last.x, y: last.z, color, label: `#${id}` });
        headsSide.push({ x: Math.hypot(last.x, last.z), y: -last.y, color, label: `#${id}` });
      }
    }
    const f = 600 * (srcW / 640);
    const hHalf = (Math.atan(srcW / 2 / f) * 180) / Math.PI;
    const vHalf = (Math.atan(srcH / 2 / f) * 180) / Math.PI;
    const pan = servo?.pan_deg ?? 0, tilt = servo?.tilt_deg ?? 0;
    const planWedge: Wedge = { centreDeg: pan, halfDeg: hHalf, label: `FOV ${num(2 * hHalf, 0)}°, pan ${num(pan, 1)}°` };
    const sideWedge: Wedge = { centreDeg: tilt, halfDeg: vHalf, fromHorizontal: true,
      label: `FOV ${num(2 * vHalf, 0)}°, tilt ${num(tilt, 1)}°` };
    plan.setData([prim, others, zones], [planWedge], headsPlan);
    side.setData([sPrim, sOthers], [sideWedge], headsSide);
  }, 250);
  cleanups.push(() => window.clearInterval(plotTimer));

  void loadPresets();
  void loadConfig();
  void restartVideo("start");

  return {
    unmount() {
      disposed = true;
      for (const fn of cleanups.reverse()) {
        try {
          fn();
        } catch {
          /* keep going */
        }
      }
      status.slot("telemetry", null);
      status.slot("video", null);
    },
  };
}
