"""What the app serves, created once in the app's lifespan and handed to the routes as a dependency.

`AppState` holds the corpus, the shipped models (one selected), caches (re-rendered camera
frames, Csc spaces per model, uploaded recordings) and, when running, the 3D viewer. Every call
into `data/` and `model/` goes through `Backend`, the one place that knows their function names.
"""

from __future__ import annotations

import hashlib
import json
import logging
import threading
import time
from collections import OrderedDict
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import cv2
import numpy as np
from fastapi import Depends, HTTPException, Request

from server.settings import Settings

if TYPE_CHECKING:
    from server.viewer import SceneViewer

logger = logging.getLogger(__name__)

SPACES = ("s", "v", "a")
VISION_FEATURE_NAMES = [f"d{k + 1}" for k in range(16)] + ["R", "G", "B", "centroid x", "centroid y"]


class Backend:
    """The real pieces of `data/` and `model/` the app calls, by the names the modules promise."""

    def __init__(self) -> None:
        from data import corpus, nao, recording
        from model import checkpoint, metrics
        from model.encoding import proprioception, utterance, vision

        self._corpus, self._nao, self._recording = corpus, nao, recording
        self._checkpoint, self._metrics = checkpoint, metrics
        self._proprioception, self._utterance, self._vision = proprioception, utterance, vision
        self.recording_error: type[Exception] = recording.RecordingError
        self.max_upload_bytes: int = int(recording.MAX_UPLOAD_BYTES)
        self.joint_names: list[str] = list(nao.JOINT_NAMES)
        self.phoneme_labels: list[str] = list(utterance.PHONEMES)
        self.forward_kinematics = nao.forward_kinematics

    # data/
    def load_corpus(self, path: Path | None) -> Any:
        return self._corpus.load_corpus(path)

    def export_recording(self, rid: str, seed: int) -> Any:
        return self._corpus.export_recording(rid, seed)

    def read_recording(self, data: bytes, filename: str) -> Any:
        return self._recording.read_recording(data, filename)

    # model/encoding
    def encode_recording(self, rec: Any) -> tuple[np.ndarray, np.ndarray]:
        prop = self._proprioception.encode_joints(rec.joints, self._nao.JOINT_LIMITS)
        vis = self._vision.encode_frames(rec.frames, workers=2)
        return prop, vis

    def encode_utterance(self, text: str) -> np.ndarray:
        return self._utterance.encode_utterance(text)

    def rays_overlay(self, frame: np.ndarray) -> np.ndarray:
        """The frame with the vision pipeline's contour, centre of mass and 16 rays drawn (Fig. 7)."""
        return self._vision.pipeline_steps(frame).rays

    # model/
    def load_model(self, directory: Path) -> tuple[Any, dict, Any]:
        """(model, meta.json, lexicon of the words it was trained on)."""
        model, meta = self._checkpoint.load(directory)
        return model, meta, self._utterance.Lexicon(meta["lexicon"])

    def describe(self, model: Any, lexicon: Any, prop: np.ndarray, vis: np.ndarray) -> Any:
        return model.describe(prop, vis, lexicon)

    def describe_batch(
        self, model: Any, lexicon: Any, props: list[np.ndarray], vis: list[np.ndarray]
    ) -> list:
        return model.describe_batch(props, vis, lexicon)

    def generate(self, model: Any, lexicon: Any, c_a: np.ndarray) -> Any:
        return model.generate_from_csc(c_a, lexicon)

    def pca(self, n_components: int) -> Any:
        return self._metrics.CscPCA(n_components)

    def measures(self, points: np.ndarray, actions: list[str]) -> dict[str, float]:
        m = self._metrics
        return {
            "d_avg": m.d_avg(points),
            "d_rel": m.d_rel(points),
            "d_inter": m.d_inter(points, actions),
            "d_intra": m.d_intra(points, actions),
        }


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
    recording: Any
    proprioception: np.ndarray
    vision: np.ndarray
    result: Result


@dataclass
class CscSpaceData:
    """The Csc patterns of every corpus recording in one space, and their PCA."""

    vectors: np.ndarray  # [N, units]
    coords: np.ndarray  # [N, 2]
    pca: Any
    explained_variance: list[float]
    explained_variance_ratio: list[float]
    measures: dict[str, float]


@dataclass
class CscCache:
    ids: list[str]
    generated: list[str]
    spaces: dict[str, CscSpaceData] = field(default_factory=dict)


@dataclass
class LoadedModel:
    name: str
    path: Path
    model: Any
    lexicon: Any
    meta: dict
    train_ids: frozenset[str]
    test_ids: frozenset[str]


def _split_ids(meta: dict, corpus_ids: list[str]) -> tuple[frozenset[str], frozenset[str]]:
    """Training and test recording ids: meta.json's ``ids`` are what the model was trained on; the
    rest of the corpus is its test set."""
    train = frozenset(meta.get("ids", []))
    return train, frozenset(rid for rid in corpus_ids if rid not in train)


class AppState:
    """The corpus, the models and the caches of one running app (no module globals)."""

    def __init__(self, settings: Settings, backend: Backend | None = None) -> None:
        self.settings = settings
        self.backend = backend or Backend()
        started = time.perf_counter()
        self.corpus = self.backend.load_corpus(settings.corpus_path)
        self.entries: dict[str, Any] = {e.id: e for e in self.corpus.entries}
        self.model_dirs = self._discover_models(settings.models_dir)
        if not self.model_dirs:
            raise FileNotFoundError(
                f"no model under {settings.models_dir} (expected <name>/model.safetensors + meta.json); "
                "train one with `make model`"
            )
        first = settings.model if settings.model in self.model_dirs else next(iter(self.model_dirs))
        self._lock = threading.RLock()  # model calls and cache updates
        self._csc_lock = threading.Lock()  # one Csc computation at a time
        self._loaded: dict[str, LoadedModel] = {}
        self._current = self._load(first)
        self._csc: dict[str, CscCache] = {}
        self._frames: OrderedDict[str, np.ndarray] = OrderedDict()
        self._uploads: OrderedDict[str, Upload] = OrderedDict()
        self._targets: dict[str, np.ndarray] = {}
        self.viewer: SceneViewer | None = None
        logger.info(
            "corpus: %d recordings; model %r; ready in %.1f s",
            len(self.entries),
            first,
            time.perf_counter() - started,
        )

    # models
    @staticmethod
    def _discover_models(root: Path) -> dict[str, Path]:
        if not root.is_dir():
            return {}
        return {p.name: p for p in sorted(root.iterdir()) if (p / "meta.json").is_file()}

    def _load(self, name: str) -> LoadedModel:
        if name not in self._loaded:
            model, meta, lexicon = self.backend.load_model(self.model_dirs[name])
            train, test = _split_ids(meta, list(self.entries))
            self._loaded[name] = LoadedModel(name, self.model_dirs[name], model, lexicon, meta, train, test)
        return self._loaded[name]

    @property
    def model(self) -> LoadedModel:
        return self._current

    def model_metas(self) -> dict[str, dict]:
        out = {}
        for name, path in self.model_dirs.items():
            if name in self._loaded:
                out[name] = self._loaded[name].meta
            else:
                out[name] = json.loads((path / "meta.json").read_text())
        return out

    def select_model(self, name: str) -> LoadedModel:
        if name not in self.model_dirs:
            raise KeyError(name)
        with self._lock:
            self._current = self._load(name)
        return self._current

    def split_of(self, rid: str) -> str:
        """'train' or 'test' for the served model, 'unknown' for ids outside the corpus."""
        m = self._current
        if rid in m.train_ids:
            return "train"
        if rid in m.test_ids:
            return "test"
        return "unknown"

    # describing
    def _describe(self, prop: np.ndarray, vis: np.ndarray, expected: str | None, timings: dict) -> Result:
        t0 = time.perf_counter()
        with self._lock:
            d = self.backend.describe(self._current.model, self._current.lexicon, prop, vis)
        timings["model_ms"] = (time.perf_counter() - t0) * 1e3
        target = self._target(expected) if expected else None
        return Result(
            text=d.text,
            words=list(d.words),
            phonemes=list(d.phonemes),
            activity=np.asarray(d.activity),
            csc={"s": np.asarray(d.csc_s), "v": np.asarray(d.csc_v), "a": np.asarray(d.csc_a)},
            expected=expected,
            target_activity=target,
            timings=timings,
        )

    def _target(self, text: str) -> np.ndarray:
        """The encoded utterance (eqs. 18-21), kept per text: the corpus has 64 of them."""
        with self._lock:
            if text not in self._targets:
                self._targets[text] = self.backend.encode_utterance(text)
            return self._targets[text]

    def describe_scene(self, rid: str) -> Result:
        entry = self.entry(rid)
        t0 = time.perf_counter()
        result = self._describe(entry.proprioception, entry.vision, entry.utterance, {})
        result.timings["total_ms"] = (time.perf_counter() - t0) * 1e3
        return result

    def describe_upload(self, data: bytes, filename: str) -> Upload:
        """Read, encode and describe an uploaded recording; raises the backend's RecordingError."""
        t0 = time.perf_counter()
        rec = self.backend.read_recording(data, filename)
        t1 = time.perf_counter()
        prop, vis = self.backend.encode_recording(rec)
        t2 = time.perf_counter()
        timings = {"read_ms": (t1 - t0) * 1e3, "encode_ms": (t2 - t1) * 1e3}
        result = self._describe(prop, vis, getattr(rec, "utterance", None) or None, timings)
        timings["total_ms"] = (time.perf_counter() - t0) * 1e3
        uid = "upload-" + hashlib.sha1(data).hexdigest()[:12]
        upload = Upload(uid, filename, self._current.name, rec, prop, vis, result)
        with self._lock:
            self._uploads[uid] = upload
            self._uploads.move_to_end(uid)
            while len(self._uploads) > self.settings.upload_cache:
                self._uploads.popitem(last=False)
        return upload

    def entry(self, rid: str) -> Any:
        try:
            return self.entries[rid]
        except KeyError:
            raise HTTPException(
                404, f"no recording {rid!r} in the corpus (ids look like 'slide-red-apple-2')"
            ) from None

    def upload(self, uid: str) -> Upload:
        try:
            return self._uploads[uid]
        except KeyError:
            raise HTTPException(404, f"no upload {uid!r} (uploads are kept while the server runs)") from None

    # camera frames
    def frames(self, rid: str) -> np.ndarray:
        """Camera frames [T, H, W, 3] of a corpus recording (re-rendered once) or of an upload."""
        if rid.startswith("upload-"):
            return self.upload(rid).recording.frames
        self.entry(rid)
        with self._lock:
            if rid in self._frames:
                self._frames.move_to_end(rid)
                return self._frames[rid]
        frames = self.backend.export_recording(rid, self.corpus.seed).frames
        with self._lock:
            self._frames[rid] = frames
            while len(self._frames) > self.settings.frame_cache:
                self._frames.popitem(last=False)
        return frames

    def frame_jpeg(self, rid: str, index: int, overlay: bool, width: int | None) -> bytes:
        frames = self.frames(rid)
        if not 0 <= index < len(frames):
            raise HTTPException(404, f"{rid} has frames 0..{len(frames) - 1}, not {index}")
        frame = np.ascontiguousarray(frames[index])
        if overlay:
            frame = self.backend.rays_overlay(frame)
        if width and width < frame.shape[1]:
            height = round(frame.shape[0] * width / frame.shape[1])
            frame = cv2.resize(frame, (width, height), interpolation=cv2.INTER_AREA)
        ok, buf = cv2.imencode(".jpg", cv2.cvtColor(frame, cv2.COLOR_RGB2BGR), [cv2.IMWRITE_JPEG_QUALITY, 88])
        if not ok:
            raise HTTPException(500, "could not encode the frame as JPEG")
        return buf.tobytes()

    # Csc spaces
    def csc_cache(self) -> CscCache:
        """Csc patterns of every corpus recording under the served model, computed once per model."""
        m = self._current
        with self._csc_lock:
            if m.name in self._csc:
                return self._csc[m.name]
            started = time.perf_counter()
            ids = list(self.entries)
            vectors: dict[str, list[np.ndarray]] = {s: [] for s in SPACES}
            generated = []
            for start in range(0, len(ids), 32):
                batch = [self.entries[rid] for rid in ids[start : start + 32]]
                with self._lock:  # one batch at a time, so that describe requests interleave
                    descriptions = self.backend.describe_batch(
                        m.model, m.lexicon, [e.proprioception for e in batch], [e.vision for e in batch]
                    )
                for d in descriptions:
                    generated.append(d.text)
                    for s, v in zip(SPACES, (d.csc_s, d.csc_v, d.csc_a), strict=True):
                        vectors[s].append(np.asarray(v, dtype=np.float64))
            actions = [self.entries[rid].scene.action for rid in ids]
            cache = CscCache(ids, generated)
            for s in SPACES:
                x = np.stack(vectors[s])
                full = self.backend.pca(min(x.shape)).fit(x)
                cache.spaces[s] = CscSpaceData(
                    vectors=x,
                    coords=full.transform(x)[:, :2],
                    pca=full,
                    explained_variance=[float(v) for v in full.explained_variance_],
                    explained_variance_ratio=[float(v) for v in full.explained_variance_ratio_],
                    measures={k: float(v) for k, v in self.backend.measures(x, actions).items()},
                )
            self._csc[m.name] = cache
            logger.info(
                "Csc spaces of %d recordings (%s) in %.1f s", len(ids), m.name, time.perf_counter() - started
            )
            return cache

    def inverse_point(self, x: float, y: float) -> np.ndarray:
        """The c_a,0 at a point of the auditory PCA plane (other components at the mean)."""
        data = self.csc_cache().spaces["a"]
        z = np.zeros((1, len(data.explained_variance)))
        z[0, :2] = (x, y)
        return data.pca.inverse_transform(z)[0]

    def project_a(self, c_a: np.ndarray) -> tuple[float, float]:
        p = self.csc_cache().spaces["a"].pca.transform(c_a[None, :])[0]
        return float(p[0]), float(p[1])

    def nearest(
        self, space: str, vector: np.ndarray, k: int, exclude: str | None = None
    ) -> list[tuple[str, float]]:
        cache = self.csc_cache()
        dist = np.linalg.norm(cache.spaces[space].vectors - vector[None, :], axis=1)
        order = [i for i in np.argsort(dist, kind="stable") if cache.ids[i] != exclude]
        return [(cache.ids[i], float(dist[i])) for i in order[:k]]

    def generate(self, c_a: np.ndarray) -> Any:
        with self._lock:
            return self.backend.generate(self._current.model, self._current.lexicon, c_a)


def get_state(request: Request) -> AppState:
    """FastAPI dependency: the AppState created in the lifespan."""
    return request.app.state.mtrnn


StateDep = Annotated[AppState, Depends(get_state)]
