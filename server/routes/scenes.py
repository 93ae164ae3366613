"""The corpus: GET /api/scenes (filterable), /api/scenes/{id}, and its camera frames."""

from __future__ import annotations

from typing import Annotated, Literal

from fastapi import APIRouter, Query, Response

from server.schemas import RecordingDetail, SceneList, SceneSummary
from server.state import VISION_FEATURE_NAMES, AppState, StateDep

router = APIRouter(prefix="/api/scenes", tags=["scenes"])


def summary_of(state: AppState, entry) -> SceneSummary:  # noqa: ANN001 - a corpus entry
    frames = len(entry.joints)
    return SceneSummary(
        id=entry.id,
        scene=entry.scene.id,
        action=entry.scene.action,
        colour=entry.scene.colour,
        shape=entry.scene.shape,
        variant=entry.variant,
        utterance=entry.utterance,
        split=state.split_of(entry.id),  # type: ignore[arg-type]
        frames=frames,
        duration_s=frames / 20.0,
    )


@router.get("", response_model=SceneList)
def list_scenes(
    state: StateDep,
    action: Annotated[str | None, Query(description="pull, push, show me or slide")] = None,
    colour: Annotated[str | None, Query(description="blue, green, red or yellow")] = None,
    shape: Annotated[str | None, Query(description="apple, banana, dice or phone")] = None,
    variant: Annotated[int | None, Query(ge=0, le=3)] = None,
    split: Annotated[
        Literal["train", "test", "unknown"] | None, Query(description="for the served model")
    ] = None,
    q: Annotated[str | None, Query(description="substring of the id or utterance")] = None,
) -> SceneList:
    out = []
    for entry in state.entries.values():
        s = summary_of(state, entry)
        if action and s.action != action.replace("-", " "):
            continue
        if (colour and s.colour != colour) or (shape and s.shape != shape):
            continue
        if (variant is not None and s.variant != variant) or (split and s.split != split):
            continue
        if q and q.lower() not in s.id and q.lower() not in s.utterance:
            continue
        out.append(s)
    return SceneList(total=len(out), scenes=out)


def _rows(array) -> list[list[float]]:  # noqa: ANN001 - any 2-D array
    return [[round(float(v), 5) for v in row] for row in array]


@router.get("/{rid}", response_model=RecordingDetail)
def get_scene(state: StateDep, rid: str) -> RecordingDetail:
    entry = state.entry(rid)
    frames = len(entry.joints)
    return RecordingDetail(
        id=entry.id,
        source="corpus",
        fps=20.0,
        frames=frames,
        duration_s=frames / 20.0,
        utterance=entry.utterance,
        joint_names=state.backend.joint_names,
        joints=_rows(entry.joints),
        proprioception=_rows(entry.proprioception),
        vision=_rows(entry.vision),
        vision_feature_names=VISION_FEATURE_NAMES[: entry.vision.shape[1]],
        summary=summary_of(state, entry),
    )


@router.get(
    "/{rid}/frames/{index}.jpg",
    response_class=Response,
    responses={200: {"content": {"image/jpeg": {}}}},
)
def get_frame(
    state: StateDep,
    rid: str,
    index: int,
    overlay: Annotated[bool, Query(description="draw the vision pipeline's contour and 16 rays")] = False,
    width: Annotated[int | None, Query(ge=16, le=1280, description="scale down to this width")] = None,
) -> Response:
    """One camera frame of a corpus recording (re-rendered from its seed) or of an upload."""
    data = state.frame_jpeg(rid, index, overlay, width)
    return Response(data, media_type="image/jpeg", headers={"Cache-Control": "max-age=3600"})
