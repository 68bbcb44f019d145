"""Security headers on every HTTP answer (a pure ASGI middleware: streams and WebSockets pass untouched).

- Content-Security-Policy: the console's own scripts, styles and connections only ('self'; no inline
  script, no eval); images also from data: and blob: URLs (snapshots); no plugins; no framing by other
  sites (frame-ancestors 'none'; X-Frame-Options for older browsers). The interactive API docs page
  (/api/docs) loads Swagger UI from its CDN with an inline bootstrap script, so it gets only the framing,
  sniffing and referrer rules.
- X-Content-Type-Options: nosniff; Referrer-Policy: no-referrer; Strict-Transport-Security over HTTPS.
"""

from __future__ import annotations

from collections.abc import Awaitable, Callable, MutableMapping
from typing import Any

Scope = MutableMapping[str, Any]
Message = MutableMapping[str, Any]
ASGIApp = Callable[[Scope, Callable[[], Awaitable[Message]], Callable[[Message], Awaitable[None]]], Awaitable[None]]

CSP = "; ".join((
    "default-src 'self'", "script-src 'self'", "style-src 'self'", "img-src 'self' data: blob:",
    "media-src 'self' blob:", "connect-src 'self'", "font-src 'self'", "object-src 'none'", "base-uri 'none'",
    "form-action 'self'", "frame-ancestors 'none'",
))
DOCS_CSP = "frame-ancestors 'none'; object-src 'none'; base-uri 'none'"
COMMON = ((b"x-content-type-options", b"nosniff"), (b"x-frame-options", b"DENY"),
          (b"referrer-policy", b"no-referrer"))


class SecurityHeaders:
    def __init__(self, app: ASGIApp, docs_path: str = "/api/docs"):
        self.app, self.docs_path = app, docs_path

    async def __call__(self, scope: Scope, receive: Callable[[], Awaitable[Message]],
                       send: Callable[[Message], Awaitable[None]]) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        csp = DOCS_CSP if scope.get("path", "").startswith(self.docs_path) else CSP
        https = scope.get("scheme") == "https"

        async def send_with_headers(message: Message) -> None:
            if message["type"] == "http.response.start":
                headers = list(message.get("headers", []))
                present = {k.lower() for k, _ in headers}
                extra = [*COMMON, (b"content-security-policy", csp.encode())]
                if https:
                    extra.append((b"strict-transport-security", b"max-age=31536000"))
                headers += [(k, v) for k, v in extra if k not in present]
                message["headers"] = headers
            await send(message)

        await self.app(scope, receive, send_with_headers)
