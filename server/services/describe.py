"""Describing a recording: the one path from a corpus scene or an uploaded file to an utterance.

Upload: `data.recording.read_recording` -> `data.encode.encode_recording` (paper 4.1.1) ->
`MultiMTRNN.describe` (3.4). A corpus scene skips the first two steps (its encodings are stored).
The uploads are kept a while, so that their scene view (frames, plots, 3D) can be shown.
"""

from __future__ import annotations

import hashlib
import threading
import time
from collections import OrderedDict
from dataclasses import dataclass

import numpy as np

from data.encode import encode_recording
from data.recording import Recording, read_recording
from model.encoding.utterance import encode_utterance
from model.multimtrnn import Description
from server.services.corpus import Corpus
from server.services.errors import NotFound
from server.services.models import ModelRegistry


@dataclass
class Result:
    """One description of one recording, with everything the API returns about it."""

    text: str
    words: list[str]
    phonemes: list[str]
    activity: np.ndarray  # [T_a, |B|]
    csc: dict[str, np.ndarray]  # s, v, a
    expected: str | None
    target_activity: np.ndarray | None
    timings: dict[str, float]


@dataclass
class Upload:
    """An uploaded recording, kept so that its scene view (frames, plots, 3D) can be shown."""

    id: str
    filename: str
    model: str  # the model that described it
    recording: Recording
    proprioception: np.ndarray
    vision: np.ndarray
    result: Result


class DescribeService:
    """What the served model says about corpus scenes and uploaded recordings."""

    def __init__(self, corpus: Corpus, models: ModelRegistry, upload_cache: int = 16) -> None:
        self.corpus, self.models, self._cache_size = corpus, models, upload_cache
        self._uploads: OrderedDict[str, Upload] = OrderedDict()
        self._targets: dict[str, np.ndarray] = {}
        self._lock = threading.Lock()

    def _describe(self, prop: np.ndarray, vis: np.ndarray, expected: str | None, timings: dict) -> Result:
        t0 = time.perf_counter()
        with self.models.lock:
            served = self.models.served
            d = served.model.describe(prop, vis, served.lexicon)
        timings["model_ms"] = (time.perf_counter() - t0) * 1e3
        return Result(
            text=d.text,
            words=list(d.words),
            phonemes=list(d.phonemes),
            activity=np.asarray(d.activity),
            csc={"s": np.asarray(d.csc_s), "v": np.asarray(d.csc_v), "a": np.asarray(d.csc_a)},
            expected=expected,
            target_activity=self._target(expected) if expected else None,
            timings=timings,
        )

    def _target(self, text: str) -> np.ndarray:
        """The encoded utterance (eqs. 18-21), kept per text: the corpus has 64 of them."""
        with self._lock:
            if text not in self._targets:
                self._targets[text] = encode_utterance(text)
            return self._targets[text]

    def describe_scene(self, rid: str) -> Result:
        entry = self.corpus.entry(rid)
        t0 = time.perf_counter()
        result = self._describe(entry.proprioception, entry.vision, entry.utterance, {})
        result.timings["total_ms"] = (time.perf_counter() - t0) * 1e3
        return result

    def describe_upload(self, data: bytes, filename: str) -> Upload:
        """Read, encode and describe an uploaded recording; raises data.recording.RecordingError."""
        t0 = time.perf_counter()
        rec = read_recording(data, filename)
        t1 = time.perf_counter()
        features = encode_recording(rec)
        t2 = time.perf_counter()
        timings = {"read_ms": (t1 - t0) * 1e3, "encode_ms": (t2 - t1) * 1e3}
        prop, vis = features.proprioception, features.vision
        result = self._describe(prop, vis, rec.utterance or None, timings)
        timings["total_ms"] = (time.perf_counter() - t0) * 1e3
        uid = "upload-" + hashlib.sha1(data).hexdigest()[:12]
        upload = Upload(uid, filename, self.models.served.name, rec, prop, vis, result)
        with self._lock:
            self._uploads[uid] = upload
            self._uploads.move_to_end(uid)
            while len(self._uploads) > self._cache_size:
                self._uploads.popitem(last=False)
        return upload

    def upload(self, uid: str) -> Upload:
        try:
            return self._uploads[uid]
        except KeyError:
            raise NotFound(f"no upload {uid!r} (uploads are kept while the server runs)") from None

    def frames(self, rid: str) -> np.ndarray:
        """Camera frames [T, H, W, 3] of an upload or of a corpus recording."""
        if rid.startswith("upload-"):
            return self.upload(rid).recording.frames
        return self.corpus.frames(rid)

    def generate(self, c_a: np.ndarray) -> Description:
        """What the served model says from a c_a,0 (MTRNN_a's generation alone)."""
        with self.models.lock:
            served = self.models.served
            return served.model.generate_from_csc(c_a, served.lexicon)
