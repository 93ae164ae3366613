"""The Csc spaces: PCA points, cluster measures, neighbours and generation from a c_a,0."""

from __future__ import annotations

from pydantic import BaseModel, Field, model_validator

from server.schemas.common import SceneLabels, Space, Split


class CscPoint(SceneLabels):
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
