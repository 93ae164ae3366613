"""Information check of the corpus (issue 3): what can a linear probe read from each modality?

The paper's scenario is built so that vision knows *what* the object is (colour and shape) and
proprioception knows *what was done* (the action) but hardly which object: all objects have
similar mass and size, with the one exception of sliding the banana. Targets, all on held-out
scenes:

- recording-averaged vision features (the 19 of the paper) -> 16 objects (colour x shape): >= 0.95
- proprioception resampled to a fixed length -> 4 actions: >= 0.95
- proprioception -> 16 objects: near chance (1/16)

Split by scene: fold k tests the scenes with (action + colour + shape) % 4 == k (indices in the
grammar), i.e. each object is tested with one action that it is never seen with in training and
each action with four objects it is never seen with in training. Four folds cover every scene once.
The object is probed twice: one 16-way logistic regression, and "factorised" (a colour probe and a
shape probe, the object right only when both are). The vision features are factorised by
construction (mean R, G, B carry the colour, the 16 distances the shape); with 12 training
recordings per object class the 16-way probe has to learn each colour x shape conjunction from
three scenes, while the factorised probes see 48 per class. The check uses the factorised probe;
both numbers are printed.

A probe that reads only the action therefore scores *below* chance on the objects (it names the
objects seen with that action in training, never the held-out one): "near chance" means that
proprioception carries no object information beyond the action.

    .venv/bin/python benchmarks/probe.py [--corpus data/artefacts/corpus.npz]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
from sklearn.linear_model import LogisticRegression
from sklearn.pipeline import make_pipeline
from sklearn.preprocessing import StandardScaler

from data.corpus import Corpus, load_corpus
from data.scenario import ACTIONS, COLOURS, SHAPES
from model.encoding.vision import VISUAL_FEATURES

FOLDS = 4
RESAMPLED_STEPS = 24


def _fold_of(corpus: Corpus) -> np.ndarray:
    scenes = [e.scene for e in corpus.entries]
    return np.array(
        [(ACTIONS.index(s.action) + COLOURS.index(s.colour) + SHAPES.index(s.shape)) % FOLDS for s in scenes]
    )


def _resample(sequence: np.ndarray, steps: int) -> np.ndarray:
    src = np.linspace(0.0, 1.0, len(sequence))
    dst = np.linspace(0.0, 1.0, steps)
    return np.stack([np.interp(dst, src, sequence[:, j]) for j in range(sequence.shape[1])], axis=1)


def features(corpus: Corpus) -> dict[str, np.ndarray]:
    vision = np.stack([e.vision[:, :VISUAL_FEATURES].mean(axis=0) for e in corpus.entries])
    proprio = np.stack([_resample(e.proprioception, RESAMPLED_STEPS).ravel() for e in corpus.entries])
    return {"vision": vision, "proprioception": proprio}


def scene_split_accuracy(x: np.ndarray, y: np.ndarray, fold: np.ndarray) -> float:
    """Accuracy over all recordings, each predicted by a probe trained on the other folds' scenes."""
    correct = 0
    for k in range(FOLDS):
        test = fold == k
        probe = make_pipeline(StandardScaler(), LogisticRegression(C=1.0, max_iter=5000))
        probe.fit(x[~test], y[~test])
        correct += int((probe.predict(x[test]) == y[test]).sum())
    return correct / len(y)


def factorised_object_accuracy(
    x: np.ndarray, colours: np.ndarray, shapes: np.ndarray, fold: np.ndarray
) -> float:
    """16-object accuracy of a colour probe and a shape probe together (right only if both are)."""
    correct = 0
    for k in range(FOLDS):
        test = fold == k
        hits = np.ones(int(test.sum()), dtype=bool)
        for y in (colours, shapes):
            probe = make_pipeline(StandardScaler(), LogisticRegression(C=1.0, max_iter=5000))
            probe.fit(x[~test], y[~test])
            hits &= probe.predict(x[test]) == y[test]
        correct += int(hits.sum())
    return correct / len(colours)


def run(corpus: Corpus) -> dict[str, float]:
    feats = features(corpus)
    fold = _fold_of(corpus)
    labels = {
        "object (16)": np.array([f"{e.scene.colour} {e.scene.shape}" for e in corpus.entries]),
        "colour (4)": np.array([e.scene.colour for e in corpus.entries]),
        "shape (4)": np.array([e.scene.shape for e in corpus.entries]),
        "action (4)": np.array([e.scene.action for e in corpus.entries]),
    }
    scores = {
        f"{modality} -> {target}": scene_split_accuracy(x, y, fold)
        for modality, x in feats.items()
        for target, y in labels.items()
    }
    for modality, x in feats.items():
        scores[f"{modality} -> object, factorised"] = factorised_object_accuracy(
            x, labels["colour (4)"], labels["shape (4)"], fold
        )
    return scores


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--corpus", type=Path, default=None, help="corpus .npz (default: the shipped one)")
    args = parser.parse_args(argv)
    corpus = load_corpus(args.corpus)
    scores = run(corpus)
    print(f"corpus: {corpus.path} ({len(corpus)} recordings, seed {corpus.seed})")
    print(f"split by scene, {FOLDS} folds; accuracy on held-out scenes:")
    for name, value in scores.items():
        print(f"  {name:38s} {value:.3f}")
    found = np.array([e.object_found for e in corpus.entries])
    print(f"  vision found the object in {found.mean():.1%} of frames (worst recording {found.min():.1%})")
    checks = {
        "vision -> object (factorised) >= 0.95": scores["vision -> object, factorised"] >= 0.95,
        "proprioception -> action >= 0.95": scores["proprioception -> action (4)"] >= 0.95,
        # chance is 1/16 = 0.0625; 0.15 leaves room for the banana-slide exception and noise
        "proprioception -> object <= 0.15": scores["proprioception -> object (16)"] <= 0.15,
    }
    for name, ok in checks.items():
        print(f"  {'PASS' if ok else 'FAIL'}  {name}")
    return 0 if all(checks.values()) else 1


if __name__ == "__main__":
    sys.exit(main())
