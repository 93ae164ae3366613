"""The live description: what a model would say if asked at every step of a recording (issue 15).

`MultiMTRNN.timeline` (3.4) over a corpus recording's stored encodings or an upload's, with each
step's time in seconds and each slot of word units named by what its phrases are (action,
colour, shape). A corpus scene is followed by the served model (or a named one), an upload by
the model that described it, so the timeline ends on the answer its page shows. Timelines are
kept per (model, recording).
"""

from __future__ import annotations

import threading
import time
from collections import OrderedDict
from dataclasses import dataclass

import numpy as np

from data.scenario import ACTIONS, COLOURS, SHAPES
from data.world import FPS
from model.multimtrnn import Timeline
from server.services.corpus import Corpus
from server.services.describe import DescribeService
from server.services.errors import Conflict
from server.services.models import LoadedModel, ModelRegistry

SLOT_NAMES = {"action": ACTIONS, "colour": COLOURS, "shape": SHAPES}


def slot_name(phrases: list[str], index: int) -> str:
    """'action', 'colour' or 'shape' when every phrase of the slot is one of the scenario's;
    else 'slot <k>' (1-based)."""
    for name, known in SLOT_NAMES.items():
        if set(phrases) <= set(known):
            return name
    return f"slot {index + 1}"


@dataclass
class RecordingTimeline:
    """One recording's timeline as one model says it, with what the API adds."""

    id: str
    model: str
    mode: str
    fps: float
    timeline: Timeline
    slot_names: list[str]
    model_ms: float

    @property
    def t(self) -> list[float]:
        """Each step's time in seconds (step t has read the recording's frames 0..t)."""
        return [t / self.fps for t in range(len(self.timeline.texts))]


class TimelineService:
    """Timelines of corpus scenes and uploads, computed once per (model, recording)."""

    def __init__(
        self, corpus: Corpus, models: ModelRegistry, describe: DescribeService, cache: int = 64
    ) -> None:
        self.corpus, self.models, self.describe = corpus, models, describe
        self._cache_size = cache
        self._cache: OrderedDict[tuple[str, str], tuple[object, RecordingTimeline]] = OrderedDict()
        self._lock = threading.Lock()

    def _features(self, rid: str, model: str | None) -> tuple[np.ndarray, np.ndarray, str]:
        """(proprioception, vision, model name) of a corpus recording or an upload (NotFound)."""
        if rid.startswith("upload-"):
            up = self.describe.upload(rid)
            return up.proprioception, up.vision, model or up.model
        entry = self.corpus.entry(rid)
        return entry.proprioception, entry.vision, model or self.models.served.name

    def of(self, rid: str, model: str | None = None) -> RecordingTimeline:
        """The timeline of recording `rid` (a corpus id or an upload id) as `model` says it."""
        proprioception, vision, name = self._features(rid, model)
        loaded = self.models.get(name)
        with self._lock:
            cached = self._cache.get((name, rid))
            if cached is not None and cached[0] is loaded.model:
                self._cache.move_to_end((name, rid))
                return cached[1]
        answer = self._compute(rid, loaded, proprioception, vision)
        with self._lock:
            self._cache[(name, rid)] = (loaded.model, answer)
            self._cache.move_to_end((name, rid))
            while len(self._cache) > self._cache_size:
                self._cache.popitem(last=False)
        return answer

    def of_upload(self, uid: str) -> RecordingTimeline | None:
        """An upload's timeline as the model that described it says it; None when that model has no
        Csc states to follow (the peer baseline)."""
        up = self.describe.upload(uid)
        if not hasattr(self.models.get(up.model).model, "timeline"):
            return None
        return self.of(uid, up.model)

    def _compute(
        self, rid: str, loaded: LoadedModel, proprioception: np.ndarray, vision: np.ndarray
    ) -> RecordingTimeline:
        if not hasattr(loaded.model, "timeline"):
            raise Conflict(
                f"model {loaded.name!r} ({loaded.mode}) has no Csc states to follow step by step: "
                "the timeline is a MultiMTRNN's (serve a faithful or end_to_end model)"
            )
        t0 = time.perf_counter()
        with self.models.lock:
            timeline = loaded.model.timeline(proprioception, vision, loaded.lexicon)
        model_ms = (time.perf_counter() - t0) * 1e3
        names: list[str] = []
        for k, phrases in enumerate(timeline.slots):
            name = slot_name(phrases, k)
            names.append(name if name not in names else f"slot {k + 1}")
        return RecordingTimeline(rid, loaded.name, loaded.mode, FPS, timeline, names, model_ms)
