// The Playback page: a recorded range of both cameras. Playing uses HLS (fMP4 byte ranges of the segment
// files) through hls.js, at 1/8x to 16x, the right camera kept in step with the left. Paused, the page shows
// the server-decoded frames (GET /api/playback/frame) of both cameras at exactly the same capture, with that
// frame's recorded telemetry; `,` and `.` step one recorded frame back or forward. Bookmarks, evidence
// locks and export of the range (playback_evidence.ts). The range's tracks, and replays of the range beside
// them (playback_tracks.ts, playback_replay.ts).
import Hls from "hls.js";
import { api, errorText } from "../api/client";
import { type Camera, type FrameTelemetry, playbackFrame, rec } from "../api/recordings";
import { field, h, notice } from "../lib/dom";
import { fromLocalInput, num, time, toLocalInput } from "../lib/format";
import { atLeast } from "../lib/session";
import { drawStrip, type Marks, Timeline } from "../lib/timeline";
import { evidencePanel, type EvidencePanel } from "./playback_evidence";
import { tracksPanels, type TracksPanels } from "./playback_tracks";
import type { Page, PageContext } from "./types";

const RATES = [0.125, 0.25, 0.5, 1, 2, 4, 8, 16];
const CAMS: Camera[] = ["left", "right"];
const WINDOW_S = 6; // telemetry fetched around the cursor for frame stepping

/** The frame's recorded telemetry as rows of (name, value). */
function telemetryRows(m: FrameTelemetry | null): [string, string][] {
  if (!m) return [["Frame", "no telemetry"]];
  const primary = m.track_id != null
    ? `#${m.track_id}: r ${num(m.r, 2)} m, θ ${num(m.theta_deg, 2)}°, φ ${num(m.phi_deg, 2)}°` : "—";
  const servo = m.servo ? `${m.servo.mode}, pan ${num(m.servo.pan_deg, 2)}°, tilt ${num(m.servo.tilt_deg, 2)}°` : "—";
  return [["Frame", String(m.frame)], ["Detections", String((m.detections ?? []).length)], ["Primary", primary],
    ["Servo", servo]];
}

class PlaybackView {
  private readonly msg = notice("status");
  private readonly range = h("select", { name: "range" }, h("option", { value: "300" }, "Last 5 minutes"),
    h("option", { value: "1800" }, "Last 30 minutes"), h("option", { value: "7200" }, "Last 2 hours"),
    h("option", { value: "86400" }, "Last day"), h("option", { value: "custom" }, "Custom (from, to)"));
  private readonly from = h("input", { type: "datetime-local", name: "from" });
  private readonly to = h("input", { type: "datetime-local", name: "to" });
  private readonly strip = h("canvas", { class: "timeline-strip", "aria-hidden": "true" });
  private readonly scrub = h("input", { type: "range", min: 0, max: 1, step: 0.001, value: 0,
    "aria-label": "Position in the range", class: "scrub" });
  private readonly videos = Object.fromEntries(CAMS.map((c) => [c, h("video", { muted: true, playsInline: true,
    preload: "auto", "aria-label": `${c} camera, recorded` })])) as Record<Camera, HTMLVideoElement>;
  private readonly stills = Object.fromEntries(CAMS.map((c) => [c, h("img", { alt: `${c} camera at the shown frame`,
    "data-testid": `still-${c}`, hidden: true })])) as Record<Camera, HTMLImageElement>;
  private readonly playBtn = h("button", { type: "button", class: "primary" }, "Play");
  private readonly rate = h("select", { name: "rate" }, ...RATES.map((r) => h("option", { value: String(r) }, `${r}x`)));
  private readonly frameOut = h("output", { "data-testid": "frame-index", "aria-live": "polite" }, "—");
  private readonly clockOut = h("output", { "data-testid": "frame-time" }, "—");
  private readonly telOut = h("dl", { class: "frame-telemetry", "data-testid": "frame-telemetry" });
  private readonly evidence: EvidencePanel;
  private readonly tracks: TracksPanels;
  private t0: number;
  private t1: number;
  private cursor: number;
  /** #/playback?t=T (an alarm's link): the range around T, shown at T */
  private readonly at: number | null;
  private tl = new Timeline([]);
  private marks: Marks = { tracks: [], bookmarks: [], locks: [], alarms: [] };
  private hls: Hls[] = [];
  private tel: FrameTelemetry[] = [];
  private shown: FrameTelemetry | null = null;
  private stepping = Promise.resolve();
  private raf = 0;

  constructor(ctx: PageContext) {
    const operator = atLeast(ctx.session, "operator");
    const now = Date.now() / 1000;
    [this.t0, this.t1, this.cursor] = [now - 300, now, now - 300];
    this.from.value = toLocalInput(now - 300);
    this.rate.value = "1";
    this.evidence = evidencePanel(operator, atLeast(ctx.session, "admin"), {
      range: () => [this.t0, this.t1], cursor: () => this.cursor,
      showAt: (t) => void this.showAt(t), say: (text, tone) => this.msg.show(text, tone),
      marked: (bookmarks, locks) => {
        this.marks = { ...this.marks, bookmarks, locks };
        this.redraw();
      },
    });
    this.tracks = tracksPanels(operator);
    const asked = Number(ctx.query.get("t") ?? NaN);
    this.at = Number.isFinite(asked) && asked > 0 ? asked : null;
    if (this.at !== null) {
      this.range.value = "custom";
      this.from.value = toLocalInput(this.at - 60);
      // the inputs hold whole minutes: end a minute later than wanted, or leave it empty (now) if that is to come
      this.to.value = this.at + 180 < now ? toLocalInput(this.at + 180) : "";
    }
    ctx.root.replaceChildren(this.layout());
    this.listen();
    this.syncRange();
    void this.load();
  }

  unmount(): void {
    this.pause();
    this.tracks.destroy();
    document.removeEventListener("keydown", this.onKey);
    for (const x of this.hls) x.destroy();
    for (const c of CAMS) URL.revokeObjectURL(this.stills[c].src);
  }

  private layout(): HTMLElement {
    const back = h("button", { type: "button", "aria-keyshortcuts": ",", onclick: () => this.queue(() => this.step(-1)) },
      "◀ Frame (,)");
    const fwd = h("button", { type: "button", "aria-keyshortcuts": ".", onclick: () => this.queue(() => this.step(1)) },
      "Frame (.) ▶");
    const form = h("form", { class: "row-form" }, field("Range", this.range), field("From", this.from),
      field("To", this.to, "empty: now"), h("button", { type: "submit", class: "primary" }, "Load"));
    form.addEventListener("submit", (ev) => {
      ev.preventDefault();
      void this.load();
    });
    return h("section", { class: "page wide" }, h("h1", null, "Playback"), form, this.msg,
      h("div", { class: "timeline" }, this.strip, this.scrub),
      h("div", { class: "playback-videos" }, ...CAMS.map((c) => h("figure", { class: "cam" }, this.videos[c], this.stills[c],
        h("figcaption", null, c === "left" ? "Left camera" : "Right camera")))),
      h("div", { class: "toolbar", role: "toolbar", "aria-label": "Playback" }, this.playBtn, field("Rate", this.rate),
        back, fwd, h("span", null, "Frame ", this.frameOut), h("span", null, this.clockOut)),
      h("div", { class: "playback-side" }, h("section", { class: "panel" }, h("h2", null, "This frame"), this.telOut),
        this.evidence.el),
      ...this.tracks.els);
  }

  private listen(): void {
    this.range.addEventListener("change", () => this.syncRange());
    this.playBtn.addEventListener("click", () => (this.videos.left.paused ? this.play() : this.queue(() => this.showAt(this.cursor))));
    this.rate.addEventListener("change", () => CAMS.forEach((c) => { this.videos[c].playbackRate = Number(this.rate.value); }));
    this.scrub.addEventListener("change", () => this.queue(() => this.showAt(this.t0 + Number(this.scrub.value) * (this.t1 - this.t0))));
    this.strip.addEventListener("click", (ev) => {
      const r = this.strip.getBoundingClientRect();
      this.queue(() => this.showAt(this.t0 + ((ev.clientX - r.left) / r.width) * (this.t1 - this.t0)));
    });
    document.addEventListener("keydown", this.onKey);
  }

  private readonly onKey = (ev: KeyboardEvent) => {
    const target = ev.target as HTMLElement | null;
    if (target && ["INPUT", "SELECT", "TEXTAREA"].includes(target.tagName) && target !== this.scrub) return;
    if (ev.key === ",") this.queue(() => this.step(-1));
    else if (ev.key === ".") this.queue(() => this.step(1));
    else return;
    ev.preventDefault();
  };

  /** Frame steps, seeks and pauses one after another, in the order asked. */
  private queue(fn: () => Promise<void>): void {
    this.stepping = this.stepping.then(fn, fn);
  }

  private syncRange(): void {
    const custom = this.range.value === "custom";
    this.from.disabled = this.to.disabled = !custom;
    if (!custom) {
      this.from.value = toLocalInput(Date.now() / 1000 - Number(this.range.value));
      this.to.value = "";
    }
  }

  private redraw(): void {
    drawStrip(this.strip, this.tl, this.t0, this.t1, this.cursor, this.marks);
    this.scrub.value = String((this.cursor - this.t0) / Math.max(this.t1 - this.t0, 1e-6));
  }

  private async load(): Promise<void> {
    this.syncRange();
    const t0 = this.t0 = fromLocalInput(this.from.value) ?? Date.now() / 1000 - 300;
    const t1 = this.t1 = fromLocalInput(this.to.value) ?? Date.now() / 1000;
    this.msg.show("Loading…");
    try {
      const [segs, tracks, bms, locks, alarms] = await Promise.all([rec.segments("left", t0, t1), rec.tracks(t0, t1),
        rec.bookmarks(t0, t1), rec.locks(t0, t1), api.alarms(undefined, t0 - 86400, 1000).catch(() => [])]);
      this.tl = new Timeline(segs.filter((s) => s.status !== "open"));
      this.marks = { tracks, bookmarks: bms, locks,
        alarms: alarms.filter((a) => a.activated_at <= t1 && (a.cleared_at ?? t1) >= t0) };
      this.evidence.show(bms, locks);
      this.tracks.load(t0, t1, tracks.map((t) => t.id));
    } catch (e) {
      this.msg.show(`Recordings could not be loaded: ${errorText(e)}`, "bad");
      return;
    }
    if (!this.tl.spans.length) {
      this.msg.show("Nothing was recorded in this range (segments appear once they close, every 10 s).", "warn");
      return;
    }
    this.msg.show(`${this.tl.spans.length} segments, ${num(this.tl.duration, 1)} s recorded`, "ok");
    for (const x of this.hls) x.destroy();
    this.hls = CAMS.map((c) => {
      const x = new Hls({ maxBufferLength: 20 });
      x.loadSource(rec.playlistUrl(c, t0, t1));
      x.attachMedia(this.videos[c]);
      return x;
    });
    const first = this.tl.spans[0].start;
    await this.showAt(this.at !== null && this.at >= first ? this.at : first);
  }

  private async telemetryAround(t: number): Promise<void> {
    const tel = this.tel;
    if (tel.length && tel[0].captured_at <= t && t <= tel[tel.length - 1].captured_at) return;
    this.tel = await rec.telemetry(t - WINDOW_S, t + WINDOW_S);
  }

  /** Pause and show the recorded frame captured last at or before t, both cameras, with its telemetry. */
  private async showAt(at: number): Promise<void> {
    this.pause();
    const t = this.tl.snap(at);
    await this.telemetryAround(t);
    const i = this.indexAt(t);
    await this.showFrame(i >= 0 ? this.tel[i] : this.tel[0] ?? null, t);
  }

  /** Index of the last telemetry message captured at or before t (-1: none). */
  private indexAt(t: number): number {
    let i = -1;
    for (let k = 0; k < this.tel.length; k++) if (this.tel[k].captured_at <= t + 1e-6) i = k;
    return i;
  }

  /** One recorded frame back (-1) or forward (+1) from the frame shown. */
  private async step(dir: 1 | -1): Promise<void> {
    this.pause();
    const at = this.shown?.captured_at ?? this.cursor;
    await this.telemetryAround(at);
    let j = this.indexAt(at) + dir;
    if (j < 0 || j >= this.tel.length) {
      this.tel = await rec.telemetry(at - WINDOW_S, at + WINDOW_S);
      j = this.indexAt(at) + dir;
    }
    if (j >= 0 && j < this.tel.length) await this.showFrame(this.tel[j], this.tel[j].captured_at);
  }

  private async showFrame(m: FrameTelemetry | null, t: number): Promise<void> {
    const at = m?.captured_at ?? t;
    try {
      const frames = await Promise.all(CAMS.map((c) => playbackFrame(c, at)));
      CAMS.forEach((c, k) => {
        URL.revokeObjectURL(this.stills[c].src);
        this.stills[c].src = frames[k].url;
        this.stills[c].hidden = false;
        this.videos[c].classList.add("under");
        this.videos[c].currentTime = this.tl.video(at);
      });
      this.shown = m;
      const cursor = this.cursor = frames[0].capturedAt;
      this.frameOut.textContent = String(frames[0].frame);
      this.clockOut.textContent = `${time(cursor)}.${String(Math.floor((cursor % 1) * 1000)).padStart(3, "0")}`;
      this.telOut.replaceChildren(...telemetryRows(m).flatMap(([k, v]) => [h("dt", null, k), h("dd", null, v)]));
      this.msg.show("");
    } catch (e) {
      this.msg.show(`No frame at ${time(at)}: ${errorText(e)}`, "warn");
    }
    this.redraw();
  }

  private play(): void {
    const { videos, stills } = this;
    for (const c of CAMS) {
      stills[c].hidden = true;
      videos[c].classList.remove("under");
      videos[c].playbackRate = Number(this.rate.value);
      void videos[c].play().catch(() => undefined);
    }
    this.shown = null;
    this.playBtn.textContent = "Pause";
    this.frameOut.textContent = "playing";
    const tick = () => {
      const w = this.tl.wall(videos.left.currentTime);
      if (w !== null) this.cursor = w;
      if (Math.abs(videos.right.currentTime - videos.left.currentTime) > 0.15) {
        videos.right.currentTime = videos.left.currentTime;
      }
      this.clockOut.textContent = time(this.cursor);
      this.redraw();
      this.raf = requestAnimationFrame(tick);
    };
    this.raf = requestAnimationFrame(tick);
  }

  private pause(): void {
    cancelAnimationFrame(this.raf);
    for (const c of CAMS) this.videos[c].pause();
    this.playBtn.textContent = "Play";
  }
}

export function playbackPage(ctx: PageContext): Page {
  const view = new PlaybackView(ctx);
  return { unmount: () => view.unmount() };
}
