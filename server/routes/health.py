"""GET /api/health: is the app up, which model does it serve."""

from __future__ import annotations

from fastapi import APIRouter

from server.schemas import Health
from server.state import StateDep

router = APIRouter(prefix="/api", tags=["health"])


@router.get("/health", response_model=Health)
def health(state: StateDep) -> Health:
    return Health(model=state.model.name, scenes=len(state.entries), viewer=state.viewer is not None)
