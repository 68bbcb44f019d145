// Jogging the mount from several inputs at once (arrow keys, the on-screen pad, a gamepad): each input
// sets its own rate vector; while the sum is non-zero a jog request of a short duration is sent every
// 250 ms (one request in flight at a time), and a zero-rate jog stops the mount when all are released.
import { api, ApiError } from "../api/client";

export type Vec = { pan: number; tilt: number };

export class JogController {
  private inputs = new Map<string, Vec>();
  private timer: number | undefined;
  private busy = false;
  private moving = false;
  private pendingStop = false;

  constructor(private readonly onError: (e: ApiError) => void, private readonly onSent?: (v: Vec) => void) {}

  set(source: string, v: Vec | null): void {
    if (!v || (v.pan === 0 && v.tilt === 0)) this.inputs.delete(source);
    else this.inputs.set(source, v);
    this.kick();
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
    if (this.busy) return;
    window.clearTimeout(this.timer);
    void this.send();
  }

  private async send(): Promise<void> {
    const v = this.sum();
    const zero = v.pan === 0 && v.tilt === 0;
    if (zero && !this.moving) return;
    this.busy = true;
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
    if (now.pan !== 0 || now.tilt !== 0) this.timer = window.setTimeout(() => void this.send(), 250);
    else if (this.moving || this.pendingStop) void this.send();
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
}
