"""Describing recordings: POST /api/scenes/{id}/describe, POST /api/describe (upload), /api/uploads/{id}."""

from __future__ import annotations

from fastapi import APIRouter, HTTPException, Request, Response
from starlette.concurrency import run_in_threadpool
from starlette.datastructures import UploadFile

from server.schemas import CscVectors, Description, Problem, RecordingDetail, Timings
from server.state import VISION_FEATURE_NAMES, Result, StateDep

router = APIRouter(prefix="/api", tags=["describe"])


def _rows(array, digits: int = 4) -> list[list[float]]:  # noqa: ANN001 - any 2-D array
    return [[round(float(v), digits) for v in row] for row in array]


def description_of(result: Result, rid: str, source: str, model: str, labels: list[str]) -> Description:
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
        correct=None if expected is None else result.text.strip().lower() == expected.strip().lower(),
        phoneme_labels=labels,
        activity=_rows(result.activity),
        target_activity=None if result.target_activity is None else _rows(result.target_activity),
        csc=CscVectors(**{k: [round(float(x), 6) for x in v] for k, v in result.csc.items()}),
        timings=Timings(**{k: round(v, 3) for k, v in result.timings.items()}),
    )


def _json(answer: Description) -> Response:
    """The answer serialised once (FastAPI would validate the ~5000 activity values again)."""
    return Response(answer.model_dump_json(), media_type="application/json")


@router.post(
    "/scenes/{rid}/describe",
    response_model=None,
    responses={200: {"model": Description}, 404: {"model": Problem}},
)
def describe_scene(state: StateDep, rid: str) -> Response:
    """What the served model says about a corpus recording (from its stored encodings)."""
    result = state.describe_scene(rid)
    return _json(description_of(result, rid, "corpus", state.model.name, state.backend.phoneme_labels))


async def _read_capped(upload: UploadFile, cap: int) -> bytes:
    chunks, size = [], 0
    while chunk := await upload.read(1 << 20):
        size += len(chunk)
        if size > cap:
            raise HTTPException(413, f"the recording is larger than the limit of {cap / 2**20:.0f} MiB")
        chunks.append(chunk)
    return b"".join(chunks)


@router.post(
    "/describe",
    response_model=None,
    responses={
        200: {"model": Description},
        400: {"model": Problem},
        413: {"model": Problem},
        422: {"model": Problem},
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
async def describe_upload(state: StateDep, request: Request) -> Response:
    """Upload a recording in format v1 (multipart field ``recording``, a .zip or .npz) and describe it."""
    cap = state.backend.max_upload_bytes
    declared = request.headers.get("content-length")
    if declared and declared.isdigit() and int(declared) > cap + (1 << 16):
        raise HTTPException(413, f"the recording is larger than the limit of {cap / 2**20:.0f} MiB")
    try:
        form = await request.form(max_files=1, max_fields=4)
    except Exception as exc:  # malformed multipart body
        raise HTTPException(400, f"could not read the multipart form: {exc}") from exc
    upload = form.get("recording")
    if not isinstance(upload, UploadFile):
        raise HTTPException(422, "send the recording as a file in the multipart field 'recording'")
    data = await _read_capped(upload, cap)
    filename = upload.filename or "recording"
    if not data:
        raise HTTPException(400, f"{filename}: the file is empty")
    try:
        up = await run_in_threadpool(state.describe_upload, data, filename)
    except state.backend.recording_error as exc:
        raise HTTPException(400, str(exc)) from exc
    return _json(description_of(up.result, up.id, "upload", up.model, state.backend.phoneme_labels))


@router.get("/uploads/{uid}", response_model=RecordingDetail, responses={404: {"model": Problem}})
def get_upload(state: StateDep, uid: str) -> RecordingDetail:
    """The time series of an uploaded recording (kept while the server runs)."""
    up = state.upload(uid)
    rec = up.recording
    fps = float(getattr(rec, "fps", 20.0) or 20.0)
    frames = len(rec.joints)
    return RecordingDetail(
        id=up.id,
        source="upload",
        fps=fps,
        frames=frames,
        duration_s=frames / fps,
        utterance=up.result.expected,
        joint_names=state.backend.joint_names,
        joints=_rows(rec.joints, 5),
        proprioception=_rows(up.proprioception, 5),
        vision=_rows(up.vision, 5),
        vision_feature_names=VISION_FEATURE_NAMES[: up.vision.shape[1]],
    )


@router.get("/uploads/{uid}/description", response_model=Description, responses={404: {"model": Problem}})
def get_upload_description(state: StateDep, uid: str) -> Description:
    """The description computed when the recording was uploaded."""
    up = state.upload(uid)
    return description_of(up.result, up.id, "upload", up.model, state.backend.phoneme_labels)
