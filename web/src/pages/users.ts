// The Users page (admin): list, create, change role / password / disabled, delete; and the audit log.
import { api, errorText } from "../api/client";
import type { AuditOut, Role, UserOut } from "../api/types";
import { field, h, notice, uid } from "../lib/dom";
import { fromLocalInput, time, toLocalInput } from "../lib/format";
import type { Page, PageContext } from "./types";

const ROLES: Role[] = ["viewer", "operator", "admin"];

type Say = (text: string, tone: string) => void;
type Fail = (what: string, e: unknown) => void;

/** One user's row: role, disabled, a new password, Save (only what changed) and Delete (not oneself).
 * changed: after a save or a delete (the list and the audit log are loaded again). The row's fields belong
 * to a form of its own (the `form` attribute: a form cannot hold a table row's cells), so that Enter in
 * them saves, and the password field is in a form, as password managers need. */
function userRow(u: UserOut, self: boolean, say: Say, fail: Fail, changed: () => void): HTMLTableRowElement {
  const formId = uid("user-form");
  const r = h("select", { name: `role-${u.id}`, form: formId, "aria-label": `Role of ${u.username}` },
    ...ROLES.map((x) => h("option", { value: x, selected: x === u.role }, x)));
  const dis = h("input", { type: "checkbox", name: `disabled-${u.id}`, form: formId, checked: u.disabled,
    "aria-label": `${u.username} is disabled` });
  const pw = h("input", { type: "password", name: `password-${u.id}`, form: formId, minLength: 12, maxLength: 128,
    autocomplete: "new-password", "aria-label": `New password for ${u.username}`, placeholder: "unchanged" });
  const save = async () => {
    const patch: { role?: Role; disabled?: boolean; password?: string } = {};
    if (r.value !== u.role) patch.role = r.value as Role;
    if (dis.checked !== u.disabled) patch.disabled = dis.checked;
    if (pw.value) patch.password = pw.value;
    if (!Object.keys(patch).length) {
      say(`Nothing changed for ${u.username}.`, "info");
      return;
    }
    try {
      await api.patchUser(u.id, patch);
      say(`Saved ${u.username}${patch.password ? " (its sessions were ended)" : ""}.`, "ok");
      changed();
    } catch (e) {
      fail(`${u.username} not saved`, e);
    }
  };
  const remove = async () => {
    if (!confirm(`Delete the user ${u.username}?`)) return;
    try {
      await api.deleteUser(u.id);
      say(`Deleted ${u.username}.`, "ok");
      changed();
    } catch (e) {
      fail(`${u.username} not deleted`, e);
    }
  };
  const form = h("form", { id: formId, "aria-label": `Change ${u.username}`, onsubmit: (ev: Event) => {
    ev.preventDefault();
    void save();
  } }, h("input", { type: "text", name: "username", autocomplete: "username", value: u.username, hidden: true,
    readOnly: true }));  // whose password it is, for password managers
  const saveBtn = h("button", { type: "submit", form: formId, class: "small", "aria-label": `Save ${u.username}` }, "Save");
  const delBtn = h("button", { type: "button", class: "small danger", "aria-label": `Delete ${u.username}`,
    disabled: self, title: self ? "You cannot delete yourself" : undefined, onclick: remove }, "Delete");
  return h("tr", { "data-user": u.username }, h("th", { scope: "row" }, u.username, self ? " (you)" : ""),
    h("td", null, r), h("td", null, time(u.created_at)), h("td", null, dis), h("td", null, pw),
    h("td", null, form, h("div", { class: "actions" }, saveBtn, delBtn)));
}

/** The audit log since a time, of one action or all, newest first (200 entries). */
function auditPanel(fail: Fail): { el: HTMLElement; load(): Promise<void> } {
  const start = h("input", { type: "datetime-local", name: "audit-start", value: toLocalInput(Date.now() / 1000 - 86400) });
  const action = h("input", { name: "audit-action", placeholder: "e.g. servo.jog", maxLength: 64 });
  const form = h("form", { class: "row-form" }, field("Since", start), field("Action", action, "empty: all"),
    h("button", { type: "submit" }, "Show audit log"));
  const body = h("tbody");
  const table = h("table", { class: "data" }, h("caption", { class: "sr-only" }, "Audit log, newest first"),
    h("thead", null, h("tr", null, ...["Time", "User", "Address", "Action", "Target", "Detail"].map((c) =>
      h("th", { scope: "col" }, c)))), body);
  async function load(): Promise<void> {
    let list: AuditOut[];
    try {
      list = await api.audit({ start: fromLocalInput(start.value), action: action.value.trim() || undefined, limit: 200 });
    } catch (e) {
      fail("Audit log could not be loaded", e);
      return;
    }
    body.replaceChildren(...(list.length ? list.map((a) => h("tr", null, h("td", null, time(a.at)),
      h("td", null, a.username ?? "—"), h("td", null, a.address ?? "—"), h("td", null, h("code", null, a.action)),
      h("td", null, a.target ?? ""), h("td", { class: "detail" }, a.detail ? JSON.stringify(a.detail) : "")))
      : [h("tr", null, h("td", { colSpan: 6, class: "muted" }, "No entries."))]));
  }
  form.addEventListener("submit", (ev) => {
    ev.preventDefault();
    void load();
  });
  const el = h("section", { class: "panel", "aria-labelledby": "audit-title" }, h("h2", { id: "audit-title" }, "Audit log"),
    form, h("div", { class: "table-wrap" }, table));
  return { el, load };
}

/** The form creating a user (username, password, role). created: after a user was made. */
function createForm(say: Say, fail: Fail, created: () => void): HTMLFormElement {
  const name = h("input", { name: "new-username", required: true, maxLength: 64, pattern: "[A-Za-z0-9_.@\\-]+",
    autocomplete: "off" });
  const pass = h("input", { name: "new-password", type: "password", required: true, minLength: 12, maxLength: 128,
    autocomplete: "new-password" });
  const role = h("select", { name: "new-role" }, ...ROLES.map((r) => h("option", { value: r }, r)));
  const form = h("form", { class: "row-form" }, field("New username", name),
    field("Password", pass, "12 to 128 characters"), field("Role", role), h("button", { type: "submit", class: "primary" }, "Create user"));
  form.addEventListener("submit", async (ev) => {
    ev.preventDefault();
    try {
      const u = await api.createUser({ username: name.value.trim(), password: pass.value, role: role.value as Role });
      say(`Created ${u.username} (${u.role}).`, "ok");
      name.value = "";
      pass.value = "";
      created();
    } catch (e) {
      fail("User not created", e);
    }
  });
  return form;
}

export function usersPage(ctx: PageContext): Page {
  const { root, session } = ctx;
  const msg = notice("status");
  const say: Say = (text, tone) => msg.show(text, tone);
  const fail: Fail = (what, e) => msg.show(`${what}: ${errorText(e)}`, "bad");
  const tbody = h("tbody");
  const table = h("table", { class: "data" }, h("caption", { class: "sr-only" }, "Users"),
    h("thead", null, h("tr", null, ...["User", "Role", "Created", "Disabled", "New password", ""].map((c) =>
      h("th", { scope: "col" }, c)))), tbody);
  const audit = auditPanel(fail);
  const changed = () => {
    void load();
    void audit.load();
  };
  root.replaceChildren(h("section", { class: "page" }, h("h1", null, "Users"), msg,
    h("div", { class: "table-wrap" }, table),
    h("section", { class: "panel", "aria-labelledby": "create-title" }, h("h2", { id: "create-title" }, "Create a user"),
      createForm(say, fail, changed)),
    audit.el));

  async function load(): Promise<void> {
    let list: UserOut[];
    try {
      list = await api.users();
    } catch (e) {
      fail("Users could not be loaded", e);
      return;
    }
    tbody.replaceChildren(...list.map((u) => userRow(u, u.username === session.username, say, fail, changed)));
  }
  changed();
  return {};
}
