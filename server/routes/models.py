"""The shipped models: GET /api/models, PUT /api/models/selected."""

from __future__ import annotations

from fastapi import APIRouter
from starlette.concurrency import run_in_threadpool

from server.deps import ModelsDep
from server.schemas.common import Problem
from server.schemas.models import ModelInfo, ModelList, SelectModel
from server.services.models import ModelRegistry

router = APIRouter(prefix="/api/models", tags=["models"])


def _list(models: ModelRegistry) -> ModelList:
    selected = models.served.name
    return ModelList(
        selected=selected,
        models=[ModelInfo(name=n, selected=n == selected, meta=m) for n, m in models.metas().items()],
    )


@router.get("", response_model=ModelList)
def list_models(models: ModelsDep) -> ModelList:
    """Every model under the models folder (each with its meta.json), and which one is served."""
    return _list(models)


@router.put("/selected", response_model=ModelList, responses={404: {"model": Problem}})
async def select_model(models: ModelsDep, body: SelectModel) -> ModelList:
    """Serve another model: every later answer (describe, Csc, generate) comes from it."""
    await run_in_threadpool(models.select, body.name)
    return _list(models)
