"""Describing recordings: POST /api/scenes/{id}/describe, POST /api/describe (upload), /api/uploads/{id}."""

from __future__ import annotations

from fastapi import APIRouter, HTTPException, Request, Response
from starlette.concurrency import run_in_threadpool

from data.recording import MAX_UPLOAD_BYTES
from server.deps import DescribeDep, ModelsDep, TimelineDep
from server.routes.forms import read_upload
from server.routes.scenes import recording_detail
from server.routes.timeline import timeline_of
from server.schemas.common import Problem
from server.schemas.describe import Description
from server.schemas.scenes import RecordingDetail
from server.services.answers import description_of
from server.services.describe import Busy

router = APIRouter(prefix="/api", tags=["describe"])


def _json(answer: Description) -> Response:
    """The answer serialised once (FastAPI would validate the ~5000 activity values again)."""
    return Response(answer.model_dump_json(), media_type="application/json")


@router.post(
    "/scenes/{rid}/describe",
    response_model=None,
    responses={200: {"model": Description}, 404: {"model": Problem}},
)
def describe_scene(describe: DescribeDep, models: ModelsDep, rid: str) -> Response:
    """What the served model says about a corpus recording (from its stored encodings)."""
    result = describe.describe_scene(rid)
    return _json(description_of(result, rid, "corpus", models.served.name))


def _too_large() -> HTTPException:
    return HTTPException(413, f"the recording is larger than the limit of {MAX_UPLOAD_BYTES / 2**20:.0f} MiB")


@router.post(
    "/describe",
    response_model=None,
    responses={
        200: {"model": Description},
        400: {"model": Problem},
        413: {"model": Problem},
        422: {"model": Problem},
        503: {"model": Problem},
    },
    openapi_extra={
        "requestBody": {
            "content": {
                "multipart/form-data": {
                    "schema": {
                        "type": "object",
                        "required": ["recording"],
                        "properties": {"recording": {"type": "string", "format": "binary"}},
                    }
                }
            }
        }
    },
)
async def describe_upload(describe: DescribeDep, timelines: TimelineDep, request: Request) -> Response:
    """Upload a recording in format v1 (multipart field ``recording``, a .zip or .npz) and describe it."""
    data, sent_name = await read_upload(request, "recording", "recording", MAX_UPLOAD_BYTES, _too_large())
    filename = sent_name or "recording"
    if not data:
        raise HTTPException(400, f"{filename}: the file is empty")
    try:
        up = await describe.describe_upload_async(data, filename)  # RecordingError: 400
    except Busy as exc:
        raise HTTPException(503, str(exc), headers={"Retry-After": str(exc.retry_after)}) from None
    timeline = await run_in_threadpool(timelines.of_upload, up.id)
    steps = None if timeline is None else timeline_of(timeline)
    return _json(description_of(up.result, up.id, "upload", up.model, steps))


@router.get("/uploads/{uid}", response_model=RecordingDetail, responses={404: {"model": Problem}})
def get_upload(describe: DescribeDep, uid: str) -> RecordingDetail:
    """The time series of an uploaded recording (kept while the server runs)."""
    up = describe.upload(uid)
    series = (up.recording.joints, up.proprioception, up.vision)
    return recording_detail(up.id, "upload", series, up.result.expected)


@router.get("/uploads/{uid}/description", response_model=Description, responses={404: {"model": Problem}})
def get_upload_description(describe: DescribeDep, uid: str) -> Description:
    """The description computed when the recording was uploaded."""
    up = describe.upload(uid)
    return description_of(up.result, up.id, "upload", up.model)
