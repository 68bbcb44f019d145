// The console's shell: session check, navigation (hash routes), one module per page, the status bar.
import "./styles.css";
import { errorText, onUnauthorized } from "./api/client";
import { alarmCenter } from "./lib/alarms";
import { AlarmBanner } from "./lib/banner";
import { h } from "./lib/dom";
import { atLeast, current, forget, logout, type Session } from "./lib/session";
import { StatusBar } from "./lib/statusbar";
import { renderLogin } from "./pages/login";
import { placeholder } from "./pages/placeholder";
import type { Page, PageFactory } from "./pages/types";
import type { Role } from "./api/types";

interface Route {
  name: string;
  label: string;
  load?: () => Promise<PageFactory>;
  role?: Role;
  soon?: string;
}

const ROUTES: Route[] = [
  { name: "live", label: "Live", load: () => import("./pages/live").then((m) => m.livePage) },
  { name: "playback", label: "Playback", load: () => import("./pages/playback").then((m) => m.playbackPage) },
  { name: "tracks", label: "Tracks", load: () => import("./pages/tracks").then((m) => m.tracksPage) },
  { name: "alarms", label: "Alarms", load: () => import("./pages/alarms").then((m) => m.alarmsPage) },
  { name: "calibration", label: "Calibration", load: () => import("./pages/calibration").then((m) => m.calibrationPage) },
  { name: "settings", label: "Settings", load: () => import("./pages/settings").then((m) => m.settingsPage) },
  { name: "users", label: "Users", role: "admin", load: () => import("./pages/users").then((m) => m.usersPage) },
];

const app = document.getElementById("app")!;
const status = new StatusBar();
let session: Session | null = null;
let page: Page | null = null;
let navToken = 0;

const nav = h("nav", { class: "nav", "aria-label": "Pages" });
const who = h("span", { class: "who", "data-testid": "who" });
const logoutBtn = h("button", { type: "button", class: "link" }, "Log out");
const main = h("main", { id: "main", tabindex: -1 });
const banner = new AlarmBanner(alarmCenter);
const shell = h("div", { class: "shell" },
  h("header", { class: "topbar" }, h("a", { class: "brand", href: "#/live" }, "TMEye"), nav,
    h("div", { class: "account" }, who, logoutBtn)),
  banner.el, main, status.el);

logoutBtn.addEventListener("click", async () => {
  await logout();
  showLogin("You are logged out.");
});

function routeOf(): { route: Route; params: string[]; query: URLSearchParams } {
  const [path, search = ""] = location.hash.replace(/^#\/?/, "").split("?", 2);
  const parts = path.split("/").filter(Boolean);
  const route = ROUTES.find((r) => r.name === parts[0]) ?? ROUTES[0];
  return { route, params: parts.slice(1), query: new URLSearchParams(search) };
}

function renderNav(active: string): void {
  nav.replaceChildren(...ROUTES.map((r) => {
    if (r.soon) {
      return h("span", { class: "nav-soon", "aria-disabled": "true", title: r.soon }, r.label,
        h("span", { class: "sr-only" }, " (coming later)"));
    }
    if (r.role && !atLeast(session, r.role)) return null;
    return h("a", { href: `#/${r.name}`, "aria-current": r.name === active ? "page" : undefined }, r.label);
  }).filter((x): x is HTMLElement => x !== null));
}

async function showPage(): Promise<void> {
  if (!session) return;
  const token = ++navToken;
  const { route, params, query } = routeOf();
  page?.unmount?.();
  page = null;
  status.clearSlots();
  renderNav(route.name);
  document.title = `${route.label} · TMEye`;
  const root = h("div", { class: `page-root page-${route.name}` });
  main.replaceChildren(root);
  let factory: PageFactory;
  if (route.soon) factory = placeholder(route.label, route.soon);
  else if (route.role && !atLeast(session, route.role)) {
    factory = placeholder(route.label, `This page needs the ${route.role} role; you are ${session.role}.`);
  } else {
    root.append(h("p", { class: "muted" }, "Loading…"));
    factory = await route.load!();
  }
  if (token !== navToken) return;
  const p = await factory({ session, root, status, params, query });
  if (token !== navToken) {
    p.unmount?.();
    return;
  }
  page = p;
}

function showLogin(message?: string): void {
  page?.unmount?.();
  page = null;
  session = null;
  status.stop();
  alarmCenter.stop();
  document.title = "Log in · TMEye";
  renderLogin(app, (s) => {
    session = s;
    enter();
  }, message);
}

function enter(): void {
  who.textContent = `${session!.username} (${session!.role})`;
  app.replaceChildren(shell);
  status.start();
  alarmCenter.start();
  void showPage();
}

onUnauthorized(() => {
  if (!session) return;
  forget();
  showLogin("Your session has ended (logged out, expired or the password changed): log in again.");
});

window.addEventListener("hashchange", () => {
  if (session) {
    void showPage();
    main.focus({ preventScroll: true });
  }
});

async function boot(): Promise<void> {
  for (let attempt = 1; ; attempt++) {
    try {
      session = await current();
      break;
    } catch (e) {
      const why = errorText(e);
      app.replaceChildren(h("section", { class: "login-page" }, h("p", { role: "status" },
        `The server cannot be reached (${why}); retrying (${attempt})…`)));
      await new Promise((r) => setTimeout(r, 2000));
    }
  }
  if (session) enter();
  else showLogin();
}

void boot();
