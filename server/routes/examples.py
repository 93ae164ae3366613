"""Recordings to try, for someone without a NAO (data.examples).

GET /api/examples          the catalogue: name, title, description, kind, url
GET /api/examples/{name}   one recording as a format-v1 .zip (rendered on its first request)
"""

from __future__ import annotations

from fastapi import APIRouter
from fastapi.responses import FileResponse

from server.deps import ExamplesDep
from server.schemas.common import Problem
from server.schemas.examples import ExampleInfo, ExampleList

router = APIRouter(prefix="/api/examples", tags=["examples"])


@router.get("", response_model=ExampleList)
def list_examples(examples: ExamplesDep) -> ExampleList:
    """Recordings to download and upload: corpus exports of each action, and some unlike the corpus
    (another camera, lighting, teacher tempo, resolution, frame rate)."""
    return ExampleList(
        examples=[
            ExampleInfo(
                name=e.name,
                title=e.title,
                description=e.description,
                kind=e.kind,
                url=f"/api/examples/{e.name}",
            )
            for e in examples.catalogue()
        ]
    )


@router.get(
    "/{name}",
    response_class=FileResponse,
    responses={200: {"content": {"application/zip": {}}}, 404: {"model": Problem}},
)
def download_example(examples: ExamplesDep, name: str) -> FileResponse:
    """One recording to try, as a format-v1 .zip (a second or two the first time: it is rendered)."""
    path = examples.path(name)
    return FileResponse(path, media_type="application/zip", filename=f"{name}.zip")
