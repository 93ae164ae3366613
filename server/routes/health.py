"""GET /api/health: is the app up, which model does it serve."""

from __future__ import annotations

from fastapi import APIRouter

from server.deps import ServicesDep
from server.schemas.common import Health

router = APIRouter(prefix="/api", tags=["health"])


@router.get("/health", response_model=Health)
def health(services: ServicesDep) -> Health:
    return Health(
        model=services.models.served.name,
        scenes=len(services.corpus.entries),
        viewer=services.viewer is not None,
    )
