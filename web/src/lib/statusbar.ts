// The status bar at the bottom of every page: the server's connection, fps, skipped frames, servo state
// and faults from GET /api/status (polled once a second), plus slots the pages fill (telemetry, video).
import { api, ApiError } from "../api/client";
import type { Status } from "../api/types";
import { h, clear } from "./dom";
import { num } from "./format";

type Tone = "ok" | "warn" | "bad" | "info";
type Listener = (s: Status | null, online: boolean) => void;

export class StatusBar {
  readonly el: HTMLElement;
  private server = h("span", { class: "sb-item", "data-testid": "sb-server" });
  private fps = h("span", { class: "sb-item", "data-testid": "sb-fps" });
  private skipped = h("span", { class: "sb-item", "data-testid": "sb-skipped" });
  private servo = h("span", { class: "sb-item", "data-testid": "sb-servo" });
  private faults = h("span", { class: "sb-item", "data-testid": "sb-faults" });
  private slots = h("span", { class: "sb-slots" });
  private slotEls = new Map<string, HTMLElement>();
  private timer: number | undefined;
  private listeners = new Set<Listener>();
  last: Status | null = null;
  online = false;
  failures = 0;

  constructor() {
    this.el = h("footer", { class: "statusbar", "aria-label": "Status" },
      this.server, this.fps, this.skipped, this.servo, this.faults, this.slots);
    this.set(this.server, "Server: connecting…", "info");
  }

  start(): void {
    if (this.timer !== undefined) return;
    const tick = async () => {
      await this.poll();
      this.timer = window.setTimeout(tick, this.online ? 1000 : 2000);
    };
    void tick();
  }

  stop(): void {
    window.clearTimeout(this.timer);
    this.timer = undefined;
  }

  subscribe(fn: Listener): () => void {
    this.listeners.add(fn);
    if (this.last) fn(this.last, this.online);
    return () => this.listeners.delete(fn);
  }

  private async poll(): Promise<void> {
    try {
      const s = await api.status();
      this.last = s;
      this.online = true;
      this.failures = 0;
      this.render(s);
    } catch (e) {
      if (e instanceof ApiError && e.status === 401) return; // the app shows the login page
      this.online = false;
      this.failures += 1;
      this.set(this.server, `Server: unreachable, retrying (${this.failures})`, "bad");
    }
    this.listeners.forEach((fn) => fn(this.last, this.online));
  }

  private render(s: Status): void {
    const running = s.state === "running";
    this.set(this.server, `Server: connected, tracker ${s.state}`, running ? "ok" : "warn");
    this.set(this.fps, `${num(s.fps, 1)} fps`, s.fps > 0 ? "ok" : "warn");
    this.set(this.skipped, `Skipped frames: ${s.skipped_frames}`, s.skipped_frames > 0 ? "warn" : "ok");
    const sv = s.servo;
    const servoText = sv.configured === false || !sv.mode
      ? "Servo: none"
      : `Servo: ${sv.mode}, pan ${num(sv.pan_deg, 1)}°, tilt ${num(sv.tilt_deg, 1)}°${sv.fault ? `, fault: ${sv.fault}` : ""}`;
    this.set(this.servo, servoText, sv.fault ? "bad" : "ok");
    const faults = s.faults.map((f) => `${f.kind}: ${f.message}`);
    this.set(this.faults, faults.length ? `Faults: ${faults.join("; ")}` : "No faults", faults.length ? "bad" : "ok");
  }

  private set(el: HTMLElement, text: string, tone: Tone): void {
    el.textContent = text;
    el.dataset.tone = tone;
  }

  /** A page's own item (e.g. "Telemetry: connected"); null removes it. */
  slot(name: string, text: string | null, tone: Tone = "info"): void {
    let el = this.slotEls.get(name);
    if (text === null) {
      el?.remove();
      this.slotEls.delete(name);
      return;
    }
    if (!el) {
      el = h("span", { class: "sb-item", "data-testid": `sb-${name}` });
      this.slotEls.set(name, el);
      this.slots.appendChild(el);
    }
    this.set(el, text, tone);
  }

  clearSlots(): void {
    clear(this.slots);
    this.slotEls.clear();
  }
}
