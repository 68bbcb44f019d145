// The Playback page: a recorded range of both cameras. Playing uses HLS (fMP4 byte ranges of the segment
// files) through hls.js, at 1/8x to 16x, the right camera kept in step with the left. Paused, the page shows
// the server-decoded frames (GET /api/playback/frame) of both cameras at exactly the same capture, with that
// frame's recorded telemetry; `,` and `.` step one recorded frame back or forward. Bookmarks, evidence
// locks and export of the range. Replays of the range (playback_replay.ts) are drawn beside the live tracks.
import Hls from "hls.js";
import { api, ApiError } from "../api/client";
import { type Bookmark, type Camera, type FrameTelemetry, type Lock, playbackFrame, rec } from "../api/recordings";
import { field, h, notice } from "../lib/dom";
import { fromLocalInput, num, time, toLocalInput } from "../lib/format";
import { atLeast } from "../lib/session";
import { MetricView, type XY } from "../lib/plots";
import { drawStrip, type Marks, Timeline } from "../lib/timeline";
import { replayPanel, type TrackDetail } from "./playback_replay";
import type { Page, PageContext } from "./types";

const RATES = [0.125, 0.25, 0.5, 1, 2, 4, 8, 16];
const CAMS: Camera[] = ["left", "right"];
const WINDOW_S = 6; // telemetry fetched around the cursor for frame stepping
const MAX_TRACKS = 40; // trajectories drawn for a range

function why(e: unknown): string {
  return e instanceof ApiError ? e.detail : e instanceof Error ? e.message : String(e);
}

/** Plan (x, z) and side (z, height) polylines of trajectories, one per track (null-separated). */
function views(tracks: TrackDetail[]): XY[] {
  const p: XY = [[], []], q: XY = [[], []];
  for (const t of tracks) {
    for (const pt of t.trajectory) {
      p[0].push(pt.x); p[1].push(pt.z); q[0].push(pt.z); q[1].push(-pt.y);
    }
    p[0].push(null); p[1].push(null); q[0].push(null); q[1].push(null);
  }
  return [p, q];
}

export function playbackPage(ctx: PageContext): Page {
  const operator = atLeast(ctx.session, "operator");
  const admin = atLeast(ctx.session, "admin");
  const now = Date.now() / 1000;
  const range = h("select", { name: "range" }, h("option", { value: "300" }, "Last 5 minutes"),
    h("option", { value: "1800" }, "Last 30 minutes"), h("option", { value: "7200" }, "Last 2 hours"),
    h("option", { value: "86400" }, "Last day"), h("option", { value: "custom" }, "Custom (from, to)"));
  const from = h("input", { type: "datetime-local", name: "from", value: toLocalInput(now - 300) });
  const to = h("input", { type: "datetime-local", name: "to" });
  const msg = notice("status");
  const form = h("form", { class: "row-form" }, field("Range", range), field("From", from), field("To", to, "empty: now"),
    h("button", { type: "submit", class: "primary" }, "Load"));
  const strip = h("canvas", { class: "timeline-strip", "aria-hidden": "true" });
  const scrub = h("input", { type: "range", min: 0, max: 1, step: 0.001, value: 0, "aria-label": "Position in the range",
    class: "scrub" });
  const videos = Object.fromEntries(CAMS.map((c) => [c, h("video", { muted: true, playsInline: true, preload: "auto",
    "aria-label": `${c} camera, recorded` })])) as Record<Camera, HTMLVideoElement>;
  const stills = Object.fromEntries(CAMS.map((c) => [c, h("img", { alt: `${c} camera at the shown frame`,
    "data-testid": `still-${c}` })])) as Record<Camera, HTMLImageElement>;
  const playBtn = h("button", { type: "button", class: "primary" }, "Play");
  const rate = h("select", { name: "rate" }, ...RATES.map((r) => h("option", { value: String(r) }, `${r}x`)));
  rate.value = "1";
  const back = h("button", { type: "button", "aria-keyshortcuts": "," }, "◀ Frame (,)");
  const fwd = h("button", { type: "button", "aria-keyshortcuts": "." }, "Frame (.) ▶");
  const frameOut = h("output", { "data-testid": "frame-index", "aria-live": "polite" }, "—");
  const clockOut = h("output", { "data-testid": "frame-time" }, "—");
  const telOut = h("dl", { class: "frame-telemetry", "data-testid": "frame-telemetry" });
  const note = h("input", { type: "text", name: "note", maxLength: 2000, disabled: !operator });
  const bmBtn = h("button", { type: "button", disabled: !operator }, "Bookmark this frame");
  const lockBtn = h("button", { type: "button", disabled: !operator }, "Lock the range");
  const exportBtn = h("button", { type: "button", disabled: !operator }, "Export the range");
  const exportOut = h("p", { class: "muted", "data-testid": "export-status", "aria-live": "polite" });
  const marksList = h("ul", { class: "marks" });
  const planEl = h("div", { class: "plot-box tall" });
  const sideEl = h("div", { class: "plot-box tall" });
  const tracksPanel = h("section", { class: "panel" }, h("h2", null, "Tracks in the range (3-D: plan and side views)"),
    h("div", { class: "track-plots" }, h("div", { class: "plot" }, planEl), h("div", { class: "plot" }, sideEl)));
  const roleHint = operator ? null : h("p", { class: "muted" }, "Bookmarks, locks and exports need the operator role.");
  ctx.root.replaceChildren(h("section", { class: "page wide" }, h("h1", null, "Playback"), form, msg,
    h("div", { class: "timeline" }, strip, scrub),
    h("div", { class: "playback-videos" }, ...CAMS.map((c) => h("figure", { class: "cam" }, videos[c], stills[c],
      h("figcaption", null, c === "left" ? "Left camera" : "Right camera")))),
    h("div", { class: "toolbar", role: "toolbar", "aria-label": "Playback" }, playBtn, field("Rate", rate), back, fwd,
      h("span", null, "Frame ", frameOut), h("span", null, clockOut)),
    h("div", { class: "playback-side" }, h("section", { class: "panel" }, h("h2", null, "This frame"), telOut),
      h("section", { class: "panel" }, h("h2", null, "Evidence"), field("Note", note), bmBtn, lockBtn, exportBtn,
        exportOut, roleHint, marksList)),
    tracksPanel));
  const plan = new MetricView(planEl, { title: "Plan view", xLabel: "x (m, right)", yLabel: "z (m, ahead)", minSpan: 4,
    series: [{ label: "trajectories", stroke: "#ffb020" }, { label: "replay", stroke: "#e040fb" }] });
  const side = new MetricView(sideEl, { title: "Side view", xLabel: "z (m, ahead)", yLabel: "height (m)", minSpan: 2,
    series: [{ label: "trajectories", stroke: "#4fd1ff" }, { label: "replay", stroke: "#e040fb" }] });
  let live: XY[] = [[[], []], [[], []]], replayed: XY[] = [[[], []], [[], []]];
  const replays = replayPanel(operator, (tracks) => {
    replayed = views(tracks);
    plan.setData([live[0], replayed[0]], [], []);
    side.setData([live[1], replayed[1]], [], []);
  });
  tracksPanel.after(replays.el);

  let t0 = now - 300, t1 = now, cursor = now - 300;
  let tl = new Timeline([]);
  let marks: Marks = { tracks: [], bookmarks: [], locks: [], alarms: [] };
  // #/playback?t=T (an alarm's link): the range around T, shown at T
  const asked = Number(ctx.query.get("t") ?? NaN);
  const at = Number.isFinite(asked) && asked > 0 ? asked : null;
  if (at !== null) {
    range.value = "custom";
    from.value = toLocalInput(at - 60);
    // the inputs hold whole minutes: end a minute later than wanted, or leave it empty (now) if that is to come
    to.value = at + 180 < Date.now() / 1000 ? toLocalInput(at + 180) : "";
  }
  let hls: Hls[] = [];
  let tel: FrameTelemetry[] = [];
  let shown: FrameTelemetry | null = null;
  let stepping = Promise.resolve();
  let raf = 0;

  const syncRange = () => {
    const custom = range.value === "custom";
    from.disabled = to.disabled = !custom;
    if (!custom) {
      from.value = toLocalInput(Date.now() / 1000 - Number(range.value));
      to.value = "";
    }
  };
  range.addEventListener("change", syncRange);

  function redraw(): void {
    drawStrip(strip, tl, t0, t1, cursor, marks);
    scrub.value = String((cursor - t0) / Math.max(t1 - t0, 1e-6));
  }

  async function load(): Promise<void> {
    syncRange();
    t0 = fromLocalInput(from.value) ?? Date.now() / 1000 - 300;
    t1 = fromLocalInput(to.value) ?? Date.now() / 1000;
    msg.show("Loading…");
    try {
      const [segs, tracks, bms, locks, alarms] = await Promise.all([rec.segments("left", t0, t1), rec.tracks(t0, t1),
        rec.bookmarks(t0, t1), rec.locks(t0, t1), api.alarms(undefined, t0 - 86400, 1000).catch(() => [])]);
      tl = new Timeline(segs.filter((s) => s.status !== "open"));
      marks = { tracks, bookmarks: bms, locks,
        alarms: alarms.filter((a) => a.activated_at <= t1 && (a.cleared_at ?? t1) >= t0) };
      showMarks(bms, locks);
      void trajectories(tracks.slice(0, MAX_TRACKS).map((t) => t.id));
      void replays.load(t0, t1);
    } catch (e) {
      msg.show(`Recordings could not be loaded: ${why(e)}`, "bad");
      return;
    }
    if (!tl.spans.length) {
      msg.show("Nothing was recorded in this range (segments appear once they close, every 10 s).", "warn");
      return;
    }
    msg.show(`${tl.spans.length} segments, ${num(tl.duration, 1)} s recorded`, "ok");
    for (const x of hls) x.destroy();
    hls = CAMS.map((c) => {
      const x = new Hls({ maxBufferLength: 20 });
      x.loadSource(rec.playlistUrl(c, t0, t1));
      x.attachMedia(videos[c]);
      return x;
    });
    const first = tl.spans[0].start;
    await showAt(at !== null && at >= first ? at : first);
  }

  /** Plan (x, z) and side (z, height) views of the tracks' trajectories, one polyline each. */
  async function trajectories(ids: number[]): Promise<void> {
    const tracks = await Promise.all(ids.map((id) => api.track(id).catch(() => null)));
    live = views(tracks.filter((t): t is TrackDetail => t !== null));
    plan.setData([live[0], replayed[0]], [], []);
    side.setData([live[1], replayed[1]], [], []);
  }

  function showMarks(bms: Bookmark[], locks: Lock[]): void {
    marksList.replaceChildren(
      ...bms.map((b) => h("li", null, h("button", { type: "button", class: "link", onclick: () => void showAt(b.t) },
        `${time(b.t)}: ${b.note}`))),
      ...locks.map((l) => h("li", null, `Locked ${time(l.start)} – ${time(l.end)}${l.note ? `: ${l.note}` : ""} `,
        admin ? h("button", { type: "button", class: "small", onclick: () => void unlock(l.id) }, "Unlock") : null)));
  }

  async function telemetryAround(t: number): Promise<void> {
    if (tel.length && tel[0].captured_at <= t && t <= tel[tel.length - 1].captured_at) return;
    tel = await rec.telemetry(t - WINDOW_S, t + WINDOW_S);
  }

  /** Pause and show the recorded frame captured last at or before t, both cameras, with its telemetry. */
  async function showAt(at: number): Promise<void> {
    pause();
    const t = tl.snap(at);
    await telemetryAround(t);
    const i = indexAt(t);
    await showFrame(i >= 0 ? tel[i] : tel[0] ?? null, t);
  }

  /** Index of the last telemetry message captured at or before t (-1: none). */
  function indexAt(t: number): number {
    let i = -1;
    for (let k = 0; k < tel.length; k++) if (tel[k].captured_at <= t + 1e-6) i = k;
    return i;
  }

  /** One recorded frame back (-1) or forward (+1) from the frame shown. */
  async function step(dir: 1 | -1): Promise<void> {
    pause();
    const at = shown?.captured_at ?? cursor;
    await telemetryAround(at);
    let j = indexAt(at) + dir;
    if (j < 0 || j >= tel.length) {
      tel = await rec.telemetry(at - WINDOW_S, at + WINDOW_S);
      j = indexAt(at) + dir;
    }
    if (j >= 0 && j < tel.length) await showFrame(tel[j], tel[j].captured_at);
  }

  async function showFrame(m: FrameTelemetry | null, t: number): Promise<void> {
    const at = m?.captured_at ?? t;
    try {
      const frames = await Promise.all(CAMS.map((c) => playbackFrame(c, at)));
      CAMS.forEach((c, k) => {
        URL.revokeObjectURL(stills[c].src);
        stills[c].src = frames[k].url;
        stills[c].hidden = false;
        videos[c].classList.add("under");
        videos[c].currentTime = tl.video(at);
      });
      shown = m;
      cursor = frames[0].capturedAt;
      frameOut.textContent = String(frames[0].frame);
      clockOut.textContent = `${time(cursor)}.${String(Math.floor((cursor % 1) * 1000)).padStart(3, "0")}`;
      showTelemetry(m);
      msg.show("");
    } catch (e) {
      msg.show(`No frame at ${time(at)}: ${why(e)}`, "warn");
    }
    redraw();
  }

  function showTelemetry(m: FrameTelemetry | null): void {
    const d = m?.detections ?? [];
    const rows: [string, string][] = m ? [["Frame", String(m.frame)], ["Detections", String(d.length)],
      ["Primary", m.track_id != null ? `#${m.track_id}: r ${num(m.r, 2)} m, θ ${num(m.theta_deg, 2)}°, φ ${num(m.phi_deg, 2)}°`
        : "—"],
      ["Servo", m.servo ? `${m.servo.mode}, pan ${num(m.servo.pan_deg, 2)}°, tilt ${num(m.servo.tilt_deg, 2)}°` : "—"]]
      : [["Frame", "no telemetry"]];
    telOut.replaceChildren(...rows.flatMap(([k, v]) => [h("dt", null, k), h("dd", null, v)]));
  }

  function play(): void {
    for (const c of CAMS) {
      stills[c].hidden = true;
      videos[c].classList.remove("under");
      videos[c].playbackRate = Number(rate.value);
      void videos[c].play().catch(() => undefined);
    }
    shown = null;
    playBtn.textContent = "Pause";
    frameOut.textContent = "playing";
    const tick = () => {
      const w = tl.wall(videos.left.currentTime);
      if (w !== null) cursor = w;
      if (Math.abs(videos.right.currentTime - videos.left.currentTime) > 0.15) {
        videos.right.currentTime = videos.left.currentTime;
      }
      clockOut.textContent = time(cursor);
      redraw();
      raf = requestAnimationFrame(tick);
    };
    raf = requestAnimationFrame(tick);
  }

  function pause(): void {
    cancelAnimationFrame(raf);
    for (const c of CAMS) videos[c].pause();
    playBtn.textContent = "Play";
  }

  async function unlock(id: number): Promise<void> {
    try {
      await rec.unlock(id);
      const [bms, locks] = await Promise.all([rec.bookmarks(t0, t1), rec.locks(t0, t1)]);
      marks = { ...marks, bookmarks: bms, locks };
      showMarks(bms, locks);
      redraw();
    } catch (e) {
      msg.show(`Unlock failed: ${why(e)}`, "bad");
    }
  }

  async function evidence(kind: "bookmark" | "lock"): Promise<void> {
    try {
      if (kind === "bookmark") await rec.addBookmark(cursor, note.value.trim() || "bookmark");
      else await rec.addLock(t0, t1, note.value.trim());
      const [bms, locks] = await Promise.all([rec.bookmarks(t0, t1), rec.locks(t0, t1)]);
      marks = { ...marks, bookmarks: bms, locks };
      showMarks(bms, locks);
      msg.show(kind === "bookmark" ? "Bookmarked." : "The range is locked: retention keeps it until an admin unlocks it.",
        "ok");
      redraw();
    } catch (e) {
      msg.show(`${kind === "bookmark" ? "Bookmark" : "Lock"} failed: ${why(e)}`, "bad");
    }
  }

  async function exportRange(): Promise<void> {
    try {
      let job = await rec.exportRange(t0, t1);
      while (job.status === "queued" || job.status === "running") {
        exportOut.textContent = `Export ${job.id}: ${job.status} ${Math.round(job.progress * 100)} %`;
        await new Promise((r) => setTimeout(r, 500));
        job = await rec.exportJob(job.id);
      }
      exportOut.replaceChildren(job.status === "done"
        ? h("a", { href: rec.exportUrl(job.id), download: "", "data-testid": "export-link" }, `Download export ${job.id}`)
        : `Export ${job.id} failed: ${job.error ?? "unknown error"}`);
    } catch (e) {
      exportOut.textContent = `Export failed: ${why(e)}`;
    }
  }

  const queue = (fn: () => Promise<void>) => {
    stepping = stepping.then(fn, fn);
  };
  form.addEventListener("submit", (ev) => {
    ev.preventDefault();
    void load();
  });
  playBtn.addEventListener("click", () => (videos.left.paused ? play() : queue(() => showAt(cursor))));
  rate.addEventListener("change", () => CAMS.forEach((c) => { videos[c].playbackRate = Number(rate.value); }));
  back.addEventListener("click", () => queue(() => step(-1)));
  fwd.addEventListener("click", () => queue(() => step(1)));
  scrub.addEventListener("change", () => queue(() => showAt(t0 + Number(scrub.value) * (t1 - t0))));
  bmBtn.addEventListener("click", () => void evidence("bookmark"));
  lockBtn.addEventListener("click", () => void evidence("lock"));
  exportBtn.addEventListener("click", () => void exportRange());
  strip.addEventListener("click", (ev) => {
    const r = strip.getBoundingClientRect();
    queue(() => showAt(t0 + ((ev.clientX - r.left) / r.width) * (t1 - t0)));
  });
  const onKey = (ev: KeyboardEvent) => {
    const target = ev.target as HTMLElement | null;
    if (target && ["INPUT", "SELECT", "TEXTAREA"].includes(target.tagName) && target !== scrub) return;
    if (ev.key === ",") queue(() => step(-1));
    else if (ev.key === ".") queue(() => step(1));
    else return;
    ev.preventDefault();
  };
  document.addEventListener("keydown", onKey);
  syncRange();
  void load();
  return {
    unmount: () => {
      pause();
      plan.destroy();
      side.destroy();
      document.removeEventListener("keydown", onKey);
      for (const x of hls) x.destroy();
      for (const c of CAMS) URL.revokeObjectURL(stills[c].src);
    },
  };
}
