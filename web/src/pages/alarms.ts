// The Alarms page: open and shelved alarms sorted by priority then time (kept current from /ws/events),
// or every alarm of the last day; acknowledge with a comment, shelve for some minutes or until the alarm
// clears (one-shot) with a reason, unshelve (operator), each alarm's history with who did what, a link to its playback; the rules
// (admin: create, enable, take out of service, delete).
import { api, errorText, request } from "../api/client";
import type { AlarmOut } from "../api/types";
import { alarmCenter, byPriorityThenTime, stateText } from "../lib/alarms";
import { h, notice } from "../lib/dom";
import { time } from "../lib/format";
import { atLeast, roleReason } from "../lib/session";
import { rulesPanel } from "./alarm_rules";
import type { Page, PageContext } from "./types";

type Run = (what: string, fn: () => Promise<unknown>) => Promise<void>;
type Fail = (what: string, e: unknown) => void;

interface Row {
  tr: HTMLTableRowElement;
  update(a: AlarmOut): void;
}

/** An alarm's history (who did what, when), shown and hidden by its toggle, loaded when shown. */
function alarmHistory(id: number, fail: Fail): { el: HTMLElement; toggle: HTMLElement; open(): boolean; load(): Promise<void> } {
  const el = h("ol", { class: "alarm-history", hidden: true, "aria-label": `History of alarm ${id}` });
  async function load(): Promise<void> {
    try {
      const d = await api.alarm(id);
      el.replaceChildren(...d.history.map((e) => h("li", null, `${time(e.at)} ${e.kind}`,
        e.state_to ? ` → ${stateText(e.state_to)}` : "", e.username ? ` by ${e.username}` : "",
        e.comment ? `: “${e.comment}”` : "", e.message ? ` (${e.message})` : "")));
    } catch (e) {
      fail("History", e);
    }
  }
  const toggle = h("button", { type: "button", class: "link", "aria-expanded": "false", onclick: () => {
    const open = el.hidden;
    toggle.setAttribute("aria-expanded", String(open));
    el.hidden = !open;
    if (open) void load();
  } }, "History");
  return { el, toggle, open: () => !el.hidden, load };
}

/** One alarm's row: its cells, and (operator) acknowledge with a comment, shelve for some minutes or until it
 * clears with a reason, unshelve, lock its footage; for everyone its history and a link to its playback.
 * run: a command, with its outcome shown; fail: an error shown. */
function alarmRow(a0: AlarmOut, canAct: boolean, run: Run, fail: Fail): Row {
  let a = a0;
  const cells = Array.from({ length: 7 }, () => h("td"));
  const comment = h("input", { name: `ack-comment-${a.id}`, maxLength: 1000, placeholder: "comment",
    "aria-label": `Comment for acknowledging alarm ${a.id}` });
  const ack = h("button", { type: "button", class: "primary", onclick: () => void run(`Acknowledge alarm ${a.id}`,
    () => api.ackAlarm(a.id, comment.value.trim() || null).then(() => { comment.value = ""; })) }, "Acknowledge");
  const minutes = h("input", { type: "number", name: `shelve-minutes-${a.id}`, min: 1, max: 480, value: 30,
    "aria-label": `Minutes to shelve alarm ${a.id}`, style: { width: "5rem" } });
  const reason = h("input", { name: `shelve-reason-${a.id}`, maxLength: 500, placeholder: "reason (required)",
    "aria-label": `Reason for shelving alarm ${a.id}` });
  const shelve = h("button", { type: "button", onclick: () => void run(`Shelve alarm ${a.id}`,
    () => api.shelveAlarm(a.id, Number(minutes.value), reason.value.trim())) }, "Shelve");
  const oneShot = h("button", { type: "button", title: "Shelved until the alarm clears",
    onclick: () => void run(`Shelve alarm ${a.id} until it clears`,
      () => api.shelveAlarmOneShot(a.id, reason.value.trim())) }, "Shelve until cleared");
  const unshelve = h("button", { type: "button", onclick: () => void run(`Unshelve alarm ${a.id}`,
    () => api.unshelveAlarm(a.id)) }, "Unshelve");
  const history = alarmHistory(a.id, fail);
  const playback = h("button", { type: "button", class: "link", onclick: () => void api.alarm(a.id).then(
    (d) => { location.hash = d.playback_url; }, (e) => fail("Playback link", e)) }, "Playback");
  const lock = h("button", { type: "button", onclick: () => void run(`Lock the footage of alarm ${a.id}`,
    () => request("POST", "/api/locks", { body: { alarm_id: a.id, note: `alarm ${a.id}: ${a.name}` } })) },
  "Lock footage");
  const actions = h("div", { class: "alarm-actions" },
    canAct ? [comment, ack, h("span", { class: "inline-unit" }, minutes, " min"), reason, shelve, oneShot, unshelve, lock]
      : null, history.toggle, playback);
  const tr = h("tr", { "data-alarm": String(a.id) }, ...cells, h("td", null, actions, history.el));

  function update(next: AlarmOut): void {
    a = next;
    tr.dataset.state = a.state;
    const state = stateText(a.state) + (a.state === "shelved" && a.shelved_one_shot ? " until it clears" : "");
    const texts = [a.priority, `${a.name}${a.message ? ` — ${a.message}` : ""}`, state,
      time(a.activated_at), a.cleared_at ? time(a.cleared_at) : "—", a.target_id != null ? `#${a.target_id}` : "—",
      a.acked_by ? `${a.acked_by}, ${time(a.acked_at)}` : "—"];
    texts.forEach((t, i) => { cells[i].textContent = t; });
    cells[0].className = `prio-${a.priority}`;
    const unack = a.state === "unack" || a.state === "rtn_unack";
    ack.disabled = comment.disabled = !unack;
    shelve.disabled = minutes.disabled = reason.disabled = !(unack || a.state === "ack");
    oneShot.disabled = !(a.state === "unack" || a.state === "ack");
    unshelve.hidden = a.state !== "shelved";
    if (history.open()) void history.load();
  }
  update(a);
  return { tr, update };
}

/** The alarm table's rows in tbody, sorted by priority then time, each alarm's row kept and updated in place;
 * clear: forget them all (another view). */
function alarmRows(tbody: HTMLTableSectionElement, canAct: boolean, run: Run, fail: Fail
): { render(list: AlarmOut[]): void; clear(): void } {
  const rows = new Map<number, Row>();
  function render(list: AlarmOut[]): void {
    const sorted = [...list].sort(byPriorityThenTime);
    const keep = new Set(sorted.map((a) => a.id));
    for (const id of [...rows.keys()]) if (!keep.has(id)) rows.delete(id);
    const ordered = sorted.map((a) => {
      let r = rows.get(a.id);
      if (r) r.update(a);
      else rows.set(a.id, (r = alarmRow(a, canAct, run, fail)));
      return r.tr;
    });
    const same = ordered.length === tbody.children.length && ordered.every((tr, i) => tbody.children[i] === tr);
    if (!same) tbody.replaceChildren(...ordered);
    if (!sorted.length) tbody.replaceChildren(h("tr", null, h("td", { colSpan: 8, class: "muted" }, "No alarms.")));
  }
  function clear(): void {
    rows.clear();
    tbody.replaceChildren();
  }
  return { render, clear };
}

export function alarmsPage(ctx: PageContext): Page {
  const { root, session } = ctx;
  const canAct = atLeast(session, "operator");
  const msg = notice("status");
  const view = h("select", { name: "alarm-view", "aria-label": "Which alarms" },
    h("option", { value: "open" }, "Open and shelved (live)"), h("option", { value: "day" }, "All of the last 24 h"));
  const tbody = h("tbody");
  const table = h("table", { class: "data", "data-testid": "alarm-table" },
    h("caption", { class: "sr-only" }, "Alarms by priority, then newest first"),
    h("thead", null, h("tr", null, ...["Priority", "Alarm", "State", "Activated", "Cleared", "Target",
      "Acknowledged", "Actions"].map((c) => h("th", { scope: "col" }, c)))), tbody);
  root.replaceChildren(h("section", { class: "page" }, h("h1", null, "Alarms"), msg,
    h("div", { class: "row-form" }, view), h("div", { class: "table-wrap" }, table),
    !canAct ? h("p", { class: "muted" }, roleReason(session, "operator", "Acknowledging and shelving")) : null,
    atLeast(session, "admin") ? rulesPanel(msg) : null));

  const fail = (what: string, e: unknown) => msg.show(`${what}: ${errorText(e)}`, "bad");

  async function run(what: string, fn: () => Promise<unknown>): Promise<void> {
    try {
      await fn();
      msg.show(`${what}: done.`, "ok");
    } catch (e) {
      fail(what, e);
    }
  }

  const { render, clear } = alarmRows(tbody, canAct, run, fail);

  async function loadDay(): Promise<void> {
    try {
      render(await api.alarms(undefined, Date.now() / 1000 - 86400, 1000));
    } catch (e) {
      fail("Alarms could not be loaded", e);
    }
  }

  const unsub = alarmCenter.subscribe((c) => {
    if (view.value === "open") render([...c.alarms.values()]);
    else void loadDay();
  });
  view.addEventListener("change", () => {
    clear();
    if (view.value === "open") render([...alarmCenter.alarms.values()]);
    else void loadDay();
  });
  return { unmount: () => unsub() };
}
