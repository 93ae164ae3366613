"""The live computations behind the seven lessons (web/lessons/), as plain functions.

Every number a lesson shows is computed here from the served models and the corpus, on request:

1. timescales    `leaky_pulse` (eq. 3 on one unit) and `timescale_activity` (MTRNN_a's IO, Cf, Cs)
2. speaking      `speak`: text -> ARPAbet -> Gaussian spikes -> softmax (eqs. 18-21) -> decoder
3. seeing        `seeing`: the vision pipeline's stages on one frame (Fig. 7)
4. feeling       `feeling`: one action on four objects, and why touch alone is ambiguous
5. abstracting   `CosineJobs` (the experiment of 3.2.2 run live) and `stored_sweeps`
6. associating   `associating`: the three Csc spaces (Fig. 10) and muting one modality
7. generalising  `generalising`: training vs novel scenes for one model

The models are loaded from the app's model folders (`AppState.model_dirs`) by `LessonStore`, which
the router keeps per app (`app.state.lessons`); nothing here is a module global.
"""

from __future__ import annotations

import base64
import importlib
import json
import logging
import math
import threading
import time
import uuid
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import torch

from data.nao import JOINT_NAMES
from data.scenario import ACTIONS, COLOURS, SHAPES
from model import checkpoint
from model.encoding.utterance import (
    PHONEMES,
    Lexicon,
    UtteranceParams,
    decode_activity,
    encode_utterance,
    spike_scale,
    text_to_phonemes,
)
from model.encoding.vision import SECTORS, VISUAL_FEATURES, VisionParams, pipeline_steps
from model.metrics import CscPCA, d_avg, d_rel, parse_slots, sentence_exact, words_of
from model.multimtrnn import MultiMTRNN

logger = logging.getLogger(__name__)

LESSONS: tuple[tuple[str, str], ...] = (
    ("timescales", "1. Timescales"),
    ("speaking", "2. Speaking in phonemes"),
    ("seeing", "3. Seeing"),
    ("feeling", "4. Feeling"),
    ("abstracting", "5. Abstracting"),
    ("associating", "6. Associating"),
    ("generalising", "7. Generalising"),
)
FEATURE_NAMES = [f"d{k + 1}" for k in range(SECTORS)] + ["R", "G", "B", "centroid x", "centroid y"]
DECODE_THRESHOLD = 0.3  # the decoder's default (model.encoding.utterance)
MAX_IMAGE_WIDTH = 640  # uploads are scaled down to this width before the pipeline


class LessonError(ValueError):
    """A request a lesson cannot answer, with a message for the learner (the API turns it into 4xx)."""

    def __init__(self, message: str, status: int = 422) -> None:
        super().__init__(message)
        self.status = status


def _r(values: Any, digits: int = 4) -> Any:
    """A numpy array (or scalar) as nested lists of rounded floats, for JSON."""
    return np.round(np.asarray(values, dtype=np.float64), digits).tolist()


# ------------------------------------------------------------------------------------ the models


@dataclass
class LessonModel:
    """One served model as the lessons need it."""

    name: str
    mode: str
    model: MultiMTRNN
    lexicon: Lexicon
    train_ids: frozenset[str]  # recording ids or scene ids the model was trained on
    test_ids: frozenset[str]

    def split_of(self, rid: str, scene_id: str) -> str:
        if rid in self.train_ids or scene_id in self.train_ids:
            return "train"
        if rid in self.test_ids or scene_id in self.test_ids:
            return "test"
        return "unknown"


@dataclass
class Survey:
    """Every corpus recording described once by one model: texts and the three Csc vectors."""

    ids: list[str]
    texts: list[str]
    c_s: np.ndarray  # [N, |Csc_s|] c_s,T
    c_v: np.ndarray  # [N, |Csc_v|] c_v,T
    c_a: np.ndarray  # [N, |Csc_a|] c_a,0


def _splits(meta: dict, all_ids: list[str]) -> tuple[frozenset[str], frozenset[str]]:
    """Training and test ids from meta.json: ``split: {train, test}``, or the training ``ids``."""
    split = meta.get("split") or {}
    if split.get("train") or split.get("test"):
        return frozenset(split.get("train", [])), frozenset(split.get("test", []))
    train = frozenset(meta.get("ids") or [])
    return (train, frozenset(i for i in all_ids if i not in train)) if train else (frozenset(), frozenset())


class LessonStore:
    """Per-app state of the lessons: loaded models, their surveys of the corpus, cosine jobs.

    `state` is the app's `AppState` (it provides `entries`, `model_dirs`, `model.name`, `frames`).
    """

    def __init__(self, state: Any) -> None:
        self.state = state
        self._lock = threading.RLock()
        self._models: dict[str, LessonModel] = {}
        self._surveys: dict[str, Survey] = {}
        self._pcas: dict[tuple[str, str], tuple[CscPCA, np.ndarray]] = {}
        self._modes: dict[str, str] = {}
        sentences = sorted({e.utterance for e in state.entries.values()})
        self.corpus_lexicon = Lexicon.from_sentences(sentences) if sentences else None
        self.cosine = CosineJobs()
        self.cosine.warm_up()
        threading.Thread(target=self._warm_survey, name="lessons-survey", daemon=True).start()

    def _warm_survey(self) -> None:
        """Describe the corpus with the served model before a lesson needs it (lessons 4, 6, 7)."""
        try:
            self.survey()
        except Exception:  # a lesson asking later gets the error with its message
            logger.exception("lessons: could not survey the corpus with the served model")

    # models
    def model_names(self) -> list[str]:
        return list(self.state.model_dirs)

    def model_modes(self) -> dict[str, str]:
        """Training mode of every model (from its meta.json, without loading the weights)."""
        with self._lock:
            for name, directory in self.state.model_dirs.items():
                if name not in self._modes:
                    meta = json.loads((Path(directory) / checkpoint.META).read_text())
                    self._modes[name] = str(meta.get("mode", "unknown"))
            return {name: self._modes[name] for name in self.state.model_dirs}

    @property
    def served(self) -> str:
        return str(self.state.model.name)

    def model(self, name: str | None = None) -> LessonModel:
        """The named model (default: the one the app serves), loaded once from its checkpoint."""
        name = name or self.served
        if name not in self.state.model_dirs:
            raise LessonError(f"no model {name!r}; available: {', '.join(self.model_names())}", 404)
        with self._lock:
            if name not in self._models:
                self._models[name] = self._load(name, Path(self.state.model_dirs[name]))
            return self._models[name]

    def _load(self, name: str, directory: Path) -> LessonModel:
        model, meta = checkpoint.load(directory)
        model.eval()
        words = meta.get("lexicon")
        lexicon = Lexicon(words) if words else self.corpus_lexicon
        if lexicon is None:
            raise LessonError(f"model {name!r} has no lexicon and the corpus is empty", 503)
        train, test = _splits(meta, list(self.state.entries))
        return LessonModel(name, str(meta.get("mode", "unknown")), model, lexicon, train, test)

    def entry(self, rid: str) -> Any:
        entry = self.state.entries.get(rid)
        if entry is None:
            raise LessonError(f"no recording {rid!r} in the corpus (ids look like 'slide-red-apple-2')", 404)
        return entry

    # surveys
    def survey(self, name: str | None = None) -> Survey:
        """Describe every corpus recording with the model (one batch, cached per model)."""
        lm = self.model(name)
        with self._lock:
            if lm.name in self._surveys:
                return self._surveys[lm.name]
        entries = list(self.state.entries.values())
        if len(entries) < 2:
            raise LessonError("the corpus needs at least two recordings", 503)
        started = time.perf_counter()
        with torch.no_grad():
            described = lm.model.describe_batch(
                [e.proprioception for e in entries], [e.vision for e in entries], lm.lexicon
            )
        survey = Survey(
            ids=[e.id for e in entries],
            texts=[d.text for d in described],
            c_s=np.stack([np.asarray(d.csc_s, dtype=np.float64) for d in described]),
            c_v=np.stack([np.asarray(d.csc_v, dtype=np.float64) for d in described]),
            c_a=np.stack([np.asarray(d.csc_a, dtype=np.float64) for d in described]),
        )
        logger.info(
            "lessons: %s described %d recordings in %.2f s",
            lm.name,
            len(entries),
            time.perf_counter() - started,
        )
        with self._lock:
            self._surveys[lm.name] = survey
        return survey

    def pca(self, name: str, space: str) -> tuple[CscPCA, np.ndarray]:
        """PCA (2 components) of one Csc space of a model's survey, and the projected points."""
        key = (self.model(name).name, space)
        with self._lock:
            if key not in self._pcas:
                x = getattr(self.survey(name), f"c_{space}")
                pca = CscPCA(2).fit(x)
                self._pcas[key] = (pca, pca.transform(x))
            return self._pcas[key]


# ------------------------------------------------------------------------- 1. timescales (eq. 3)

TABLE1_TAUS = {"IO": 2.0, "Cf": 5.0, "Cs": 70.0}  # MTRNN_a, Table 1


def leaky_pulse(tau: float, steps: int = 120, onset: int = 10, width: int = 10) -> dict:
    """One leaky-integrator unit (eq. 3 with one input) answering a pulse of `width` steps.

    z_t = (1 - 1/tau) z_{t-1} + (1/tau) x_t, x = 1 during the pulse and 0 otherwise. Returned for
    `tau` and for the three timescales of MTRNN_a (Table 1), with the half-life of the decay.
    """
    if not (math.isfinite(tau) and 1.0 <= tau <= 200.0):
        raise LessonError(f"tau must be between 1 and 200 (1 = no memory), got {tau}")
    x = np.zeros(steps)
    x[onset : onset + width] = 1.0

    def integrate(t: float) -> np.ndarray:
        z = np.zeros(steps)
        for k in range(1, steps):
            z[k] = (1.0 - 1.0 / t) * z[k - 1] + x[k] / t  # eq. (3)
        return z

    z = integrate(tau)
    half_life = math.inf if tau == 1.0 else math.log(0.5) / math.log(1.0 - 1.0 / tau)
    end = onset + width - 1
    return {
        "tau": tau,
        "input": _r(x, 3),
        "z": _r(z),
        "peak": round(float(z.max()), 4),
        "half_life_steps": None if tau == 1.0 else round(half_life, 2),
        "left_after_20_steps": round(float(z[min(end + 20, steps - 1)] / max(z[end], 1e-12)), 4),
        "references": {name: _r(integrate(t)) for name, t in TABLE1_TAUS.items()},
    }


def _layer_speed(y: np.ndarray) -> float:
    """Mean |y_t - y_{t-1}| over units and steps: how fast a layer's activity changes."""
    return float(np.abs(np.diff(y, axis=0)).mean()) if len(y) > 1 else 0.0


def timescale_activity(store: LessonStore, rid: str) -> dict:
    """MTRNN_a's IO, Cf and Cs activity while it speaks about one corpus recording."""
    entry = store.entry(rid)
    lm = store.model()
    trace = lm.model.activity_trace(entry.proprioception, entry.vision, lm.lexicon)
    a = trace.auditory
    winners = a.io.argmax(axis=1)
    strong = a.io[np.arange(len(a.io)), winners] >= DECODE_THRESHOLD
    cfg = lm.model.config.auditory
    return {
        "id": rid,
        "model": lm.name,
        "expected": entry.utterance,
        "said": trace.description.text,
        "phonemes": trace.description.phonemes,
        "steps": len(a.io),
        "phoneme_labels": list(PHONEMES),
        "phoneme_at": [PHONEMES[w] if s else "" for w, s in zip(winners, strong, strict=True)],
        "layers": {
            "IO": {"tau": cfg.tau_io, "y": _r(a.io.T, 3), "speed": round(_layer_speed(a.io), 5)},
            "Cf": {"tau": cfg.tau_cf, "y": _r(a.cf.T, 3), "speed": round(_layer_speed(a.cf), 5)},
            "Cs": {"tau": cfg.tau_cs, "y": _r(a.cs.T, 3), "speed": round(_layer_speed(a.cs), 5)},
        },
    }


# ----------------------------------------------------------------- 2. speaking (eqs. 18-21)


def speak(text: str, gamma: int, omega: int, sigma2: float, nu: int, grammar: Lexicon | None) -> dict:
    """Encode a sentence as the auditory IO activity and read it back with the decoder."""
    text = text.strip()
    if not text:
        raise LessonError("type a sentence, e.g. 'slide the red apple.'")
    if len(text) > 160:
        raise LessonError(f"keep the sentence under 160 characters (got {len(text)})")
    if not (0 <= gamma <= 12 and 0 <= omega <= 12 and 1 <= nu <= 8):
        raise LessonError("gamma must be in 0..12, omega in 0..12 and nu in 1..8")
    if omega % 2:
        raise LessonError(f"omega must be even (spikes span -omega/2..omega/2), got {omega}")
    if not (math.isfinite(sigma2) and 0.05 <= sigma2 <= 4.0):
        raise LessonError(f"sigma^2 must be between 0.05 and 4, got {sigma2}")
    if gamma + nu < omega // 2:
        raise LessonError(
            "the first spike would start before t = 0: "
            f"need gamma + nu >= omega/2 ({gamma} + {nu} < {omega // 2})"
        )
    try:
        phonemes = text_to_phonemes(text)
    except ValueError as err:
        raise LessonError(str(err)) from None
    params = UtteranceParams(gamma=gamma, omega=omega, sigma2=sigma2, nu=nu)
    y = encode_utterance(phonemes, params).astype(np.float64)  # eqs. (18)-(21)
    # The softmax input z of eq. (19) is 0 for every neuron without a spike, so z = ln y - min ln y.
    lam = spike_scale(len(PHONEMES))  # eq. (20)
    logs = np.log(y)
    spikes = (logs - logs.min(axis=1, keepdims=True)) / lam  # g of eq. (18), max over overlaps
    decoded = decode_activity(y, DECODE_THRESHOLD)
    words = words_of(text)
    lexicon = Lexicon([*words, *(grammar.words if grammar else ())])
    read_back = lexicon.words_to_text(lexicon.phonemes_to_words(decoded))
    used = list(dict.fromkeys(PHONEMES.index(p) for p in phonemes))  # in order of first use (Fig. 8a)
    return {
        "text": text,
        "phonemes": phonemes,
        "params": {"gamma": gamma, "omega": omega, "sigma2": sigma2, "nu": nu},
        "lambda": round(lam, 4),
        "steps": len(y),
        "labels": [PHONEMES[i] for i in used],
        "spikes": _r(spikes[:, used].T, 3),
        "activity": _r(y[:, used].T, 3),
        "peak": round(float(y.max()), 4),
        "decoded": decoded,
        "read_back": read_back,
        "exact": decoded == phonemes,
    }


# ---------------------------------------------------------------------------- 3. seeing (Fig. 7)


def _data_url(image: np.ndarray) -> str:
    """A stage image as a data URL: masks and edges (grey) as PNG, colour pictures as JPEG."""
    if image.ndim == 2:
        ok, buf = cv2.imencode(".png", image, [cv2.IMWRITE_PNG_COMPRESSION, 3])
        kind = "png"
    else:
        ok, buf = cv2.imencode(".jpg", cv2.cvtColor(image, cv2.COLOR_RGB2BGR), [cv2.IMWRITE_JPEG_QUALITY, 88])
        kind = "jpeg"
    if not ok:
        raise LessonError("could not encode an image", 500)
    return f"data:image/{kind};base64," + base64.b64encode(buf.tobytes()).decode("ascii")


def decode_image(data: bytes) -> np.ndarray:
    """Uploaded bytes (PNG, JPEG, ...) -> RGB uint8, scaled down to at most MAX_IMAGE_WIDTH wide."""
    if not data:
        raise LessonError("the uploaded file is empty")
    image = cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_COLOR)
    if image is None:
        raise LessonError("the upload is not an image OpenCV can read (PNG, JPEG, BMP, ...)")
    if image.shape[1] > MAX_IMAGE_WIDTH:
        h = round(image.shape[0] * MAX_IMAGE_WIDTH / image.shape[1])
        image = cv2.resize(image, (MAX_IMAGE_WIDTH, h), interpolation=cv2.INTER_AREA)
    return cv2.cvtColor(image, cv2.COLOR_BGR2RGB)


def seeing(frame: np.ndarray, colour_radius: int) -> dict:
    """Every stage of the vision pipeline on one RGB frame, and the 19 (+2) features."""
    if not 4 <= colour_radius <= 64:
        raise LessonError(f"colour_radius must be in 4..64, got {colour_radius}")
    started = time.perf_counter()
    try:
        steps = pipeline_steps(frame, VisionParams(colour_radius=colour_radius))
    except ValueError as err:
        raise LessonError(str(err)) from None
    ms = (time.perf_counter() - started) * 1e3
    stages = [
        ("original", "the camera frame", steps.original),
        ("mean_shift", "mean-shift segmentation", steps.mean_shift),
        ("saturation", "colour saturation (object candidates)", steps.saturation),
        ("edges", "Canny edges", steps.edges),
        ("object_mask", "the chosen object", steps.object_mask),
        ("contour", "its contour", steps.contour),
        ("rays", "centre of mass and 16 salient distances", steps.rays),
    ]
    return {
        "width": int(frame.shape[1]),
        "height": int(frame.shape[0]),
        "found": bool(steps.found),
        "pipeline_ms": round(ms, 1),
        "stages": [{"key": k, "title": t, "image": _data_url(img)} for k, t, img in stages],
        "features": _r(steps.features, 4),
        "feature_names": FEATURE_NAMES[: len(steps.features)],
        "paper_features": VISUAL_FEATURES,
    }


# ----------------------------------------------------------------------------------- 4. feeling


def _resample(x: np.ndarray, steps: int = 50) -> np.ndarray:
    """A [T, F] sequence linearly resampled to `steps` steps (compares sequences of any length)."""
    t = np.linspace(0.0, 1.0, len(x))
    grid = np.linspace(0.0, 1.0, steps)
    return np.stack([np.interp(grid, t, x[:, j]) for j in range(x.shape[1])], axis=1)


def _rms(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.sqrt(((_resample(a) - _resample(b)) ** 2).mean()))


def _find(store: LessonStore, action: str, colour: str, shape: str, variant: int | None = None) -> Any | None:
    """The corpus entry of a scene (the given variant, else the lowest one present)."""
    matches = [
        e
        for e in store.state.entries.values()
        if (e.scene.action, e.scene.colour, e.scene.shape) == (action, colour, shape)
        and (variant is None or e.variant == variant)
    ]
    return min(matches, key=lambda e: e.variant) if matches else None


def feeling(store: LessonStore, action: str, colour: str) -> dict:
    """Proprioception of one action on the four shapes of one colour, and the ambiguity of touch."""
    if action not in ACTIONS:
        raise LessonError(f"action must be one of {', '.join(ACTIONS)}")
    if colour not in COLOURS:
        raise LessonError(f"colour must be one of {', '.join(COLOURS)}")
    series = []
    for shape in SHAPES:
        e = _find(store, action, colour, shape)
        if e is not None:
            series.append(
                {
                    "id": e.id,
                    "shape": shape,
                    "fps": 20.0,
                    "proprioception": _r(np.asarray(e.proprioception).T, 4),
                }
            )
    if not series:
        raise LessonError(f"the corpus has no '{action}' on a {colour} object", 404)

    # Why touch alone cannot tell a red apple from a blue phone: compare distances.
    a = _find(store, action, "red", "apple")
    b = _find(store, action, "blue", "phone")
    other_action = next(x for x in ACTIONS if x != action)
    c = _find(store, other_action, "red", "apple")
    a2 = next(
        (
            e
            for e in store.state.entries.values()
            if a is not None and e.scene == a.scene and e.variant != a.variant
        ),
        None,
    )
    comparison = None
    if a is not None and b is not None and c is not None:
        survey = store.survey()
        index = {rid: i for i, rid in enumerate(survey.ids)}

        def csc(space: str, e: Any) -> np.ndarray:
            return getattr(survey, f"c_{space}")[index[e.id]]

        def dist(space: str, x: Any, y: Any) -> float:
            return round(float(np.linalg.norm(csc(space, x) - csc(space, y))), 4)

        rows = [
            {
                "pair": f"{action} red apple vs {action} blue phone",
                "what": "same action, different object",
                "joints_rms": round(_rms(a.proprioception, b.proprioception), 4),
                "c_s": dist("s", a, b),
                "c_v": dist("v", a, b),
            },
            {
                "pair": f"{action} red apple vs {other_action} red apple",
                "what": "different action, same object",
                "joints_rms": round(_rms(a.proprioception, c.proprioception), 4),
                "c_s": dist("s", a, c),
                "c_v": dist("v", a, c),
            },
        ]
        if a2 is not None:
            rows.append(
                {
                    "pair": f"{action} red apple, teacher {a.variant} vs teacher {a2.variant}",
                    "what": "same scene, another teacher",
                    "joints_rms": round(_rms(a.proprioception, a2.proprioception), 4),
                    "c_s": dist("s", a, a2),
                    "c_v": dist("v", a, a2),
                }
            )
        comparison = {"ids": [a.id, b.id, c.id], "rows": rows, "model": store.served}
    return {
        "action": action,
        "colour": colour,
        "joint_names": list(JOINT_NAMES),
        "series": series,
        "comparison": comparison,
    }


# ------------------------------------------------------------------ 5. abstracting (3.2.2, Fig. 3)

LIVE_COSINE_EPOCHS = 1000  # the live run stops here if the error has not fallen below threshold
LIVE_SNAPSHOT_EVERY = 10  # epochs between two Csc snapshots streamed to the page
KEPT_COSINE_RUNS = 64  # finished runs kept for replay


@dataclass
class CosineJob:
    id: str
    psi: float
    seed: int
    epochs: int  # upper bound of the run (it stops earlier once the error is below threshold)
    status: str = "queued"  # queued, running, done, failed
    epoch: int = 0
    loss: float | None = None
    frames: list[dict] = field(default_factory=list)  # Csc snapshots: points, targets, d_avg, d_rel
    result: dict | None = None
    error: str | None = None
    seconds: float = 0.0

    def public(self, since: int = 0) -> dict:
        return {
            "id": self.id,
            "psi": self.psi,
            "seed": self.seed,
            "status": self.status,
            "epoch": self.epoch,
            "epochs": self.epochs,
            "progress": 1.0 if self.status == "done" else round(self.epoch / self.epochs, 4),
            "loss": self.loss,
            "frames": self.frames[since:],
            "frame_count": len(self.frames),
            "result": self.result,
            "error": self.error,
            "seconds": round(self.seconds, 2),
        }


def _snapshot(info: dict) -> dict:
    """One Csc snapshot of the cosine run: the network's abstracted c_T of the four sequences
    (eq. 3 at t = T) and the self-organising targets (eq. 12), with d_avg and d_rel (eqs. 14-15)."""
    points = np.asarray(info["csc"], dtype=np.float64)
    targets = np.asarray(info["targets"], dtype=np.float64)
    return {
        "epoch": int(info["epoch"]),
        "error": round(float(info.get("error", info.get("loss", 0.0))), 7),
        "points": _r(points, 4),
        "targets": _r(targets, 4),
        "d_avg": round(d_avg(points), 5),
        "d_rel": round(d_rel(points), 5),
        "target_d_avg": round(d_avg(targets), 5),
        "target_d_rel": round(d_rel(targets), 5),
    }


class CosineJobs:
    """Live runs of the cosine experiment (`model.experiments.cosine`), one at a time (the machine is small).
    A run is deterministic in (psi, seed), so asking for it again returns the kept run."""

    def __init__(
        self, max_epochs: int = LIVE_COSINE_EPOCHS, snapshot_every: int = LIVE_SNAPSHOT_EVERY
    ) -> None:
        self.max_epochs = max_epochs
        self.snapshot_every = snapshot_every
        self._lock = threading.Lock()
        self._jobs: dict[str, CosineJob] = {}
        self._by_key: dict[tuple[float, int], str] = {}
        self._warm = False

    def warm_up(self) -> None:
        """Import in the background what a run's first optimiser step imports (torch._dynamo,
        seconds on a busy machine), so that the learner's first run starts at once."""
        with self._lock:
            if self._warm:
                return
            self._warm = True
        threading.Thread(target=importlib.import_module, args=("torch._dynamo",), daemon=True).start()

    def start(self, psi: float, seed: int) -> CosineJob:
        if not (math.isfinite(psi) and 0.0 <= psi <= 0.01):
            raise LessonError(f"psi must be between 0 and 0.01 (the paper tries 0 .. 2e-4), got {psi}")
        if not 0 <= seed <= 10_000:
            raise LessonError(f"seed must be in 0..10000, got {seed}")
        key = (float(psi), int(seed))
        with self._lock:
            if key in self._by_key and self._jobs[self._by_key[key]].status != "failed":
                return self._jobs[self._by_key[key]]
            busy = [j for j in self._jobs.values() if j.status in ("queued", "running")]
            if busy:
                raise LessonError(
                    f"a cosine run (psi = {busy[0].psi:g}) is still in progress; try again when it ends", 409
                )
            job = CosineJob(uuid.uuid4().hex[:12], float(psi), int(seed), self.max_epochs)
            self._jobs[job.id] = job
            self._by_key[key] = job.id
            while len(self._jobs) > KEPT_COSINE_RUNS:  # forget the oldest finished runs
                oldest = next(iter(self._jobs.values()))
                del self._jobs[oldest.id]
                self._by_key.pop((oldest.psi, oldest.seed), None)
        threading.Thread(target=self._run, args=(job,), name=f"cosine-{job.id}", daemon=True).start()
        return job

    def get(self, job_id: str) -> CosineJob:
        job = self._jobs.get(job_id)
        if job is None:
            raise LessonError(f"no cosine run {job_id!r} (runs are kept while the server runs)", 404)
        return job

    def _run(self, job: CosineJob) -> None:
        from model.experiments.cosine import CosineSetup, run_cosine

        job.status = "running"
        started = time.perf_counter()

        def progress(info: dict) -> None:
            job.epoch = int(info["epoch"])
            job.loss = round(float(info.get("error", info.get("loss", 0.0))), 7)
            job.frames.append(_snapshot(info))
            job.seconds = time.perf_counter() - started

        threads = torch.get_num_threads()
        try:
            torch.set_num_threads(1)
            setup = CosineSetup(max_epochs=self.max_epochs, snapshot_every=self.snapshot_every)
            summary = run_cosine(job.psi, runs=1, seed=job.seed, progress=progress, setup=setup)
            run = summary["per_run"][0]
            job.result = {
                k: run[k] for k in ("epochs", "converged", "d_avg", "d_rel", "target_d_avg", "target_d_rel")
            }
            job.epoch = int(run["epochs"])
            job.status = "done"
        except Exception as err:  # the learner sees the message; the log keeps the traceback
            logger.exception("cosine run %s failed", job.id)
            job.error = f"{type(err).__name__}: {err}"
            job.status = "failed"
        finally:
            torch.set_num_threads(threads)
            job.seconds = time.perf_counter() - started


def _clean(rows: list[dict]) -> list[dict]:
    """Sweep table rows with NaN (no value) as None, so they are valid JSON."""
    return [
        {k: (None if isinstance(v, float) and not math.isfinite(v) else v) for k, v in row.items()}
        for row in rows
    ]


def stored_sweeps(run_dir: Path) -> dict:
    """The psi_s sweep (Fig. 9) and the cosine sweep (Fig. 3 a-b) from the protocol's run store,
    as `model.experiments.sweeps` tabulates them, if they have been run. Never creates a store."""
    from model.experiments.runstore import DB_NAME, RunStore
    from model.experiments.sweeps import cosine_table, psi_s_table

    if not (run_dir / DB_NAME).is_file():
        return {"available": False, "reason": f"no run store at {run_dir} yet", "psi_s": [], "cosine": []}
    store = RunStore(run_dir)
    psi_s = _clean(psi_s_table(store.runs(experiment="psi_s")))
    cosine = _clean(cosine_table(store.runs(experiment="cosine")))
    reason = "" if psi_s else f"the run store at {run_dir} holds no psi_s sweep yet"
    return {"available": bool(psi_s), "reason": reason, "psi_s": psi_s, "cosine": cosine}


# ------------------------------------------------------------------------- 6. associating (Fig. 10)

MUTES = ("none", "vision", "proprioception")


def _labels(store: LessonStore, ids: list[str], lm: LessonModel) -> list[dict]:
    out = []
    for rid in ids:
        e = store.state.entries[rid]
        out.append(
            {
                "id": rid,
                "action": e.scene.action,
                "colour": e.scene.colour,
                "shape": e.scene.shape,
                "split": lm.split_of(rid, e.scene.id),
            }
        )
    return out


def associating(store: LessonStore, rid: str, mute: str) -> dict:
    """The three Csc spaces of the served model side by side, one recording highlighted, and what
    the model says when one modality is muted.

    Muting replaces that modality's abstracted context (c_s,T or c_v,T) by its mean over the corpus:
    the cell assemblies (eq. 17) then receive no information from it about this scene.
    """
    if mute not in MUTES:
        raise LessonError(f"mute must be one of {', '.join(MUTES)}")
    entry = store.entry(rid)
    lm = store.model()
    survey = store.survey()
    i = survey.ids.index(rid)
    c_s, c_v = survey.c_s[i].copy(), survey.c_v[i].copy()
    if mute == "vision":
        c_v = survey.c_v.mean(axis=0)
    elif mute == "proprioception":
        c_s = survey.c_s.mean(axis=0)
    with torch.no_grad():
        c_a = lm.model.assemblies(
            torch.as_tensor(c_s, dtype=torch.float32)[None], torch.as_tensor(c_v, dtype=torch.float32)[None]
        )[0].numpy()  # eq. (17)
    said = lm.model.generate_from_csc(c_a, lm.lexicon)
    spaces = {}
    for space in ("s", "v", "a"):
        pca, coords = store.pca(lm.name, space)
        spaces[space] = {
            "x": _r(coords[:, 0], 6),
            "y": _r(coords[:, 1], 6),
            "explained": _r(pca.explained_variance_ratio_, 4),
        }
    pca_a, _ = store.pca(lm.name, "a")
    point = pca_a.transform(c_a[None].astype(np.float64))[0]
    near = int(np.argmin(np.linalg.norm(survey.c_a - c_a[None], axis=1)))
    expected = parse_slots(entry.utterance, ACTIONS, COLOURS, SHAPES)
    got = parse_slots(said.text, ACTIONS, COLOURS, SHAPES)
    return {
        "id": rid,
        "model": lm.name,
        "mute": mute,
        "expected": entry.utterance,
        "said": said.text,
        "unmuted": survey.texts[i],
        "slots": {k: {"expected": expected[k], "said": got[k]} for k in expected},
        "index": i,
        "point_a": _r(point[:2], 6),
        "moved": round(float(np.linalg.norm(c_a - survey.c_a[i])), 6),
        "nearest": {"id": survey.ids[near], "said": survey.texts[near]},
        "labels": _labels(store, survey.ids, lm),
        "spaces": spaces,
    }


# -------------------------------------------------------------------------------- 7. generalising


def generalising(store: LessonStore, name: str | None) -> dict:
    """How one model describes every scene: exact sentences and slots, training vs novel scenes,
    and for novel scenes whether their object and action pairings were ever seen in training."""
    lm = store.model(name)
    survey = store.survey(lm.name)
    scenes: dict[str, dict] = {}
    for rid, text in zip(survey.ids, survey.texts, strict=True):
        e = store.state.entries[rid]
        s = scenes.setdefault(
            e.scene.id,
            {
                "scene": e.scene.id,
                "action": e.scene.action,
                "colour": e.scene.colour,
                "shape": e.scene.shape,
                "expected": e.utterance,
                "split": lm.split_of(rid, e.scene.id),
                "recordings": [],
            },
        )
        got = parse_slots(text, ACTIONS, COLOURS, SHAPES)
        target = {"action": e.scene.action, "colour": e.scene.colour, "object": e.scene.shape}
        s["recordings"].append(
            {
                "id": rid,
                "said": text,
                "exact": sentence_exact(text, e.utterance),
                "wrong": [k for k in target if got[k] != target[k]],
            }
        )
    trained = [s for s in scenes.values() if s["split"] == "train"]
    seen_objects = {(s["colour"], s["shape"]) for s in trained}
    seen_action_colour = {(s["action"], s["colour"]) for s in trained}
    seen_action_shape = {(s["action"], s["shape"]) for s in trained}
    for s in scenes.values():
        recs = s["recordings"]
        s["exact"] = round(sum(r["exact"] for r in recs) / len(recs), 4)
        s["wrong_slots"] = {k: sum(k in r["wrong"] for r in recs) for k in ("action", "colour", "object")}
        s["seen"] = {
            "object": (s["colour"], s["shape"]) in seen_objects,
            "action_with_colour": (s["action"], s["colour"]) in seen_action_colour,
            "action_with_shape": (s["action"], s["shape"]) in seen_action_shape,
        }

    def summary(group: list[dict]) -> dict:
        recs = [r for s in group for r in s["recordings"]]
        if not recs:
            return {"recordings": 0}
        return {
            "recordings": len(recs),
            "exact": round(sum(r["exact"] for r in recs) / len(recs), 4),
            "slot_errors": {
                k: round(sum(k in r["wrong"] for r in recs) / len(recs), 4)
                for k in ("action", "colour", "object")
            },
        }

    novel = [s for s in scenes.values() if s["split"] == "test"]
    return {
        "model": lm.name,
        "mode": lm.mode,
        "actions": list(ACTIONS),
        "objects": [f"{c} {s}" for c in COLOURS for s in SHAPES],
        "scenes": list(scenes.values()),
        "train": summary(trained),
        "test": summary(novel),
        "test_object_seen": summary([s for s in novel if s["seen"]["object"]]),
        "test_object_unseen": summary([s for s in novel if not s["seen"]["object"]]),
    }
