// The Live page's pictures: both cameras over WebRTC (else MJPEG, else none), each with the overlay of the
// telemetry of the frame on screen (matched by RTP timestamp; the latest where there is none), the video
// and layout choices, and clicks on a picture turned into source pixels.
import { ApiError } from "../api/client";
import type { Telemetry } from "../api/types";
import { field, h } from "../lib/dom";
import type { StatusBar } from "../lib/statusbar";
import { motionOf, type Match } from "../lib/telemetry";
import { detectionAt, drawOverlay } from "../video/overlay";
import { paint, readStamp } from "../video/stamp";
import { mjpegAvailable, startWebRtc, VideoUnavailable, type RtcVideo } from "../video/webrtc";
import type { Camera, LiveState, Source } from "./live_state";

type VideoMode = "auto" | "webrtc" | "mjpeg" | "off";

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
}

/** The cameras whose WebRTC video is shown by painting each presented frame into a canvas, the video
 * element itself kept invisible (opacity 0: decoded, presented and called back, not composited). Chromium
 * takes a page with more than one visible video layer for a video conference: unless the page draws faster
 * than 30 frames per second it halves the compositor's rate to 30 Hz (cc::FrameRateEstimator), and two
 * 30 fps streams whose frames arrive with some jitter then lose one frame in five or six (measured: 24 to 25
 * shown per second of 30 decoded, against 28 with one visible video layer). */
const PAINTED: ReadonlySet<Camera> = new Set<Camera>(["right"]);

function makeCam(camera: Camera, title: string, canDrive: boolean): CamView {
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
  if (canDrive) frame.classList.add("clickable");
  return { camera, fig, frame, video, img, picture, canvas, state, frames: 0, shown: null };
}

/** What the pictures ask of the page: a click at source pixel (u, v), with the detection there (left
 * camera) or null; and the telemetry of a frame now on screen, for the readouts. */
export interface VideoHooks {
  clicked(camera: Camera, u: number, v: number, trackId: number | null): void;
  shown(tel: Telemetry, sync: string): void;
}

export class LiveVideo {
  readonly toolbar: HTMLElement;
  readonly el: HTMLElement;
  source: Source = "none";
  private readonly cams: Record<Camera, CamView>;
  private readonly select = h("select", { name: "video" },
    h("option", { value: "auto" }, "Auto (WebRTC, else MJPEG)"), h("option", { value: "webrtc" }, "WebRTC"),
    h("option", { value: "mjpeg" }, "MJPEG"), h("option", { value: "off" }, "Off (overlay only)"));
  private readonly note = h("span", { class: "muted", "data-testid": "video-note" });
  private rtc: RtcVideo | null = null;
  private gen = 0;
  private retryTimer: number | undefined;
  private raf = 0;

  constructor(private readonly state: LiveState, private readonly status: StatusBar, private readonly hooks: VideoHooks) {
    this.cams = { left: makeCam("left", "Left camera", state.canDrive), right: makeCam("right", "Right camera", state.canDrive) };
    this.select.value = (localStorage.getItem("tmeye.video") as VideoMode | null) ?? "auto";
    this.select.addEventListener("change", () => {
      localStorage.setItem("tmeye.video", this.select.value);
      void this.restart("selected");
    });
    const layout = h("select", { name: "layout" },
      h("option", { value: "side" }, "Side by side"), h("option", { value: "large" }, "Left large, right small"));
    layout.value = localStorage.getItem("tmeye.layout") ?? "side";
    this.el = h("div", { class: `videos layout-${layout.value}`, role: "group", "aria-label": "Cameras" },
      this.cams.left.fig, this.cams.right.fig);
    layout.addEventListener("change", () => {
      this.el.className = `videos layout-${layout.value}`;
      localStorage.setItem("tmeye.layout", layout.value);
    });
    this.toolbar = h("div", { class: "toolbar" }, field("Video", this.select), field("Layout", layout), this.note);
    for (const cam of this.all()) cam.frame.addEventListener("click", (ev) => this.onClick(cam, ev));
    this.sizeChanged();
    this.setSource("none");
  }

  /** The source's image size changed (state.srcW, state.srcH): the pictures take its aspect ratio. */
  sizeChanged(): void {
    for (const c of this.all()) c.frame.style.aspectRatio = `${this.state.srcW} / ${this.state.srcH}`;
  }

  dispose(): void {
    this.stop();
    cancelAnimationFrame(this.raf);
  }

  /** Stop the video and start it again in the mode selected: WebRTC, else (auto) MJPEG, else none, retrying. */
  async restart(reason: string): Promise<void> {
    this.stop();
    const gen = this.gen;
    const mode = this.select.value as VideoMode;
    this.note.textContent = "";
    if (mode === "off") {
      this.setCamState("video off");
      this.status.slot("video", "Video: off", "info");
      this.note.textContent = "Video off: the overlay shows the latest telemetry.";
      return;
    }
    let why = "";
    if (mode === "auto" || mode === "webrtc") {
      const failed = await this.useWebRtc(gen);
      if (failed === null || gen !== this.gen || this.state.disposed) return; // playing, superseded or logged out
      why = failed;
      if (mode === "webrtc") {
        this.setCamState(why, "bad");
        this.status.slot("video", "Video: none", "bad");
        this.note.textContent = `${why}; retrying in 10 s.`;
        this.retryTimer = window.setTimeout(() => void this.restart("retry"), 10000);
        return;
      }
    }
    if (await this.useMjpeg(gen, why ? `${why}: using MJPEG.` : "")) return;
    if (gen !== this.gen || this.state.disposed) return;
    const msg = `${why ? `${why}; ` : ""}no MJPEG stream either`;
    this.setCamState("no video", "bad");
    this.status.slot("video", "Video: none", "bad");
    this.note.textContent = `${msg}: the overlay shows the latest telemetry. Retrying in 30 s.`;
    this.retryTimer = window.setTimeout(() => void this.restart(`retry after ${reason}`), 30000);
  }

  private all(): CamView[] {
    return [this.cams.left, this.cams.right];
  }

  private onClick(cam: CamView, ev: MouseEvent): void {
    const { srcW, srcH } = this.state;
    const r = cam.frame.getBoundingClientRect();
    const s = Math.min(r.width / srcW, r.height / srcH);
    const u = (ev.clientX - r.left - (r.width - srcW * s) / 2) / s, v = (ev.clientY - r.top - (r.height - srcH * s) / 2) / s;
    if (u < 0 || v < 0 || u > srcW || v > srcH) return;
    const d = cam.camera === "left" ? detectionAt(cam.shown ?? this.state.buffer.latest, u, v) : null;
    this.hooks.clicked(cam.camera, u, v, d ? d.track_id : null);
  }

  /** WebRTC for both cameras: null once playing (or when superseded, or the session ended), else why not. */
  private async useWebRtc(gen: number): Promise<string | null> {
    this.setCamState("WebRTC: connecting…");
    this.status.slot("video", "Video: connecting…", "info");
    try {
      const r = await startWebRtc((st) => {
        if (gen !== this.gen) return;
        if (st === "failed" || st === "closed" || st === "disconnected") {
          this.setCamState(`WebRTC ${st}`, "bad");
          this.status.slot("video", `Video: WebRTC ${st}, reconnecting`, "bad");
          window.clearTimeout(this.retryTimer);
          this.retryTimer = window.setTimeout(() => void this.restart(`WebRTC ${st}`), st === "disconnected" ? 3000 : 1000);
        }
      });
      if (gen !== this.gen || this.state.disposed) {
        r.close();
        return null;
      }
      this.rtc = r;
      this.cams.left.video.srcObject = r.left;
      this.cams.right.video.srcObject = r.right;
      for (const c of this.all()) {
        c.video.hidden = false;
        if (c.picture) {
          c.video.classList.add("painted");
          c.picture.hidden = false;
        }
        c.frame.classList.add("has-video");
        void c.video.play().catch(() => undefined);
        this.onVideoFrames(c, gen);
      }
      this.setSource("webrtc");
      this.setCamState("WebRTC", "ok");
      this.status.slot("video", "Video: WebRTC", "ok");
      return null;
    } catch (e) {
      if (e instanceof ApiError && e.status === 401) return null;
      return e instanceof VideoUnavailable ? e.message : `WebRTC failed: ${e instanceof Error ? e.message : String(e)}`;
    }
  }

  private async useMjpeg(gen: number, why: string): Promise<boolean> {
    this.setCamState("MJPEG: connecting…");
    const ok = await mjpegAvailable("left");
    if (gen !== this.gen || this.state.disposed || !ok) return false;
    for (const c of this.all()) {
      c.img.hidden = false;
      c.img.onerror = () => {
        if (gen !== this.gen) return;
        c.state.textContent = "MJPEG: stream ended, retrying…";
        c.state.dataset.tone = "bad";
        window.clearTimeout(this.retryTimer);
        this.retryTimer = window.setTimeout(() => void this.restart("mjpeg error"), 3000);
      };
      c.img.src = `/api/live/${c.camera}.mjpeg?t=${Date.now()}`;
      c.frame.classList.add("has-video");
    }
    this.setSource("mjpeg");
    this.setCamState("MJPEG", "ok");
    this.note.textContent = why;
    this.status.slot("video", "Video: MJPEG", "ok");
    return true;
  }

  private stop(): void {
    this.gen += 1;
    window.clearTimeout(this.retryTimer);
    this.rtc?.close();
    this.rtc = null;
    for (const c of this.all()) {
      c.video.srcObject = null;
      c.video.hidden = true;
      c.video.classList.remove("painted");
      if (c.picture) c.picture.hidden = true;
      c.img.removeAttribute("src");
      c.img.hidden = true;
      c.frame.classList.remove("has-video");
    }
    this.setSource("none");
  }

  private setCamState(text: string, tone = "info"): void {
    for (const c of this.all()) {
      c.state.textContent = text;
      c.state.dataset.tone = tone;
    }
  }

  // without frame timestamps (MJPEG, no video) the overlay shows the latest telemetry, drawn at the display's
  // rate; with WebRTC the video's frame callbacks draw it, and no idle animation frames are asked for
  private setSource(s: Source): void {
    this.source = s;
    this.state.debug.source = s;
    if (s !== "webrtc" && !this.raf) this.raf = requestAnimationFrame(this.drawLatest);
  }

  private readonly drawLatest = () => {
    this.raf = 0;
    if (this.source === "webrtc" || this.state.disposed) return;
    this.raf = requestAnimationFrame(this.drawLatest);
    const sync = this.source === "mjpeg" ? "latest (MJPEG)" : "latest (no video)";
    this.draw(this.cams.left, this.state.buffer.latest, sync);
    this.draw(this.cams.right, this.state.buffer.latest, sync);
  };

  private draw(cam: CamView, tel: Telemetry | null, sync: string): void {
    cam.shown = tel;
    const { debug, buffer, srcW, srcH, deadbandFrac } = this.state;
    if (cam.camera === "left") {
      debug.shown = (tel?.detections ?? []).map((d) => ({ track_id: d.track_id, box: d.box }));
      debug.primary = tel?.track_id ?? null;
    }
    const motion = tel ? motionOf(buffer.before(tel, 0.6)) : null;
    drawOverlay(cam.canvas, { camera: cam.camera, srcW, srcH, tel, motion, deadbandFrac, sync });
  }

  /** Each frame the video presents: its telemetry (by RTP timestamp) drawn over it, its stamp read (tests). */
  private onVideoFrames(cam: CamView, gen: number): void {
    const v = cam.video;
    if (!("requestVideoFrameCallback" in v)) return;
    const debug = this.state.debug;
    const cb = (_now: number, meta: VideoFrameCallbackMetadata) => {
      if (this.state.disposed || gen !== this.gen) return;
      cam.frames += 1;
      debug.frames[cam.camera] = cam.frames;
      const rtp = meta.rtpTimestamp;
      const m: Match | null = rtp !== undefined ? this.state.buffer.match(rtp) : null;
      const sync = rtp === undefined ? "no RTP timestamp" : !m ? "no telemetry for this frame" :
        m.offsetTicks === 0 ? "in sync" : `±${Math.round(Math.abs(m.offsetTicks) / 90)} ms`;
      debug.sync[cam.camera] = { rtp: rtp ?? -1, frame: m?.msg.frame ?? null, offsetTicks: m?.offsetTicks ?? null,
        matched: m ? (m.offsetTicks === 0 ? "exact" : "near") : "none" };
      const tel = m?.msg ?? null;
      if (cam.picture) paint(cam.picture, v);
      if ((window as unknown as { __tmeyeVerifyStamps?: boolean }).__tmeyeVerifyStamps) {
        const st = readStamp(cam.picture ?? v, this.state.srcW); // what is on screen: the painted picture if any
        if (st !== null) {
          debug.stamps.push({ camera: cam.camera, stamp: st, frame: tel?.frame ?? null, offsetTicks: m?.offsetTicks ?? null });
          if (debug.stamps.length > 1200) debug.stamps.shift();
        }
      }
      this.draw(cam, tel, sync);
      if (cam.camera === "left" && tel) this.hooks.shown(tel, sync);
      v.requestVideoFrameCallback(cb);
    };
    v.requestVideoFrameCallback(cb);
  }
}
