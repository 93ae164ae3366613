"""The time cursor of a 3D view and the commands that move it; a view is named by its id (`VIEW_ID`)."""

from __future__ import annotations

from pydantic import BaseModel, ConfigDict, Field

VIEW_ID = r"^[A-Za-z0-9_-]{1,32}$"  # made by the page (web/js/cursor.js), random unless shared on purpose


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
