"""The shipped models: GET /api/models, PUT /api/models/selected."""

from __future__ import annotations

from fastapi import APIRouter, HTTPException
from starlette.concurrency import run_in_threadpool

from server.schemas import ModelInfo, ModelList, Problem, SelectModel
from server.state import AppState, StateDep

router = APIRouter(prefix="/api/models", tags=["models"])


def _list(state: AppState) -> ModelList:
    selected = state.model.name
    metas = state.model_metas()
    return ModelList(
        selected=selected,
        models=[ModelInfo(name=n, selected=n == selected, meta=m) for n, m in metas.items()],
    )


@router.get("", response_model=ModelList)
def list_models(state: StateDep) -> ModelList:
    """Every model under the models folder (each with its meta.json), and which one is served."""
    return _list(state)


@router.put("/selected", response_model=ModelList, responses={404: {"model": Problem}})
async def select_model(state: StateDep, body: SelectModel) -> ModelList:
    """Serve another model: every later answer (describe, Csc, generate) comes from it."""
    try:
        await run_in_threadpool(state.select_model, body.name)
    except KeyError:
        raise HTTPException(404, f"no model {body.name!r}; available: {sorted(state.model_dirs)}") from None
    return _list(state)
