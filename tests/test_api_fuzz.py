"""Every route of the OpenAPI document, on a real server, with bad values: path ids past SQLite's range
or not numbers, query values of the wrong kind or size, bodies built from each route's own schema with
one field at a time replaced by NaN, infinity, huge or negative numbers, the wrong type, or a field the
schema does not name. Each answer is a 2xx or a 4xx with a one-line {"detail": ...}: never a 5xx, and
the server keeps running. Seeded: the same requests every run, about 4,000 of them. On the code before
a9601d9, 14 of them failed: a bookmark at NaN s, a lock's track_id or alarm_id of 2^70 and GET
/api/tracks?replay=2^70 were 500s (and the connection closed after each)."""

from __future__ import annotations

import json
import random
import urllib.parse
from collections.abc import Iterator
from typing import Any

import httpx
import pytest
from server_helpers import Server, start_server

BAD: list[Any] = [float("nan"), float("inf"), -float("inf"), 2**70, -(2**70), None, -1, 1e308, "", "x" * 3000, [],
                  {"a": {"b": []}}, True, "../../etc/passwd"]
PATH_VALUES = ["1", "0", "-1", "99999999999999999999999", "abc", "1.5", "x" * 300, "%00"]
SKIP = {("POST", "/api/auth/logout"), ("POST", "/api/auth/login")}  # the session the fuzz runs in


@pytest.fixture(scope="module")
def server(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Server]:
    s = start_server(tmp_path_factory.mktemp("fuzz") / "data")
    yield s
    s.stop()


class Bodies:
    """Sample JSON bodies of an OpenAPI schema (its components resolved; one alternative of an anyOf or
    oneOf drawn at random) and the paths of their leaves."""

    def __init__(self, spec: dict[str, Any], rng: random.Random):
        self.components = spec.get("components", {}).get("schemas", {})
        self.rng = rng

    def resolve(self, s: dict[str, Any]) -> dict[str, Any]:
        while "$ref" in s:
            s = self.components[s["$ref"].rsplit("/", 1)[-1]]
        return s

    def sample(self, s: dict[str, Any]) -> Any:
        s = self.resolve(s)
        for key in ("anyOf", "oneOf"):
            if key in s:
                return self.sample(self.rng.choice(s[key]))
        if "enum" in s:
            return self.rng.choice(s["enum"])
        kind = s.get("type")
        if kind == "object" or "properties" in s:
            return {k: self.sample(v) for k, v in s.get("properties", {}).items()}
        if kind == "array":
            return [self.sample(s.get("items", {}))]
        choices: dict[str, list[Any]] = {"integer": [1, 5, 100], "number": [0.5, 10.0, 1795376480.0],
                                         "boolean": [True, False], "string": ["a", "gate", "2026-12-06T00:00:00Z"]}
        return self.rng.choice(choices.get(str(kind), [None]))


def leaves(v: Any, at: tuple[Any, ...] = ()) -> Iterator[tuple[Any, ...]]:
    """The paths (keys and indices) of a JSON value's leaves, and of the value itself."""
    yield at
    items = v.items() if isinstance(v, dict) else enumerate(v) if isinstance(v, list) else ()
    for k, x in items:
        yield from leaves(x, (*at, k))


def replaced(v: Any, at: tuple[Any, ...], new: Any) -> Any:
    """A copy of v with the value at path `at` replaced by `new`."""
    if not at:
        return new
    out: Any = dict(v) if isinstance(v, dict) else list(v)
    out[at[0]] = replaced(v[at[0]], at[1:], new)
    return out


def requests_of(rng: random.Random, bodies: Bodies, path: str, op: dict[str, Any]) -> Iterator[tuple[str, Any]]:
    """(url, body or None) of one operation: each bad path value; each query parameter with each bad value;
    three sample bodies, each as drawn and with each of its leaves replaced by each bad value in turn and
    with a field the schema does not name."""
    params = op.get("parameters", [])
    ids = PATH_VALUES[1:] if path.startswith("/api/users/") else PATH_VALUES  # not the admin's own row
    names = [p["name"] for p in params if p["in"] == "path"]
    urls = [path.replace("{" + n + "}", urllib.parse.quote(v, safe="%")) for v in ids for n in names[:1]] or [path]
    for n in names[1:]:
        urls = [u.replace("{" + n + "}", "1") for u in urls]
    ok_url = urls[0]
    queries = [urllib.parse.urlencode({p["name"]: str(v)}) for p in params if p["in"] == "query" for v in BAD]
    schema = op.get("requestBody", {}).get("content", {}).get("application/json", {}).get("schema")
    samples = [bodies.sample(schema) for _ in range(3)] if schema is not None else [None]
    for url in urls:
        yield url, samples[0]
    for q in queries:
        yield f"{ok_url}?{q}", samples[0]
    for body in samples if schema is not None else []:
        for at in leaves(body):
            for bad in BAD:
                yield ok_url, replaced(body, at, bad)
        if isinstance(body, dict):
            yield ok_url, {**body, "unnamed": 1}


def _one_line_detail(r: httpx.Response) -> bool:
    try:
        detail = r.json().get("detail")
    except ValueError:
        return False
    return isinstance(detail, str) and "\n" not in detail


def _send(c: httpx.Client, rng: random.Random, method: str, url: str, body: Any, form: str | None) -> httpx.Response:
    if body is not None:
        return c.request(method, url, content=json.dumps(body), headers={"content-type": "application/json"})
    if form is not None and form != "application/json":  # a form or an upload: bytes that are neither
        return c.request(method, url, content=bytes(rng.randrange(256) for _ in range(64)),
                         headers={"content-type": form})
    return c.request(method, url)


def test_bad_values_on_every_route_are_never_a_5xx(server: Server) -> None:
    rng = random.Random(12)
    failures, answered = [], 0
    with server.as_admin() as c:
        spec = c.get("/api/openapi.json").json()
        bodies = Bodies(spec, rng)
        for path, ops in spec["paths"].items():
            for method, op in ops.items():
                if (method.upper(), path) in SKIP:
                    continue
                form = next(iter(op.get("requestBody", {}).get("content", {})), None)
                for url, body in requests_of(rng, bodies, path, op):
                    answered += 1
                    try:
                        r = _send(c, rng, method, url, body, form)
                    except httpx.TransportError as exc:  # the server closed the connection: after a 500
                        failures.append(f"{method.upper()} {url} {json.dumps(body)[:120]} -> {exc!r}")
                        continue
                    if r.status_code >= 500 or r.status_code >= 400 and not _one_line_detail(r):
                        failures.append(f"{method.upper()} {url} {json.dumps(body)[:120]} -> {r.status_code} "
                                        f"{r.text[:200]}")
        assert c.get("/api/health").json()["status"] in ("ok", "starting")
    assert answered > 1000
    assert not failures, f"{len(failures)} of {answered}:\n" + "\n".join(failures[:40])
