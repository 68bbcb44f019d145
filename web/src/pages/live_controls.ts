// The Live page's mount controls: the servo mode, jogging by the on-screen pad, the arrow keys and a
// gamepad, go-to, presets, and the commands the pictures send (point there, make a detection primary).
// Every command that moves the mount or sets its mode waits for jogging to stop first (drive()).
import { api, ApiError } from "../api/client";
import type { Preset, ServoMode, ServoStatus } from "../api/types";
import { field, h, notice } from "../lib/dom";
import { num } from "../lib/format";
import { JogController, type Vec } from "../lib/jog";
import type { Camera, LiveState } from "./live_state";

const MODES: ServoMode[] = ["auto", "manual", "hold", "home"];
const MODE_HELP: Record<ServoMode, string> = {
  auto: "Auto: follow the primary target",
  manual: "Manual: stay at the operator's angles",
  hold: "Hold: stop where it is",
  home: "Home: go to the home position",
};
const KEYS: Record<string, Vec> = { ArrowUp: { pan: 0, tilt: 1 }, ArrowDown: { pan: 0, tilt: -1 },
  ArrowLeft: { pan: -1, tilt: 0 }, ArrowRight: { pan: 1, tilt: 0 } };
const PAD: [string, string, string, Vec][] = [
  ["up", "Tilt up", "▲", { pan: 0, tilt: 1 }], ["left", "Pan left", "◀", { pan: -1, tilt: 0 }],
  ["right", "Pan right", "▶", { pan: 1, tilt: 0 }], ["down", "Tilt down", "▼", { pan: 0, tilt: -1 }],
];

const typing = (t: EventTarget | null) => t instanceof HTMLElement &&
  (t.isContentEditable || ["INPUT", "SELECT", "TEXTAREA"].includes(t.tagName));

export class MountControls {
  readonly el: HTMLElement;
  private readonly msg = notice("status");
  private readonly jog = new JogController((e) => this.showError(e, "Jog"));
  private readonly modeButtons: HTMLButtonElement[];
  private readonly speed = h("input", { type: "range", min: 1, max: 90, step: 1, name: "jog-speed" });
  private readonly presetList = h("ul", { class: "preset-list", "aria-label": "Presets" });
  private readonly gamepadState = h("p", { class: "muted small", "data-testid": "gamepad" }, "Gamepad: none connected");
  private readonly cleanups: (() => void)[] = [];

  /** onServo: the mount's state changed (a command's answer, telemetry, the status). */
  constructor(private readonly state: LiveState, private readonly onServo: (s: ServoStatus) => void) {
    this.modeButtons = MODES.map((m) => h("button", { type: "button", class: "mode", "aria-pressed": "false",
      title: MODE_HELP[m], "data-mode": m, onclick: () => void this.drive(() => api.setMode(m), `Mode ${m}`) },
      m[0].toUpperCase() + m.slice(1)));
    const reasonId = "drive-reason";
    const fieldset = h("fieldset", { class: "controls-set", disabled: !state.canDrive,
      "aria-describedby": state.canDrive ? undefined : reasonId },
      h("legend", { class: "sr-only" }, "Mount control"),
      h("div", { class: "ctl-block" }, h("h3", null, "Mode"),
        h("div", { class: "modes", role: "group", "aria-label": "Servo mode" }, ...this.modeButtons)),
      this.jogBlock(),
      h("div", { class: "ctl-block" }, h("h3", null, "Go to"), this.gotoForm()),
      h("div", { class: "ctl-block" }, h("h3", null, "Presets"), this.presetList, this.presetForm()));
    this.el = h("aside", { class: "panel controls", "aria-labelledby": "ctl-title" },
      h("h2", { id: "ctl-title" }, "Mount"),
      state.canDrive ? null : h("p", { class: "reason", id: reasonId, role: "note", "data-testid": "drive-reason" },
        state.driveReason),
      this.msg, fieldset);
    this.cleanups.push(this.listenKeys(), this.listenGamepads());
  }

  dispose(): void {
    for (const fn of this.cleanups) fn();
    this.jog.stopAll();
  }

  /** Run a command, showing its outcome; an answer carrying the mount's state updates it. */
  async act(fn: () => Promise<unknown>, what: string): Promise<boolean> {
    if (!this.state.canDrive) {
      this.msg.show(this.state.driveReason, "warn");
      return false;
    }
    try {
      const r = await fn();
      if (r && typeof r === "object" && "mode" in r) this.updateServo(r as ServoStatus);
      this.msg.show(`${what}: done`, "ok");
      return true;
    } catch (e) {
      this.showError(e, what);
      return false;
    }
  }

  /** act() for a command that moves the mount or sets its mode: jogging stops first, and the command is sent
   * once the server has answered the last jog (a stop still in flight would otherwise arrive after the
   * command and switch the mount back to manual). */
  async drive(fn: () => Promise<unknown>, what: string): Promise<boolean> {
    if (this.state.canDrive) await this.jog.halt();
    return this.act(fn, what);
  }

  /** A click on a camera's picture at source pixel (u, v): make the detection there primary (trackId), or
   * point the camera there. */
  clicked(camera: Camera, u: number, v: number, trackId: number | null): void {
    if (!this.state.canDrive) {
      this.msg.show(this.state.driveReason, "warn");
      return;
    }
    if (trackId !== null) void this.act(() => api.makePrimary(trackId), `Primary target #${trackId}`);
    else void this.drive(() => api.point({ camera, u: Math.round(u * 10) / 10, v: Math.round(v * 10) / 10 }),
      `Point ${camera} camera at (${u.toFixed(0)}, ${v.toFixed(0)})`);
  }

  updateServo(s: ServoStatus | null | undefined): void {
    if (!s) return;
    const servo = { ...this.state.servo, ...s };
    this.state.servo = servo;
    this.state.debug.servo = servo;
    for (const b of this.modeButtons) b.setAttribute("aria-pressed", String(b.dataset.mode === servo.mode));
    this.onServo(servo);
  }

  async loadPresets(): Promise<void> {
    let list: Preset[];
    try {
      list = await api.presets();
    } catch (e) {
      if (!(e instanceof ApiError && e.status === 401)) {
        this.presetList.replaceChildren(h("li", { class: "muted" }, "Presets could not be loaded"));
      }
      return;
    }
    this.presetList.replaceChildren(...(list.length ? list.map((p) => h("li", null,
      h("span", { class: "preset-name" }, `${p.name}`), h("span", { class: "muted" }, ` ${num(p.pan_deg, 1)}°, ${num(p.tilt_deg, 1)}°`),
      h("span", { class: "preset-actions" },
        h("button", { type: "button", "aria-label": `Go to preset ${p.name}`,
          onclick: () => void this.drive(() => api.gotoPreset(p.id), `Preset ${p.name}`) }, "Go"),
        h("button", { type: "button", class: "danger", "aria-label": `Delete preset ${p.name}`,
          onclick: () => void this.act(() => api.deletePreset(p.id), `Delete ${p.name}`).then(() => this.loadPresets()) },
          "Delete"))))
      : [h("li", { class: "muted" }, "No presets yet")]));
  }

  private showError(e: unknown, what: string): void {
    const err = e instanceof ApiError ? e : new ApiError(0, String(e));
    this.state.debug.lastError = `${what}: ${err.status} ${err.detail}`;
    const text = err.status === 403 ? `${what} refused: ${err.detail}` :
      err.status === 404 ? `${what}: not available on this server (${err.detail})` :
      err.offline ? `${what}: the server cannot be reached` : `${what} failed: ${err.detail}`;
    this.msg.show(text, "bad");
  }

  private rate(): number {
    return Number(this.speed.value) || 15;
  }

  private jogBlock(): HTMLElement {
    const speed = this.speed;
    speed.value = localStorage.getItem("tmeye.jogspeed") ?? "15";
    const speedOut = h("output", { for: "" }, `${speed.value}°/s`);
    speed.addEventListener("input", () => {
      speedOut.textContent = `${speed.value}°/s`;
      localStorage.setItem("tmeye.jogspeed", speed.value);
    });
    const [up, left, right, down] = PAD.map(([name, label, glyph, v]) => this.padButton(name, label, glyph, v));
    const stop = h("button", { type: "button", class: "pad-stop", "aria-label": "Stop", title: "Stop jogging",
      onclick: () => void this.drive(() => api.setMode("hold"), "Hold") }, "■");
    const pad = h("div", { class: "pad", role: "group", "aria-label": "Jog pad" }, up, left, stop, right, down);
    return h("div", { class: "ctl-block" }, h("h3", null, "Jog"), field("Jog speed", speed), speedOut, pad,
      h("p", { class: "muted small" }, "Arrow keys jog while held (not in a text field); Shift doubles the speed."),
      this.gamepadState);
  }

  /** A pad button: jogs while the pointer holds it; Enter or Space jogs one pulse. */
  private padButton(name: string, label: string, glyph: string, v: Vec): HTMLButtonElement {
    const b = h("button", { type: "button", class: `pad-${name}`, "aria-label": label, title: `${label} (hold)` }, glyph);
    const scaled = () => ({ pan: v.pan * this.rate(), tilt: v.tilt * this.rate() });
    const stop = () => this.jog.set("pad", null);
    b.addEventListener("pointerdown", (ev) => {
      ev.preventDefault();
      b.setPointerCapture?.(ev.pointerId);
      this.jog.set("pad", scaled());
    });
    b.addEventListener("pointerup", stop);
    b.addEventListener("pointercancel", stop);
    b.addEventListener("lostpointercapture", stop);
    b.addEventListener("keydown", (ev) => {
      if (ev.key === "Enter" || ev.key === " ") {
        ev.preventDefault();
        if (!ev.repeat) void this.jog.pulse(scaled());
      }
    });
    return b;
  }

  private gotoForm(): HTMLFormElement {
    const pan = h("input", { type: "number", step: 0.1, min: -360, max: 360, name: "pan", required: true, value: "0" });
    const tilt = h("input", { type: "number", step: 0.1, min: -90, max: 90, name: "tilt", required: true, value: "0" });
    const form = h("form", { class: "row-form" }, field("Pan (°)", pan), field("Tilt (°)", tilt),
      h("button", { type: "submit" }, "Go to"));
    form.addEventListener("submit", (ev) => {
      ev.preventDefault();
      void this.drive(() => api.goto({ pan_deg: Number(pan.value), tilt_deg: Number(tilt.value) }), "Go to");
    });
    return form;
  }

  private presetForm(): HTMLFormElement {
    const name = h("input", { name: "preset-name", maxLength: 64, pattern: "[\\w .\\-]+", required: true });
    const form = h("form", { class: "row-form" }, field("Preset name", name),
      h("button", { type: "submit" }, "Save current position"));
    form.addEventListener("submit", (ev) => {
      ev.preventDefault();
      void this.drive(() => api.createPreset({ name: name.value.trim() }), "Save preset").then((ok) => {
        if (ok) {
          name.value = "";
          void this.loadPresets();
        }
      });
    });
    return form;
  }

  /** Arrow keys jog while held (not in a text field), Shift doubling the rate. Returns the cleanup. */
  private listenKeys(): () => void {
    const down = new Set<string>();
    let shift = false;
    const vec = (): Vec | null => {
      if (!down.size) return null;
      let pan = 0, tilt = 0;
      for (const key of down) {
        pan += KEYS[key].pan;
        tilt += KEYS[key].tilt;
      }
      const k = this.rate() * (shift ? 2 : 1);
      return { pan: pan * k, tilt: tilt * k };
    };
    const onKeyDown = (ev: KeyboardEvent) => {
      shift = ev.shiftKey;
      if (!(ev.key in KEYS) || typing(ev.target) || ev.altKey || ev.ctrlKey || ev.metaKey) return;
      ev.preventDefault();
      if (!this.state.canDrive) {
        this.msg.show(this.state.driveReason, "warn");
        return;
      }
      if (ev.repeat && down.has(ev.key)) return;
      down.add(ev.key);
      this.jog.set("keys", vec());
    };
    const onKeyUp = (ev: KeyboardEvent) => {
      shift = ev.shiftKey;
      if (down.delete(ev.key)) this.jog.set("keys", vec());
    };
    const onBlur = () => {
      down.clear();
      this.jog.set("keys", null);
    };
    window.addEventListener("keydown", onKeyDown);
    window.addEventListener("keyup", onKeyUp);
    window.addEventListener("blur", onBlur);
    return () => {
      window.removeEventListener("keydown", onKeyDown);
      window.removeEventListener("keyup", onKeyUp);
      window.removeEventListener("blur", onBlur);
    };
  }

  /** The first connected gamepad's left stick or d-pad jogs (at twice the pad's rate), polled every animation
   * frame while one is connected. Returns the cleanup. */
  private listenGamepads(): () => void {
    let raf = 0;
    const poll = () => {
      raf = 0;
      const pads = (navigator.getGamepads?.() ?? []).filter((g): g is Gamepad => !!g && g.connected);
      if (!pads.length) {
        this.gamepadState.textContent = "Gamepad: none connected";
        this.jog.set("gamepad", null);
        return;
      }
      const g = pads[0];
      this.gamepadState.textContent = `Gamepad: ${g.id.slice(0, 40)} (left stick or d-pad jogs)`;
      const dz = (x: number) => (Math.abs(x) < 0.15 ? 0 : x);
      let pan = dz(g.axes[0] ?? 0), tilt = -dz(g.axes[1] ?? 0);
      const pressed = (i: number) => !!g.buttons[i]?.pressed;
      if (pressed(12)) tilt = 1;
      if (pressed(13)) tilt = -1;
      if (pressed(14)) pan = -1;
      if (pressed(15)) pan = 1;
      if (this.state.canDrive) this.jog.set("gamepad", { pan: pan * this.rate() * 2, tilt: tilt * this.rate() * 2 });
      raf = requestAnimationFrame(poll);
    };
    const onPad = () => {
      if (!raf) raf = requestAnimationFrame(poll);
    };
    window.addEventListener("gamepadconnected", onPad);
    window.addEventListener("gamepaddisconnected", onPad);
    onPad();
    return () => {
      window.removeEventListener("gamepadconnected", onPad);
      window.removeEventListener("gamepaddisconnected", onPad);
      cancelAnimationFrame(raf);
    };
  }
}
