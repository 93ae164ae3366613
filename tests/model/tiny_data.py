"""A tiny, deterministic scene set for protocol tests: 8 scenes x 2 recordings of the grammar
"ACT the COL OBJ." with short proprioception (per action) and vision (per colour and object)
sequences, and a config with a few epochs per net, so that a whole run takes well under a second."""

from __future__ import annotations

import numpy as np

from data.nao import NAO_ARM
from model.data import SequenceSet

SCENES = [
    ("pull", "red", "apple"),
    ("push", "blue", "dice"),
    ("slide", "green", "banana"),
    ("pull", "yellow", "phone"),
    ("push", "red", "banana"),
    ("slide", "blue", "apple"),
    ("pull", "green", "dice"),
    ("push", "yellow", "apple"),
]
ACTION_PHASE = {"pull": 0.0, "push": 1.5, "slide": 3.0}
COLOUR_RGB = {
    "red": (0.9, 0.1, 0.1),
    "blue": (0.1, 0.2, 0.9),
    "green": (0.1, 0.8, 0.2),
    "yellow": (0.9, 0.9, 0.1),
}
SHAPE_BASE = {"apple": 0.5, "dice": 0.3, "banana": 0.8, "phone": 0.6}


def tiny_sequence_set(variants: int = 2, steps: int = 12) -> SequenceSet:
    rng = np.random.default_rng(0)
    prop, vis, texts, ids = [], [], [], []
    t = np.linspace(0.0, 1.0, steps)[:, None]
    for action, colour, shape in SCENES:
        for v in range(variants):
            phase = ACTION_PHASE[action]
            p = 0.5 + 0.4 * np.sin(2 * np.pi * t + phase + np.arange(5)[None, :] * 0.3)
            prop.append(np.clip(p + rng.normal(0, 0.01, p.shape), 0, 1))
            shape_part = SHAPE_BASE[shape] + 0.1 * np.cos(np.arange(16) * SHAPE_BASE[shape])
            frame = np.concatenate([shape_part, COLOUR_RGB[colour], [0.5, 0.5]])
            vis.append(np.repeat(frame[None, :], steps, axis=0) + rng.normal(0, 0.01, (steps, 21)))
            texts.append(f"{action} the {colour} {shape}.")
            ids.append(f"{action}-{colour}-{shape}-{v}")
    return SequenceSet(prop, vis, texts, ids, arm=NAO_ARM.to_dict())  # codes of the NAO's joints


TINY_OVERRIDES = {
    "training.epochs_auditory": 3,
    "training.epochs_somatosensory": 2,
    "training.epochs_visual": 2,
    "training.epochs_assemblies": 2,
}
