"""Property-based fuzzing of the whole OpenAPI document (schemathesis) against a real `tmeye serve`, as
the admin: every operation gets valid (positive) and invalid (negative) requests; no answer may be a
5xx, or break the schema, content type or status codes its own document gives.

The server runs without a servo (`--servo none`: the servo routes answer their documented 409): random
go-to angles on the simulated gimbal point the cameras outside the surveyed background, where a frame
takes seconds on a loaded machine, and every request the worker takes between frames then answers 503
after its 2 s limit. That is the tracker's real-time budget, reported to its owners, not an API fault.

Left out: logout (it would end the admin's session) and the endless MJPEG stream (its body never ends;
its status and headers are covered by the role walk in test_server_api.py). The admin's own user is not
patched or deleted (a new password would end the session the fuzzer runs on). Each accepted tracker
settings change is applied for real and then undone: extreme but valid values (ε of 1 or 2 grey levels)
make a frame take 0.15-0.4 s, and on a loaded machine the next control requests would wait past their
2 s limit (a 503) for reasons that are tuning, not the request being fuzzed."""

from __future__ import annotations

import time
from collections import Counter
from collections.abc import Iterator
from typing import Any

import httpx
import pytest
from server_helpers import Server, start_server

schemathesis = pytest.importorskip("schemathesis")
hypothesis = pytest.importorskip("hypothesis")

from hypothesis import HealthCheck, Phase, given, settings  # noqa: E402
from hypothesis.errors import Unsatisfiable  # noqa: E402
from schemathesis.checks import not_a_server_error  # noqa: E402
from schemathesis.core.failures import FailureGroup  # noqa: E402
from schemathesis.generation import GenerationMode  # noqa: E402
from schemathesis.specs.openapi.checks import (  # noqa: E402
    content_type_conformance,
    response_schema_conformance,
    status_code_conformance,
)

EXCLUDED = {("POST", "/api/auth/logout"), ("GET", "/api/live/{camera}.mjpeg")}
EXAMPLES = {GenerationMode.POSITIVE: 60, GenerationMode.NEGATIVE: 40}
MIN_REQUESTS = 2000
CHECKS = [not_a_server_error, response_schema_conformance, content_type_conformance, status_code_conformance]


@pytest.fixture(scope="module")
def server(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Server]:
    s = start_server(tmp_path_factory.mktemp("fuzz") / "data", "--servo", "none")
    yield s
    s.stop()


def _restore(base_url: str, headers: dict[str, str], tuning: dict[str, Any]) -> None:
    """Put the tracker settings back (retried: a frame under the fuzzed settings may outlast the 2 s limit)."""
    deadline = time.monotonic() + 60
    while (r := httpx.patch(f"{base_url}/api/tracker/config", json=tuning, headers=headers, timeout=30)
           ).status_code == 503 and time.monotonic() < deadline:
        time.sleep(0.5)
    r.raise_for_status()


def _fuzz_operation(op: Any, mode: GenerationMode, base_url: str, headers: dict[str, str], admin_id: int,
                    tuning: dict[str, Any], counts: Counter[str], failures: list[str]) -> None:
    strategy = op.as_strategy(generation_mode=mode).filter(
        lambda c: c.path_parameters is None or c.path_parameters.get("user_id") != admin_id)

    @settings(max_examples=EXAMPLES[mode], deadline=None, database=None, derandomize=True,
              phases=[Phase.explicit, Phase.generate], suppress_health_check=list(HealthCheck))
    @given(case=strategy)
    def run(case: Any) -> None:
        try:
            response = case.call(base_url=base_url, headers=headers, timeout=30)
        except Exception as exc:  # a dropped connection counts as a failure too
            failures.append(f"{op.method.upper()} {op.path} [{mode}]: no answer: {exc}")
            return
        counts[f"{response.status_code // 100}xx"] += 1
        counts["requests"] += 1
        if op.path == "/api/tracker/config" and op.method.upper() == "PATCH" and response.status_code == 200:
            _restore(base_url, headers, tuning)
        try:
            case.validate_response(response, checks=CHECKS)
        except FailureGroup as group:
            for f in group.exceptions:
                first = (str(f.message).splitlines() or [""])[0][:200]
                failures.append(f"{op.method.upper()} {op.path} [{mode}] -> {response.status_code}: "
                                f"{f.title}: {first} | body {response.text[:200]!r}")
        except AssertionError as exc:
            failures.append(f"{op.method.upper()} {op.path} [{mode}] -> {response.status_code}: {exc}"[:600])

    try:
        run()
    except Unsatisfiable:  # nothing in the operation can be made invalid (no parameters, no body)
        if mode is not GenerationMode.NEGATIVE:
            raise


def test_fuzz_whole_api_as_admin(server: Server) -> None:
    token = server.login()
    headers = {"Authorization": f"Bearer {token}"}
    spec = httpx.get(f"{server.url}/api/openapi.json").json()
    with server.as_admin() as c:
        admin_id = next(u["id"] for u in c.get("/api/users").json() if u["username"] == "admin")
        tuning = c.get("/api/tracker/config").json()
    schema = schemathesis.openapi.from_dict(spec)
    counts: Counter[str] = Counter()
    failures: list[str] = []
    operations = 0
    for result in schema.get_all_operations():
        op = result.ok()
        if (op.method.upper(), op.path) in EXCLUDED:
            continue
        operations += 1
        for mode in EXAMPLES:
            _fuzz_operation(op, mode, server.url, headers, admin_id, tuning, counts, failures)
    print(f"fuzz: {operations} operations, {dict(counts)}")
    kinds = Counter(f.split(": ", 2)[0] + ": " + f.split(": ", 2)[1] for f in failures)
    assert not failures, f"{len(failures)} failures: {dict(kinds)}\n" + "\n".join(
        next(f for f in failures if f.startswith(k)) for k in kinds)
    assert counts["requests"] >= MIN_REQUESTS, counts
    assert counts["5xx"] == 0
    assert httpx.get(f"{server.url}/api/health").json()["status"] == "ok"
    with server.client(token) as c:
        assert c.get("/api/status").json()["state"] == "running"
    assert "Traceback" not in server.log_text(), server.log_text()[-3000:]

