"""The console's API types are generated from web/openapi.json: it must be the server's own document, or the
TypeScript compiler checks the console against an API that no longer exists (`make openapi` refreshes both)."""

from __future__ import annotations

import json

from server_helpers import ROOT

from server.app import create_app
from server.settings import Settings


def test_web_openapi_is_the_servers_document(tmp_path: object) -> None:
    spec = create_app(Settings(data_dir=tmp_path)).openapi()  # type: ignore[arg-type]
    saved = json.loads((ROOT / "web" / "openapi.json").read_text())
    stale = sorted(set(spec["paths"]) ^ set(saved["paths"]))
    assert not stale, f"web/openapi.json differs in paths {stale[:8]}: run `make openapi`"
    assert saved == spec, "web/openapi.json differs from the server's document: run `make openapi`"
