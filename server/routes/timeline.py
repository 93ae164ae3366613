"""The live description: GET /api/scenes/{id}/timeline (a corpus recording or an upload)."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Query

from server.deps import TimelineDep
from server.schemas.common import Problem
from server.schemas.timeline import Settle, Settles, SlotTrack, Timeline
from server.services.timeline import RecordingTimeline

router = APIRouter(prefix="/api/scenes", tags=["timeline"])


def timeline_of(rt: RecordingTimeline) -> Timeline:
    """The API's answer for one recording's timeline (also in the upload describe answer)."""
    tl, times = rt.timeline, rt.t

    def settle(word: str, step: int) -> Settle:
        return Settle(word=word, step=step, t=round(step / rt.fps, 3))

    slots, slot_settles = {}, {}
    tracks = zip(rt.slot_names, tl.slots, tl.slot_probabilities, tl.slot_settles, strict=True)
    for name, phrases, p, step in tracks:
        slots[name] = SlotTrack(words=phrases, probability=[[round(float(v), 4) for v in row] for row in p.T])
        slot_settles[name] = settle(phrases[int(p[-1].argmax())], step)
    words = [settle(w, s) for w, s in zip(tl.words[-1], tl.word_settles, strict=True)]
    return Timeline(
        id=rt.id,
        model=rt.model,
        mode=rt.mode,
        fps=rt.fps,
        t=[round(t, 3) for t in times],
        utterance=tl.texts,
        words=tl.words,
        settles=Settles(words=words, slots=slot_settles),
        slots=slots,
        model_ms=round(rt.model_ms, 3),
    )


@router.get(
    "/{rid}/timeline",
    response_model=Timeline,
    responses={404: {"model": Problem}, 409: {"model": Problem}},
)
def get_timeline(
    timelines: TimelineDep,
    rid: str,
    model: Annotated[str | None, Query(description="a model's name (default: the served one)")] = None,
) -> Timeline:
    """What the model would say if asked at every step of the recording (`id`: a corpus
    recording or an upload), the step at which each word settles, and for end_to_end each slot's
    word-unit probabilities per step; the last entry is the model's describe answer."""
    return timeline_of(timelines.of(rid, model))
