// The alarm banner under the top bar of every page: open alarms per priority, how many are
// unacknowledged, the most urgent one, the flood state, and Silence (stops the sound; the alarms stay
// unacknowledged). role="alert" on the newest critical/high activation so screen readers announce it.
import { h } from "./dom";
import { type AlarmCenter, PRIORITIES } from "./alarms";

export class AlarmBanner {
  readonly el: HTMLElement;
  private counts = h("span", { class: "ab-counts" });
  private top = h("span", { class: "ab-top", "data-testid": "banner-top" });
  private flood = h("span", { class: "ab-flood", "data-testid": "banner-flood", hidden: true });
  private silenceBtn = h("button", { type: "button", "data-testid": "banner-silence",
    title: "Stop the sound; the alarms stay unacknowledged" }, "Silence");
  private live = h("span", { class: "sr-only", role: "alert" });
  private lastLoud = 0;

  constructor(private readonly center: AlarmCenter) {
    this.el = h("div", { class: "alarm-banner", "data-testid": "alarm-banner", "aria-label": "Alarms" },
      h("a", { href: "#/alarms", class: "ab-title" }, "Alarms"), this.counts, this.top, this.flood,
      this.silenceBtn, this.live);
    this.silenceBtn.addEventListener("click", () => center.silence());
    center.subscribe(() => this.render());
  }

  private render(): void {
    const c = this.center;
    const counts = c.counts();
    const open = c.open();
    const unack = c.unacknowledged().length;
    this.counts.replaceChildren(...PRIORITIES.map((p) => h("span", { class: `ab-chip prio-${p}`,
      "data-testid": `banner-${p}`, "data-count": String(counts[p]) }, `${counts[p]} ${p}`)),
      h("span", { class: "ab-unack", "data-testid": "banner-unack" }, `${unack} unacknowledged`));
    const first = open[0];
    this.top.textContent = first ? `${first.name} (${first.priority}, ${first.state.replace("_", " ")})` : "No alarms";
    this.el.dataset.level = first ? first.priority : "none";
    this.el.dataset.beeps = String(c.beeps);
    this.flood.hidden = !c.flood;
    this.flood.textContent = c.flood ? `Alarm flood${c.floodMessage ? `: ${c.floodMessage}` : ""}` : "";
    const sounding = c.sounding();
    this.silenceBtn.disabled = sounding.length === 0;
    this.silenceBtn.textContent = sounding.length ? `Silence (${sounding.length})` : "Silence";
    const loud = sounding.reduce((m, a) => Math.max(m, a.activated_at), 0);
    if (loud > this.lastLoud) {
      this.lastLoud = loud;
      this.live.textContent = `New ${sounding[0].priority} alarm: ${sounding[0].name}`;
    }
  }
}
