// The Login page: a labelled form (Username, Password, "Log in") posting to /api/auth/login.
import { ApiError } from "../api/client";
import { field, h, notice } from "../lib/dom";
import { login, type Session } from "../lib/session";

export function renderLogin(root: HTMLElement, onDone: (s: Session) => void, message?: string): void {
  const user = h("input", { name: "username", autocomplete: "username", required: true, autocapitalize: "none",
    spellcheck: false });
  const pass = h("input", { name: "password", type: "password", autocomplete: "current-password", required: true });
  const msg = notice("alert");
  const button = h("button", { type: "submit", class: "primary" }, "Log in");
  const form = h("form", { class: "login-form", "aria-labelledby": "login-title" },
    h("h1", { id: "login-title" }, "TMEye console"),
    h("p", { class: "muted" }, "Log in to see the cameras and drive the mount."),
    field("Username", user), field("Password", pass), msg, button);
  if (message) msg.show(message, "warn");
  form.addEventListener("submit", async (ev) => {
    ev.preventDefault();
    button.disabled = true;
    msg.show("Logging in…", "info");
    try {
      const s = await login(user.value.trim(), pass.value);
      pass.value = "";
      msg.show("", "info");
      onDone(s);
    } catch (e) {
      const err = e instanceof ApiError ? e : new ApiError(0, String(e));
      msg.show(
        err.status === 401 ? "Wrong username or password." :
        err.status === 429 ? `Too many failed logins: try again in ${err.retryAfter ?? "a few"} s.` :
        err.offline ? "The server cannot be reached: check that it runs and try again." :
        `Login failed: ${err.detail}`, "bad");
      (err.status === 401 ? pass : user).focus();
    } finally {
      button.disabled = false;
    }
  });
  root.replaceChildren(h("section", { class: "login-page" }, form));
  (user.value ? pass : user).focus();
}
