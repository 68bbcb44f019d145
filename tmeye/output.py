"""Printing a command's result: one JSON object, or aligned `name value` lines for a person."""

from __future__ import annotations

import json
from collections.abc import Mapping


def emit(result: Mapping[str, object], as_json: bool) -> None:
    if as_json:
        print(json.dumps(dict(result)))
        return
    width = max((len(k) for k in result), default=0) + 2
    for k, v in result.items():
        print(f"{k:{width}s}{v}")
