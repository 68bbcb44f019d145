// The Playback page's replays: the tracker re-run on the loaded range (POST /api/replays, operator) with
// another threshold, and a selector of the finished replays overlapping the range whose trajectories the
// page draws beside the live ones (in another colour), with the replay's agreement with the live result.
import { api, errorText, request } from "../api/client";
import type { components } from "../api/schema";
import { field, h } from "../lib/dom";
import { num, time } from "../lib/format";

type Replay = components["schemas"]["ReplayOut"];
export type TrackDetail = components["schemas"]["TrackDetail"];

const MAX_TRACKS = 40;

export interface ReplayPanel {
  el: HTMLElement;
  /** List the replays overlapping t0..t1 (keeps the selection when it still overlaps). */
  load(t0: number, t1: number): Promise<void>;
}

/** A replay in a few words: its threshold and rig, and its agreement with the live result. */
function describe(r: Replay): string {
  const a = r.agreement;
  const agree = a && a.frames ? `, same detection in ${num(100 * Number(a.same_detected), 1)} % of ${a.frames} frames`
    + (a.range_diff_median_m != null ? `, |Δr| median ${num(Number(a.range_diff_median_m), 3)} m` : "") : "";
  return `Replay ${r.id} (ε ${String(r.settings.threshold)}, ${String(r.settings.rig)})${agree}`;
}

/** The tracks of replay id within t0..t1 (at most MAX_TRACKS; those that cannot be loaded left out). */
async function replayTracks(id: number, t0: number, t1: number): Promise<TrackDetail[]> {
  const list = await request<{ id: number }[]>("GET", "/api/tracks",
    { query: { start: t0, end: t1, replay: id, limit: MAX_TRACKS } });
  const tracks = await Promise.all(list.map((t) => api.track(t.id).catch(() => null)));
  return tracks.filter((t): t is TrackDetail => t !== null);
}

/** Start a replay (body: its range and threshold) and wait until it ends, its progress shown in out. */
async function runReplay(body: Record<string, number>, out: HTMLElement): Promise<Replay> {
  let job = await request<Replay>("POST", "/api/replays", { body });
  while (job.status === "queued" || job.status === "running") {
    out.textContent = `Replay ${job.id}: ${job.status} ${Math.round(job.progress * 100)} %`;
    await new Promise((r) => setTimeout(r, 700));
    job = await request<Replay>("GET", `/api/replays/${job.id}`);
  }
  return job;
}

export function replayPanel(operator: boolean, draw: (tracks: TrackDetail[]) => void): ReplayPanel {
  const select = h("select", { name: "replay", "aria-label": "Replay shown" }, h("option", { value: "" }, "none"));
  const threshold = h("input", { type: "number", name: "threshold", min: 1, max: 254, placeholder: "live",
    disabled: !operator });
  const runBtn = h("button", { type: "button", disabled: !operator }, "Re-run the tracker on the range");
  const out = h("p", { class: "muted", "data-testid": "replay-status", "aria-live": "polite" });
  const el = h("section", { class: "panel" }, h("h2", null, "Replays (the tracker re-run on the recording)"),
    field("Shown (magenta)", select), field("Threshold ε", threshold, "empty: the live one"), runBtn, out);
  let t0 = 0, t1 = 0;
  let replays: Replay[] = [];

  async function show(): Promise<void> {
    const r = replays.find((x) => String(x.id) === select.value);
    out.textContent = r ? describe(r) : "";
    if (!r) return draw([]);
    draw(await replayTracks(r.id, t0, t1));
  }

  async function load(a: number, b: number): Promise<void> {
    t0 = a; t1 = b;
    const keep = select.value;
    try {
      replays = operator ? (await request<Replay[]>("GET", "/api/replays"))
        .filter((r) => r.status === "done" && r.start <= b && r.end >= a) : [];
    } catch {
      replays = [];
    }
    select.replaceChildren(h("option", { value: "" }, "none"), ...replays.map((r) =>
      h("option", { value: String(r.id) }, `${r.id}: ${time(r.start)} – ${time(r.end)}, ε ${String(r.settings.threshold)}`)));
    select.value = replays.some((r) => String(r.id) === keep) ? keep : "";
    await show();
  }

  async function run(): Promise<void> {
    const body: Record<string, number> = { start: t0, end: t1 };
    if (threshold.value) body.threshold = Number(threshold.value);
    try {
      const job = await runReplay(body, out);
      if (job.status === "failed") {
        out.textContent = `Replay ${job.id} failed: ${job.error ?? ""}`;
        return;
      }
      await load(t0, t1);
      select.value = String(job.id);
      await show();
    } catch (e) {
      out.textContent = `Replay failed: ${errorText(e)}`;
    }
  }

  select.addEventListener("change", () => void show());
  runBtn.addEventListener("click", () => void run());
  return { el, load };
}
