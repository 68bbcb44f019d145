"""Service errors as HTTP answers: NotFound 404, Conflict 409, Invalid 422, Unavailable 503; request
validation errors as a one-line 400/422; and the OpenAPI document saying so (FastAPI's default 422 schema,
a list of error objects, is replaced by the `{"detail": "one line"}` the server really sends)."""

from __future__ import annotations

import logging
from typing import Any

from fastapi import FastAPI, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse
from sqlalchemy.exc import OperationalError

from server.services.control import Unavailable
from server.services.errors import Conflict, Invalid, NotFound

log = logging.getLogger("tmeye.server")
STATUS = {NotFound: 404, Conflict: 409, Invalid: 422, Unavailable: 503}


def describe(exc: RequestValidationError) -> tuple[int, str]:
    """(status, one line) for a request that failed validation: 400 for a body that is not JSON, 422 else."""
    parts, status = [], 422
    for e in exc.errors():
        loc = ".".join(str(x) for x in e.get("loc", ()) if x != "body" or len(e.get("loc", ())) == 1)
        if e.get("type") == "json_invalid":
            status = 400
            err = (e.get("ctx") or {}).get("error", "")
            parts.append(f"request body is not valid JSON ({err} at character {e['loc'][-1]})")
            continue
        parts.append(f"{loc}: {e.get('msg', 'invalid')}" if loc else str(e.get("msg", "invalid")))
    return status, "; ".join(parts) or "invalid request"


ONE_LINE_ERROR = {"title": "HTTPValidationError", "type": "object", "required": ["detail"],
                  "properties": {"detail": {"type": "string", "title": "Detail",
                                            "description": "what is wrong, in one line"}}}


def _one_line_openapi(app: FastAPI) -> None:
    build = app.openapi

    def openapi() -> dict[str, Any]:
        if app.openapi_schema is None:
            doc = build()
            schemas = doc.get("components", {}).get("schemas", {})
            if "HTTPValidationError" in schemas:
                schemas["HTTPValidationError"] = ONE_LINE_ERROR
                schemas.pop("ValidationError", None)
            for ops in doc.get("paths", {}).values():
                for op in ops.values():
                    if "requestBody" in op:  # a body that is not JSON (or not a form) is a 400
                        op.setdefault("responses", {}).setdefault("400", {
                            "description": "the request body cannot be parsed",
                            "content": {"application/json": {"schema": {"$ref": "#/components/schemas/"
                                                                                "HTTPValidationError"}}}})
            app.openapi_schema = doc
        return app.openapi_schema
    app.openapi = openapi  # type: ignore[method-assign]


def install(app: FastAPI) -> None:
    _one_line_openapi(app)

    async def db_unavailable(_req: Request, exc: Exception) -> JSONResponse:
        # SQLite locked past the busy timeout, read-only, or its disk full: nothing was stored (the
        # session rolls back), the request may be repeated
        orig = getattr(exc, "orig", None) or exc
        log.warning("database unavailable: %s", orig)
        first = (str(orig).splitlines() or ["error"])[0][:200]
        return JSONResponse({"detail": f"database unavailable ({first}); nothing was changed, try again"},
                            status_code=503, headers={"Retry-After": "5"})
    app.add_exception_handler(OperationalError, db_unavailable)
    async def invalid(_req: Request, exc: Exception) -> JSONResponse:
        assert isinstance(exc, RequestValidationError)
        status, msg = describe(exc)
        return JSONResponse({"detail": msg}, status_code=status)
    app.add_exception_handler(RequestValidationError, invalid)
    for exc_type, code in STATUS.items():
        async def handler(_req: Request, exc: Exception, code: int = code) -> JSONResponse:
            return JSONResponse({"detail": str(exc)}, status_code=code)
        app.add_exception_handler(exc_type, handler)
