"""The 3D viewer's shared time cursor and the commands that move it."""

from __future__ import annotations

from pydantic import BaseModel, ConfigDict, Field


class ViewerState(BaseModel):
    available: bool = Field(description="whether the 3D viewer runs in this process")
    source: str | None = Field(description="recording shown (corpus id or upload id)")
    t: float = Field(description="time cursor, seconds")
    duration_s: float
    playing: bool
    speed: float


class ViewerCommand(BaseModel):
    model_config = ConfigDict(allow_inf_nan=False)  # NaN or infinity: 422, never the cursor

    show: str | None = Field(default=None, max_length=200, description="recording id or upload id to show")
    t: float | None = Field(default=None, ge=0.0, description="move the time cursor (seconds)")
    playing: bool | None = None
    speed: float | None = Field(default=None, gt=0.0, le=8.0)
