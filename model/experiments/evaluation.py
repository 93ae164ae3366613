"""One evaluation run of the paper's protocol (4.2): a 50:50 split by scene, training, scores.

`run_once` is the one "split, train, score, build meta" for every training mode (the peer
baseline included): the many-run protocol calls it (locally or in Ray tasks), and so do
`mtrnn train` and the app's training jobs. Plain arguments in, JSON-serialisable metrics out,
deterministic for a given (fold, seed).
"""

from __future__ import annotations

import logging
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from model import checkpoint
from model.data import SequenceSet, scene_key
from model.encoding.utterance import Lexicon, text_to_phonemes
from model.metrics import Transcript, d_avg, d_inter, d_intra, d_rel, parse_slots, summarise
from model.multimtrnn import CSC_SPACES, csc_vectors
from model.training import TrainedModel, train
from model.training.common import Describer, ProgressFn

log = logging.getLogger(__name__)


def fold_split(scene_keys: Sequence[str], fold: int, seed: int = 0) -> tuple[list[int], list[int]]:
    """50:50 split of recordings by scene (4.2): every recording of a scene on the same side.

    `scene_keys` are per recording (recording ids work too: a trailing "-N" is dropped). The
    scenes are shuffled by a generator seeded with (seed, fold); the first half (rounded up)
    trains. Returns sorted recording indices (train, test)."""
    keys = [scene_key(k) for k in scene_keys]
    scenes = sorted(set(keys))
    if len(scenes) < 2:
        raise ValueError(f"a split by scene needs at least 2 scenes, got {len(scenes)}")
    order = np.random.default_rng([seed, fold]).permutation(len(scenes))
    train_scenes = {scenes[i] for i in order[: (len(scenes) + 1) // 2]}
    train_idx = [i for i, k in enumerate(keys) if k in train_scenes]
    test_idx = [i for i, k in enumerate(keys) if k not in train_scenes]
    return train_idx, test_idx


def slot_vocabularies(utterances: Sequence[str]) -> tuple[list[str], list[str], list[str]] | None:
    """Actions, colours and objects read from target sentences "ACT the COL OBJ."."""
    slots = [parse_slots(u) for u in utterances]
    if any(v is None for s in slots for v in s.values()):
        return None
    return tuple(sorted({s[k] for s in slots}) for k in ("action", "colour", "object"))


def csc_measures(points: np.ndarray, labels: Sequence[str]) -> dict[str, float | None]:
    """d_avg, d_rel (eqs. 13-15) and d_inter, d_intra (eqs. 22-23, clusters = `labels`)."""
    out: dict[str, float | None] = {"d_avg": None, "d_rel": None, "d_inter": None, "d_intra": None}
    if len(points) < 2:
        return out
    out["d_avg"], out["d_rel"] = d_avg(points), d_rel(points)
    try:
        out["d_inter"] = d_inter(points, labels)
        out["d_intra"] = d_intra(points, labels)
    except ValueError:  # a cluster with one pattern, or only one cluster: not defined
        pass
    return out


def score(
    model: Describer,
    data: SequenceSet,
    lexicon: Lexicon,
    vocabularies: tuple[Sequence[str], Sequence[str], Sequence[str]] | None = None,
) -> dict:
    """Describe every scene of `data` and score it against the teacher's utterance.

    Returns the means of `model.metrics.summarise` (sentence_exact, f1, precision, recall,
    edit_distance, word_accuracy, slot_action, slot_colour, slot_object, n) and "csc": per space
    the Csc measures of the abstracted c_s,T, c_v,T and of the c_a,0 the assemblies produce, with
    the action of each scene as its cluster (4.3). `vocabularies` (actions, colours, objects)
    default to those of the target sentences."""
    descriptions = model.describe_batch(data.proprioception, data.vision, lexicon)
    pairs = [
        (Transcript(tuple(d.phonemes), d.text), Transcript(tuple(text_to_phonemes(u)), u))
        for d, u in zip(descriptions, data.utterances, strict=True)
    ]
    vocab = vocabularies or slot_vocabularies(data.utterances)
    result: dict = summarise(pairs, *(vocab or (None, None, None)))
    actions = [parse_slots(u)["action"] or "" for u in data.utterances]
    points = csc_vectors(descriptions)
    result["csc"] = {space: csc_measures(points[space], actions) for space in CSC_SPACES}
    return result


def mixed_metrics(train, test):
    """The paper's "mixed" (4.3): train and test with equal weight, for every numeric leaf."""
    if isinstance(train, dict):
        return {k: mixed_metrics(train[k], test.get(k)) for k in train if k in test}
    if train is None or test is None:
        return None
    return (float(train) + float(test)) / 2.0


def score_split(
    model: Describer,
    lexicon: Lexicon,
    train_set: SequenceSet,
    test_set: SequenceSet,
    vocabularies: tuple[Sequence[str], Sequence[str], Sequence[str]] | None,
) -> dict:
    """{"train", "test", "mixed"}: `score` on both sides of a split and their mean (4.3)."""
    metrics = {
        "train": score(model, train_set, lexicon, vocabularies),
        "test": score(model, test_set, lexicon, vocabularies),
    }
    metrics["mixed"] = mixed_metrics(metrics["train"], metrics["test"])
    return metrics


@dataclass
class RunResult:
    metrics: dict  # {"train": ..., "test": ..., "mixed": ...}, JSON-serialisable
    model: Describer
    seconds: float
    meta: dict


def run_once(
    data: SequenceSet,
    mode: str,
    fold: int,
    seed: int,
    config: Any = None,
    out_dir: str | Path | None = None,
    progress: ProgressFn | None = None,
) -> RunResult:
    """Split `data` by scene (`fold_split(ids, fold)`), train `mode` with `seed` and its `config`
    (see `model.training.train`), score both sides.

    As in 4.2, the split depends on the fold only and the seed is the random initialisation, so
    folds x seeds gives the paper's 10 x 10 runs. With `out_dir`, the model is saved there as a
    checkpoint whose meta carries the metrics and the split."""
    start = time.perf_counter()
    train_idx, test_idx = fold_split(data.ids, fold, seed=0)
    train_set, test_set = data.subset(train_idx), data.subset(test_idx)
    trained = train(train_set, mode=mode, config=config, seed=seed, progress=progress)
    metrics = score_split(
        trained.model, trained.lexicon, train_set, test_set, slot_vocabularies(data.utterances)
    )
    seconds = time.perf_counter() - start
    meta = run_meta(trained, fold, train_set, test_set, metrics)
    meta["seconds_run"] = seconds
    if out_dir is not None:
        checkpoint.save(trained.model, out_dir, meta, trained.csc)
    log.info(
        "%s fold %d seed %d: test exact %.3f F1 %.3f (%.1f s)",
        mode,
        fold,
        seed,
        metrics["test"]["sentence_exact"],
        metrics["test"]["f1"],
        seconds,
    )
    return RunResult(metrics, trained.model, seconds, meta)


def run_meta(
    trained: TrainedModel, fold: int, train_set: SequenceSet, test_set: SequenceSet, metrics: dict
) -> dict:
    """The training's meta with the run's fold, split and metrics."""
    meta = dict(trained.meta)
    meta.update(
        {
            "fold": fold,
            "split": {"train": list(train_set.ids), "test": list(test_set.ids)},
            "metrics": metrics,
        }
    )
    return meta
