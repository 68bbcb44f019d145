// The overlay drawn in the browser over a camera picture from one frame's telemetry: every detection's
// box and id (left image), the primary target's centroid cross, the aim zone, and r, θ, φ with their 1-σ,
// speed and heading of the primary.
import type { Detection, Telemetry } from "../api/types";
import { num } from "../lib/format";
import type { Motion } from "../lib/telemetry";

export interface OverlayInput {
  camera: "left" | "right";
  srcW: number;
  srcH: number;
  tel: Telemetry | null;
  motion: Motion | null;
  deadbandFrac: number;
  sync: string;
  hoverId?: number | null;
}

const PRIMARY = "#ffb020";
const OTHER = "#4fd1ff";
const AIM = "rgba(140, 255, 160, 0.9)";

/** The canvas's scale: source pixel (u, v) to canvas pixel (X(u), Y(v)), letterboxed like the picture. */
interface Frame {
  X: (u: number) => number;
  Y: (v: number) => number;
  s: number;
  dpr: number;
  font: number;
  ch: number;
}

export function drawOverlay(canvas: HTMLCanvasElement, o: OverlayInput): void {
  const dpr = window.devicePixelRatio || 1;
  const cw = Math.max(1, Math.round(canvas.clientWidth * dpr));
  const ch = Math.max(1, Math.round(canvas.clientHeight * dpr));
  if (canvas.width !== cw || canvas.height !== ch) {
    canvas.width = cw;
    canvas.height = ch;
  }
  const ctx = canvas.getContext("2d");
  if (!ctx) return;
  ctx.clearRect(0, 0, cw, ch);
  const s = Math.min(cw / o.srcW, ch / o.srcH);
  const ox = (cw - o.srcW * s) / 2;
  const oy = (ch - o.srcH * s) / 2;
  const font = Math.max(11, Math.round(12 * dpr * Math.min(1.4, Math.max(0.8, cw / (640 * dpr)))));
  const f: Frame = { X: (u) => ox + u * s, Y: (v) => oy + v * s, s, dpr, font, ch };
  ctx.font = `${font}px ui-monospace, SFMono-Regular, Menlo, Consolas, monospace`;
  ctx.textBaseline = "top";
  drawAimZone(ctx, o, f);
  const tel = o.tel;
  if (!tel) {
    label(ctx, "waiting for telemetry", 8 * dpr, 8 * dpr, "#ddd");
    return;
  }
  if (o.camera === "left") {
    for (const d of tel.detections ?? []) drawDetection(ctx, d, d.track_id === tel.track_id, d.track_id === o.hoverId,
      f.X, f.Y, dpr);
    const p = tel.detections?.find((d) => d.track_id === tel.track_id);
    if (p) drawCross(ctx, p.centroid, f);
  }
  drawReadouts(ctx, o, tel, f);
}

/** The aim zone: the dead band about the image centre, a dashed circle with ticks. */
function drawAimZone(ctx: CanvasRenderingContext2D, o: OverlayInput, f: Frame): void {
  const { X, Y, dpr } = f;
  const r = Math.max(4, o.deadbandFrac * o.srcW) * f.s;
  const cx = X(o.srcW / 2), cy = Y(o.srcH / 2);
  ctx.strokeStyle = AIM;
  ctx.lineWidth = 1.5 * dpr;
  ctx.setLineDash([5 * dpr, 4 * dpr]);
  ctx.beginPath();
  ctx.arc(cx, cy, r, 0, 2 * Math.PI);
  ctx.stroke();
  ctx.setLineDash([]);
  const t = 6 * dpr;
  ctx.beginPath();
  ctx.moveTo(cx - r - t, cy);
  ctx.lineTo(cx - r, cy);
  ctx.moveTo(cx + r, cy);
  ctx.lineTo(cx + r + t, cy);
  ctx.moveTo(cx, cy - r - t);
  ctx.lineTo(cx, cy - r);
  ctx.moveTo(cx, cy + r);
  ctx.lineTo(cx, cy + r + t);
  ctx.stroke();
}

/** The primary target's centroid (eq. 10), a cross. */
function drawCross(ctx: CanvasRenderingContext2D, [cu, cv]: number[], f: Frame): void {
  const { X, Y, dpr } = f;
  const a = 9 * dpr;
  ctx.strokeStyle = PRIMARY;
  ctx.lineWidth = 2 * dpr;
  ctx.beginPath();
  ctx.moveTo(X(cu) - a, Y(cv));
  ctx.lineTo(X(cu) + a, Y(cv));
  ctx.moveTo(X(cu), Y(cv) - a);
  ctx.lineTo(X(cu), Y(cv) + a);
  ctx.stroke();
}

/** The primary target's r, θ, φ with their 1-σ, speed and heading (left camera), and the frame, bottom left. */
function drawReadouts(ctx: CanvasRenderingContext2D, o: OverlayInput, tel: Telemetry, f: Frame): void {
  const { dpr, font, ch } = f;
  const lines: string[] = o.camera === "right" ? [] : tel.detected && tel.r != null
    ? [
        `#${tel.track_id ?? "—"}  r ${num(tel.r, 2)} ± ${num(tel.sigma_r, 2)} m`,
        `θ ${num(tel.theta_deg, 2)} ± ${num(tel.sigma_theta_deg, 2)}°  φ ${num(tel.phi_deg, 2)} ± ${num(tel.sigma_phi_deg, 2)}°`,
        o.motion ? `${num(o.motion.speed, 2)} m/s  heading ${num(o.motion.heading, 0)}°` : "speed —  heading —",
      ]
    : ["no target"];
  lines.push(`frame ${tel.frame}  ${o.sync}`);
  const lh = font * 1.25;
  const bw = Math.max(...lines.map((l) => ctx.measureText(l).width)) + 12 * dpr;
  const by = ch - lines.length * lh - 10 * dpr;
  ctx.fillStyle = "rgba(0, 0, 0, 0.55)";
  ctx.fillRect(4 * dpr, by - 4 * dpr, bw, lines.length * lh + 8 * dpr);
  lines.forEach((l, i) => {
    ctx.fillStyle = i === 0 && o.camera === "left" && tel.detected ? PRIMARY : "#f2f2f2";
    ctx.fillText(l, 10 * dpr, by + i * lh);
  });
}

function drawDetection(ctx: CanvasRenderingContext2D, d: Detection, primary: boolean, hover: boolean,
                       X: (u: number) => number, Y: (v: number) => number, dpr: number): void {
  const [x0, y0, x1, y1] = d.box;
  ctx.strokeStyle = primary ? PRIMARY : OTHER;
  ctx.lineWidth = (primary || hover ? 2.5 : 1.5) * dpr;
  ctx.strokeRect(X(x0), Y(y0), X(x1) - X(x0), Y(y1) - Y(y0));
  const text = `#${d.track_id} ${num(d.r, 1)} m`;
  const w = ctx.measureText(text).width + 6 * dpr;
  const fh = parseInt(ctx.font, 10) * 1.2;
  const ty = Math.max(0, Y(y0) - fh - 2 * dpr);
  ctx.fillStyle = primary ? "rgba(255, 176, 32, 0.85)" : "rgba(79, 209, 255, 0.8)";
  ctx.fillRect(X(x0), ty, w, fh);
  ctx.fillStyle = "#000";
  ctx.fillText(text, X(x0) + 3 * dpr, ty + 1 * dpr);
}

function label(ctx: CanvasRenderingContext2D, text: string, x: number, y: number, color: string): void {
  const w = ctx.measureText(text).width + 8;
  ctx.fillStyle = "rgba(0,0,0,0.55)";
  ctx.fillRect(x - 4, y - 2, w, parseInt(ctx.font, 10) * 1.3);
  ctx.fillStyle = color;
  ctx.fillText(text, x, y);
}

/** The detection whose box holds the left-image pixel (u, v); the smallest when boxes overlap. */
export function detectionAt(tel: Telemetry | null, u: number, v: number): Detection | null {
  let best: Detection | null = null;
  for (const d of tel?.detections ?? []) {
    const [x0, y0, x1, y1] = d.box;
    if (u >= x0 && u <= x1 && v >= y0 && v <= y1) {
      if (!best || (x1 - x0) * (y1 - y0) < (best.box[2] - best.box[0]) * (best.box[3] - best.box[1])) best = d;
    }
  }
  return best;
}
