"""The corpus: GET /api/scenes (filterable), /api/scenes/{id}, and its camera frames."""

from __future__ import annotations

from typing import Annotated, Any, Literal

import numpy as np
from fastapi import APIRouter, Query, Response

from data.nao import JOINT_NAMES
from data.world import FPS
from model.metrics import sentence_exact
from server.deps import CorpusDep, DescribeDep, ModelsDep, SurveyDep
from server.schemas.scenes import RecordingDetail, SceneList, SceneSummary
from server.services.answers import rows
from server.services.corpus import frame_jpeg
from server.services.models import LoadedModel
from server.services.survey import Survey

router = APIRouter(prefix="/api/scenes", tags=["scenes"])

VISION_FEATURE_NAMES = [f"d{k + 1}" for k in range(16)] + ["R", "G", "B", "centroid x", "centroid y"]


def summary_of(served: LoadedModel, entry: Any, survey: Survey | None) -> SceneSummary:
    """A corpus recording's labels, its split for the served model and what that model says about
    it (from `survey`, the served model's; None while it is not ready)."""
    frames = len(entry.joints)
    said = survey.said(entry.id) if survey is not None else None
    return SceneSummary(
        id=entry.id,
        scene=entry.scene.id,
        action=entry.scene.action,
        colour=entry.scene.colour,
        shape=entry.scene.shape,
        variant=entry.variant,
        utterance=entry.utterance,
        split=served.split_of(entry.id),  # type: ignore[arg-type]
        frames=frames,
        duration_s=frames / FPS,
        said=said,
        correct=None if said is None else sentence_exact(said, entry.utterance),
    )


def _matches(s: SceneSummary, filters: dict[str, Any], q: str | None) -> bool:
    if any(value is not None and getattr(s, key) != value for key, value in filters.items()):
        return False
    return not q or q.lower() in s.id or q.lower() in s.utterance


@router.get("", response_model=SceneList)
def list_scenes(
    corpus: CorpusDep,
    models: ModelsDep,
    survey: SurveyDep,
    action: Annotated[str | None, Query(description="pull, push, show me or slide")] = None,
    colour: Annotated[str | None, Query(description="blue, green, red or yellow")] = None,
    shape: Annotated[str | None, Query(description="apple, banana, dice or phone")] = None,
    variant: Annotated[int | None, Query(ge=0, le=3)] = None,
    split: Annotated[
        Literal["train", "test", "unknown"] | None, Query(description="for the served model")
    ] = None,
    q: Annotated[str | None, Query(description="substring of the id or utterance")] = None,
) -> SceneList:
    filters = {
        "action": action.replace("-", " ") if action else None,
        "colour": colour or None,
        "shape": shape or None,
        "variant": variant,
        "split": split or None,
    }
    served = models.served
    surveyed = survey.ready(served.name)  # never waits for the survey
    entries = corpus.entries.values()
    out = [s for e in entries if _matches(s := summary_of(served, e, surveyed), filters, q)]
    return SceneList(total=len(out), scenes=out)


def recording_detail(
    rid: str,
    source: str,
    series: tuple[np.ndarray, np.ndarray, np.ndarray],
    utterance: str | None,
    summary: SceneSummary | None = None,
) -> RecordingDetail:
    """The time series (joints, proprioception, vision) of a recording at data.world.FPS."""
    joints, proprioception, vision = series
    frames = len(joints)
    return RecordingDetail(
        id=rid,
        source=source,  # type: ignore[arg-type]
        fps=FPS,
        frames=frames,
        duration_s=frames / FPS,
        utterance=utterance,
        joint_names=list(JOINT_NAMES),
        joints=rows(joints),
        proprioception=rows(proprioception),
        vision=rows(vision),
        vision_feature_names=VISION_FEATURE_NAMES[: vision.shape[1]],
        summary=summary,
    )


@router.get("/{rid}", response_model=RecordingDetail)
def get_scene(corpus: CorpusDep, models: ModelsDep, survey: SurveyDep, rid: str) -> RecordingDetail:
    entry = corpus.entry(rid)
    series = (entry.joints, entry.proprioception, entry.vision)
    summary = summary_of(models.served, entry, survey.ready(models.served.name))
    return recording_detail(entry.id, "corpus", series, entry.utterance, summary)


@router.get(
    "/{rid}/frames/{index}.jpg",
    response_class=Response,
    responses={200: {"content": {"image/jpeg": {}}}},
)
def get_frame(
    describe: DescribeDep,
    rid: str,
    index: int,
    overlay: Annotated[bool, Query(description="draw the vision pipeline's contour and 16 rays")] = False,
    width: Annotated[int | None, Query(ge=16, le=1280, description="scale down to this width")] = None,
) -> Response:
    """One camera frame of a corpus recording (re-rendered from its seed) or of an upload."""
    data = frame_jpeg(describe.frames(rid), rid, index, overlay, width)
    return Response(data, media_type="image/jpeg", headers={"Cache-Control": "max-age=3600"})
