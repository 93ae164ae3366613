"""The corpus the app serves: its recordings by id and their camera frames (re-rendered on demand).

`Corpus` wraps what `data.corpus.load_corpus` returns (entries with encodings, the build seed);
frames are not stored in the corpus file, so a recording's frames are rendered again from its
seed (`data.corpus.export_recording`) and the last few are kept.
"""

from __future__ import annotations

import threading
from collections import OrderedDict
from collections.abc import Callable
from typing import Any

import cv2
import numpy as np

from model.encoding.utterance import Lexicon
from model.encoding.vision import pipeline_steps
from server.services.errors import NotFound, ServiceError
from server.settings import Settings

Render = Callable[[str, int], np.ndarray]  # (recording id, corpus seed) -> frames [T, H, W, 3]


def _export_frames(rid: str, seed: int) -> np.ndarray:
    from data.corpus import export_recording

    return export_recording(rid, seed).frames


class Corpus:
    """Recordings by id (`entries`), the lookup that names a missing one, and a frame cache."""

    def __init__(self, corpus: Any, frame_cache: int = 8, render: Render = _export_frames) -> None:
        self.seed = int(corpus.seed)
        self.entries: dict[str, Any] = {e.id: e for e in corpus.entries}
        self._render, self._cache_size = render, frame_cache
        self._frames: OrderedDict[str, np.ndarray] = OrderedDict()
        self._lock = threading.Lock()
        sentences = sorted({e.utterance for e in self.entries.values()})
        self.lexicon = Lexicon.from_sentences(sentences) if sentences else None  # the corpus's words

    @classmethod
    def load(cls, settings: Settings) -> Corpus:
        """The corpus file of the settings (data.corpus's default when none is named)."""
        from data.corpus import load_corpus

        return cls(load_corpus(settings.corpus_path), settings.frame_cache)

    def entry(self, rid: str) -> Any:
        try:
            return self.entries[rid]
        except KeyError:
            raise NotFound(
                f"no recording {rid!r} in the corpus (ids look like 'slide-red-apple-2')"
            ) from None

    def frames(self, rid: str) -> np.ndarray:
        """Camera frames [T, H, W, 3] of a corpus recording, rendered once and kept a while."""
        self.entry(rid)
        with self._lock:
            if rid in self._frames:
                self._frames.move_to_end(rid)
                return self._frames[rid]
        frames = self._render(rid, self.seed)
        with self._lock:
            self._frames[rid] = frames
            while len(self._frames) > self._cache_size:
                self._frames.popitem(last=False)
        return frames


def frame_jpeg(frames: np.ndarray, name: str, index: int, overlay: bool, width: int | None) -> bytes:
    """One frame as JPEG, optionally with the vision pipeline's contour and 16 rays (Fig. 7)."""
    if not 0 <= index < len(frames):
        raise NotFound(f"{name} has frames 0..{len(frames) - 1}, not {index}")
    frame = np.ascontiguousarray(frames[index])
    if overlay:
        frame = pipeline_steps(frame).rays
    if width and width < frame.shape[1]:
        height = round(frame.shape[0] * width / frame.shape[1])
        frame = cv2.resize(frame, (width, height), interpolation=cv2.INTER_AREA)
    ok, buf = cv2.imencode(".jpg", cv2.cvtColor(frame, cv2.COLOR_RGB2BGR), [cv2.IMWRITE_JPEG_QUALITY, 88])
    if not ok:
        raise ServiceError("could not encode the frame as JPEG")
    return buf.tobytes()
