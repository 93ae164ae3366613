"""Schemas shared by the resources: the Csc spaces' and splits' names, a recording's labels, errors."""

from __future__ import annotations

from typing import Literal

from pydantic import BaseModel, Field

Space = Literal["s", "v", "a"]
Split = Literal["train", "test", "unknown"]


class SceneLabels(BaseModel):
    """What names one corpus recording: its id, its scene and the scene's slots."""

    id: str = Field(description="recording id, e.g. 'slide-red-apple-2'")
    scene: str = Field(description="scene id without the variant, e.g. 'slide-red-apple'")
    action: str
    colour: str
    shape: str
    variant: int


class Health(BaseModel):
    status: Literal["ok"] = "ok"
    model: str = Field(description="name of the model being served")
    scenes: int = Field(description="recordings in the corpus")
    viewer: bool = Field(description="whether the embedded 3D viewer (viser) is running")


class PageList(BaseModel):
    pages: list[str] = Field(description="page modules under web/pages/, loaded by the navigation")


class Problem(BaseModel):
    detail: str
