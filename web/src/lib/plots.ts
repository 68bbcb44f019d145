// Metric x-y views drawn with uPlot (mode 2: each series its own x and y arrays): equal metres per pixel on
// both axes, polylines with gaps (null) between tracks, and a field-of-view wedge from the rig's origin.
import uPlot from "uplot";
import "uplot/dist/uPlot.min.css";

/** title and legend above and below the canvas (px) on one line each: what is left for them before a plot
 * is drawn (canvasHeight) */
const CHROME_PX = 52;

/** The canvas height (px) that leaves room in the box for the plot's title and legend, as drawn (a legend
 * that wraps to a second line in a narrow box takes more: the Live page's plan view at 1280 px wide). */
function canvasHeight(box: HTMLElement, plot: uPlot | null): number {
  let chrome = CHROME_PX;
  if (plot) {
    const title = plot.root.querySelector<HTMLElement>(".u-title");
    const legend = plot.root.querySelector<HTMLElement>(".u-legend");
    chrome = (title?.offsetHeight ?? 0) + (legend?.offsetHeight ?? 0) + 4;
  }
  return Math.max(120, Math.floor(box.getBoundingClientRect().height) - chrome);
}

export type XY = [(number | null)[], (number | null)[]];

export interface Wedge {
  /** centre direction (deg), measured from the view's vertical axis toward its horizontal axis */
  centreDeg: number;
  halfDeg: number;
  /** measured from the horizontal axis up (side view) instead of from the vertical axis */
  fromHorizontal?: boolean;
  label?: string;
}

export interface SeriesSpec {
  label: string;
  stroke: string;
  width?: number;
}

export interface MetricViewOptions {
  title: string;
  xLabel: string;
  yLabel: string;
  series: SeriesSpec[];
  /** smallest half-extent shown (m) */
  minSpan?: number;
  /** always include these points (e.g. the origin) */
  include?: [number, number][];
}

const gapPaths: uPlot.Series.PathBuilder = (u, sidx) => {
  const [xs, ys] = (u.data as unknown as XY[])[sidx] ?? [[], []];
  const stroke = new Path2D();
  let pen = false;
  for (let i = 0; i < xs.length; i++) {
    const x = xs[i];
    const y = ys[i];
    if (x === null || y === null || x === undefined || y === undefined) {
      pen = false;
      continue;
    }
    const X = u.valToPos(x, "x", true);
    const Y = u.valToPos(y, "y", true);
    if (pen) stroke.lineTo(X, Y);
    else stroke.moveTo(X, Y);
    pen = true;
  }
  return { stroke, fill: null, clip: undefined, flags: 0 };
};

export class MetricView {
  readonly el: HTMLElement;
  private plot: uPlot | null = null;
  private data: XY[] = [];
  private wedges: Wedge[] = [];
  private heads: { x: number; y: number; color: string; label: string }[] = [];
  private xr: [number, number] = [-10, 10];
  private yr: [number, number] = [0, 20];
  private ro: ResizeObserver;

  constructor(container: HTMLElement, private readonly opts: MetricViewOptions) {
    this.el = container;
    this.data = opts.series.map(() => [[], []] as XY);
    this.ro = new ResizeObserver(() => this.resize());
    this.ro.observe(container);
  }

  private size(): { width: number; height: number } {
    const r = this.el.getBoundingClientRect();
    // the box holds the title and the legend too
    return { width: Math.max(160, Math.floor(r.width)), height: canvasHeight(this.el, this.plot) };
  }

  private create(): void {
    const { width, height } = this.size();
    const o = this.opts;
    const opts: uPlot.Options = {
      mode: 2,
      width,
      height,
      title: o.title,
      legend: { show: true, live: false },
      cursor: { show: false, drag: { x: false, y: false } },
      scales: {
        x: { time: false, auto: false, range: () => this.xr },
        y: { auto: false, range: () => this.yr },
      },
      axes: [
        { label: o.xLabel, stroke: "#b8c2cc", grid: { stroke: "rgba(255,255,255,0.08)" }, size: 36, labelSize: 18 },
        { label: o.yLabel, stroke: "#b8c2cc", grid: { stroke: "rgba(255,255,255,0.08)" }, size: 40, labelSize: 18 },
      ],
      series: [
        {},
        ...o.series.map((s) => ({
          label: s.label,
          stroke: s.stroke,
          width: s.width ?? 2,
          paths: gapPaths,
          points: { show: false },
          facets: [{ scale: "x", auto: false }, { scale: "y", auto: false }],
        } as uPlot.Series)),
      ],
      hooks: {
        drawAxes: [(u) => this.drawWedges(u)],
        draw: [(u) => this.drawHeads(u)],
      },
    };
    this.plot = new uPlot(opts, [null, ...this.data] as unknown as uPlot.AlignedData, this.el);
    const legend = this.plot.root.querySelector(".u-legend");  // laid out, or wrapped anew: sized again
    if (legend) this.ro.observe(legend);
  }

  private resize(): void {
    if (!this.plot) {
      if (this.el.isConnected && this.el.getBoundingClientRect().width > 0) {
        this.fit();
        this.create();
      }
      return;
    }
    this.fit();
    this.plot.setSize(this.size());
  }

  /** Equal scale on both axes: fit the data (and the origin) and widen the other axis to the plot's aspect. */
  private fit(): void {
    let x0 = Infinity, x1 = -Infinity, y0 = Infinity, y1 = -Infinity;
    const take = (x: number | null, y: number | null) => {
      if (x === null || y === null) return;
      x0 = Math.min(x0, x); x1 = Math.max(x1, x); y0 = Math.min(y0, y); y1 = Math.max(y1, y);
    };
    for (const [xs, ys] of this.data) for (let i = 0; i < xs.length; i++) take(xs[i], ys[i]);
    for (const [x, y] of this.opts.include ?? [[0, 0]]) take(x, y);
    const min = this.opts.minSpan ?? 5;
    let cx = (x0 + x1) / 2, cy = (y0 + y1) / 2;
    let hx = Math.max((x1 - x0) / 2 * 1.15, min), hy = Math.max((y1 - y0) / 2 * 1.15, min);
    const plotW = Math.max(1, (this.plot?.bbox.width ?? this.size().width * devicePixelRatio) - 0);
    const plotH = Math.max(1, (this.plot?.bbox.height ?? this.size().height * devicePixelRatio * 0.7));
    const aspect = plotW / plotH;
    if (hx / hy < aspect) hx = hy * aspect;
    else hy = hx / aspect;
    // round the view so that it does not jitter every update
    const q = hx > 20 ? 5 : hx > 8 ? 2 : 1;
    hx = Math.ceil(hx / q) * q; hy = hx / aspect;
    cx = Math.round(cx / q) * q; cy = Math.round(cy / q) * q;
    this.xr = [cx - hx, cx + hx];
    this.yr = [cy - hy, cy + hy];
  }

  setData(data: XY[], wedges: Wedge[] = [], heads: MetricView["heads"] = []): void {
    this.data = data;
    this.wedges = wedges;
    this.heads = heads;
    if (!this.plot) {
      this.resize();
      return;
    }
    this.fit();
    this.plot.batch(() => {
      this.plot!.setData([null, ...data] as unknown as uPlot.AlignedData, false);
      this.plot!.setScale("x", { min: this.xr[0], max: this.xr[1] });
      this.plot!.setScale("y", { min: this.yr[0], max: this.yr[1] });
    });
  }

  private drawWedges(u: uPlot): void {
    const ctx = u.ctx;
    const { left, top, width, height } = u.bbox;
    ctx.save();
    ctx.textAlign = "left";
    ctx.textBaseline = "alphabetic";
    ctx.beginPath();
    ctx.rect(left, top, width, height);
    ctx.clip();
    const ox = u.valToPos(0, "x", true);
    const oy = u.valToPos(0, "y", true);
    const reach = 4 * Math.max(this.xr[1] - this.xr[0], this.yr[1] - this.yr[0]);
    for (const w of this.wedges) {
      const dir = (deg: number): [number, number] => {
        const a = (deg * Math.PI) / 180;
        return w.fromHorizontal ? [Math.cos(a) * reach, Math.sin(a) * reach] : [Math.sin(a) * reach, Math.cos(a) * reach];
      };
      const [ax, ay] = dir(w.centreDeg - w.halfDeg);
      const [bx, by] = dir(w.centreDeg + w.halfDeg);
      const [cx, cy] = dir(w.centreDeg);
      ctx.beginPath();
      ctx.moveTo(ox, oy);
      ctx.lineTo(u.valToPos(ax, "x", true), u.valToPos(ay, "y", true));
      ctx.lineTo(u.valToPos(bx, "x", true), u.valToPos(by, "y", true));
      ctx.closePath();
      ctx.fillStyle = "rgba(120, 220, 140, 0.10)";
      ctx.fill();
      ctx.strokeStyle = "rgba(120, 220, 140, 0.55)";
      ctx.lineWidth = 1 * devicePixelRatio;
      ctx.stroke();
      ctx.setLineDash([4 * devicePixelRatio, 4 * devicePixelRatio]);
      ctx.beginPath();
      ctx.moveTo(ox, oy);
      ctx.lineTo(u.valToPos(cx, "x", true), u.valToPos(cy, "y", true));
      ctx.stroke();
      ctx.setLineDash([]);
      if (w.label) {
        ctx.fillStyle = "rgba(150, 230, 160, 0.9)";
        ctx.font = `${11 * devicePixelRatio}px system-ui, sans-serif`;
        ctx.fillText(w.label, left + 6 * devicePixelRatio, top + 14 * devicePixelRatio);
      }
    }
    // the rig
    ctx.fillStyle = "#e0e0e0";
    ctx.beginPath();
    ctx.arc(ox, oy, 4 * devicePixelRatio, 0, 2 * Math.PI);
    ctx.fill();
    ctx.restore();
  }

  private drawHeads(u: uPlot): void {
    const ctx = u.ctx;
    const { left, top, width, height } = u.bbox;
    ctx.save();
    ctx.beginPath();
    ctx.rect(left, top, width, height);
    ctx.clip();
    ctx.textAlign = "left";
    ctx.textBaseline = "alphabetic";
    ctx.font = `${11 * devicePixelRatio}px system-ui, sans-serif`;
    for (const p of this.heads) {
      const X = u.valToPos(p.x, "x", true);
      const Y = u.valToPos(p.y, "y", true);
      ctx.fillStyle = p.color;
      ctx.beginPath();
      ctx.arc(X, Y, 4 * devicePixelRatio, 0, 2 * Math.PI);
      ctx.fill();
      ctx.fillText(p.label, X + 6 * devicePixelRatio, Y - 6 * devicePixelRatio);
    }
    ctx.restore();
  }

  destroy(): void {
    this.ro.disconnect();
    this.plot?.destroy();
    this.plot = null;
  }
}

/** A plain time series (one x array shared by the series) for the Tracks page. */
export class TimeView {
  private plot: uPlot | null = null;
  private legend: Element | null = null;
  private ro: ResizeObserver;
  constructor(private readonly el: HTMLElement, private readonly title: string, private readonly yLabel: string,
              private readonly series: SeriesSpec[]) {
    this.ro = new ResizeObserver(() => {
      const r = this.el.getBoundingClientRect();
      this.plot?.setSize({ width: Math.max(200, Math.floor(r.width)), height: canvasHeight(this.el, this.plot) });
    });
    this.ro.observe(el);
  }

  setData(data: uPlot.AlignedData): void {
    if (this.legend) this.ro.unobserve(this.legend);
    this.plot?.destroy();
    const r = this.el.getBoundingClientRect();
    this.plot = new uPlot({
      width: Math.max(200, Math.floor(r.width)),
      height: Math.max(120, Math.floor(r.height) - CHROME_PX),
      title: this.title,
      scales: { x: { time: false } },
      axes: [
        { label: "time since first seen (s)", stroke: "#b8c2cc", grid: { stroke: "rgba(255,255,255,0.08)" } },
        { label: this.yLabel, stroke: "#b8c2cc", grid: { stroke: "rgba(255,255,255,0.08)" } },
      ],
      series: [{ label: "t (s)" }, ...this.series.map((s) => ({ label: s.label, stroke: s.stroke, width: s.width ?? 2 }))],
    }, data, this.el);
    this.legend = this.plot.root.querySelector(".u-legend");  // laid out, or wrapped anew: sized again
    if (this.legend) this.ro.observe(this.legend);
  }

  destroy(): void {
    this.ro.disconnect();
    this.plot?.destroy();
  }
}
