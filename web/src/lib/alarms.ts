// The console's alarm centre, shared by every page: the open alarms (GET /api/alarms?state=open, then
// kept current by the "alarm" messages of /ws/events), the flood state, and the audible alarm. A new
// critical or high alarm sounds (WebAudio beeps, repeated every 2 s) until it is acknowledged or the
// operator silences it; silencing is not acknowledging: the alarms stay unacknowledged, and a newer
// critical or high alarm sounds again.
import { api } from "../api/client";
import type { AlarmOut, Priority, ServerEvent } from "../api/types";
import { ReconnectingSocket, type SocketState } from "./socket";

export const PRIORITIES: Priority[] = ["critical", "high", "medium", "low"];
export const OPEN_STATES = new Set(["unack", "ack", "rtn_unack"]);
const STATE_TEXT: Record<string, string> = { unack: "active, unacknowledged", ack: "active, acknowledged",
  rtn_unack: "cleared, unacknowledged", shelved: "shelved", suppressed: "suppressed by design",
  out_of_service: "out of service", normal: "normal" };

/** An alarm state (ISA-18.2's, as the API names them) in words: "rtn_unack" is "cleared, unacknowledged". */
export function stateText(state: string | null | undefined): string {
  return state ? STATE_TEXT[state] ?? state.replace(/_/g, " ") : "—";
}
const LOUD = new Set<Priority>(["critical", "high"]);

export interface AlarmTransition {
  kind: string;
  t: number;
  user: string | null;
  comment: string | null;
  state_to: string | null;
  priority: string | null;
  opened: boolean;
}

type Listener = (c: AlarmCenter) => void;

export function byPriorityThenTime(a: AlarmOut, b: AlarmOut): number {
  return PRIORITIES.indexOf(a.priority) - PRIORITIES.indexOf(b.priority) || b.activated_at - a.activated_at;
}

export class AlarmCenter {
  /** Alarms by id: the open ones (unack, ack, rtn_unack, shelved) and the latest state of any other seen. */
  readonly alarms = new Map<number, AlarmOut>();
  flood = false;
  floodMessage = "";
  socketState: SocketState = "connecting";
  /** Ids of loud alarms that sounded and were silenced. */
  private silenced = new Set<number>();
  private listeners = new Set<Listener>();
  private socket: ReconnectingSocket<ServerEvent> | null = null;
  private audio: AudioContext | null = null;
  private beepTimer: number | undefined;
  /** Beeps played (for the tests and the banner). */
  beeps = 0;

  start(): void {
    if (this.socket) return;
    this.socket = new ReconnectingSocket<ServerEvent>({
      path: "/ws/events",
      onMessage: (ev) => this.onEvent(ev),
      onState: (s) => {
        this.socketState = s;
        if (s === "open") void this.reload();
        this.emit();
      },
    });
  }

  stop(): void {
    this.socket?.close();
    this.socket = null;
    window.clearInterval(this.beepTimer);
    this.beepTimer = undefined;
    this.alarms.clear();
  }

  subscribe(fn: Listener): () => void {
    this.listeners.add(fn);
    fn(this);
    return () => this.listeners.delete(fn);
  }

  async reload(): Promise<void> {
    const [list, summary] = await Promise.all([api.alarms("open", undefined, 1000), api.alarmSummary()]);
    this.alarms.clear();
    for (const a of list) this.alarms.set(a.id, a);
    this.flood = summary.flood;
    this.emit();
  }

  /** Open alarms (shelved ones are out of the list), by priority then newest first. */
  open(): AlarmOut[] {
    return [...this.alarms.values()].filter((a) => OPEN_STATES.has(a.state)).sort(byPriorityThenTime);
  }

  counts(): Record<Priority, number> {
    const c = { critical: 0, high: 0, medium: 0, low: 0 } as Record<Priority, number>;
    for (const a of this.open()) c[a.priority] += 1;
    return c;
  }

  unacknowledged(): AlarmOut[] {
    return this.open().filter((a) => a.state === "unack" || a.state === "rtn_unack");
  }

  /** Loud alarms that are unacknowledged and not silenced. */
  sounding(): AlarmOut[] {
    return this.unacknowledged().filter((a) => LOUD.has(a.priority) && !this.silenced.has(a.id));
  }

  silence(): void {
    for (const a of this.unacknowledged()) this.silenced.add(a.id);
    this.updateSound();
    this.emit();
  }

  private onEvent(ev: ServerEvent): void {
    if (ev.type === "alarm_flood") {
      // the flood is counted per operator: the summary says whether this user is in flood
      this.floodMessage = String(ev.message ?? "");
      void api.alarmSummary().then((s) => {
        this.flood = s.flood;
        this.emit();
      }, () => undefined);
      return;
    }
    if (ev.type !== "alarm") return;
    const a = ev.alarm as AlarmOut;
    const tr = ev.transition as AlarmTransition;
    if (tr.kind === "activated") this.silenced.delete(a.id); // an alarm that comes back sounds again
    this.alarms.set(a.id, a);
    if (!OPEN_STATES.has(a.state) && a.state !== "shelved") {
      this.alarms.delete(a.id);
      this.silenced.delete(a.id);
    }
    this.emit();
  }

  private emit(): void {
    this.updateSound();
    this.listeners.forEach((fn) => fn(this));
  }

  private updateSound(): void {
    const loud = this.sounding().length > 0;
    if (loud && this.beepTimer === undefined) {
      this.beep();
      this.beepTimer = window.setInterval(() => this.beep(), 2000);
    } else if (!loud && this.beepTimer !== undefined) {
      window.clearInterval(this.beepTimer);
      this.beepTimer = undefined;
    }
  }

  /** Two short tones (880 Hz then 660 Hz). Browsers may keep the audio suspended until the first click. */
  private beep(): void {
    try {
      this.audio ??= new AudioContext();
      const ctx = this.audio;
      if (ctx.state === "suspended") void ctx.resume();
      const t0 = ctx.currentTime;
      [880, 660].forEach((f, i) => {
        const osc = ctx.createOscillator();
        const gain = ctx.createGain();
        osc.frequency.value = f;
        gain.gain.setValueAtTime(0.0001, t0 + i * 0.22);
        gain.gain.exponentialRampToValueAtTime(0.2, t0 + i * 0.22 + 0.02);
        gain.gain.exponentialRampToValueAtTime(0.0001, t0 + i * 0.22 + 0.2);
        osc.connect(gain).connect(ctx.destination);
        osc.start(t0 + i * 0.22);
        osc.stop(t0 + i * 0.22 + 0.21);
      });
      this.beeps += 1;
    } catch {
      /* no audio device: the banner still shows it */
    }
  }
}

export const alarmCenter = new AlarmCenter();
