"""What the served model says about a recording: the utterance, activity and Csc vectors."""

from __future__ import annotations

from typing import Literal

from pydantic import BaseModel, Field

from server.schemas.timeline import Timeline


class Timings(BaseModel):
    read_ms: float = Field(0.0, description="parsing the uploaded file")
    encode_ms: float = Field(0.0, description="proprioception + vision encoding")
    model_ms: float = Field(description="MultiMTRNN: abstraction, cell assemblies, generation")
    total_ms: float


class CscVectors(BaseModel):
    s: list[float] = Field(description="c_s,T: final Csc state of MTRNN_s (somatosensory)")
    v: list[float] = Field(description="c_v,T: final Csc state of MTRNN_v (visual)")
    a: list[float] = Field(description="c_a,0: initial Csc state of MTRNN_a, from the cell assemblies")


class Familiarity(BaseModel):
    """How far the recording lies from the model's training recordings (model/familiarity.py)."""

    proprioception: float = Field(
        ge=0.0,
        le=1.0,
        description="the arm's joint angles: the fraction of training recordings whose own distance to "
        "the nearest training recording of another scene is at least this recording's distance to the "
        "nearest training recording (1: like a training recording; about 0.5: like a new scene of the "
        "training set; near 0: farther than all of them)",
    )
    vision: float = Field(ge=0.0, le=1.0, description="the camera's features, calibrated the same way")


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
    timeline: Timeline | None = Field(None, description="uploads: what the model would say at every step")
    familiarity: Familiarity | None = Field(
        None,
        description="per sense, how familiar the recording is to the model (None: not known for this model)",
    )
    warnings: list[str] = Field(
        default_factory=list,
        description="plain sentences: what could not be compared (words of the expected utterance outside "
        "the lexicon, ...) and how the recording is unlike what the model learned from (postures, motion, "
        "camera view, duration, joints at their limits, frames without the object)",
    )
