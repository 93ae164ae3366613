"""Shared fixtures for the model tests: a tiny synthetic corpus and tiny nets (fast on 2 cores).

The perception is structured so that it carries the scene: proprioception depends on the action,
vision on colour and object (plus noise), like the real corpus but a few steps long.
"""

from __future__ import annotations

import numpy as np

from data.nao import NAO_ARM
from model.config import MTRNNConfig, MultiMTRNNConfig, TrainingConfig
from model.data import SequenceSet
from model.encoding.utterance import PHONEMES

ACTIONS = ("pull", "push", "slide")
COLOURS = ("red", "blue")
OBJECTS = ("apple", "dice")


def tiny_corpus(variants: int = 2, seed: int = 0) -> SequenceSet:
    rng = np.random.default_rng(seed)
    p, v, u, ids = [], [], [], []
    for a, action in enumerate(ACTIONS):
        for c, colour in enumerate(COLOURS):
            for o, obj in enumerate(OBJECTS):
                for k in range(variants):
                    steps = int(rng.integers(12, 18))
                    t = np.linspace(0, 1, steps)[:, None]
                    joints = 0.5 + 0.4 * np.sin((a + 1) * np.pi * t + np.arange(5))
                    vision = np.zeros((steps, 21))
                    vision[:, :16] = 0.3 + 0.4 * o + 0.05 * np.cos(np.arange(16) + a)
                    vision[:, 16 + c] = 0.9
                    p.append((joints + 0.01 * rng.standard_normal(joints.shape)).astype(np.float32))
                    v.append((vision + 0.01 * rng.standard_normal(vision.shape)).astype(np.float32))
                    u.append(f"{action} the {colour} {obj}.")
                    ids.append(f"{action}-{colour}-{obj}-{k}")
    return SequenceSet(p, v, u, ids, arm=NAO_ARM.to_dict())  # codes of the NAO's joints


def tiny_config(epochs: int = 5) -> MultiMTRNNConfig:
    return MultiMTRNNConfig(
        auditory=MTRNNConfig(
            io=len(PHONEMES),
            cf=12,
            cs=6,
            tau_io=2,
            tau_cf=5,
            tau_cs=70,
            io_activation="softmax",
            csc_init=0.01,
        ),
        somatosensory=MTRNNConfig(io=5, cf=6, cs=4, tau_io=2, tau_cf=5, tau_cs=50),
        visual=MTRNNConfig(io=19, cf=6, cs=4, tau_io=2, tau_cf=5, tau_cs=16),
        training=TrainingConfig(
            epochs_auditory=epochs,
            epochs_somatosensory=epochs,
            epochs_visual=epochs,
            epochs_assemblies=epochs,
            progress_every=1,
        ),
    )
