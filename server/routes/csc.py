"""The Csc spaces: GET /api/csc (PCA, measures), /api/csc/neighbours, POST /api/csc/generate."""

from __future__ import annotations

from typing import Annotated

import numpy as np
from fastapi import APIRouter, HTTPException, Query
from starlette.concurrency import run_in_threadpool

from server.schemas import (
    CscMeasures,
    CscPoint,
    CscSpace,
    Generated,
    GenerateRequest,
    Neighbour,
    Neighbours,
    Problem,
    Space,
)
from server.state import StateDep

router = APIRouter(prefix="/api/csc", tags=["csc"])


@router.get("", response_model=CscSpace)
async def csc_space(
    state: StateDep,
    space: Annotated[
        Space, Query(description="s (somatosensory c_s,T), v (visual c_v,T) or a (auditory c_a,0)")
    ],
) -> CscSpace:
    """PCA (exact SVD) of one Csc space over all corpus recordings, with the paper's cluster measures."""
    cache = await run_in_threadpool(state.csc_cache)
    data = cache.spaces[space]
    points = []
    for i, rid in enumerate(cache.ids):
        scene = state.entries[rid].scene
        points.append(
            CscPoint(
                id=rid,
                scene=scene.id,
                action=scene.action,
                colour=scene.colour,
                shape=scene.shape,
                variant=state.entries[rid].variant,
                split=state.split_of(rid),  # type: ignore[arg-type]
                x=round(float(data.coords[i, 0]), 6),
                y=round(float(data.coords[i, 1]), 6),
                generated=cache.generated[i],
            )
        )
    return CscSpace(
        space=space,
        model=state.model.name,
        dims=int(data.vectors.shape[1]),
        explained_variance=data.explained_variance,
        explained_variance_ratio=data.explained_variance_ratio,
        measures=CscMeasures(**data.measures),
        points=points,
    )


@router.get("/neighbours", response_model=Neighbours, responses={404: {"model": Problem}})
async def neighbours(
    state: StateDep,
    space: Annotated[Space, Query()],
    id: Annotated[str, Query(description="recording id")],
    k: Annotated[int, Query(ge=1, le=50)] = 5,
) -> Neighbours:
    """The k recordings whose Csc patterns are closest to this one's, in the original (not PCA) space."""
    state.entry(id)
    cache = await run_in_threadpool(state.csc_cache)
    vector = cache.spaces[space].vectors[cache.ids.index(id)]
    near = state.nearest(space, vector, k, exclude=id)
    text = dict(zip(cache.ids, cache.generated, strict=True))
    return Neighbours(
        space=space, id=id, neighbours=[Neighbour(id=r, distance=d, utterance=text[r]) for r, d in near]
    )


@router.post("/generate", response_model=Generated, responses={422: {"model": Problem}})
async def generate(state: StateDep, body: GenerateRequest) -> Generated:
    """What the robot would say from a c_a,0: given directly, or a point of the auditory PCA plane."""
    cache = await run_in_threadpool(state.csc_cache)
    dims = cache.spaces["a"].vectors.shape[1]
    if body.csc is not None:
        if len(body.csc) != dims or not np.all(np.isfinite(body.csc)):
            raise HTTPException(422, f"'csc' must hold {dims} finite numbers (one per auditory Csc unit)")
        c_a = np.asarray(body.csc, dtype=np.float64)
        point = state.project_a(c_a)
    else:
        assert body.point is not None
        if not np.all(np.isfinite(body.point)):
            raise HTTPException(422, "'point' must be two finite numbers")
        point = (float(body.point[0]), float(body.point[1]))
        c_a = state.inverse_point(*point)
    g = await run_in_threadpool(state.generate, c_a)
    ((rid, dist),) = state.nearest("a", c_a, 1)
    text = cache.generated[cache.ids.index(rid)]
    return Generated(
        model=state.model.name,
        utterance=g.text,
        words=list(g.words),
        phonemes=list(g.phonemes),
        csc=[round(float(x), 6) for x in c_a],
        point=point,
        nearest=Neighbour(id=rid, distance=dist, utterance=text),
        phoneme_labels=state.backend.phoneme_labels,
        activity=[[round(float(v), 4) for v in row] for row in np.asarray(g.activity)],
    )
