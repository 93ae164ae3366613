"""Jobs: what starts one (every number bounded, the overrides checked against the mode's config by
`server.jobs.bounds`), and a job as the API lists it (status, queue position, progress, result)."""

from __future__ import annotations

import re
from typing import Any, Literal

from pydantic import BaseModel, Field, field_validator

from model.experiments.splits import SPLITS
from server.jobs.bounds import MAX_TRAIN_SCENES, ranges_text
from server.jobs.presets import PRESETS
from server.settings import CORES

NAME = re.compile(r"[a-z0-9-]{1,64}")
MAX_OVERRIDES = 64
LIMITS: dict[str, tuple[int, int]] = {  # field -> inclusive range, checked with a message naming it
    "fold": (0, 999),
    "seed": (0, 1_000_000),
    "folds": (1, 10),
    "inits": (1, 10),
    "workers": (1, CORES),
    "train_scenes": (1, MAX_TRAIN_SCENES),
}


def _limit(name: str, text: str, default: int) -> Any:
    low, high = LIMITS[name]
    return Field(
        default, description=f"{text} ({low}..{high})", json_schema_extra={"minimum": low, "maximum": high}
    )


class JobRequest(BaseModel):
    kind: Literal["train", "evaluate"]
    mode: str = Field(description="faithful or end_to_end (train); also peer (evaluate)")
    fold: int = _limit("fold", "train: which 50:50 scene split", 0)
    seed: int = _limit("seed", "train: initialisation seed; evaluate: base seed", 0)
    folds: int = _limit("folds", "evaluate: K", 2)
    inits: int = _limit("inits", "evaluate: N", 1)
    workers: int = _limit("workers", "evaluate: local worker processes, at most one per core", 1)
    split: Literal[SPLITS] = Field(  # type: ignore[valid-type]
        "scenes",
        description="the protocol split (model.experiments.splits): scenes (the paper's 50:50 by scene), "
        "objects (held-out colour x shape pairs) or action-object (held-out action x shape pairs), each "
        "Latin square with folds 0..3, or size (the training-size curve, with train_scenes)",
    )
    train_scenes: int | None = Field(
        None,
        description=f"size split only: how many scenes to train on (1..{MAX_TRAIN_SCENES}; the curve: 8, 16, "
        "32, 48), tested on the same novel 16",
        json_schema_extra={"minimum": 1, "maximum": MAX_TRAIN_SCENES},
    )
    name: str | None = Field(
        None,
        description="train: the model's name, 1-64 characters of a-z, 0-9 and '-', not taken by another "
        "model or an unfinished job (default: mode-fold-seed-id)",
        json_schema_extra={"pattern": NAME.pattern},
    )
    preset: Literal[tuple(PRESETS)] | None = Field(  # type: ignore[valid-type]
        None,
        description="epoch budget for the mode: "
        + "; ".join(f"{k}: every epoch count of the mode x {p.scale:g}" for k, p in PRESETS.items())
        + " (applied before the overrides)",
    )
    overrides: dict[str, Any] = Field(
        default_factory=dict,
        description='dotted keys of the mode\'s config, e.g. {"training.epochs_auditory": 200} (faithful), '
        '{"options.auditory_epochs": 300} (end_to_end), {"epochs": 100} (peer); at most '
        f"{MAX_OVERRIDES}. The IO sizes and T_a are fixed. Ranges by key: {ranges_text()}",
    )

    @field_validator("fold", "seed", "folds", "inits", "workers")
    @classmethod
    def _within(cls, value: int, info: Any) -> int:
        low, high = LIMITS[info.field_name]
        if not low <= value <= high:
            raise ValueError(f"{info.field_name} must be in {low}..{high}, got {value}")
        return value

    @field_validator("train_scenes")
    @classmethod
    def _scenes(cls, value: int | None, info: Any) -> int | None:
        return None if value is None else cls._within(value, info)

    @field_validator("name")
    @classmethod
    def _name(cls, value: str | None) -> str | None:
        if value is not None and not NAME.fullmatch(value):
            shown = value if len(value) <= 40 else value[:37] + "..."
            raise ValueError(f"name must be 1-64 characters of a-z, 0-9 and '-', got {shown!r}")
        return value

    @field_validator("overrides")
    @classmethod
    def _few(cls, value: dict[str, Any]) -> dict[str, Any]:
        if len(value) > MAX_OVERRIDES:
            raise ValueError(f"overrides: at most {MAX_OVERRIDES} keys, got {len(value)}")
        return value


class Job(BaseModel):
    id: str
    kind: str
    params: dict
    status: str = Field(description="queued, running, done, failed, cancelled, interrupted")
    position: int | None = Field(None, description="queued: its place in the queue (1 = next to start)")
    created: float
    updated: float
    progress: dict | None = Field(
        None,
        description="the latest progress event: stage, epoch, epochs, loss, attempt and attempts (a stage "
        "that restarts), eta (seconds left in the stage) or done, total, eta (evaluate)",
    )
    result: dict | None = None
    error: str | None = None
