"""Service errors as HTTP answers: NotFound 404, Conflict 409, Invalid 422, Unavailable 503."""

from __future__ import annotations

from fastapi import FastAPI, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse

from server.services.control import Unavailable
from server.services.errors import Conflict, Invalid, NotFound

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


def install(app: FastAPI) -> None:
    async def invalid(_req: Request, exc: Exception) -> JSONResponse:
        assert isinstance(exc, RequestValidationError)
        status, msg = describe(exc)
        return JSONResponse({"detail": msg}, status_code=status)
    app.add_exception_handler(RequestValidationError, invalid)
    for exc_type, code in STATUS.items():
        async def handler(_req: Request, exc: Exception, code: int = code) -> JSONResponse:
            return JSONResponse({"detail": str(exc)}, status_code=code)
        app.add_exception_handler(exc_type, handler)
