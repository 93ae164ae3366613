"""The corpus: GET /api/scenes (filterable), /api/scenes/{id}, and its camera frames."""

from __future__ import annotations

from typing import Annotated, Any, Literal

import numpy as np
from fastapi import APIRouter, Query, Response

from data.nao import JOINT_NAMES
from data.world import FPS
from server.deps import CorpusDep, DescribeDep, ModelsDep
from server.schemas.scenes import RecordingDetail, SceneList, SceneSummary
from server.services.corpus import frame_jpeg
from server.services.models import LoadedModel

router = APIRouter(prefix="/api/scenes", tags=["scenes"])

VISION_FEATURE_NAMES = [f"d{k + 1}" for k in range(16)] + ["R", "G", "B", "centroid x", "centroid y"]


def rows(array: Any, digits: int = 5) -> list[list[float]]:
    """A 2-D array as rows of rounded floats."""
    return [[round(float(v), digits) for v in row] for row in array]


def summary_of(served: LoadedModel, entry: Any) -> SceneSummary:
    frames = len(entry.joints)
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
    )


def _matches(s: SceneSummary, filters: dict[str, Any], q: str | None) -> bool:
    if any(value is not None and getattr(s, key) != value for key, value in filters.items()):
        return False
    return not q or q.lower() in s.id or q.lower() in s.utterance


@router.get("", response_model=SceneList)
def list_scenes(
    corpus: CorpusDep,
    models: ModelsDep,
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
    out = [s for e in corpus.entries.values() if _matches(s := summary_of(served, e), filters, q)]
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
def get_scene(corpus: CorpusDep, models: ModelsDep, rid: str) -> RecordingDetail:
    entry = corpus.entry(rid)
    series = (entry.joints, entry.proprioception, entry.vision)
    return recording_detail(entry.id, "corpus", series, entry.utterance, summary_of(models.served, entry))


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
