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


def test_the_schema_examples_are_valid_instances() -> None:
    """Every example a model shows in the OpenAPI document validates against that model."""
    import inspect

    from pydantic import BaseModel

    from server import alarm_schemas, recording_schemas, schemas, settings_schemas
    from server.routes import live

    checked = 0
    for module in (schemas, alarm_schemas, recording_schemas, settings_schemas, live):
        for _, model in inspect.getmembers(module, inspect.isclass):
            if not issubclass(model, BaseModel) or model.__module__ != module.__name__:
                continue
            extra = model.model_config.get("json_schema_extra")
            for example in (extra or {}).get("examples", []) if isinstance(extra, dict) else []:
                model.model_validate(example)
                checked += 1
    assert checked >= 20
