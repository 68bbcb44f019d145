// Telemetry of the last few seconds keyed by the RTP timestamp of the frame it belongs to, so that the
// overlay drawn on a video frame is that frame's: rtpTimestamp = round(captured_at * 90000) mod 2^32.
import type { Telemetry } from "../api/types";

export const RTP_CLOCK = 90000;
const WRAP = 2 ** 32;

export function rtpKey(capturedAt: number): number {
  const k = Math.round(capturedAt * RTP_CLOCK) % WRAP;
  return k < 0 ? k + WRAP : k;
}

/** Signed difference a - b of two 32-bit RTP timestamps, in (-2^31, 2^31]. */
export function rtpDiff(a: number, b: number): number {
  let d = (a - b) % WRAP;
  if (d > WRAP / 2) d -= WRAP;
  if (d <= -WRAP / 2) d += WRAP;
  return d;
}

export interface Match {
  msg: Telemetry;
  /** frame's timestamp minus the message's, in RTP ticks (0: exact). */
  offsetTicks: number;
}

export class TelemetryBuffer {
  private byKey = new Map<number, Telemetry>();
  private order: Telemetry[] = [];
  latest: Telemetry | null = null;

  constructor(readonly keepS = 3, readonly toleranceTicks = 1500) {}

  push(msg: Telemetry): void {
    this.latest = msg;
    this.order.push(msg);
    this.byKey.set(rtpKey(msg.captured_at), msg);
    const oldest = msg.captured_at - this.keepS;
    while (this.order.length && this.order[0].captured_at < oldest) {
      const old = this.order.shift()!;
      const k = rtpKey(old.captured_at);
      if (this.byKey.get(k) === old) this.byKey.delete(k);
    }
  }

  clear(): void {
    this.byKey.clear();
    this.order = [];
    this.latest = null;
  }

  get size(): number {
    return this.order.length;
  }

  /** The message whose key equals `rtpTimestamp`, else the nearest within the tolerance, else null. */
  match(rtpTimestamp: number): Match | null {
    const exact = this.byKey.get(rtpTimestamp >>> 0);
    if (exact) return { msg: exact, offsetTicks: 0 };
    let best: Match | null = null;
    for (const m of this.order) {
      const d = rtpDiff(rtpTimestamp, rtpKey(m.captured_at));
      if (Math.abs(d) <= this.toleranceTicks && (!best || Math.abs(d) < Math.abs(best.offsetTicks)))
        best = { msg: m, offsetTicks: d };
    }
    return best;
  }

  /** Messages captured within `windowS` before `msg` (inclusive), oldest first. */
  before(msg: Telemetry, windowS: number): Telemetry[] {
    return this.order.filter((m) => m.captured_at <= msg.captured_at && m.captured_at >= msg.captured_at - windowS);
  }
}

export interface Motion {
  speed: number; // m/s in the horizontal plane (x, z)
  heading: number; // degrees, 0 along +z (away from the rig), positive to the right (+x)
}

/** Speed and heading of the primary target from successive x, z of `history` (oldest first): the line
 * from the first to the last sample of the same track within the window. Null with too little data. */
export function motionOf(history: Telemetry[], minSpanS = 0.2): Motion | null {
  const last = history[history.length - 1];
  if (!last || last.track_id === null || last.x == null || last.z == null) return null;
  let first: Telemetry | null = null;
  for (const m of history) {
    if (m.track_id === last.track_id && m.x != null && m.z != null) {
      first = m;
      break;
    }
  }
  if (!first) return null;
  const dt = last.captured_at - first.captured_at;
  if (dt < minSpanS) return null;
  const dx = last.x - first.x!;
  const dz = last.z - first.z!;
  const speed = Math.hypot(dx, dz) / dt;
  let heading = (Math.atan2(dx, dz) * 180) / Math.PI;
  if (heading < 0) heading += 360;
  return { speed, heading };
}
