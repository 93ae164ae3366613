"""The seven lessons' answers (server/lessons/), one schema per live computation."""

from __future__ import annotations

from typing import Any, Literal

from pydantic import BaseModel, Field


class LessonInfo(BaseModel):
    id: str
    title: str


class SceneChoice(BaseModel):
    id: str
    utterance: str
    split: str


class LessonIndex(BaseModel):
    lessons: list[LessonInfo]
    model: str = Field(description="the served model")
    models: list[str] = Field(description="every model the app can serve")
    modes: dict[str, str] = Field(description="training mode of each model (faithful, end_to_end, ...)")
    scenes: list[SceneChoice] = Field(description="corpus recordings, first variant of each scene")


class Pulse(BaseModel):
    tau: float
    input: list[float]
    z: list[float] = Field(description="internal state of the unit, eq. (3)")
    peak: float
    half_life_steps: float | None
    left_after_20_steps: float = Field(description="share of z left 20 steps after the pulse ends")
    references: dict[str, list[float]] = Field(
        description="the same pulse at MTRNN_a's IO, Cf, Cs timescales"
    )


class Layer(BaseModel):
    tau: float
    y: list[list[float]] = Field(description="[units][T] activations")
    speed: float = Field(description="mean |y_t - y_t-1|: how fast the layer's activity changes")


class Activity(BaseModel):
    id: str
    model: str
    expected: str
    said: str
    phonemes: list[str]
    steps: int
    phoneme_labels: list[str]
    phoneme_at: list[str] = Field(description="the phoneme the IO layer produces at each step ('' if none)")
    layers: dict[str, Layer]


class Speech(BaseModel):
    text: str
    phonemes: list[str]
    params: dict[str, float]
    lambda_: float = Field(alias="lambda", description="eq. (20)")
    steps: int
    labels: list[str] = Field(description="the neurons of B the sentence uses")
    spikes: list[list[float]] = Field(description="[used neurons][T] Gaussian spikes g, eqs. (18)-(19)")
    activity: list[list[float]] = Field(description="[used neurons][T] softmax activity y*, eq. (21)")
    peak: float
    decoded: list[str]
    read_back: str
    exact: bool


class Stage(BaseModel):
    key: str
    title: str
    image: str = Field(description="data URL: PNG for masks and edges, JPEG for colour pictures")


class Seen(BaseModel):
    width: int
    height: int
    found: bool
    pipeline_ms: float
    stages: list[Stage]
    features: list[float]
    feature_names: list[str]
    paper_features: int
    source: str = Field("", description="where the picture came from")
    frames: int = Field(0, description="frames of the recording (0 for an upload)")


class Feeling(BaseModel):
    action: str
    colour: str
    joint_names: list[str]
    reads: Literal["joints", "joints+hand", "hand"] = Field(
        description="what the served model's MTRNN_s reads (MultiMTRNNConfig.proprioception)"
    )
    object_motion: Literal["none", "visual", "somatosensory"] = Field(
        description="which net also reads the object's motion in the image (MultiMTRNNConfig.object_motion)"
    )
    series: list[dict[str, Any]]
    comparison: dict[str, Any] | None


class CosineStart(BaseModel):
    psi: float = Field(ge=0.0, le=0.01, description="self-organisation forcing (eqs. 11-12)")
    seed: int = Field(0, ge=0, le=10_000)


class CosineRun(BaseModel):
    id: str
    psi: float
    seed: int
    status: Literal["queued", "running", "done", "failed"]
    epoch: int
    epochs: int
    progress: float
    loss: float | None
    frames: list[dict[str, Any]] = Field(description="Csc points (and d_avg, d_rel) over training")
    frame_count: int
    result: dict[str, Any] | None
    error: str | None
    seconds: float


class Association(BaseModel):
    id: str
    model: str
    mute: str
    expected: str
    said: str
    unmuted: str
    slots: dict[str, dict[str, str | None]]
    index: int
    point_a: list[float]
    moved: float = Field(description="how far c_a,0 moved in the auditory Csc space by muting")
    nearest: dict[str, str]
    labels: list[dict[str, str]]
    spaces: dict[str, dict[str, list[float]]]


class Generalisation(BaseModel):
    model: str
    mode: str
    actions: list[str]
    objects: list[str]
    scenes: list[dict[str, Any]]
    train: dict[str, Any]
    test: dict[str, Any]
    test_object_seen: dict[str, Any]
    test_object_unseen: dict[str, Any]
    split: str = Field(description="the model's protocol split (model.experiments.splits), from its meta")
    fold: int | None = None
    held_out: list[dict[str, Any]] = Field(
        description="objects split: per held-out object the colour and shape words said for it"
    )
    objects_models: list[dict[str, Any]] = Field(description="the models trained on the objects split")


class Sweeps(BaseModel):
    available: bool = Field(description="whether a psi_s sweep is stored")
    reason: str = Field(description="why not, when it is not")
    psi_s: list[dict[str, Any]] = Field(
        description="per psi_s: Fig. 9 measures, mean and *_sem (model.experiments.sweeps)"
    )
    cosine: list[dict[str, Any]] = Field(
        description="per psi: Fig. 3 (a, b) measures of the stored cosine sweep"
    )
