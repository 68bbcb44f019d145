// The recorded timeline of a range: segments laid end to end as the HLS player sees them (each file a
// discontinuity, its duration = last frame - first frame + one frame period), mapped to and from wall-clock
// time; and a canvas strip drawing the recorded spans, tracks, bookmarks and locks.
import type { Segment } from "../api/recordings";

export interface Span { start: number; end: number; offset: number; dur: number }

export class Timeline {
  readonly spans: Span[] = [];

  constructor(segments: Segment[]) {
    let offset = 0;
    for (const s of [...segments].sort((a, b) => a.start - b.start)) {
      if (s.end == null || s.frames < 1) continue;
      const period = s.frames > 1 ? (s.end - s.start) / (s.frames - 1) : 1 / 30;
      const dur = s.end - s.start + period;
      this.spans.push({ start: s.start, end: s.start + dur, offset, dur });
      offset += dur;
    }
  }

  get duration(): number {
    const last = this.spans[this.spans.length - 1];
    return last ? last.offset + last.dur : 0;
  }

  /** Wall-clock time (Unix s) of a player position (s). */
  wall(videoT: number): number | null {
    for (const s of this.spans) if (videoT < s.offset + s.dur) return s.start + Math.max(videoT - s.offset, 0);
    const last = this.spans[this.spans.length - 1];
    return last ? last.end : null;
  }

  /** t itself when recorded, else the start of the next recorded span (or the end of the last). */
  snap(t: number): number {
    for (const s of this.spans) {
      if (t < s.start) return s.start;
      if (t < s.end) return t;
    }
    const last = this.spans[this.spans.length - 1];
    return last ? last.end - 1e-3 : t;
  }

  /** Player position (s) of a wall-clock time; a time in a gap goes to the next recorded span. */
  video(t: number): number {
    for (const s of this.spans) {
      if (t < s.start) return s.offset;
      if (t < s.end) return s.offset + (t - s.start);
    }
    return this.duration;
  }
}

export interface Marks {
  tracks: { first_seen: number; last_seen: number }[];
  bookmarks: { t: number }[];
  locks: { start: number; end: number }[];
  /** alarms: from activation to clearing (open ones to the range's end), coloured by priority */
  alarms: { activated_at: number; cleared_at: number | null; priority: string }[];
}

const PRIORITY_COLOUR: Record<string, string> = { critical: "#ff4d4d", high: "#ffb020", medium: "#c9a0ff",
  low: "#8fa3b8" };

/** Draw the strip for [t0, t1] with the cursor at `at` (all Unix s). */
export function drawStrip(c: HTMLCanvasElement, tl: Timeline, t0: number, t1: number, at: number, m: Marks): void {
  const w = (c.width = c.clientWidth * devicePixelRatio);
  const hgt = (c.height = c.clientHeight * devicePixelRatio);
  const g = c.getContext("2d")!;
  const x = (t: number) => ((t - t0) / Math.max(t1 - t0, 1e-6)) * w;
  g.fillStyle = "#1c2430";
  g.fillRect(0, 0, w, hgt);
  g.fillStyle = "#2f8f5b";
  for (const s of tl.spans) g.fillRect(x(s.start), hgt * 0.3, Math.max(x(s.end) - x(s.start), 1), hgt * 0.4);
  g.fillStyle = "rgba(255,176,32,0.8)";
  for (const t of m.tracks) g.fillRect(x(t.first_seen), 0, Math.max(x(t.last_seen) - x(t.first_seen), 2), hgt * 0.2);
  g.fillStyle = "rgba(79,209,255,0.35)";
  for (const l of m.locks) g.fillRect(x(l.start), hgt * 0.75, Math.max(x(l.end) - x(l.start), 2), hgt * 0.25);
  for (const a of m.alarms) {
    g.fillStyle = PRIORITY_COLOUR[a.priority] ?? "#ff4d4d";
    const end = a.cleared_at ?? t1;
    g.fillRect(x(a.activated_at), hgt * 0.2, Math.max(x(end) - x(a.activated_at), 2), hgt * 0.1);
    g.fillRect(x(a.activated_at) - devicePixelRatio, 0, 2 * devicePixelRatio, hgt * 0.3);
  }
  g.fillStyle = "#e14eca";
  for (const b of m.bookmarks) g.fillRect(x(b.t) - 1, 0, 3 * devicePixelRatio, hgt);
  g.fillStyle = "#ffffff";
  g.fillRect(x(at) - devicePixelRatio, 0, 2 * devicePixelRatio, hgt);
}
