// A WebSocket that reconnects by itself (backoff 0.5 s doubling to 5 s) after a server restart or a
// network drop, and reports its state. The session cookie authenticates it; a close with code 1008
// (policy: not logged in) is reported as "unauthorized" and not retried.
export type SocketState = "connecting" | "open" | "closed" | "unauthorized";

export interface ReconnectingSocketOptions<T> {
  path: string;
  onMessage: (msg: T) => void;
  onState?: (state: SocketState, info: { attempts: number; reason?: string }) => void;
}

export class ReconnectingSocket<T = unknown> {
  private ws: WebSocket | null = null;
  private timer: number | undefined;
  private attempts = 0;
  private stopped = false;
  state: SocketState = "connecting";
  /** How many times the socket opened (a second open means a reconnection). */
  opens = 0;

  constructor(private readonly opts: ReconnectingSocketOptions<T>) {
    this.connect();
  }

  private url(): string {
    const proto = location.protocol === "https:" ? "wss:" : "ws:";
    return `${proto}//${location.host}${this.opts.path}`;
  }

  private setState(s: SocketState, reason?: string): void {
    this.state = s;
    this.opts.onState?.(s, { attempts: this.attempts, reason });
  }

  private connect(): void {
    if (this.stopped) return;
    this.setState("connecting");
    let ws: WebSocket;
    try {
      ws = new WebSocket(this.url());
    } catch {
      this.retry();
      return;
    }
    this.ws = ws;
    ws.onopen = () => {
      this.attempts = 0;
      this.opens += 1;
      this.setState("open");
    };
    ws.onmessage = (ev) => {
      let msg: T;
      try {
        msg = JSON.parse(typeof ev.data === "string" ? ev.data : "") as T;
      } catch {
        return;
      }
      this.opts.onMessage(msg);
    };
    ws.onclose = (ev) => {
      if (this.ws !== ws) return;
      this.ws = null;
      if (this.stopped) return;
      if (ev.code === 1008) {
        this.setState("unauthorized", ev.reason);
        return;
      }
      this.retry();
    };
  }

  private retry(): void {
    this.attempts += 1;
    this.setState("closed");
    const delay = Math.min(5000, 500 * 2 ** Math.min(this.attempts - 1, 4));
    this.timer = window.setTimeout(() => this.connect(), delay);
  }

  /** Reconnect now (e.g. after logging in again). */
  reconnect(): void {
    window.clearTimeout(this.timer);
    this.attempts = 0;
    if (this.ws) {
      const ws = this.ws;
      this.ws = null;
      ws.close();
    }
    this.connect();
  }

  close(): void {
    this.stopped = true;
    window.clearTimeout(this.timer);
    this.ws?.close();
    this.ws = null;
  }
}
