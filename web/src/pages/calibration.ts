// The Calibration page: upload left/right chessboard image pairs with the board spec (admin), follow the
// progress from /ws/events, list the records, activate one (admin), download its rig file.
import { api, errorText } from "../api/client";
import type { CalibrationOut, ServerEvent } from "../api/types";
import { field, h, notice } from "../lib/dom";
import { num, time } from "../lib/format";
import { atLeast, roleReason } from "../lib/session";
import { ReconnectingSocket } from "../lib/socket";
import type { Page, PageContext } from "./types";

type Notice = ReturnType<typeof notice>;

/** A record's result in a few words: its RMS reprojection error, or why it failed. */
function summary(c: CalibrationOut): string {
  if (c.status === "failed") return c.error ?? "failed";
  if (c.status === "running") return "running…";
  const rep = (c.report ?? {}) as Record<string, unknown>;
  const rms = rep.rms_px ?? rep.stereo_rms_px ?? rep.rms;
  return typeof rms === "number" ? `RMS ${num(rms, 3)} px` : "done";
}

/** A calibration record's row: download its rig file (done), activate it (done, not active; refusal: why this
 * session may not, null when it may). */
function calibrationRow(c: CalibrationOut, refusal: string | null, activate: (id: number) => void): HTMLTableRowElement {
  return h("tr", null, h("th", { scope: "row" }, String(c.id)),
    h("td", null, time(c.created_at)), h("td", null, c.status), h("td", null, `${c.board}, ${num(c.square_m * 1000, 1)} mm`),
    h("td", null, String(c.images)), h("td", { class: "detail" }, summary(c)), h("td", null, c.active ? "active" : ""),
    h("td", null, h("div", { class: "actions" },
      c.status === "done" ? h("a", { href: api.rigUrl(c.id), download: `rig-${c.id}.json`, class: "button small" },
        "Download rig", h("span", { class: "sr-only" }, ` of calibration ${c.id}`)) : null,
      c.status === "done" && !c.active ? h("button", { type: "button", class: "small", disabled: refusal !== null,
        title: refusal ?? undefined, "aria-label": `Activate calibration ${c.id}`, onclick: () => activate(c.id) },
      "Activate") : null)));
}

/** The progress of the calibration uploaded last (or of any, before an upload) from /ws/events. */
function calibrationProgress(): { progress: HTMLProgressElement; text: HTMLElement; started(id: number): void;
  onEvent(ev: ServerEvent): boolean } {
  const progress = h("progress", { max: 1, value: 0, "aria-label": "Calibration progress", hidden: true });
  const text = h("p", { class: "muted", role: "status", "aria-live": "polite", "data-testid": "cal-progress" });
  let watching: number | null = null;
  return {
    progress, text,
    started(id) {
      watching = id;
      progress.hidden = false;
      progress.removeAttribute("value");
      text.textContent = `Calibration #${id} started.`;
    },
    /** Show an event; true when a calibration ended (done or failed): the records changed. */
    onEvent(ev) {
      if (!ev.type?.startsWith("calibration.")) return false;
      if (watching !== null && ev.id !== watching) return false;
      if (ev.type === "calibration.progress") {
        const msg = String(ev.message ?? "");
        const m = /(\d+)\s*\/\s*(\d+)/.exec(msg);
        progress.hidden = false;
        if (m && Number(m[2]) > 0) progress.value = Number(m[1]) / Number(m[2]);
        else progress.removeAttribute("value");
        text.textContent = `Calibration #${ev.id}: ${msg}`;
        return false;
      }
      if (ev.type === "calibration.done") {
        progress.value = 1;
        text.textContent = `Calibration #${ev.id} done.`;
        return true;
      }
      if (ev.type === "calibration.failed") {
        progress.hidden = true;
        text.textContent = `Calibration #${ev.id} failed: ${ev.message ?? "see the record"}`;
        return true;
      }
      return false;
    },
  };
}

/** The upload form: left and right images, the board and its square size (admin; disabled otherwise). On
 * submit it checks the pairs, uploads them, says so in msg; uploaded: with the new record's id. */
function uploadForm(canEdit: boolean, msg: Notice, uploaded: (id: number) => void): HTMLFormElement {
  const left = h("input", { type: "file", name: "left", multiple: true, accept: "image/*", required: true });
  const right = h("input", { type: "file", name: "right", multiple: true, accept: "image/*", required: true });
  const board = h("input", { name: "board", value: "9x6", required: true, pattern: "\\d+x\\d+", size: 6 });
  const square = h("input", { name: "square", type: "number", step: "any", min: 0.001, max: 10, value: "0.025",
    required: true });
  const submit = h("button", { type: "submit", class: "primary" }, "Upload and calibrate");
  const form = h("form", { class: "row-form upload" },
    h("fieldset", { disabled: !canEdit, class: "plain" },
      h("legend", { class: "sr-only" }, "New calibration"),
      field("Left images", left, "in the same order as the right ones"), field("Right images", right),
      field("Board (inner corners)", board, "COLSxROWS, e.g. 9x6"), field("Square size (m)", square), submit));
  form.addEventListener("submit", async (ev) => {
    ev.preventDefault();
    if (!canEdit) return;
    const lf = Array.from(left.files ?? []), rf = Array.from(right.files ?? []);
    if (!lf.length || lf.length !== rf.length) {
      msg.show(`Choose as many right images as left ones (${lf.length} left, ${rf.length} right).`, "bad");
      return;
    }
    const fd = new FormData();
    lf.forEach((f) => fd.append("left", f, f.name));
    rf.forEach((f) => fd.append("right", f, f.name));
    fd.append("board", board.value.trim());
    fd.append("square", square.value);
    submit.disabled = true;
    msg.show(`Uploading ${lf.length} pairs…`, "info");
    try {
      const rec = await api.uploadCalibration(fd);
      uploaded(rec.id);
    } catch (e) {
      msg.show(`Upload refused: ${errorText(e)}`, "bad");
    } finally {
      submit.disabled = false;
    }
  });
  return form;
}

export function calibrationPage(ctx: PageContext): Page {
  const { root, session, status } = ctx;
  const canEdit = atLeast(session, "admin");
  const msg = notice("status");
  const watch = calibrationProgress();
  const form = uploadForm(canEdit, msg, (id) => {
    watch.started(id);
    msg.show(`Uploaded: calibration #${id} is running.`, "ok");
    void load();
  });
  const tbody = h("tbody");
  const table = h("table", { class: "data" }, h("caption", { class: "sr-only" }, "Calibrations, newest first"),
    h("thead", null, h("tr", null, ...["#", "Created", "Status", "Board", "Pairs", "Result", "Active", ""].map((c) =>
      h("th", { scope: "col" }, c)))), tbody);
  root.replaceChildren(h("section", { class: "page" }, h("h1", null, "Calibration"),
    h("section", { class: "panel", "aria-labelledby": "upload-title" }, h("h2", { id: "upload-title" }, "New calibration"),
      canEdit ? h("p", { class: "muted" }, "Upload pairs of chessboard photos taken by the left and right cameras at the same moments.")
        : h("p", { class: "reason", role: "note", "data-testid": "cal-reason" }, roleReason(session, "admin", "Calibrating")),
      form, watch.progress, watch.text),
    msg, h("div", { class: "table-wrap" }, table)));

  const onEvent = (ev: ServerEvent) => {
    if (watch.onEvent(ev)) void load();
  };
  const socket = new ReconnectingSocket<ServerEvent>({ path: "/ws/events", onMessage: onEvent,
    onState: (s) => status.slot("events", s === "open" ? "Events: connected" : "Events: reconnecting…", s === "open" ? "ok" : "warn") });

  const refusal = canEdit ? null : roleReason(session, "admin", "Activating a calibration");
  const activate = async (id: number) => {
    try {
      await api.activateCalibration(id);
      msg.show(`Calibration #${id} is now the tracker's rig.`, "ok");
      void load();
    } catch (e) {
      msg.show(`Not activated: ${errorText(e)}`, "bad");
    }
  };

  async function load(): Promise<void> {
    let list: CalibrationOut[];
    try {
      list = await api.calibrations();
    } catch (e) {
      msg.show(`Calibrations could not be loaded: ${errorText(e)}`, "bad");
      return;
    }
    tbody.replaceChildren(...(list.length ? list.map((c) => calibrationRow(c, refusal, (id) => void activate(id)))
      : [h("tr", null, h("td", { colSpan: 8, class: "muted" }, "No calibrations yet."))]));
  }
  void load();
  return { unmount: () => { socket.close(); status.slot("events", null); } };
}
