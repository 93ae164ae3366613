"""Describing a recording: the one path from a corpus scene or an uploaded file to an utterance.

Upload: `data.recording.read_recording` -> `data.encode.encode_recording` (paper 4.1.1) ->
`MultiMTRNN.describe` (3.4). A corpus scene skips the first two steps (its encodings are stored).
Either way the served model's `Familiarity` (`model/familiarity.py`) says how far the encodings
the model read lie from its training recordings, per sense, and adds its warnings to the answer's.
The uploads are kept a while, so that their scene view (frames, plots, 3D) can be shown: the
newest `upload_cache` of them, at most `UPLOAD_CACHE_BYTES` together (the newest always kept). At
most `decode_slots` uploads are read and encoded at once; another waits up to `SLOT_WAIT_S`, then
gets `Busy` (503 with Retry-After).
"""

from __future__ import annotations

import contextlib
import hashlib
import threading
import time
from collections import OrderedDict
from collections.abc import Iterator
from dataclasses import dataclass, field

import anyio
import numpy as np

from data.encode import encode_recording
from data.recording import Recording, read_recording
from data.world import FPS
from model.encoding.utterance import Lexicon, encode_utterance
from model.encoding.words import words_of
from model.multimtrnn import Description
from server.services.corpus import Corpus
from server.services.errors import NotFound, Unavailable
from server.services.models import ModelRegistry
from server.settings import Settings

UPLOAD_CACHE_BYTES = 512 * 1024**2  # frames and encodings of the kept uploads
SLOT_WAIT_S = 20.0  # an upload waits this long for a decode slot (a few uploads ahead), then gets Busy
SLOT_POLL_S = 0.05
RETRY_AFTER_S = 5
TARGET_CACHE = 256  # encoded utterances kept (the corpus has 64)


class Busy(Unavailable):
    """Every decode slot is taken; try again in `retry_after` seconds."""

    retry_after = RETRY_AFTER_S


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
    warnings: list[str] = field(default_factory=list)  # e.g. words of `expected` the model cannot say
    familiarity: dict[str, float] | None = None  # per sense in [0, 1]; None: the model has no Familiarity


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

    @property
    def nbytes(self) -> int:
        arrays = (self.recording.frames, self.recording.joints, self.proprioception, self.vision)
        return sum(a.nbytes for a in arrays) + self.result.activity.nbytes


class DescribeService:
    """What the served model says about corpus scenes and uploaded recordings."""

    def __init__(
        self,
        corpus: Corpus,
        models: ModelRegistry,
        upload_cache: int = Settings.upload_cache,
        decode_slots: int = Settings.decode_slots,
        cache_bytes: int = UPLOAD_CACHE_BYTES,
    ) -> None:
        self.corpus, self.models, self._cache_size, self._cache_bytes = (
            corpus,
            models,
            upload_cache,
            cache_bytes,
        )
        self._uploads: OrderedDict[str, Upload] = OrderedDict()
        self._targets: dict[str, np.ndarray] = {}
        self._lock = threading.Lock()
        self.decode_slots = decode_slots
        self._slots = threading.BoundedSemaphore(decode_slots)

    @contextlib.contextmanager
    def decode_slot(self, wait: float = SLOT_WAIT_S) -> Iterator[None]:
        """One of the `decode_slots` (reading and encoding an upload); `Busy` after `wait` seconds."""
        if not self._slots.acquire(timeout=wait):
            raise self._busy()
        try:
            yield
        finally:
            self._slots.release()

    def _busy(self) -> Busy:
        return Busy(
            f"the server is reading {self.decode_slots} other recording(s); "
            f"send this one again in {RETRY_AFTER_S} s"
        )

    def _describe(
        self, prop: np.ndarray, vis: np.ndarray, found: float, expected: str | None, timings: dict
    ) -> Result:
        """The served model's description; `found`: the fraction of frames with the object."""
        t0 = time.perf_counter()
        with self.models.lock:
            served = self.models.served
            d = served.model.describe(prop, vis, served.lexicon)
        timings["model_ms"] = (time.perf_counter() - t0) * 1e3
        target, warnings = self._expected(expected, served.lexicon)
        assessed = None if served.familiarity is None else served.familiarity.assess(prop, vis, found, FPS)
        warnings += [] if assessed is None else assessed.warnings
        return Result(
            text=d.text,
            words=list(d.words),
            phonemes=list(d.phonemes),
            activity=np.asarray(d.activity),
            csc={"s": np.asarray(d.csc_s), "v": np.asarray(d.csc_v), "a": np.asarray(d.csc_a)},
            expected=expected,
            target_activity=target,
            timings=timings,
            warnings=warnings,
            familiarity=None if assessed is None else assessed.familiarity,
        )

    def _target(self, text: str) -> np.ndarray:
        """The encoded utterance (eqs. 18-21), kept per text (the corpus has 64 of them); raises
        ValueError for a word outside CMUdict or a character that is not a letter or .!?'."""
        with self._lock:
            target = self._targets.get(text)
        if target is None:
            target = encode_utterance(text)
            with self._lock:
                if len(self._targets) < TARGET_CACHE:
                    self._targets[text] = target
        return target

    def _expected(self, expected: str | None, lexicon: Lexicon) -> tuple[np.ndarray | None, list[str]]:
        """The target activity of what the teacher said, and warnings about what cannot be compared."""
        if not expected:
            return None, []
        warnings = []
        unknown = [w for w in dict.fromkeys(words_of(expected)) if w not in lexicon.words]
        if unknown:
            listed = ", ".join(repr(w) for w in unknown)
            warnings.append(
                f"the model's lexicon has no word {listed}: it can never say the expected utterance"
            )
        try:
            return self._target(expected), warnings
        except ValueError as exc:
            return None, [*warnings, f"the expected utterance has no target activity: {exc}"]

    def describe_scene(self, rid: str) -> Result:
        entry = self.corpus.entry(rid)
        t0 = time.perf_counter()
        result = self._describe(entry.proprioception, entry.vision, entry.object_found, entry.utterance, {})
        result.timings["total_ms"] = (time.perf_counter() - t0) * 1e3
        return result

    def describe_upload(self, data: bytes, filename: str) -> Upload:
        """Read, encode and describe an uploaded recording; raises data.recording.RecordingError,
        or `Busy` when no decode slot frees within SLOT_WAIT_S."""
        t0 = time.perf_counter()
        with self.decode_slot():
            return self._describe_upload(data, filename, t0)

    async def describe_upload_async(self, data: bytes, filename: str) -> Upload:
        """`describe_upload` for the event loop: waiting for a slot holds no worker thread."""
        t0 = time.perf_counter()
        while not self._slots.acquire(blocking=False):
            if time.perf_counter() - t0 > SLOT_WAIT_S:
                raise self._busy()
            await anyio.sleep(SLOT_POLL_S)
        try:
            return await anyio.to_thread.run_sync(self._describe_upload, data, filename, t0)
        finally:
            self._slots.release()

    def _describe_upload(self, data: bytes, filename: str, t0: float) -> Upload:
        """The work of one upload, in a decode slot; `t0` is when it arrived."""
        t_slot = time.perf_counter()
        rec = read_recording(data, filename)
        t1 = time.perf_counter()
        features = encode_recording(rec)
        t2 = time.perf_counter()
        timings = {"read_ms": (t1 - t_slot) * 1e3, "encode_ms": (t2 - t1) * 1e3}
        prop, vis = features.proprioception, features.vision
        found = float(np.mean(features.object_found))
        result = self._describe(prop, vis, found, rec.utterance or None, timings)
        timings["total_ms"] = (time.perf_counter() - t0) * 1e3
        uid = "upload-" + hashlib.sha1(data).hexdigest()[:12]
        upload = Upload(uid, filename, self.models.served.name, rec, prop, vis, result)
        self._keep(upload)
        return upload

    def _keep(self, upload: Upload) -> None:
        """Cache `upload`; drop the oldest beyond `upload_cache` uploads or `cache_bytes` (the
        newest is always kept)."""
        with self._lock:
            self._uploads[upload.id] = upload
            self._uploads.move_to_end(upload.id)
            total = sum(u.nbytes for u in self._uploads.values())
            while len(self._uploads) > 1 and (
                len(self._uploads) > self._cache_size or total > self._cache_bytes
            ):
                total -= self._uploads.popitem(last=False)[1].nbytes

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
