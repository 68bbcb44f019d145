"""Health (no login), status and telemetry over REST."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, HTTPException, Query

from server.deps import CtxDep, Viewer
from server.schemas import Health, Status, Telemetry
from server.services.control import servo_state
from tmeye import __version__

router = APIRouter(prefix="/api", tags=["status"])


@router.get("/health", response_model=Health, summary="Liveness; status ok once the tracker runs")
def health(ctx: CtxDep) -> Health:
    rt = ctx.runtime
    ok = rt.state == "running" and rt.latest is not None
    starting = rt.state in ("created", "starting", "running")
    status = "ok" if ok else "failed" if rt.state == "failed" else "starting" if starting else "stopped"
    return Health(status=status, runtime=rt.state, version=__version__,
                  frame=rt.latest.frame_no if rt.latest else None)


@router.get("/status", response_model=Status, summary="Frame, rate, skipped frames, source, servo, faults")
def get_status(ctx: CtxDep, _p: Viewer,
               window_s: Annotated[float, Query(gt=0, le=600, description="window of the lag and latency "
                                                "percentiles and of the longest frame gap (s)")] = 60.0) -> Status:
    st = ctx.runtime.status(window_s)
    st["servo"] = servo_state(ctx.runtime)
    if ctx.recorder is not None:
        st["recording"] = ctx.recorder.status()
        if st["recording"]["fault"]:
            st["faults"].append({"kind": "recording", "message": st["recording"]["fault"]})
    st.update(ctx.monitor.figures(window_s))
    return Status.model_validate(st)


@router.get("/telemetry/latest", response_model=Telemetry, summary="The latest frame's telemetry",
            responses={404: {"description": "no frame processed yet"}})
def latest(ctx: CtxDep, _p: Viewer) -> Telemetry:
    ev = ctx.runtime.latest
    if ev is None:
        raise HTTPException(404, "no frame has been processed yet")
    return Telemetry.model_validate(ev.telemetry)
