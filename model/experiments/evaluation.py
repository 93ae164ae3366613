"""One evaluation run of the paper's protocol (4.2): a split (the paper's 50:50 by scene, or one of
`model.experiments.splits`), training, scores.

`run_once` is the one "split, train, score, build meta" for every training mode (the peer
baseline included): the many-run protocol calls it (locally or in Ray tasks), and so do
`mtrnn train` and the app's training jobs. Plain arguments in, JSON-serialisable metrics out,
deterministic for a given (split, fold, seed).
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
from model.data import SequenceSet
from model.encoding.utterance import Lexicon, text_to_phonemes
from model.experiments.splits import split_indices
from model.metrics import Transcript, d_avg, d_inter, d_intra, d_rel, parse_slots, summarise
from model.multimtrnn import CSC_SPACES, csc_vectors
from model.training import TrainedModel, train
from model.training.common import Describer, ProgressFn

log = logging.getLogger(__name__)


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
    split: str = "scenes",
    train_scenes: int | None = None,
) -> RunResult:
    """Split `data` (`split_indices(ids, utterances, fold, split, train_scenes=...)`: the paper's
    50:50 by scene by default; `train_scenes` is the size split's number of training scenes),
    train `mode` with `seed` and its `config` (see `model.training.train`), score both sides.

    As in 4.2, the split depends on the fold only and the seed is the random initialisation, so
    folds x seeds gives the paper's 10 x 10 runs. With `out_dir`, the model is saved there as a
    checkpoint whose meta carries the metrics, the split's name (`split_kind`, `train_scenes`) and
    its recordings (`split`)."""
    start = time.perf_counter()
    train_set, test_set = split_sets(data, fold, split, train_scenes)
    trained = train(train_set, mode=mode, config=config, seed=seed, progress=progress)
    return scored_run(trained, data, fold, seed, train_set, test_set, start, out_dir, split, train_scenes)


def split_sets(
    data: SequenceSet, fold: int, split: str = "scenes", train_scenes: int | None = None
) -> tuple[SequenceSet, SequenceSet]:
    """The training and test recordings of `fold` on `split` (`split_indices`)."""
    train_idx, test_idx = split_indices(data.ids, data.utterances, fold, split, train_scenes=train_scenes)
    return data.subset(train_idx), data.subset(test_idx)


def scored_run(
    trained: TrainedModel,
    data: SequenceSet,
    fold: int,
    seed: int,
    train_set: SequenceSet,
    test_set: SequenceSet,
    start: float,
    out_dir: str | Path | None = None,
    split: str = "scenes",
    train_scenes: int | None = None,
) -> RunResult:
    """`trained` scored on both sides of its split, with its meta (and saved to `out_dir` if given);
    the run's seconds are counted from `start` (`time.perf_counter()`)."""
    metrics = score_split(
        trained.model, trained.lexicon, train_set, test_set, slot_vocabularies(data.utterances)
    )
    seconds = time.perf_counter() - start
    meta = run_meta(trained, fold, train_set, test_set, metrics)
    meta.update({"split_kind": split, "train_scenes": train_scenes})
    meta["seconds_run"] = seconds
    if out_dir is not None:
        checkpoint.save(trained.model, out_dir, meta, trained.csc, trained.familiarity)
    log.info(
        "%s %s fold %d seed %d: test exact %.3f F1 %.3f (%.1f s)",
        meta["mode"],
        split,
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
