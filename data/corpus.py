"""The simulated corpora: 64 scenes x 4 teachers (the paper's), or x 16 over a wide variety of
setups, encoded once and shipped as compressed .npz files.

Each recording (scene, variant) is made from random streams derived from
``(seed, scene.index, variant)``: the teacher (`Teacher.sample`), the motion (`generate_motion`)
and the camera's appearance (`Appearance.sample`); the "wide" variety (`data.variety`) draws the
recording's `Setup` (table, object, postures, IK solution, tempo, camera) from a fourth. Its frames
are rendered (`render_frames`) and encoded like any uploaded recording
(`data.encode.encode_recording`); the frames themselves are not stored, since `export_recording`
re-renders them from the same streams.

File layout (``data/artefacts/corpus.npz``, no pickles; ragged sequences concatenated):

- ``joints`` [N, 5] float64 radians, ``proprioception`` [N, 5] float32, ``vision`` [N, 21] float32,
  where N is the total number of 20 Hz steps over all recordings;
- ``offsets`` [R + 1] int64: recording r spans rows ``offsets[r]:offsets[r + 1]``;
- ``metadata`` uint8: UTF-8 JSON with the format version, seed and, per recording, id, scene,
  variant, utterance, teacher and appearance parameters and the fraction of frames in which the
  vision encoder found the object. A wide corpus adds ``variety`` ("wide"; absent: "paper") and,
  per recording, its ``setup`` (`data.setup.Setup.to_dict`) and ``labels`` (`data.variety.labels`:
  table height, placement, posture family, IK preference, tempo, shape variant, camera).

The zip is written member by member with fixed timestamps, so the same seed gives the same bytes.
"""

from __future__ import annotations

import io
import json
import logging
import zipfile
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from multiprocessing import get_context
from pathlib import Path

import cv2
import numpy as np

from data.camera import Appearance, render_frames
from data.encode import encode_recording
from data.motion import Teacher, generate_motion
from data.nao import JOINT_LIMITS, NAO_ARM
from data.recording import Recording, add_zip_member, atomic_write
from data.scenario import VARIANTS, Scene, all_scenes, parse_recording_id, recording_id
from data.setup import PAPER_SETUP, Setup
from data.variety import VARIETIES, labels, sample_appearance, sample_setup, sample_teacher
from data.world import FPS
from model.data import SequenceSet

logger = logging.getLogger(__name__)

CORPUS_FORMAT = 1
DEFAULT_PATH = Path(__file__).resolve().parent / "artefacts" / "corpus.npz"
WIDE_PATH = DEFAULT_PATH.with_name("corpus_wide.npz")
VARIANTS_PER_SCENE = 4  # the paper's corpus (`build_corpus(recordings_per_scene=...)` for more)


@dataclass
class CorpusEntry:
    """One encoded recording of the corpus."""

    id: str  # e.g. "slide-red-apple-2"
    scene: Scene
    variant: int
    joints: np.ndarray  # [T, 5] radians
    proprioception: np.ndarray  # [T, 5] in [0, 1]
    vision: np.ndarray  # [T, 21]: 19 paper features + centroid
    utterance: str
    teacher: dict = field(default_factory=dict)
    appearance: dict = field(default_factory=dict)
    object_found: float = 1.0  # fraction of frames in which the vision encoder found the object
    setup: dict = field(default_factory=dict)  # wide corpus: `Setup.to_dict()` (empty: the paper's)
    labels: dict = field(default_factory=dict)  # wide corpus: the regions it lies in (`data.variety.labels`)


@dataclass
class Corpus:
    """The encoded corpus, in `all_scenes()` order with variants 0..3 (wide: 0..15) per scene."""

    entries: list[CorpusEntry]
    seed: int
    path: Path | None = None
    variety: str = "paper"

    def __post_init__(self) -> None:
        self._index = {e.id: i for i, e in enumerate(self.entries)}

    def __len__(self) -> int:
        return len(self.entries)

    def by_id(self, rid: str) -> CorpusEntry:
        """The entry with recording id `rid` (raises KeyError naming it)."""
        if rid not in self._index:
            raise KeyError(f"no recording {rid!r} in the corpus")
        return self.entries[self._index[rid]]

    def index_of(self, rid: str) -> int:
        return self._index[rid]

    @property
    def ids(self) -> list[str]:
        return [e.id for e in self.entries]

    @property
    def scene_ids(self) -> list[str]:
        """Scene id of every entry (aligned with `entries`): the groups for scene-wise splits."""
        return [e.scene.id for e in self.entries]

    def training_data(self, indices: Iterable[int] | None = None) -> SequenceSet:
        """The entries at `indices` (all by default) as what training needs."""
        picked = [self.entries[int(i)] for i in (range(len(self.entries)) if indices is None else indices)]
        return SequenceSet(
            proprioception=[e.proprioception for e in picked],
            vision=[e.vision for e in picked],
            utterances=[e.utterance for e in picked],
            ids=[e.id for e in picked],
            arm=NAO_ARM.to_dict(),
        )


# ---------------------------------------------------------------------------------------- simulation


def _streams(seed: int, scene: Scene, variant: int, count: int = 3) -> tuple[np.random.Generator, ...]:
    """Independent generators for teacher, motion, appearance (and setup) of one recording."""
    children = np.random.SeedSequence([seed, scene.index, variant]).spawn(count)
    return tuple(np.random.default_rng(child) for child in children)


def _check_variety(variety: str) -> None:
    if variety not in VARIETIES:
        raise ValueError(f"unknown variety {variety!r}; expected one of {VARIETIES}")


def _simulate(
    seed: int, scene: Scene, variant: int, variety: str = "paper"
) -> tuple[Teacher, Setup, Appearance, Recording]:
    _check_variety(variety)
    if variety == "paper":
        teacher_rng, motion_rng, appearance_rng = _streams(seed, scene, variant)
        teacher, setup = Teacher.sample(teacher_rng), PAPER_SETUP
        motion = generate_motion(scene, teacher, motion_rng)
        appearance = Appearance.sample(appearance_rng)
    else:
        teacher_rng, motion_rng, appearance_rng, setup_rng = _streams(seed, scene, variant, 4)
        teacher, setup = sample_teacher(teacher_rng), sample_setup(setup_rng)
        motion = generate_motion(scene, teacher, motion_rng, setup)
        appearance = sample_appearance(appearance_rng, setup.world)
    frames = render_frames(scene, motion, appearance, setup.world)
    recording = Recording(joints=motion.joints, frames=frames, fps=FPS, utterance=scene.utterance)
    return teacher, setup, appearance, recording


def export_recording(rid: str, seed: int = 0, variety: str = "paper") -> Recording:
    """Recording `rid` of the corpus built with `seed` and `variety`, frames re-rendered (format-v1 ready)."""
    scene, variant = parse_recording_id(rid)
    return _simulate(seed, scene, variant, variety)[3]


def _params(obj: object) -> dict:
    """JSON-friendly parameters of a Teacher or an Appearance."""
    return json.loads(json.dumps(obj.to_dict()))


def _init_worker() -> None:
    cv2.setNumThreads(1)  # one process per core; OpenCV's own threads would oversubscribe


def _build_one(task: tuple[int, int, int, str]) -> dict:
    """Simulate and encode one recording (runs in a worker process; top level for spawn)."""
    seed, scene_index, variant, variety = task
    scene = all_scenes()[scene_index]
    teacher, setup, appearance, rec = _simulate(seed, scene, variant, variety)
    features = encode_recording(rec, workers=1)
    meta = {
        "id": recording_id(scene, variant),
        "scene": scene.id,
        "variant": variant,
        "utterance": scene.utterance,
        "steps": len(rec.joints),
        "object_found": round(float(features.object_found.mean()), 4),
        "teacher": _params(teacher),
        "appearance": _params(appearance),
    }
    if variety != "paper":
        meta["setup"] = _params(setup)
        meta["labels"] = labels(scene, setup, teacher, appearance, len(rec.joints))
    return {
        "id": recording_id(scene, variant),
        "joints": rec.joints,
        "proprioception": features.proprioception,
        "vision": features.vision,
        "meta": meta,
    }


# --------------------------------------------------------------------------------------------- build


def build_corpus(
    seed: int = 0,
    workers: int = 2,
    out: Path | None = None,
    recordings: Sequence[str] | None = None,
    progress: Callable[[int, int], None] | None = None,
    variety: str = "paper",
    recordings_per_scene: int = VARIANTS_PER_SCENE,
) -> Path:
    """Simulate, encode and save the corpus; returns the path written (atomically).

    `variety` is "paper" (today's sampling) or "wide" (`data.variety`); by default all 64 scenes x
    `recordings_per_scene` (variants 0..n-1); `recordings` restricts the build to those ids (tests).
    `progress(done, total)` is called after each recording (the CLI draws a progress bar).
    """
    _check_variety(variety)
    if not 1 <= recordings_per_scene <= len(VARIANTS):
        raise ValueError(f"recordings per scene must be 1..{len(VARIANTS)}, got {recordings_per_scene}")
    out = Path(out) if out is not None else DEFAULT_PATH
    if recordings is None:
        tasks = [(seed, s.index, v, variety) for s in all_scenes() for v in range(recordings_per_scene)]
    else:
        tasks = []
        for rid in recordings:
            scene, variant = parse_recording_id(rid)
            tasks.append((seed, scene.index, variant, variety))
    results: list[dict] = []
    if workers <= 1:
        for task in tasks:
            results.append(_build_one(task))
            if progress:
                progress(len(results), len(tasks))
    else:
        with get_context("spawn").Pool(workers, initializer=_init_worker) as pool:
            for result in pool.imap(_build_one, tasks, chunksize=1):
                results.append(result)
                if progress:
                    progress(len(results), len(tasks))
    _write(results, seed, variety, out)
    logger.info("wrote %d recordings to %s (%.1f MB)", len(results), out, out.stat().st_size / 1024**2)
    return out


def _write(results: list[dict], seed: int, variety: str, out: Path) -> None:
    lengths = [len(r["joints"]) for r in results]
    arrays = {
        "joints": np.concatenate([r["joints"] for r in results]).astype(np.float64),
        "proprioception": np.concatenate([r["proprioception"] for r in results]).astype(np.float32),
        "vision": np.concatenate([r["vision"] for r in results]).astype(np.float32),
        "offsets": np.concatenate([[0], np.cumsum(lengths)]).astype(np.int64),
    }
    metadata = {
        "format": CORPUS_FORMAT,
        "seed": seed,
        "fps": FPS,
        "joint_limits": JOINT_LIMITS.tolist(),
        "entries": [r["meta"] for r in results],
    }
    if variety != "paper":  # the paper's corpus file predates varieties: no key, same bytes
        metadata["variety"] = variety
    arrays["metadata"] = np.frombuffer(json.dumps(metadata, sort_keys=True).encode("utf-8"), dtype=np.uint8)

    def write(tmp: Path) -> None:
        with zipfile.ZipFile(tmp, "w") as archive:
            for key, array in arrays.items():
                buf = io.BytesIO()
                np.lib.format.write_array(buf, np.ascontiguousarray(array), allow_pickle=False)
                add_zip_member(archive, f"{key}.npy", buf.getvalue(), zipfile.ZIP_DEFLATED)

    atomic_write(out, write)


# ---------------------------------------------------------------------------------------------- load


def load_corpus(path: Path | None = None) -> Corpus:
    """Read a corpus written by `build_corpus`, of either variety (default: the shipped
    ``data/artefacts/corpus.npz``; the wide one is `WIDE_PATH`)."""
    path = Path(path) if path is not None else DEFAULT_PATH
    if not path.is_file():
        raise FileNotFoundError(f"no corpus at {path}; build it with `mtrnn corpus build`")
    with np.load(path, allow_pickle=False) as npz:
        arrays = {k: npz[k] for k in ("joints", "proprioception", "vision", "offsets", "metadata")}
    metadata = json.loads(arrays["metadata"].tobytes().decode("utf-8"))
    if metadata.get("format") != CORPUS_FORMAT:
        raise ValueError(f"{path}: corpus format {metadata.get('format')} is not {CORPUS_FORMAT}; rebuild it")
    offsets = arrays["offsets"]
    entries = []
    for r, meta in enumerate(metadata["entries"]):
        rows = slice(int(offsets[r]), int(offsets[r + 1]))
        scene, variant = parse_recording_id(meta["id"])
        entries.append(
            CorpusEntry(
                id=meta["id"],
                scene=scene,
                variant=variant,
                joints=arrays["joints"][rows],
                proprioception=arrays["proprioception"][rows],
                vision=arrays["vision"][rows],
                utterance=meta["utterance"],
                teacher=meta["teacher"],
                appearance=meta["appearance"],
                object_found=meta["object_found"],
                setup=meta.get("setup", {}),
                labels=meta.get("labels", {}),
            )
        )
    return Corpus(
        entries=entries, seed=int(metadata["seed"]), path=path, variety=metadata.get("variety", "paper")
    )
