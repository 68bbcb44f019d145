// The Playback page's evidence: a note, a bookmark at the frame shown, a lock of the range (retention
// keeps it until an admin unlocks it), an export of the range (both cameras) with its progress and link,
// and the list of the range's bookmarks (click: show that frame) and locks (admin: unlock).
import { errorText } from "../api/client";
import { type Bookmark, type Lock, rec } from "../api/recordings";
import { field, h } from "../lib/dom";
import { time } from "../lib/format";

/** What the panel asks of the page. */
export interface EvidenceHooks {
  /** the range loaded (t0, t1) and the capture time of the frame shown (s) */
  range(): [number, number];
  cursor(): number;
  /** show the frame captured at t */
  showAt(t: number): void;
  /** the range's bookmarks and locks changed: the timeline marks them */
  marked(bookmarks: Bookmark[], locks: Lock[]): void;
  say(text: string, tone: string): void;
}

export interface EvidencePanel {
  el: HTMLElement;
  /** List the range's bookmarks and locks. */
  show(bookmarks: Bookmark[], locks: Lock[]): void;
}

/** Export the range t0..t1 (both cameras), its progress and then its download link (or why not) in out. */
async function exportRange([t0, t1]: [number, number], out: HTMLElement): Promise<void> {
  try {
    let job = await rec.exportRange(t0, t1);
    while (job.status === "queued" || job.status === "running") {
      out.textContent = `Export ${job.id}: ${job.status} ${Math.round(job.progress * 100)} %`;
      await new Promise((r) => setTimeout(r, 500));
      job = await rec.exportJob(job.id);
    }
    out.replaceChildren(job.status === "done"
      ? h("a", { href: rec.exportUrl(job.id), download: "", "data-testid": "export-link" }, `Download export ${job.id}`)
      : `Export ${job.id} failed: ${job.error ?? "unknown error"}`);
  } catch (e) {
    out.textContent = `Export failed: ${errorText(e)}`;
  }
}

export function evidencePanel(operator: boolean, admin: boolean, hooks: EvidenceHooks): EvidencePanel {
  const note = h("input", { type: "text", name: "note", maxLength: 2000, disabled: !operator });
  const bmBtn = h("button", { type: "button", disabled: !operator }, "Bookmark this frame");
  const lockBtn = h("button", { type: "button", disabled: !operator }, "Lock the range");
  const exportBtn = h("button", { type: "button", disabled: !operator }, "Export the range");
  const exportOut = h("p", { class: "muted", "data-testid": "export-status", "aria-live": "polite" });
  const marksList = h("ul", { class: "marks" });
  const roleHint = operator ? null : h("p", { class: "muted" }, "Bookmarks, locks and exports need the operator role.");
  const el = h("section", { class: "panel" }, h("h2", null, "Evidence"), field("Note", note), bmBtn, lockBtn, exportBtn,
    exportOut, roleHint, marksList);

  function show(bms: Bookmark[], locks: Lock[]): void {
    marksList.replaceChildren(
      ...bms.map((b) => h("li", null, h("button", { type: "button", class: "link", onclick: () => hooks.showAt(b.t) },
        `${time(b.t)}: ${b.note}`))),
      ...locks.map((l) => h("li", null, `Locked ${time(l.start)} – ${time(l.end)}${l.note ? `: ${l.note}` : ""} `,
        admin ? h("button", { type: "button", class: "small", onclick: () => void unlock(l.id) }, "Unlock") : null)));
  }

  /** List the range's bookmarks and locks again, and mark them on the timeline. */
  async function reload(): Promise<void> {
    const [t0, t1] = hooks.range();
    const [bms, locks] = await Promise.all([rec.bookmarks(t0, t1), rec.locks(t0, t1)]);
    show(bms, locks);
    hooks.marked(bms, locks);
  }

  async function unlock(id: number): Promise<void> {
    try {
      await rec.unlock(id);
      await reload();
    } catch (e) {
      hooks.say(`Unlock failed: ${errorText(e)}`, "bad");
    }
  }

  async function evidence(kind: "bookmark" | "lock"): Promise<void> {
    const [t0, t1] = hooks.range();
    try {
      if (kind === "bookmark") await rec.addBookmark(hooks.cursor(), note.value.trim() || "bookmark");
      else await rec.addLock(t0, t1, note.value.trim());
      await reload();
      hooks.say(kind === "bookmark" ? "Bookmarked." : "The range is locked: retention keeps it until an admin unlocks it.",
        "ok");
    } catch (e) {
      hooks.say(`${kind === "bookmark" ? "Bookmark" : "Lock"} failed: ${errorText(e)}`, "bad");
    }
  }

  bmBtn.addEventListener("click", () => void evidence("bookmark"));
  lockBtn.addEventListener("click", () => void evidence("lock"));
  exportBtn.addEventListener("click", () => void exportRange(hooks.range(), exportOut));
  return { el, show };
}
