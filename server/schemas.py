"""Pydantic schemas of the REST API: what clients send and receive, apart from the internals."""

from __future__ import annotations

from typing import Literal

from pydantic import BaseModel, Field, model_validator

Space = Literal["s", "v", "a"]
Split = Literal["train", "test", "unknown"]


class Health(BaseModel):
    status: Literal["ok"] = "ok"
    model: str = Field(description="name of the model being served")
    scenes: int = Field(description="recordings in the corpus")
    viewer: bool = Field(description="whether the embedded 3D viewer (viser) is running")


class SceneSummary(BaseModel):
    id: str = Field(description="recording id, e.g. 'slide-red-apple-2'")
    scene: str = Field(description="scene id without the variant, e.g. 'slide-red-apple'")
    action: str
    colour: str
    shape: str
    variant: int
    utterance: str = Field(description="what the teacher said")
    split: Split = Field(description="whether the served model was trained on this scene")
    frames: int = Field(description="time steps at 20 fps")
    duration_s: float


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


class Timings(BaseModel):
    read_ms: float = Field(0.0, description="parsing the uploaded file")
    encode_ms: float = Field(0.0, description="proprioception + vision encoding")
    model_ms: float = Field(description="MultiMTRNN: abstraction, cell assemblies, generation")
    total_ms: float


class CscVectors(BaseModel):
    s: list[float] = Field(description="c_s,T: final Csc state of MTRNN_s (somatosensory)")
    v: list[float] = Field(description="c_v,T: final Csc state of MTRNN_v (visual)")
    a: list[float] = Field(description="c_a,0: initial Csc state of MTRNN_a, from the cell assemblies")


class Description(BaseModel):
    id: str = Field(description="recording id (corpus) or upload id")
    source: Literal["corpus", "upload"]
    model: str
    utterance: str = Field(description="the utterance the model generated")
    words: list[str]
    phonemes: list[str]
    expected: str | None = Field(description="what the teacher said, if the recording carries it")
    correct: bool | None = Field(description="generated == expected (None when nothing is expected)")
    phoneme_labels: list[str] = Field(description="the alphabet B: one label per output neuron")
    activity: list[list[float]] = Field(description="[T_a][|B|] softmax output of MTRNN_a")
    target_activity: list[list[float]] | None = Field(description="[T_a][|B|] encoded expected utterance")
    csc: CscVectors
    timings: Timings


class CscPoint(BaseModel):
    id: str
    scene: str
    action: str
    colour: str
    shape: str
    variant: int
    split: Split
    x: float = Field(description="PC1")
    y: float = Field(description="PC2")
    generated: str = Field(description="what the model says for this recording")


class CscMeasures(BaseModel):
    d_avg: float = Field(description="eq. (14): mean pairwise distance of all patterns")
    d_rel: float = Field(description="eq. (15): geometric mean of distance / d_avg (1 = evenly spread)")
    d_inter: float = Field(description="eq. (22): mean distance within a manipulation, averaged")
    d_intra: float = Field(description="eq. (23): mean distance between the manipulations' centroids")


class CscSpace(BaseModel):
    space: Space
    model: str
    dims: int = Field(description="Csc units of this space")
    explained_variance: list[float] = Field(description="variance per principal component")
    explained_variance_ratio: list[float]
    measures: CscMeasures
    points: list[CscPoint]


class Neighbour(BaseModel):
    id: str
    distance: float = Field(description="Euclidean distance in the original Csc space")
    utterance: str


class Neighbours(BaseModel):
    space: Space
    id: str
    neighbours: list[Neighbour]


class GenerateRequest(BaseModel):
    """Either a full c_a,0 vector or a point of the auditory PCA plane (inverse projection)."""

    csc: list[float] | None = Field(default=None, description="c_a,0, one value per auditory Csc unit")
    point: tuple[float, float] | None = Field(default=None, description="(PC1, PC2) of the auditory plane")

    @model_validator(mode="after")
    def _exactly_one(self) -> GenerateRequest:
        if (self.csc is None) == (self.point is None):
            raise ValueError("give exactly one of 'csc' (a c_a,0 vector) or 'point' ([PC1, PC2])")
        return self


class Generated(BaseModel):
    model: str
    utterance: str
    words: list[str]
    phonemes: list[str]
    csc: list[float] = Field(description="the c_a,0 the generation started from")
    point: tuple[float, float] = Field(description="its (PC1, PC2) on the auditory plane")
    nearest: Neighbour = Field(description="the corpus recording whose c_a,0 is closest")
    phoneme_labels: list[str]
    activity: list[list[float]]


class ModelInfo(BaseModel):
    name: str
    selected: bool
    meta: dict = Field(description="meta.json of the checkpoint (config, mode, seed, split, metrics)")


class ModelList(BaseModel):
    selected: str
    models: list[ModelInfo]


class SelectModel(BaseModel):
    name: str


class ViewerState(BaseModel):
    available: bool = Field(description="whether the 3D viewer runs in this process")
    source: str | None = Field(description="recording shown (corpus id or upload id)")
    t: float = Field(description="time cursor, seconds")
    duration_s: float
    playing: bool
    speed: float


class ViewerCommand(BaseModel):
    show: str | None = Field(default=None, description="recording id or upload id to show")
    t: float | None = Field(default=None, ge=0.0, description="move the time cursor (seconds)")
    playing: bool | None = None
    speed: float | None = Field(default=None, gt=0.0, le=8.0)


class PageList(BaseModel):
    pages: list[str] = Field(description="page modules under web/pages/, loaded by the navigation")


class Problem(BaseModel):
    detail: str
