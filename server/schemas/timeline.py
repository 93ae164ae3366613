"""The live description: what the model would say if asked at every step of a recording."""

from __future__ import annotations

from pydantic import BaseModel, Field


class Settle(BaseModel):
    word: str = Field(description="a word of the last utterance, or a slot's most probable phrase at the end")
    step: int = Field(description="the step from which it stays (one past the last step it was otherwise)")
    t: float = Field(description="that step's time in seconds")


class Settles(BaseModel):
    words: list[Settle] = Field(description="each word of the last utterance, in order")
    slots: dict[str, Settle] = Field(
        description="per slot of word units (end_to_end); none for the paper's CAs"
    )


class SlotTrack(BaseModel):
    words: list[str] = Field(description="the slot's phrases, one word unit each")
    probability: list[list[float]] = Field(description="[word][step]: each word unit's probability")


class Timeline(BaseModel):
    id: str = Field(description="recording id (corpus) or upload id")
    model: str
    mode: str = Field(description="the model's training mode (faithful, end_to_end, ...)")
    fps: float = Field(description="steps per second")
    t: list[float] = Field(description="each step's time in seconds")
    utterance: list[str] = Field(description="what the model would say at each step; the last is its answer")
    words: list[list[str]] = Field(description="the words of each step's utterance")
    settles: Settles
    slots: dict[str, SlotTrack] = Field(description="end_to_end: each slot's word units per step")
    model_ms: float = Field(description="computing the timeline (when it was not kept already)")
