// The Live page's plan and side views of the last minute's tracks (metres), with the alarm zones and the
// cameras' field of view at the mount's pan and tilt.
import { api } from "../api/client";
import type { Telemetry } from "../api/types";
import { h } from "../lib/dom";
import { num } from "../lib/format";
import { MetricView, type Wedge, type XY } from "../lib/plots";
import { zoneOutlines } from "../lib/zones";
import type { LiveState } from "./live_state";

const HISTORY_S = 60;
const PRIMARY = "#ffb020", OTHER = "#4fd1ff";

type Point = { t: number; x: number; y: number; z: number };
type Head = { x: number; y: number; color: string; label: string };

export class TrackPlots {
  readonly el: HTMLElement;
  private readonly plan: MetricView;
  private readonly side: MetricView;
  private readonly history = new Map<number, Point[]>();
  private primaryId: number | null = null;
  private zones: XY = [[], []];
  private readonly timers: number[];
  /** the wedges' labels as text, for screen readers (the plots are canvases) */
  private readonly fovText = [h("p", { class: "sr-only", "data-testid": "fov-plan" }),
    h("p", { class: "sr-only", "data-testid": "fov-side" })];

  constructor(private readonly state: LiveState) {
    const planEl = h("div", { class: "plot-box" });
    const sideEl = h("div", { class: "plot-box" });
    this.el = h("div", { class: "plots" },
      h("section", { class: "panel plot", "aria-label": "Plan view of the last minute (metres)" }, planEl, this.fovText[0]),
      h("section", { class: "panel plot", "aria-label": "Side view of the last minute (metres)" }, sideEl, this.fovText[1]));
    this.plan = new MetricView(planEl, { title: "Plan view (last minute)", xLabel: "x (m, right)",
      yLabel: "z (m, ahead)", minSpan: 6, include: [[0, 0], [0, 6]],
      series: [{ label: "primary", stroke: PRIMARY }, { label: "other targets", stroke: OTHER, width: 1.5 },
        { label: "alarm zones", stroke: "#ff6b6b", width: 1.5 }] });
    this.side = new MetricView(sideEl, { title: "Side view (last minute)", xLabel: "ground range (m)",
      yLabel: "height (m, up)", minSpan: 3, include: [[0, 0], [6, 0]],
      series: [{ label: "primary", stroke: PRIMARY }, { label: "other targets", stroke: OTHER, width: 1.5 }] });
    void this.loadZones();
    this.timers = [window.setInterval(() => void this.loadZones(), 5000), window.setInterval(() => this.redraw(), 250)];
  }

  dispose(): void {
    for (const t of this.timers) window.clearInterval(t);
    this.plan.destroy();
    this.side.destroy();
  }

  /** A telemetry message: each detection's position kept at up to 10 Hz. */
  push(msg: Telemetry): void {
    this.primaryId = msg.track_id;
    for (const d of msg.detections ?? []) {
      let pts = this.history.get(d.track_id);
      if (!pts) this.history.set(d.track_id, (pts = []));
      const last = pts[pts.length - 1];
      if (!last || msg.captured_at - last.t >= 0.1) pts.push({ t: msg.captured_at, x: d.x, y: d.y, z: d.z });
    }
  }

  private async loadZones(): Promise<void> {
    try {
      this.zones = zoneOutlines(await api.alarmRules());
    } catch {
      /* keep the zones drawn last */
    }
  }

  private redraw(): void {
    const now = this.state.buffer.latest?.captured_at ?? Date.now() / 1000;
    const prim: XY = [[], []], others: XY = [[], []];
    const sPrim: XY = [[], []], sOthers: XY = [[], []];
    const headsPlan: Head[] = [], headsSide: Head[] = [];
    for (const [id, pts] of this.history) {
      while (pts.length && pts[0].t < now - HISTORY_S) pts.shift();
      if (!pts.length) {
        this.history.delete(id);
        continue;
      }
      const isPrim = id === this.primaryId;
      const [pp, ss] = isPrim ? [prim, sPrim] : [others, sOthers];
      for (const p of pts) {
        pp[0].push(p.x); pp[1].push(p.z);
        ss[0].push(Math.hypot(p.x, p.z)); ss[1].push(-p.y);
      }
      pp[0].push(null); pp[1].push(null); ss[0].push(null); ss[1].push(null);
      const last = pts[pts.length - 1];
      if (now - last.t < 1.0) {
        const color = isPrim ? PRIMARY : OTHER;
        headsPlan.push({ x: last.x, y: last.z, color, label: `#${id}` });
        headsSide.push({ x: Math.hypot(last.x, last.z), y: -last.y, color, label: `#${id}` });
      }
    }
    const [planWedge, sideWedge] = this.wedges();
    [planWedge, sideWedge].forEach((w, k) => {
      const text = w?.label ?? "Field of view not known yet";
      if (this.fovText[k].textContent !== text) this.fovText[k].textContent = text;
    });
    this.plan.setData([prim, others, this.zones], planWedge ? [planWedge] : [], headsPlan);
    this.side.setData([sPrim, sOthers], sideWedge ? [sideWedge] : [], headsSide);
  }

  /** The left camera's field of view in the plan (about the pan) and the side view (about the tilt), from the
   * rig in use (the status gives it); none until it is known. */
  private wedges(): [Wedge | null, Wedge | null] {
    const fov = this.state.fovDeg;
    if (!fov) return [null, null];
    const pan = this.state.servo?.pan_deg ?? 0, tilt = this.state.servo?.tilt_deg ?? 0;
    return [{ centreDeg: pan, halfDeg: fov[0] / 2, label: `FOV ${num(fov[0], 0)}°, pan ${num(pan, 1)}°` },
      { centreDeg: tilt, halfDeg: fov[1] / 2, fromHorizontal: true, label: `FOV ${num(fov[1], 0)}°, tilt ${num(tilt, 1)}°` }];
  }
}
