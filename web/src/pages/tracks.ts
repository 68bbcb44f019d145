// The Tracks page: tracks seen within a time range, and one track's trajectory (plan view, range and
// height against time).
import { api, errorText } from "../api/client";
import type { TrackDetail, TrackOut } from "../api/types";
import { field, h, notice } from "../lib/dom";
import { duration, fromLocalInput, num, time, toLocalInput } from "../lib/format";
import { MetricView, TimeView, type XY } from "../lib/plots";
import type { Page, PageContext } from "./types";

const LIMIT = 500;

/** A track's row: id, first seen, duration, detections, peak speed, size, closest range, and a button showing
 * its trajectory. */
function trackRow(t: TrackOut, show: (id: number) => Promise<void>): HTMLTableRowElement {
  return h("tr", { "data-track": String(t.id) },
    h("th", { scope: "row", title: `run ${t.run_id}, track ${t.track_no} of that run` }, `#${t.id}`),
    h("td", null, time(t.first_seen)), h("td", null, duration(t.last_seen - t.first_seen)),
    h("td", null, String(t.detections)), h("td", null, `${num(t.peak_speed_mps, 2)} m/s`),
    h("td", null, t.width_m != null ? `${num(t.width_m, 2)} × ${num(t.height_m, 2)} m` : "—"),
    h("td", null, t.min_range_m != null ? `${num(t.min_range_m, 1)} m` : "—"),
    h("td", null, h("button", { type: "button", class: "small", "aria-label": `Show trajectory of track ${t.id}`,
      onclick: () => void show(t.id) }, "Trajectory")));
}

/** One track's trajectory: its plan view, and range and height against time. */
function trackDetail(): { el: HTMLElement; show(id: number, rows: HTMLElement): Promise<void>; destroy(): void } {
  const title = h("h2", { id: "track-detail-title" }, "Trajectory");
  const info = h("p", { class: "muted", "data-testid": "track-detail" }, "Choose a track to see its trajectory.");
  const planEl = h("div", { class: "plot-box tall" });
  const timeEl = h("div", { class: "plot-box tall" });
  const el = h("section", { class: "panel", "aria-labelledby": "track-detail-title" }, title, info,
    h("div", { class: "track-plots" }, h("div", { class: "plot" }, planEl), h("div", { class: "plot" }, timeEl)));
  const plan = new MetricView(planEl, { title: "Plan view", xLabel: "x (m, right)", yLabel: "z (m, ahead)", minSpan: 4,
    series: [{ label: "trajectory", stroke: "#ffb020" }] });
  const tv = new TimeView(timeEl, "Range and height", "m", [{ label: "r (m)", stroke: "#ffb020" },
    { label: "height (m)", stroke: "#4fd1ff" }]);

  /** Show track id, its row in rows marked as selected. */
  async function show(id: number, rows: HTMLElement): Promise<void> {
    let t: TrackDetail;
    try {
      t = await api.track(id);
    } catch (e) {
      info.textContent = `Track ${id} could not be loaded: ${errorText(e)}`;
      return;
    }
    for (const tr of rows.querySelectorAll("tr")) tr.classList.toggle("selected", tr.dataset.track === String(id));
    title.textContent = `Trajectory of track #${t.id}`;
    info.textContent = `${t.trajectory.length} points from ${time(t.first_seen)} over ${duration(t.last_seen - t.first_seen)}; ` +
      `peak speed ${num(t.peak_speed_mps, 2)} m/s.`;
    const xy: XY = [t.trajectory.map((p) => p.x), t.trajectory.map((p) => p.z)];
    const last = t.trajectory[t.trajectory.length - 1];
    plan.setData([xy], [], last ? [{ x: last.x, y: last.z, color: "#ffb020", label: "end" }] : []);
    const t0 = t.trajectory[0]?.t ?? 0;
    tv.setData([t.trajectory.map((p) => p.t - t0), t.trajectory.map((p) => p.r), t.trajectory.map((p) => -p.y)]);
    // one column (tablet): bring the plot into view; side by side it is already there
    if (matchMedia("(max-width: 1100px)").matches) el.scrollIntoView({ block: "nearest" });
  }
  return { el, show, destroy: () => { plan.destroy(); tv.destroy(); } };
}

/** The time range form: a preset (the last 10 minutes to the last week) or custom from / to; syncRange: the
 * from / to fields follow the preset (enabled for a custom range only). */
function rangeForm(): { form: HTMLFormElement; start: HTMLInputElement; end: HTMLInputElement; syncRange(): void } {
  const now = Date.now() / 1000;
  const start = h("input", { type: "datetime-local", name: "start", value: toLocalInput(now - 3600) });
  const end = h("input", { type: "datetime-local", name: "end" });
  const range = h("select", { name: "range" },
    h("option", { value: "600" }, "Last 10 minutes"), h("option", { value: "3600" }, "Last hour"),
    h("option", { value: "86400" }, "Last day"), h("option", { value: "604800" }, "Last week"),
    h("option", { value: "custom" }, "Custom (from, to)"));
  range.value = "3600";
  const form = h("form", { class: "row-form" }, field("Time range", range), field("From", start), field("To", end,
    "empty: now"), h("button", { type: "submit", class: "primary" }, "Show tracks"));
  const syncRange = () => {
    const custom = range.value === "custom";
    start.disabled = !custom;
    end.disabled = !custom;
    if (!custom) {
      start.value = toLocalInput(Date.now() / 1000 - Number(range.value));
      end.value = "";
    }
  };
  range.addEventListener("change", syncRange);
  return { form, start, end, syncRange };
}

export function tracksPage(ctx: PageContext): Page {
  const { root } = ctx;
  const { form, start, end, syncRange } = rangeForm();
  const msg = notice("status");
  const tbody = h("tbody");
  const table = h("table", { class: "data" },
    h("caption", { class: "sr-only" }, "Tracks, newest first"),
    h("thead", null, h("tr", null, ...["Track", "First seen", "Duration", "Detections", "Peak speed", "Size (w × h)",
      "Closest", ""].map((c) => h("th", { scope: "col" }, c)))), tbody);
  const detail = trackDetail();
  root.replaceChildren(h("section", { class: "page wide" }, h("h1", null, "Tracks"), form, msg,
    h("div", { class: "tracks-layout" }, h("div", { class: "table-wrap scroll", tabindex: 0,
      "aria-label": "Tracks, newest first" }, table), detail.el)));

  syncRange();

  async function load(): Promise<void> {
    syncRange();
    msg.show("Loading…");
    let list: TrackOut[];
    try {
      list = await api.tracks(fromLocalInput(start.value), fromLocalInput(end.value), LIMIT);
    } catch (e) {
      msg.show(`Tracks could not be loaded: ${errorText(e)}`, "bad");
      return;
    }
    msg.show(list.length >= LIMIT ? `${list.length} tracks: the newest ${LIMIT} in this range (narrow it to see older ones)`
      : `${list.length} track${list.length === 1 ? "" : "s"}`, "ok");
    tbody.replaceChildren(...(list.length ? list.map((t) => trackRow(t, show))
      : [h("tr", null, h("td", { colSpan: 8, class: "muted" }, "No tracks in this range."))]));
  }

  const show = (id: number) => detail.show(id, tbody);

  form.addEventListener("submit", (ev) => {
    ev.preventDefault();
    void load();
  });
  void load().then(() => {
    const id = Number(ctx.params[0]);
    if (id) void show(id);
  });
  return { unmount: () => detail.destroy() };
}
