"""Passwords, session tokens and login throttling (no I/O here).

- Passwords: argon2id (argon2-cffi) at OWASP's first recommended setting, m = 19 MiB, t = 2, p = 1;
  12 to 128 characters.
- Tokens: `v1.<session id>.<expiry>.<HMAC-SHA256>` signed with the server's secret key; a token is valid
  while its signature holds, it has not expired and its session row is not revoked (checked by the caller).
- CSRF: a cookie-authenticated unsafe request must carry `X-CSRF-Token` equal to HMAC(key, "csrf" + session).
- Throttling: a sliding window of failed logins per username and per address.
- Idle expiry: a session with no request for `session_idle_s` ends (ASVS 7.3.1); the absolute lifetime is
  the token's expiry (ASVS 7.3.2).
"""

from __future__ import annotations

import base64
import hashlib
import hmac
import secrets
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass

from argon2 import PasswordHasher
from argon2.exceptions import InvalidHashError, VerificationError, VerifyMismatchError

MIN_PASSWORD, MAX_PASSWORD = 12, 128
_hasher = PasswordHasher(time_cost=2, memory_cost=19 * 1024, parallelism=1)


def check_password_rules(password: str) -> None:
    if not MIN_PASSWORD <= len(password) <= MAX_PASSWORD:
        raise ValueError(f"password must be {MIN_PASSWORD} to {MAX_PASSWORD} characters long")


def hash_password(password: str) -> str:
    check_password_rules(password)
    return _hasher.hash(password)


def verify_password(password_hash: str, password: str) -> bool:
    try:
        return _hasher.verify(password_hash, password)
    except (VerifyMismatchError, VerificationError, InvalidHashError):
        return False


def dummy_verify() -> None:
    """Spend the time of one verification (a login for an unknown user must not answer faster)."""
    verify_password(_DUMMY, "not the password at all")


_DUMMY = _hasher.hash("a dummy password for timing")


def new_secret() -> bytes:
    return secrets.token_bytes(32)


def new_session_id() -> str:
    return secrets.token_urlsafe(24)


def _mac(key: bytes, msg: str) -> str:
    d = hmac.new(key, msg.encode(), hashlib.sha256).digest()
    return base64.urlsafe_b64encode(d).rstrip(b"=").decode()


def make_token(key: bytes, session_id: str, expires_at: float) -> str:
    body = f"v1.{session_id}.{int(expires_at)}"
    return f"{body}.{_mac(key, body)}"


@dataclass(frozen=True)
class TokenClaims:
    session_id: str
    expires_at: float


def read_token(key: bytes, token: str, now: float | None = None) -> TokenClaims | None:
    """The token's claims if its signature is right and it has not expired; None otherwise."""
    parts = token.split(".")
    if len(parts) != 4 or parts[0] != "v1" or not parts[2].isdigit():
        return None
    body = ".".join(parts[:3])
    if not hmac.compare_digest(_mac(key, body), parts[3]):
        return None
    exp = float(parts[2])
    if exp <= (time.time() if now is None else now):
        return None
    return TokenClaims(parts[1], exp)


def csrf_token(key: bytes, session_id: str) -> str:
    return _mac(key, f"csrf.{session_id}")


class LoginThrottle:
    """Failed logins within `window_s`: more than `per_user` for one username or `per_address` from one
    address makes `retry_after` return the seconds to wait (0 when allowed). Thread-safe enough for one
    event loop (no awaits inside)."""

    def __init__(self, per_user: int, per_address: int, window_s: float, clock: Callable[[], float] = time.monotonic):
        self.per_user, self.per_address, self.window_s, self.clock = per_user, per_address, window_s, clock
        self._fails: dict[tuple[str, str], deque[float]] = {}
        self._sweep_at = 1024  # keys held when the next sweep of expired ones runs

    def _recent(self, key: tuple[str, str]) -> deque[float]:
        """The key's failures within the window (a new, unstored queue for a key with none)."""
        q = self._fails.get(key, deque())
        cutoff = self.clock() - self.window_s
        while q and q[0] <= cutoff:
            q.popleft()
        return q

    def retry_after(self, username: str, address: str) -> int:
        waits = []
        for key, limit in ((("user", username.lower()), self.per_user), (("addr", address), self.per_address)):
            q = self._recent(key)
            if len(q) >= limit:
                waits.append(q[-limit] + self.window_s - self.clock())
        return max(1, int(max(waits)) + 1) if waits else 0

    def failed(self, username: str, address: str) -> None:
        """Count a failure. Keys whose failures have all expired are dropped once the keys held double:
        names tried once each (a spray of usernames) do not pile up in memory."""
        now = self.clock()
        for key in (("user", username.lower()), ("addr", address)):
            q = self._recent(key)
            q.append(now)
            self._fails[key] = q
        if len(self._fails) >= self._sweep_at:
            cutoff = now - self.window_s
            self._fails = {k: q for k, q in self._fails.items() if q[-1] > cutoff}
            self._sweep_at = max(1024, 2 * len(self._fails))

    def succeeded(self, username: str) -> None:
        self._fails.pop(("user", username.lower()), None)


class IdleTimer:
    """The time of each session's last request, in memory: `touch` answers False (and forgets the session)
    when more than `idle_s` passed since the previous one; a session not seen yet (a new login, or any
    session after a restart) starts its timer now."""

    def __init__(self, idle_s: float, clock: Callable[[], float] = time.monotonic):
        self.idle_s, self.clock = idle_s, clock
        self._seen: dict[str, float] = {}

    def touch(self, session_id: str) -> bool:
        now = self.clock()
        last = self._seen.get(session_id)
        if last is not None and now - last > self.idle_s:
            del self._seen[session_id]
            return False
        self._seen[session_id] = now
        if len(self._seen) > 10_000:  # forget the longest idle (they have expired anyway)
            for sid, t in sorted(self._seen.items(), key=lambda kv: kv[1])[:1000]:
                if now - t > self.idle_s:
                    del self._seen[sid]
        return True

    def forget(self, session_id: str) -> None:
        self._seen.pop(session_id, None)
