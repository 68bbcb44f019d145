"""Passwords, tokens, CSRF values and login throttling (pure functions, no server)."""

from __future__ import annotations

import pytest

from server.security import (
    LoginThrottle,
    csrf_token,
    hash_password,
    make_token,
    new_secret,
    read_token,
    verify_password,
)


def test_argon2id_with_owasp_parameters() -> None:
    h = hash_password("a long enough password")
    assert h.startswith("$argon2id$") and "m=19456,t=2,p=1" in h
    assert verify_password(h, "a long enough password") and not verify_password(h, "a long enough passworD")
    assert not verify_password("not a hash", "x")
    with pytest.raises(ValueError, match="12 to 128"):
        hash_password("short")
    with pytest.raises(ValueError, match="12 to 128"):
        hash_password("x" * 129)


def test_tokens_are_signed_and_expire() -> None:
    key = new_secret()
    tok = make_token(key, "abc", 2000.0)
    assert read_token(key, tok, now=1000.0) is not None
    assert read_token(key, tok, now=2000.0) is None  # expired
    assert read_token(new_secret(), tok, now=1000.0) is None  # another key
    forged = tok.replace(".2000.", ".9999.")
    assert read_token(key, forged, now=1000.0) is None
    assert read_token(key, "garbage", now=1000.0) is None
    assert csrf_token(key, "abc") != csrf_token(key, "abd")


def test_throttle_by_username_and_by_address() -> None:
    now = [0.0]
    th = LoginThrottle(per_user=5, per_address=20, window_s=600, clock=lambda: now[0])
    for _ in range(5):
        assert th.retry_after("Bob", "1.2.3.4") == 0
        th.failed("bob", "1.2.3.4")
    assert th.retry_after("BOB", "5.6.7.8") == 601  # the username is throttled from any address
    now[0] = 601.0
    assert th.retry_after("bob", "1.2.3.4") == 0  # the window passed
    for i in range(20):
        th.failed(f"user{i}", "9.9.9.9")
    assert th.retry_after("someone-else", "9.9.9.9") > 0
    th.succeeded("bob")
    assert th.retry_after("bob", "1.2.3.4") == 0


def test_throttle_memory_stays_bounded_under_a_spray_of_usernames() -> None:
    now = [0.0]
    th = LoginThrottle(per_user=5, per_address=20, window_s=600, clock=lambda: now[0])
    for i in range(5000):  # asking stores nothing
        assert th.retry_after(f"probe{i}", "1.2.3.4") == 0
    assert len(th._fails) == 0
    for i in range(100_000):  # a spray from many addresses, each name tried once, a minute apart in blocks
        now[0] = 60.0 * (i // 1000)
        th.failed(f"name{i}", f"10.0.0.{i % 200}")
    # only keys with a failure within the last 10 minutes stay (11 blocks of 1,000 names, 200 addresses),
    # swept as the keys held double: 100,200 without the sweep
    assert len(th._fails) <= 2 * (11 * 1000 + 200)
    assert th.retry_after("name99999", "1.1.1.1") == 0 and th.retry_after("x", "10.0.0.7") > 0
    for _ in range(5):
        th.failed("carol", "2.2.2.2")
    assert th.retry_after("carol", "3.3.3.3") > 0  # still throttled as before
