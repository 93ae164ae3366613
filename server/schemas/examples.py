"""Recordings to try (GET /api/examples): what each one shows and where to download it."""

from __future__ import annotations

from typing import Literal

from pydantic import BaseModel, Field


class ExampleInfo(BaseModel):
    name: str = Field(description="URL-safe name, e.g. 'other-camera'")
    title: str = Field(description="the scene and what is unusual about the recording")
    description: str = Field(description="how it was made, and how it differs from the corpus")
    kind: Literal["corpus", "unlike"] = Field(
        description="a corpus recording, or one made outside the ranges the corpus samples"
    )
    url: str = Field(description="where to download it: a format-v1 .zip")


class ExampleList(BaseModel):
    examples: list[ExampleInfo]
