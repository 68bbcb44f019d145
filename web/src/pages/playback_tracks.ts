// The Playback page's tracks: plan and side views of the trajectories of the tracks in the range, and
// beside them those of a replay of the range (playback_replay.ts), in another colour.
import { api } from "../api/client";
import { h } from "../lib/dom";
import { MetricView, type XY } from "../lib/plots";
import { replayPanel, type TrackDetail } from "./playback_replay";

const MAX_TRACKS = 40; // trajectories drawn for a range

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

export interface TracksPanels {
  /** the tracks' panel and the replays' */
  els: HTMLElement[];
  /** Draw the trajectories of the range's tracks (ids, the first MAX_TRACKS) and list its replays. */
  load(t0: number, t1: number, ids: number[]): void;
  destroy(): void;
}

export function tracksPanels(operator: boolean): TracksPanels {
  const planEl = h("div", { class: "plot-box tall" });
  const sideEl = h("div", { class: "plot-box tall" });
  const panel = h("section", { class: "panel" }, h("h2", null, "Tracks in the range (3-D: plan and side views)"),
    h("div", { class: "track-plots" }, h("div", { class: "plot" }, planEl), h("div", { class: "plot" }, sideEl)));
  const plan = new MetricView(planEl, { title: "Plan view", xLabel: "x (m, right)", yLabel: "z (m, ahead)", minSpan: 4,
    series: [{ label: "trajectories", stroke: "#ffb020" }, { label: "replay", stroke: "#e040fb" }] });
  const side = new MetricView(sideEl, { title: "Side view", xLabel: "z (m, ahead)", yLabel: "height (m)", minSpan: 2,
    series: [{ label: "trajectories", stroke: "#4fd1ff" }, { label: "replay", stroke: "#e040fb" }] });
  let live: XY[] = [[[], []], [[], []]], replayed: XY[] = [[[], []], [[], []]];
  const draw = () => {
    plan.setData([live[0], replayed[0]], [], []);
    side.setData([live[1], replayed[1]], [], []);
  };
  const replays = replayPanel(operator, (tracks) => {
    replayed = views(tracks);
    draw();
  });

  async function trajectories(ids: number[]): Promise<void> {
    const tracks = await Promise.all(ids.slice(0, MAX_TRACKS).map((id) => api.track(id).catch(() => null)));
    live = views(tracks.filter((t): t is TrackDetail => t !== null));
    draw();
  }

  return {
    els: [panel, replays.el],
    load(t0, t1, ids) {
      void trajectories(ids);
      void replays.load(t0, t1);
    },
    destroy() {
      plan.destroy();
      side.destroy();
    },
  };
}
