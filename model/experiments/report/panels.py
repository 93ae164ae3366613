"""Fig. 10-style panels: a stored run's checkpoint describes every recording, and the PCA of each
Csc space is laid out with the recordings' actions, colours, objects and split."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from model import checkpoint
from model.encoding.utterance import Lexicon
from model.experiments.runstore import RunRecord
from model.metrics import CscPCA, parse_slots
from model.multimtrnn import csc_vectors

SPACE_NAMES = {"somatosensory": "MTRNN_s (c_s,T)", "visual": "MTRNN_v (c_v,T)", "auditory": "MTRNN_a (c_a,0)"}


def csc_panels(run: RunRecord, data: Any, spaces: Sequence[str] = tuple(SPACE_NAMES)) -> list[dict]:
    """PCA (normalised to [-1, 1] per axis, as Fig. 10) of each Csc space over every recording."""
    model, meta = checkpoint.load(run.checkpoint)
    descriptions = model.describe_batch(data.proprioception, data.vision, Lexicon(meta["lexicon"]))
    train_ids = set(meta.get("split", {}).get("train", []))
    slots = [parse_slots(u) for u in data.utterances]
    vectors = csc_vectors(descriptions)
    panels = []
    for space in spaces:
        pca = CscPCA(2).fit(vectors[space])
        xy = pca.transform(vectors[space])
        xy = xy / np.maximum(np.abs(xy).max(axis=0), 1e-12)  # normalised, as in Fig. 10
        explained = pca.explained_variance_ratio_[:2].sum()
        panels.append(
            {
                "space": space,
                "title": f"{run.mode} {SPACE_NAMES[space]}; PC1+2 {explained:.0%}",
                "xy": xy.round(4).tolist(),
                "ids": list(data.ids),
                "action": [s["action"] or "?" for s in slots],
                "colour": [s["colour"] or "?" for s in slots],
                "object": [s["object"] or "?" for s in slots],
                "split": ["train" if rid in train_ids else "test" for rid in data.ids],
                "generated": [d.text for d in descriptions],
            }
        )
    return panels
