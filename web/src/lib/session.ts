// Who is logged in. The session itself is the HttpOnly cookie; the console remembers the username and
// role from the login answer (localStorage) to shape the pages, and asks the server when it can.
import { api, ApiError, request, setCsrfToken } from "../api/client";
import type { Role } from "../api/types";

export interface Session {
  username: string;
  role: Role;
}

const KEY = "tmeye.session";
const RANK: Record<Role, number> = { viewer: 0, operator: 1, admin: 2 };

export function atLeast(s: Session | null, role: Role): boolean {
  return !!s && RANK[s.role] >= RANK[role];
}

export function roleReason(s: Session | null, role: Role, what: string): string {
  return `${what} needs the ${role} role; you are logged in as ${s?.username ?? "?"} (${s?.role ?? "no role"}).`;
}

function remembered(): Session | null {
  try {
    const s = JSON.parse(localStorage.getItem(KEY) ?? "null") as Session | null;
    return s && typeof s.username === "string" && s.role in RANK ? s : null;
  } catch {
    return null;
  }
}

function remember(s: Session | null): void {
  if (s) localStorage.setItem(KEY, JSON.stringify(s));
  else localStorage.removeItem(KEY);
}

export async function login(username: string, password: string): Promise<Session> {
  const ans = await api.login(username, password);
  setCsrfToken(ans.csrf_token);
  const s = { username, role: ans.role };
  remember(s);
  return s;
}

export async function logout(): Promise<void> {
  try {
    await api.logout();
  } catch {
    /* the session may already be gone */
  }
  forget();
}

export function forget(): void {
  setCsrfToken(null);
  remember(null);
}

/** The current session, or null when the cookie is missing or no longer valid. Throws ApiError(0) while
 * the server cannot be reached. */
export async function current(): Promise<Session | null> {
  try {
    const me = await api.me();
    if (me && me.role in RANK) {
      const s = { username: me.username, role: me.role as Role };
      remember(s);
      return s;
    }
  } catch (e) {
    if (e instanceof ApiError && e.status === 401) {
      forget();
      return null;
    }
    if (e instanceof ApiError && e.offline) throw e;
    // no /api/auth/me on this server: fall through
  }
  try {
    await api.health();
    await request("GET", "/api/servo", { quiet401: true });
  } catch (e) {
    if (e instanceof ApiError && e.status === 401) {
      forget();
      return null;
    }
    throw e;
  }
  return remembered() ?? (await probeRole());
}

/** Without /api/auth/me and with nothing remembered: find the role from what the server allows. */
async function probeRole(): Promise<Session> {
  const allowed = async (method: string, path: string, body?: unknown) => {
    try {
      await request(method, path, { body, quiet401: true });
      return true;
    } catch (e) {
      return !(e instanceof ApiError && (e.status === 403 || e.status === 401));
    }
  };
  // GET /api/users needs admin; an invalid mode is refused with 422 after the operator check (403 before).
  const role: Role = (await allowed("GET", "/api/users"))
    ? "admin"
    : (await allowed("PUT", "/api/servo/mode", { mode: "?" }))
      ? "operator"
      : "viewer";
  const s = { username: "(this browser)", role };
  remember(s);
  return s;
}
