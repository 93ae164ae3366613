"""Describing recordings: POST /api/scenes/{id}/describe, POST /api/describe (upload), /api/uploads/{id}."""

from __future__ import annotations

from fastapi import APIRouter, HTTPException, Request, Response
from starlette.concurrency import run_in_threadpool
from starlette.datastructures import UploadFile
from starlette.types import Message, Receive

from data.recording import MAX_UPLOAD_BYTES
from model.encoding.utterance import PHONEMES
from model.metrics import sentence_exact
from server.deps import DescribeDep, ModelsDep, TimelineDep
from server.routes.scenes import recording_detail, rows
from server.routes.timeline import timeline_of
from server.schemas.common import Problem
from server.schemas.describe import CscVectors, Description, Timings
from server.schemas.scenes import RecordingDetail
from server.schemas.timeline import Timeline
from server.services.describe import Busy, Result

router = APIRouter(prefix="/api", tags=["describe"])


def description_of(
    result: Result, rid: str, source: str, model: str, timeline: Timeline | None = None
) -> Description:
    """The API's answer for one described recording (also what `mtrnn describe --json` prints)."""
    expected = result.expected
    return Description(
        id=rid,
        source=source,  # type: ignore[arg-type]
        model=model,
        utterance=result.text,
        words=result.words,
        phonemes=result.phonemes,
        expected=expected,
        correct=None if expected is None else sentence_exact(result.text, expected),
        phoneme_labels=list(PHONEMES),
        activity=rows(result.activity, 4),
        target_activity=None if result.target_activity is None else rows(result.target_activity, 4),
        csc=CscVectors(**{k: [round(float(x), 6) for x in v] for k, v in result.csc.items()}),
        timings=Timings(**{k: round(v, 3) for k, v in result.timings.items()}),
        timeline=timeline,
        warnings=result.warnings,
    )


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


def _capped(receive: Receive) -> Receive:
    """`receive` that answers 413 as soon as the body passes the cap, chunked or not: the body is
    counted while it arrives, before the multipart parser spools it."""
    received = 0

    async def capped() -> Message:
        nonlocal received
        message = await receive()
        if message["type"] == "http.request":
            received += len(message.get("body", b""))
            if received > MAX_UPLOAD_BYTES + (1 << 16):  # the file plus the multipart framing
                raise _too_large()
        return message

    return capped


async def _read_capped(upload: UploadFile) -> bytes:
    """The uploaded file, read once (a 413 if it passes the cap)."""
    if upload.size is not None and upload.size > MAX_UPLOAD_BYTES:
        raise _too_large()
    data = await upload.read(MAX_UPLOAD_BYTES + 1)
    if len(data) > MAX_UPLOAD_BYTES:
        raise _too_large()
    return data


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
    declared = request.headers.get("content-length")
    if declared and declared.isdigit() and int(declared) > MAX_UPLOAD_BYTES + (1 << 16):
        raise _too_large()
    try:
        form = await Request(request.scope, _capped(request.receive)).form(max_files=1, max_fields=4)
    except HTTPException:
        raise
    except Exception as exc:  # malformed multipart body
        raise HTTPException(400, f"could not read the multipart form: {exc}") from exc
    upload = form.get("recording")
    if not isinstance(upload, UploadFile):
        raise HTTPException(422, "send the recording as a file in the multipart field 'recording'")
    data = await _read_capped(upload)
    filename = upload.filename or "recording"
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
