"""A tiny scene set with the full 4 x 4 grids the Latin-square splits need: every colour x shape
object once, its action (4 of them) cycling so that every action x shape pair occurs too; vision
per colour and shape, proprioception per action, as `tests.model.tiny_data` builds them."""

from __future__ import annotations

import numpy as np

from data.nao import NAO_ARM
from model.data import SequenceSet
from tests.model.tiny_data import COLOUR_RGB, SHAPE_BASE

ACTIONS = ("pull", "push", "slide", "show me")
PHASE = {"pull": 0.0, "push": 1.5, "slide": 3.0, "show me": 4.5}


def square_sequence_set(variants: int = 1, steps: int = 10) -> SequenceSet:
    """16 scenes (colour i, shape j, action (i + 2 j) mod 4) x `variants` recordings."""
    rng = np.random.default_rng(0)
    prop, vis, texts, ids = [], [], [], []
    t = np.linspace(0.0, 1.0, steps)[:, None]
    for i, colour in enumerate(COLOUR_RGB):
        for j, shape in enumerate(SHAPE_BASE):
            action = ACTIONS[(i + 2 * j) % 4]
            for v in range(variants):
                p = 0.5 + 0.4 * np.sin(2 * np.pi * t + PHASE[action] + np.arange(5)[None, :] * 0.3)
                prop.append(np.clip(p + rng.normal(0, 0.01, p.shape), 0, 1))
                shape_part = SHAPE_BASE[shape] + 0.1 * np.cos(np.arange(16) * SHAPE_BASE[shape])
                frame = np.concatenate([shape_part, COLOUR_RGB[colour], [0.5, 0.5]])
                vis.append(np.repeat(frame[None, :], steps, axis=0) + rng.normal(0, 0.01, (steps, 21)))
                texts.append(f"{action} the {colour} {shape}.")
                ids.append(f"{action.replace(' ', '-')}-{colour}-{shape}-{v}")
    return SequenceSet(prop, vis, texts, ids, arm=NAO_ARM.to_dict())  # codes of the NAO's joints
