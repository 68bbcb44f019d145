// The Live page's readouts: the primary target's frame, r, θ, φ with their 1-σ, speed, heading and
// position, the mount's state, and the list of detections (each can be made the primary target).
import { api } from "../api/client";
import type { ServoStatus, Telemetry } from "../api/types";
import { h } from "../lib/dom";
import { num } from "../lib/format";
import { motionOf } from "../lib/telemetry";
import type { LiveState } from "./live_state";

type Act = (fn: () => Promise<unknown>, what: string) => Promise<boolean>;

/** The DOM is updated at most every DOM_MS, however fast telemetry or video frames come. */
const DOM_MS = 100;

export class Readouts {
  readonly el: HTMLElement;
  private readonly dd: Record<string, HTMLElement> = {};
  private readonly detList = h("ul", { class: "det-list", "aria-label": "Detections" });
  private lastDom = 0;

  constructor(private readonly state: LiveState, private readonly act: Act) {
    const rows = [["frame", "Frame"], ["target", "Primary"], ["r", "r"], ["theta", "θ"], ["phi", "φ"],
      ["speed", "Speed"], ["heading", "Heading"], ["xyz", "x, y, z"], ["servo", "Mount"]].flatMap(([key, label]) => {
      this.dd[key] = h("dd", { "data-testid": `ro-${key}` }, "—");
      return [h("dt", null, label), this.dd[key]];
    });
    this.el = h("section", { class: "panel readouts", "aria-labelledby": "ro-title" },
      h("h2", { id: "ro-title" }, "Target"), h("dl", null, ...rows), h("h3", null, "Detections"), this.detList);
  }

  /** render(), unless the DOM was updated less than DOM_MS ago. */
  maybeRender(tel: Telemetry, sync: string): void {
    const now = performance.now();
    if (now - this.lastDom <= DOM_MS) return;
    this.lastDom = now;
    this.render(tel, sync);
  }

  private render(tel: Telemetry, sync: string): void {
    const m = motionOf(this.state.buffer.before(tel, 0.6));
    const set = (key: string, text: string) => { this.dd[key].textContent = text; };
    set("frame", `${tel.frame} · ${sync}`);
    set("target", tel.detected && tel.track_id !== null ? `#${tel.track_id}` : "none");
    set("r", tel.r != null ? `${num(tel.r, 2)} ± ${num(tel.sigma_r, 3)} m` : "—");
    set("theta", tel.theta_deg != null ? `${num(tel.theta_deg, 2)} ± ${num(tel.sigma_theta_deg, 3)}°` : "—");
    set("phi", tel.phi_deg != null ? `${num(tel.phi_deg, 2)} ± ${num(tel.sigma_phi_deg, 3)}°` : "—");
    set("speed", m ? `${num(m.speed, 2)} m/s` : "—");
    set("heading", m && m.speed > 0.1 ? `${num(m.heading, 0)}° (0° = away from the rig, 90° = right)` : "—");
    set("xyz", tel.x != null ? `${num(tel.x, 2)}, ${num(tel.y, 2)}, ${num(tel.z, 2)} m` : "—");
    this.renderDetections(tel);
  }

  showServo(servo: ServoStatus): void {
    this.dd.servo.textContent = servo.mode
      ? `${servo.mode}, pan ${num(servo.pan_deg, 2)}°, tilt ${num(servo.tilt_deg, 2)}°${servo.fault ? `, fault: ${servo.fault}` : ""}`
      : "no servo";
  }

  private renderDetections(tel: Telemetry): void {
    const dets = tel.detections ?? [];
    const ids = dets.map((d) => `${d.track_id}:${tel.track_id === d.track_id}`).join(",");
    if (this.detList.dataset.ids === ids) return;
    this.detList.dataset.ids = ids;
    this.detList.replaceChildren(...(dets.length ? dets.map((d) => h("li", null,
      h("span", null, `#${d.track_id}${d.track_id === tel.track_id ? " (primary)" : ""} `),
      h("span", { class: "muted" }, `${num(d.r, 1)} m`),
      d.track_id !== tel.track_id && this.state.canDrive
        ? h("button", { type: "button", class: "small", onclick: () => void this.act(() => api.makePrimary(d.track_id),
          `Primary target #${d.track_id}`) }, "Make primary") : null))
      : [h("li", { class: "muted" }, "none")]));
  }
}
