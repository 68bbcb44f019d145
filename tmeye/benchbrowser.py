"""`tmeye bench --browser`: the console's Live page in headless chromium, measured.

Starts `tmeye serve` (the default simulated scene, closed loop), logs in through the console's form in
Debian's chromium driven by Playwright (the Python package; it never downloads a browser), waits until
both cameras play over WebRTC, then over a window counts per camera the frames the page was called back
for (requestVideoFrameCallback: frames composited on screen) and, from the peer connection's inbound-rtp
statistics, the frames received, decoded and dropped and the freezes; and the server's CPU meanwhile."""

from __future__ import annotations

import os
import secrets
import time
from pathlib import Path
from typing import Any

CHROMIUM = Path(os.environ.get("TMEYE_CHROMIUM", "/usr/bin/chromium"))
CHROMIUM_ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                 "--disable-background-networking", "--disable-component-update", "--disable-sync",
                 "--allow-loopback-in-peer-connection", "--disable-features=WebRtcHideLocalIpsWithMdns",
                 "--autoplay-policy=no-user-gesture-required"]

# keeps every RTCPeerConnection the page makes, to read its statistics
_HOOK = """(() => { const O = window.RTCPeerConnection; window.__pcs = [];
  window.RTCPeerConnection = function (...a) { const pc = new O(...a); window.__pcs.push(pc); return pc; };
  window.RTCPeerConnection.prototype = O.prototype; })();"""
_STATS = """async () => { const out = {};
  for (const pc of window.__pcs) { if (pc.connectionState !== 'connected') continue;
    (await pc.getStats()).forEach(r => { if (r.type === 'inbound-rtp' && r.kind === 'video')
      out[r.mid] = {received: r.framesReceived, decoded: r.framesDecoded, dropped: r.framesDropped,
                    freezes: r.freezeCount, decode_s: r.totalDecodeTime}; }); }
  return out; }"""


def _snapshot(page: Any) -> tuple[float, dict[str, int], dict[str, dict[str, float]]]:
    frames = page.evaluate("() => ({...window.__tmeye.frames})")
    return time.monotonic(), frames, page.evaluate(_STATS)


def _rates(a: tuple[float, dict[str, int], dict[str, dict[str, float]]],
           b: tuple[float, dict[str, int], dict[str, dict[str, float]]]) -> dict[str, Any]:
    dt = b[0] - a[0]
    out: dict[str, Any] = {"window_s": round(dt, 2)}
    for mid, cam in (("0", "left"), ("1", "right")):
        s0, s1 = a[2].get(mid, {}), b[2].get(mid, {})
        per: dict[str, Any] = {"rvfc_fps": round((b[1][cam] - a[1][cam]) / dt, 2)}
        for k in ("received", "decoded", "dropped", "freezes"):
            if k in s1 and k in s0 and s1[k] is not None and s0[k] is not None:
                per[f"{k}_per_s" if k != "freezes" else k] = round((s1[k] - s0[k]) / (dt if k != "freezes" else 1), 2)
        out[cam] = per
    return out


def run_browser_bench(seconds: float, extra: list[str]) -> dict[str, Any]:
    """Log in to a fresh server's console in headless chromium and measure the Live page's video."""
    import httpx
    from playwright.sync_api import sync_playwright

    from tmeye.benchserver import _cpu_s, served

    if not CHROMIUM.exists():
        raise RuntimeError(f"{CHROMIUM} is missing (apt-get install -y chromium)")
    password = secrets.token_urlsafe(12)
    with served(extra) as (pid, base, token):
        httpx.post(f"{base}/api/users", headers={"Authorization": f"Bearer {token}"},
                   json={"username": "bench", "password": password, "role": "viewer"}).raise_for_status()
        with sync_playwright() as p:
            browser = p.chromium.launch(executable_path=str(CHROMIUM), args=CHROMIUM_ARGS)
            try:
                ctx = browser.new_context(viewport={"width": 1280, "height": 720}, base_url=base,
                                          permissions=["camera", "microphone"])
                ctx.add_init_script(_HOOK)
                page = ctx.new_page()
                page.goto("/")
                page.get_by_label("Username").fill("bench")
                page.get_by_label("Password").fill(password)
                page.get_by_role("button", name="Log in").click()
                page.wait_for_function("() => window.__tmeye && window.__tmeye.source === 'webrtc' && "
                                       "window.__tmeye.frames.left > 30 && window.__tmeye.frames.right > 30",
                                       timeout=60000)
                page.wait_for_timeout(2000)
                cpu0, a = _cpu_s(pid), _snapshot(page)
                page.wait_for_timeout(int(seconds * 1000))
                b = _snapshot(page)
                cpu = (_cpu_s(pid) - cpu0) / (b[0] - a[0])
            finally:
                browser.close()
    return {**_rates(a, b), "server_cpu_cores": round(cpu, 3), "chromium": str(CHROMIUM)}
