"""Recorded footage: segments, their files (HTTP ranges), frame-exact JPEGs, the HLS playlist the browser's
player seeks in, and the recorded telemetry."""

from __future__ import annotations

from typing import Annotated, Any

from fastapi import APIRouter, Query
from fastapi.responses import FileResponse, PlainTextResponse, Response

from server.deps import CtxDep, DbDep, RowId, Viewer
from server.recording_schemas import Camera, SegmentOut, TelemetryRecord
from server.schemas import Message
from server.services import hls, playback
from server.services import segments as seg_service

router = APIRouter(prefix="/api", tags=["recordings"])
Time = Annotated[float, Query(description="Unix s")]
NOT_FOUND: dict[int | str, dict[str, Any]] = {404: {"model": Message}}


@router.get("/recordings", response_model=list[SegmentOut], summary="Recorded segments overlapping start..end")
def list_recordings(_p: Viewer, db: DbDep, camera: Camera | None = None, start: Time | None = None,
                    end: Time | None = None, limit: Annotated[int, Query(ge=1, le=100000)] = 5000) -> list[Any]:
    return seg_service.list_segments(db, camera, start, end, limit)


@router.get("/recordings/{seg_id}/file", response_class=FileResponse, responses=NOT_FOUND,
            summary="A segment's fragmented MP4 (HTTP range requests)")
def recording_file(seg_id: RowId, ctx: CtxDep, _p: Viewer, db: DbDep) -> FileResponse:
    seg = seg_service.get_segment(db, seg_id)
    return FileResponse(ctx.settings.data_dir / seg.path, media_type="video/mp4")


@router.get("/playback/frame", response_class=Response, responses={**NOT_FOUND, 200: {"content": {"image/jpeg": {}}}},
            summary="JPEG of the last frame captured at or before t, with X-Frame-Index and X-Captured-At")
def playback_frame(ctx: CtxDep, _p: Viewer, db: DbDep, camera: Camera, t: Time) -> Response:
    # a plain def: FastAPI runs it in its thread pool, so the decoding stays off the event loop
    assert ctx.frames is not None
    jf = ctx.frames.jpeg(playback.locate(db, camera, t))
    return Response(jf.data, media_type="image/jpeg", headers={
        "X-Frame-Index": str(jf.frame_no), "X-Captured-At": f"{jf.captured_at:.6f}",
        "X-Segment-Id": str(jf.segment_id), "X-Segment-Time": f"{jf.t_in_segment:.6f}",
        "Cache-Control": "private, max-age=3600"})


@router.get("/playback/{camera}.m3u8", response_class=Response,
            responses={**NOT_FOUND, 200: {"content": {"application/vnd.apple.mpegurl": {}}}},
            summary="HLS (fMP4) playlist of a camera's footage in start..end, for hls.js")
def playlist(camera: Camera, ctx: CtxDep, _p: Viewer, db: DbDep, start: Time, end: Time) -> PlainTextResponse:
    segs = [s for s in seg_service.list_segments(db, camera, start, end, 20000) if s.status != "open"]
    text = hls.playlist(segs, ctx.settings.data_dir)
    return PlainTextResponse(text, media_type="application/vnd.apple.mpegurl")


@router.get("/telemetry", response_model=list[TelemetryRecord],
            summary="Recorded telemetry of start..end: one message per recorded frame, oldest first")
def recorded_telemetry(_p: Viewer, db: DbDep, start: Time, end: Time,
                       limit: Annotated[int, Query(ge=1, le=200000)] = 20000) -> list[dict[str, Any]]:
    return seg_service.telemetry_range(db, start, end, limit)
