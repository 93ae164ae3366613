"""One uploaded file out of a multipart body, its bytes counted while they arrive.

The recording upload (POST /api/describe) and the Seeing lesson's picture (POST /api/lessons/seeing)
read their file through `read_upload`: a body past the cap, declared or chunked, is answered 413 as
soon as it passes it, before the multipart parser spools it; a malformed body is a 400.
"""

from __future__ import annotations

from fastapi import HTTPException, Request
from starlette.datastructures import UploadFile
from starlette.types import Message, Receive

MULTIPART_FRAMING = 1 << 16  # bytes of multipart boundaries and headers allowed beyond the file


def _capped(receive: Receive, cap: int, too_large: HTTPException) -> Receive:
    """`receive` that raises `too_large` as soon as the body passes `cap` plus the framing."""
    received = 0

    async def capped() -> Message:
        nonlocal received
        message = await receive()
        if message["type"] == "http.request":
            received += len(message.get("body", b""))
            if received > cap + MULTIPART_FRAMING:
                raise too_large
        return message

    return capped


async def read_upload(
    request: Request, field: str, what: str, cap: int, too_large: HTTPException
) -> tuple[bytes, str | None]:
    """(bytes, file name if sent) of the one file (a `what`) in multipart field `field`, <= `cap` bytes."""
    declared = request.headers.get("content-length")
    if declared and declared.isdigit() and int(declared) > cap + MULTIPART_FRAMING:
        raise too_large
    try:
        form = await Request(request.scope, _capped(request.receive, cap, too_large)).form(
            max_files=1, max_fields=4
        )
    except HTTPException:
        raise
    except Exception as exc:  # malformed multipart body
        raise HTTPException(400, f"could not read the multipart form: {exc}") from exc
    upload = form.get(field)
    if not isinstance(upload, UploadFile):
        raise HTTPException(422, f"send the {what} as a file in the multipart field {field!r}")
    if upload.size is not None and upload.size > cap:
        raise too_large
    data = await upload.read(cap + 1)
    if len(data) > cap:
        raise too_large
    return data, upload.filename or None
