// The Live page: both cameras with the overlay of the frame on screen (telemetry matched by RTP
// timestamp), readouts of the primary target, plan and side views of the last minute's tracks with the
// cameras' field of view, and the mount's controls (mode, jog by keys / pad / gamepad, go-to, click to
// point, click a detection to make it primary, presets). This module composes the parts (live_*.ts) and
// feeds them the telemetry socket and the status.
import { api } from "../api/client";
import type { Status, Telemetry } from "../api/types";
import { h } from "../lib/dom";
import { ReconnectingSocket, type SocketState } from "../lib/socket";
import type { StatusBar } from "../lib/statusbar";
import { MountControls } from "./live_controls";
import { TrackPlots } from "./live_plots";
import { Readouts } from "./live_readouts";
import { type Debug, liveState, type LiveState } from "./live_state";
import { LiveVideo } from "./live_video";
import type { Page, PageContext } from "./types";

/** The aim's dead band from the tracker's settings (the default kept when they cannot be read). */
async function loadDeadband(state: LiveState): Promise<void> {
  try {
    state.deadbandFrac = (await api.trackerConfig()).aim.deadband_frac ?? state.deadbandFrac;
  } catch {
    /* keep the default */
  }
}

/** The telemetry socket, its state shown in the status bar; reconnected: the server came back (opened again). */
function telemetrySocket(status: StatusBar, debug: Debug, onMessage: (msg: Telemetry) => void, reconnected: () => void
): ReconnectingSocket<Telemetry> {
  // onState runs in the constructor already ("connecting"), before `socket` is assigned
  let socket: ReconnectingSocket<Telemetry> | null = null;
  socket = new ReconnectingSocket<Telemetry>({ path: "/ws/telemetry", onMessage,
    onState: (s: SocketState, info: { attempts: number }) => {
      const opens = socket?.opens ?? 0;
      debug.socketOpens = opens;
      const text = s === "open" ? "Telemetry: connected" : s === "connecting" ? "Telemetry: connecting…" :
        s === "unauthorized" ? "Telemetry: not logged in" : `Telemetry: disconnected, reconnecting (${info.attempts})`;
      status.slot("telemetry", text, s === "open" ? "ok" : s === "connecting" ? "info" : "bad");
      if (s === "open" && opens > 1) reconnected();
    } });
  return socket;
}

/** Take in a status: the source's size and field of view, and the mount's state (all of it when the
 * telemetry, last at telemetryAt (performance.now()), has not flowed for 2 s; else its limits). */
function applyStatus(s: Status, state: LiveState, video: LiveVideo, controls: MountControls, telemetryAt: number): void {
  const w = Number(s.source?.width), hh = Number(s.source?.height);
  if (w > 0 && hh > 0 && (w !== state.srcW || hh !== state.srcH)) {
    state.srcW = w;
    state.srcH = hh;
    state.debug.size = [w, hh];
    video.sizeChanged();
  }
  const fh = Number(s.source?.hfov_deg), fv = Number(s.source?.vfov_deg);
  state.fovDeg = fh > 0 && fv > 0 ? [fh, fv] : null;
  // the telemetry carries the servo state of every frame; the status fills in when it does not flow
  if (performance.now() - telemetryAt > 2000) controls.updateServo(s.servo);
  else if (s.servo.limits) controls.updateServo({ limits: s.servo.limits } as typeof s.servo);
}

/** Run each clean-up in turn, going on when one throws. */
function disposeAll(fns: (() => void)[]): void {
  for (const fn of fns) {
    try {
      fn();
    } catch {
      /* keep going */
    }
  }
}

export function livePage(ctx: PageContext): Page {
  const { session, root, status } = ctx;
  const state = liveState(session);
  const { buffer, debug } = state;
  let readouts: Readouts | null = null;
  const controls = new MountControls(state, (s) => readouts?.showServo(s));
  readouts = new Readouts(state, (fn, what) => controls.act(fn, what));
  const video = new LiveVideo(state, status, {
    clicked: (camera, u, v, trackId) => controls.clicked(camera, u, v, trackId),
    shown: (tel, sync) => readouts?.maybeRender(tel, sync),
  });
  const plots = new TrackPlots(state);
  root.replaceChildren(h("section", { class: "live" },
    h("h1", { class: "sr-only" }, "Live"),
    h("div", { class: "live-main" }, video.toolbar, video.el, h("div", { class: "live-lower" }, readouts.el, plots.el)),
    controls.el));

  let telemetryAt = 0;
  const onTelemetry = (msg: Telemetry) => {
    debug.telemetryMessages += 1;
    telemetryAt = performance.now();
    buffer.push(msg);
    if (msg.servo) controls.updateServo(msg.servo);
    plots.push(msg);
    // with WebRTC the readouts follow the frame on screen (video `shown`); else the latest message
    if (video.source !== "webrtc") {
      readouts?.maybeRender(msg, video.source === "mjpeg" ? "latest (MJPEG has no frame timestamps)" : "latest");
    }
  };
  // the server came back: video, presets and settings again
  const socket = telemetrySocket(status, debug, onTelemetry, () => {
    buffer.clear();
    void video.restart("reconnected");
    void controls.loadPresets();
    void loadDeadband(state);
  });
  const unsubscribe = status.subscribe((s: Status | null, online: boolean) => {
    if (s && online) applyStatus(s, state, video, controls, telemetryAt);
  });

  void controls.loadPresets();
  void loadDeadband(state);
  void video.restart("start");

  return {
    unmount() {
      state.disposed = true;
      disposeAll([unsubscribe, () => video.dispose(), () => socket.close(), () => plots.dispose(),
        () => controls.dispose()]);
      status.slot("telemetry", null);
      status.slot("video", null);
    },
  };
}
