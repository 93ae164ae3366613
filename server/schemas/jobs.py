"""Jobs: what starts one, and a job as the API lists it (status, progress, result)."""

from __future__ import annotations

from typing import Any, Literal

from pydantic import BaseModel, Field


class JobRequest(BaseModel):
    kind: Literal["train", "evaluate"]
    mode: str = Field(description="faithful or end_to_end (train); also peer (evaluate)")
    fold: int = Field(0, ge=0, description="train: the 50:50 scene split")
    seed: int = Field(0, ge=0, description="train: initialisation seed; evaluate: base seed")
    folds: int = Field(2, ge=1, le=10, description="evaluate: K")
    inits: int = Field(1, ge=1, le=10, description="evaluate: N")
    workers: int = Field(1, ge=1, le=8, description="evaluate: local worker processes")
    name: str | None = Field(None, description="train: model folder name (default: mode-fold-seed-id)")
    overrides: dict[str, Any] = Field(
        default_factory=dict, description='e.g. {"training.epochs_auditory": 200}'
    )


class Job(BaseModel):
    id: str
    kind: str
    params: dict
    status: str = Field(description="queued, running, done, failed, cancelled, interrupted")
    created: float
    updated: float
    progress: dict | None = None
    result: dict | None = None
    error: str | None = None
