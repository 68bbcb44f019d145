// Jogging the mount from several inputs at once (arrow keys, the on-screen pad, a gamepad): each input
// sets its own rate vector; while the sum is non-zero a jog request of a short duration is sent every
// 250 ms (one request in flight at a time), and a zero-rate jog stops the mount when all are released.
// A change of rate is sent at once, but no sooner than MIN_GAP_MS after the previous request (an analog
// stick polled every animation frame changes a little each time); a stop is always sent at once.
// halt() stops every input and resolves once the server has answered the last jog request, so that a
// command sent after it (a mode, a go-to) reaches the server after the stop and is not undone by it.
import { api, ApiError } from "../api/client";

export type Vec = { pan: number; tilt: number };

const MIN_GAP_MS = 100;

export class JogController {
  private inputs = new Map<string, Vec>();
  private timer: number | undefined;
  private busy = false;
  private moving = false;
  private lastSent = -Infinity;
  private flight: Promise<void> | null = null; // the jog request in flight and what it sends next

  constructor(private readonly onError: (e: ApiError) => void, private readonly onSent?: (v: Vec) => void) {}

  set(source: string, v: Vec | null): void {
    const before = this.sum();
    if (!v || (v.pan === 0 && v.tilt === 0)) this.inputs.delete(source);
    else this.inputs.set(source, v);
    const after = this.sum();
    if (after.pan !== before.pan || after.tilt !== before.tilt) this.kick();
  }

  get active(): boolean {
    return this.inputs.size > 0;
  }

  private sum(): Vec {
    let pan = 0, tilt = 0;
    for (const v of this.inputs.values()) {
      pan += v.pan;
      tilt += v.tilt;
    }
    const clamp = (x: number) => Math.max(-180, Math.min(180, x));
    return { pan: clamp(pan), tilt: clamp(tilt) };
  }

  private kick(): void {
    if (this.busy) return; // the request in flight sends the new rates when it is answered
    window.clearTimeout(this.timer);
    const v = this.sum();
    const wait = v.pan === 0 && v.tilt === 0 ? 0 : this.lastSent + MIN_GAP_MS - performance.now();
    if (wait <= 0) this.run();
    else this.timer = window.setTimeout(() => this.run(), wait);
  }

  private run(): void {
    const p: Promise<void> = this.send().finally(() => {
      if (this.flight === p) this.flight = null;
    });
    this.flight = p;
  }

  private async send(): Promise<void> {
    const v = this.sum();
    const zero = v.pan === 0 && v.tilt === 0;
    if (zero && !this.moving) return;
    this.busy = true;
    this.lastSent = performance.now();
    try {
      await api.jog({ pan_dps: v.pan, tilt_dps: v.tilt, duration_s: zero ? 0.05 : 0.6 });
      this.moving = !zero;
      this.onSent?.(v);
    } catch (e) {
      if (e instanceof ApiError) this.onError(e);
      if (e instanceof ApiError && (e.status === 403 || e.status === 401)) this.inputs.clear();
      this.moving = !zero;
    } finally {
      this.busy = false;
    }
    const now = this.sum();
    if (now.pan !== v.pan || now.tilt !== v.tilt) this.kick(); // changed while the request was in flight
    else if (now.pan !== 0 || now.tilt !== 0) this.timer = window.setTimeout(() => this.run(), 250);
  }

  /** A single short move (keyboard Enter/Space on a pad button). */
  async pulse(v: Vec, duration = 0.5): Promise<void> {
    try {
      await api.jog({ pan_dps: v.pan, tilt_dps: v.tilt, duration_s: duration });
      this.onSent?.(v);
    } catch (e) {
      if (e instanceof ApiError) this.onError(e);
    }
  }

  stopAll(): void {
    this.inputs.clear();
    window.clearTimeout(this.timer);
    if (this.moving) this.kick();
  }

  /** stopAll(), then wait until the server has answered every jog request, the stop included. */
  async halt(): Promise<void> {
    this.stopAll();
    while (this.flight) await this.flight;
  }
}
