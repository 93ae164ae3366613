"""The Csc spaces: GET /api/csc (PCA, measures), /api/csc/neighbours, POST /api/csc/generate."""

from __future__ import annotations

from typing import Annotated

import numpy as np
from fastapi import APIRouter, HTTPException, Query
from starlette.concurrency import run_in_threadpool

from model.encoding.utterance import PHONEMES
from server.deps import CorpusDep, DescribeDep, ModelsDep, SurveyDep
from server.schemas.common import Problem, Space
from server.schemas.csc import (
    CscMeasures,
    CscPoint,
    CscSpace,
    Generated,
    GenerateRequest,
    Neighbour,
    Neighbours,
)
from server.services.survey import SurveyService

router = APIRouter(prefix="/api/csc", tags=["csc"])


@router.get("", response_model=CscSpace)
async def csc_space(
    corpus: CorpusDep,
    models: ModelsDep,
    survey: SurveyDep,
    space: Annotated[
        Space, Query(description="s (somatosensory c_s,T), v (visual c_v,T) or a (auditory c_a,0)")
    ],
) -> CscSpace:
    """PCA (exact SVD) of one Csc space over all corpus recordings, with the paper's cluster measures."""
    surveyed = await run_in_threadpool(survey.spaces)
    data = surveyed.spaces[space]
    served = models.served
    points = []
    for i, rid in enumerate(surveyed.ids):
        entry = corpus.entries[rid]
        points.append(
            CscPoint(
                id=rid,
                scene=entry.scene.id,
                action=entry.scene.action,
                colour=entry.scene.colour,
                shape=entry.scene.shape,
                variant=entry.variant,
                split=served.split_of(rid),  # type: ignore[arg-type]
                x=round(float(data.coords[i, 0]), 6),
                y=round(float(data.coords[i, 1]), 6),
                generated=surveyed.texts[i],
            )
        )
    return CscSpace(
        space=space,
        model=served.name,
        dims=int(data.vectors.shape[1]),
        explained_variance=data.explained_variance,
        explained_variance_ratio=data.explained_variance_ratio,
        measures=CscMeasures(**data.measures),
        points=points,
    )


@router.get("/neighbours", response_model=Neighbours, responses={404: {"model": Problem}})
async def neighbours(
    corpus: CorpusDep,
    survey: SurveyDep,
    space: Annotated[Space, Query()],
    id: Annotated[str, Query(description="recording id")],
    k: Annotated[int, Query(ge=1, le=50)] = 5,
) -> Neighbours:
    """The k recordings whose Csc patterns are closest to this one's, in the original (not PCA) space."""
    corpus.entry(id)
    surveyed = await run_in_threadpool(survey.spaces)
    vector = surveyed.spaces[space].vectors[surveyed.ids.index(id)]
    near = survey.nearest(space, vector, k, exclude=id)
    text = dict(zip(surveyed.ids, surveyed.texts, strict=True))
    return Neighbours(
        space=space, id=id, neighbours=[Neighbour(id=r, distance=d, utterance=text[r]) for r, d in near]
    )


def _start_point(
    survey: SurveyService, body: GenerateRequest, dims: int
) -> tuple[np.ndarray, tuple[float, float]]:
    """(c_a,0, its point on the auditory plane) from the request's vector or point."""
    if body.csc is not None:
        if len(body.csc) != dims or not np.all(np.isfinite(body.csc)):
            raise HTTPException(422, f"'csc' must hold {dims} finite numbers (one per auditory Csc unit)")
        c_a = np.asarray(body.csc, dtype=np.float64)
        return c_a, survey.project_a(c_a)
    assert body.point is not None
    if not np.all(np.isfinite(body.point)):
        raise HTTPException(422, "'point' must be two finite numbers")
    point = (float(body.point[0]), float(body.point[1]))
    return survey.inverse_point(*point), point


@router.post("/generate", response_model=Generated, responses={422: {"model": Problem}})
async def generate(
    models: ModelsDep, survey: SurveyDep, describe: DescribeDep, body: GenerateRequest
) -> Generated:
    """What the robot would say from a c_a,0: given directly, or a point of the auditory PCA plane."""
    surveyed = await run_in_threadpool(survey.spaces)
    c_a, point = _start_point(survey, body, surveyed.spaces["a"].vectors.shape[1])
    g = await run_in_threadpool(describe.generate, c_a)
    ((rid, dist),) = survey.nearest("a", c_a, 1)
    text = surveyed.texts[surveyed.ids.index(rid)]
    return Generated(
        model=models.served.name,
        utterance=g.text,
        words=list(g.words),
        phonemes=list(g.phonemes),
        csc=[round(float(x), 6) for x in c_a],
        point=point,
        nearest=Neighbour(id=rid, distance=dist, utterance=text),
        phoneme_labels=list(PHONEMES),
        activity=[[round(float(v), 4) for v in row] for row in np.asarray(g.activity)],
    )
