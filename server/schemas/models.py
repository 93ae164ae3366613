"""The model registry: the models the app can serve and which one it serves."""

from __future__ import annotations

from pydantic import BaseModel, Field


class ModelInfo(BaseModel):
    name: str
    selected: bool
    meta: dict = Field(description="meta.json of the checkpoint (config, mode, seed, split, metrics)")


class ModelList(BaseModel):
    selected: str
    models: list[ModelInfo]


class SelectModel(BaseModel):
    name: str
