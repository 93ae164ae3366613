"""The corpus: scene summaries, the scene list and the time series of one recording."""

from __future__ import annotations

from typing import Literal

from pydantic import BaseModel, Field

from server.schemas.common import SceneLabels, Split


class SceneSummary(SceneLabels):
    utterance: str = Field(description="what the teacher said")
    split: Split = Field(description="whether the served model was trained on this scene")
    frames: int = Field(description="time steps at 20 fps")
    duration_s: float
    said: str | None = Field(
        description="what the served model says about this recording (from its Csc survey); "
        "null while the survey is not ready"
    )
    correct: bool | None = Field(
        description="whether it said the teacher's sentence (model.metrics.sentence_exact); "
        "null while the survey is not ready"
    )


class SceneList(BaseModel):
    total: int = Field(description="recordings matching the filters")
    scenes: list[SceneSummary]


class RecordingDetail(BaseModel):
    """Time series of one recording (corpus scene or upload), for plots and the 3D replay."""

    id: str
    source: Literal["corpus", "upload"]
    fps: float
    frames: int
    duration_s: float
    utterance: str | None = Field(description="what the teacher said, if known")
    joint_names: list[str]
    joints: list[list[float]] = Field(description="[T][5] joint angles, radians")
    proprioception: list[list[float]] = Field(description="[T][5] joint angles scaled to [0, 1]")
    vision: list[list[float]] = Field(description="[T][F] visual features (16 distances, RGB, centroid)")
    vision_feature_names: list[str]
    summary: SceneSummary | None = Field(default=None, description="corpus metadata (corpus scenes only)")
