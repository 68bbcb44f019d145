"""OWASP ASVS checks on a real `tmeye serve` (the items test_server_api.py does not already cover: it has
throttling, logout and password-change revocation, the CSRF header and the role walk over OpenAPI):

- V3 / V14: security headers (CSP with the console's own scripts only, nosniff, frame-ancestors);
- V7.3: idle and absolute session expiry;
- V4 / V7: WebSocket handshakes need a live session; a cookie-authenticated one must be same-origin;
- V7.1 / V8: no passwords, tokens or keys in the log;
- V9: HTTPS served directly (--tls-cert/--tls-key) with Secure cookies and HSTS;
- V12: X-Forwarded-For and -Proto believed only from --trusted-proxy addresses.
"""

from __future__ import annotations

import asyncio
import base64
import datetime as dt
import ipaddress
import json
import ssl
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import httpx
import pytest
import websockets
from server_helpers import Server, start_server

PASSWORD = "correct horse battery"


@pytest.fixture(scope="module")
def server(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Server]:
    s = start_server(tmp_path_factory.mktemp("harden") / "data", "--log-level", "debug")
    yield s
    s.stop()


def _ws_url(server: Server, path: str) -> str:
    return server.url.replace("http", "ws", 1) + path


async def _ws_first(url: str, headers: dict[str, str]) -> tuple[str, Any]:
    """('message', the first message) or ('closed', (code, reason))."""
    async with websockets.connect(url, additional_headers=headers, open_timeout=10) as ws:
        try:
            return "message", json.loads(await asyncio.wait_for(ws.recv(), 10))
        except websockets.ConnectionClosed as exc:
            return "closed", (exc.rcvd.code if exc.rcvd else None, exc.rcvd.reason if exc.rcvd else "")


def ws_first(server: Server, path: str, headers: dict[str, str]) -> tuple[str, Any]:
    return asyncio.run(_ws_first(_ws_url(server, path), headers))


def test_security_headers(server: Server) -> None:
    for path in ("/api/health", "/api/openapi.json", "/", "/api/status"):
        r = httpx.get(server.url + path)
        csp = r.headers["content-security-policy"]
        assert "script-src 'self'" in csp and "frame-ancestors 'none'" in csp and "unsafe" not in csp, (path, csp)
        assert "default-src 'self'" in csp and "object-src 'none'" in csp
        assert r.headers["x-content-type-options"] == "nosniff" and r.headers["x-frame-options"] == "DENY"
        assert "strict-transport-security" not in r.headers  # plain HTTP: no HSTS
    docs = httpx.get(server.url + "/api/docs")
    assert docs.status_code == 200 and docs.headers["content-security-policy"].startswith("frame-ancestors 'none'")


def test_console_runs_under_its_csp_in_chromium(server: Server) -> None:
    """Every page of the built console loads and works with the CSP on: no violation reported."""
    from web_helpers import admin, browser, login, new_page, skip_reason

    if skip_reason():
        pytest.skip(skip_reason() or "")
    violations: list[str] = []
    with browser() as b:
        page = new_page(b, server)
        page.on("console", lambda m: violations.append(m.text) if "Content Security Policy" in m.text else None)
        login(page, *admin(server))
        page.wait_for_function("() => document.body.innerText.match(/frame/i)", timeout=20000)
        for hash_ in ("#/tracks", "#/settings", "#/users", "#/calibration", "#/"):
            page.goto("/" + hash_)
            page.get_by_role("navigation", name="Pages").wait_for()
            page.wait_for_timeout(500)
        csp = page.evaluate("async () => (await fetch('/')).headers.get('content-security-policy')")
        assert "script-src 'self'" in csp
        page.context.close()
    assert not violations, violations


def test_websockets_need_a_live_session(server: Server) -> None:
    token = server.add_user("wendy", "viewer", PASSWORD)
    for path in ("/ws/telemetry", "/ws/events"):
        kind, what = ws_first(server, path, {})
        assert kind == "closed" and what[0] == 1008 and "not logged in" in what[1], (path, what)
        kind, what = ws_first(server, path, {"Authorization": "Bearer v1.forged.9999999999.abc"})
        assert kind == "closed" and what[0] == 1008 and "invalid" in what[1], (path, what)
    kind, msg = ws_first(server, "/ws/telemetry", {"Authorization": f"Bearer {token}"})
    assert kind == "message" and msg["frame"] >= 0
    with server.client(token) as c:
        assert c.post("/api/auth/logout").status_code == 204
    kind, what = ws_first(server, "/ws/telemetry", {"Authorization": f"Bearer {token}"})
    assert kind == "closed" and what[0] == 1008 and "session ended" in what[1]


def test_cookie_websocket_must_be_same_origin(server: Server) -> None:
    r = httpx.post(f"{server.url}/api/auth/login", data={"username": "admin", "password": server.admin_password})
    cookie = f"tmeye_session={r.cookies['tmeye_session']}"
    host = server.url.split("//", 1)[1]
    kind, msg = ws_first(server, "/ws/telemetry", {"Cookie": cookie, "Origin": f"http://{host}"})
    assert kind == "message" and "frame" in msg
    kind, what = ws_first(server, "/ws/telemetry", {"Cookie": cookie, "Origin": "https://evil.example"})
    assert kind == "closed" and what[0] == 1008 and "cross-origin" in what[1]


def test_no_secrets_in_the_log(server: Server) -> None:
    secrets: list[str] = [server.admin_password, PASSWORD, "a brand new password 123", "wrong password 1234"]
    token = server.add_user("logan", "operator", PASSWORD)
    secrets.append(token)
    httpx.post(f"{server.url}/api/auth/login", data={"username": "logan", "password": "wrong password 1234"})
    with server.as_admin() as a:
        uid = next(u["id"] for u in a.get("/api/users").json() if u["username"] == "logan")
        assert a.patch(f"/api/users/{uid}", json={"password": "a brand new password 123"}).status_code == 200
        r = a.post("/api/users", json={"username": "short", "password": "tiny pw", "role": "viewer"})
        assert r.status_code == 422 and "tiny pw" not in r.text
    secrets.append(server.tokens["admin"])
    r = httpx.post(f"{server.url}/api/auth/login", data={"username": "admin", "password": server.admin_password})
    secrets += [r.json()["access_token"], r.json()["csrf_token"]]
    key = (server.data_dir / "secret-key").read_bytes()
    secrets += [key.hex(), base64.b64encode(key).decode(), base64.urlsafe_b64encode(key).decode().rstrip("=")]
    time.sleep(0.5)
    log = server.log_text()
    assert "DEBUG" in log  # the most talkative level was on
    for s in secrets:
        assert s not in log, f"a secret is in the log: {s[:6]}..."
    signatures = [t.rsplit(".", 1)[1] for t in secrets if t.startswith("v1.")]
    assert signatures and not any(sig in log for sig in signatures)


def test_forwarded_for_is_ignored_from_untrusted_peers(server: Server) -> None:
    r = httpx.post(f"{server.url}/api/auth/login", data={"username": "admin", "password": server.admin_password},
                   headers={"X-Forwarded-For": "203.0.113.9", "X-Forwarded-Proto": "https"})
    assert "secure" not in r.headers["set-cookie"].lower()
    with server.as_admin() as a:
        entry = a.get("/api/audit", params={"action": "auth.login"}).json()[0]
    assert entry["address"] == "127.0.0.1"


def test_idle_and_absolute_session_expiry(tmp_path: Path) -> None:
    s = start_server(tmp_path / "data", env={"TMEYE_SESSION_IDLE_S": "3", "TMEYE_TOKEN_TTL_S": "9"})
    try:
        idle, busy = s.login(), s.login()
        t0 = time.monotonic()
        with s.client(idle) as c:
            assert c.get("/api/auth/me").status_code == 200
        with s.client(busy) as c:
            while time.monotonic() - t0 < 4.5:  # a request a second keeps the idle timer from running out
                assert c.get("/api/auth/me").status_code == 200
                time.sleep(1.0)
        with s.client(idle) as c:
            r = c.get("/api/auth/me")
            assert r.status_code == 401 and "without a request" in r.json()["detail"]
            assert c.get("/api/auth/me").status_code == 401  # and it stays ended
        with s.client(busy) as c:
            while time.monotonic() - t0 < 10.0:  # past the absolute lifetime, however busy
                code = c.get("/api/auth/me").status_code
                if code == 401:
                    break
                time.sleep(1.0)
            assert code == 401 and time.monotonic() - t0 > 8.0
    finally:
        s.stop()


def _self_signed(directory: Path) -> tuple[Path, Path]:
    from cryptography import x509
    from cryptography.hazmat.primitives import hashes, serialization
    from cryptography.hazmat.primitives.asymmetric import ec
    from cryptography.x509.oid import NameOID

    key = ec.generate_private_key(ec.SECP256R1())
    name = x509.Name([x509.NameAttribute(NameOID.COMMON_NAME, "127.0.0.1")])
    now = dt.datetime.now(dt.UTC)
    cert = (x509.CertificateBuilder().subject_name(name).issuer_name(name).public_key(key.public_key())
            .serial_number(x509.random_serial_number()).not_valid_before(now - dt.timedelta(minutes=1))
            .not_valid_after(now + dt.timedelta(days=1))
            .add_extension(x509.SubjectAlternativeName([x509.IPAddress(ipaddress.ip_address("127.0.0.1"))]), False)
            .sign(key, hashes.SHA256()))
    cert_path, key_path = directory / "cert.pem", directory / "key.pem"
    cert_path.write_bytes(cert.public_bytes(serialization.Encoding.PEM))
    key_path.write_bytes(key.private_bytes(serialization.Encoding.PEM, serialization.PrivateFormat.PKCS8,
                                           serialization.NoEncryption()))
    return cert_path, key_path


def test_https_directly_and_trusted_proxy(tmp_path: Path) -> None:
    cert, key = _self_signed(tmp_path)
    s = start_server(tmp_path / "data", "--tls-cert", str(cert), "--tls-key", str(key),
                     "--trusted-proxy", "127.0.0.1")
    try:
        assert s.url.startswith("https://")
        with httpx.Client(base_url=s.url, verify=ssl.create_default_context(cafile=str(cert))) as c:
            assert c.get("/api/health").json()["status"] == "ok"
            r = c.post("/api/auth/login", data={"username": "admin", "password": s.admin_password},
                       headers={"X-Forwarded-For": "198.51.100.7"})
            cookies = r.headers.get_list("set-cookie")
            assert all("Secure" in h and "HttpOnly" in h and "SameSite=strict" in h
                       for h in cookies if h.startswith("tmeye_session=")), cookies
            assert r.headers["strict-transport-security"].startswith("max-age=")
            audit = c.get("/api/audit", params={"action": "auth.login"},
                          headers={"Authorization": f"Bearer {r.json()['access_token']}"}).json()
            assert audit[0]["address"] == "198.51.100.7"  # from a trusted proxy, X-Forwarded-For is the client
        with pytest.raises(httpx.HTTPError):
            httpx.get(s.url.replace("https", "http", 1) + "/api/health", timeout=5)
    finally:
        s.stop()


def test_bad_tls_and_proxy_settings_are_one_line_errors(tmp_path: Path) -> None:
    import subprocess
    import sys

    from server_helpers import ROOT

    for args, needle in ((["--tls-cert", str(tmp_path / "c.pem")], "tls_cert and tls_key go together"),
                         (["--tls-cert", str(tmp_path / "c.pem"), "--tls-key", str(tmp_path / "k.pem")],
                          "is not a readable file"),
                         (["--trusted-proxy", "proxy.lan"], "not an IP address or network")):
        p = subprocess.run([sys.executable, "-m", "tmeye", "serve", "--port", "0", "--data-dir",
                            str(tmp_path / "d"), *args], cwd=ROOT, capture_output=True, text=True, timeout=60)
        assert p.returncode != 0 and needle in p.stderr, (args, p.stderr)
        assert len(p.stderr.strip().splitlines()) == 1, p.stderr


def test_a_locked_database_is_a_503_and_no_crash(server: Server) -> None:
    import sqlite3

    with server.as_admin() as a:
        lock = sqlite3.connect(server.data_dir / "tmeye.db", timeout=1)
        try:
            lock.execute("BEGIN EXCLUSIVE")  # another writer holds the database past the 5 s busy timeout
            r = a.post("/api/servo/presets", json={"name": "while-locked", "pan_deg": 1, "tilt_deg": 1})
            assert r.status_code == 503 and "database unavailable (database is locked)" in r.json()["detail"], r.text
            assert r.headers["retry-after"] == "5"
            assert a.get("/api/status").json()["state"] == "running"  # reads go on (WAL)
        finally:
            lock.rollback()
            lock.close()
        assert "while-locked" not in [p["name"] for p in a.get("/api/servo/presets").json()]  # nothing half-stored
        r = a.post("/api/servo/presets", json={"name": "after-lock", "pan_deg": 1, "tilt_deg": 1})
        assert r.status_code == 201, r.text
    assert httpx.get(f"{server.url}/api/health").json()["status"] == "ok"
